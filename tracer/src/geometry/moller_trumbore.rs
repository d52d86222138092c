//! The ray–triangle test of Möller and Trumbore, "Fast, minimum storage ray/triangle intersection" (JGT 1997).
//!
//! The hit `o + t·d = (1 − u − v)·p0 + u·p1 + v·p2` is solved by Cramer's rule with the edges `e1 = p1 − p0`,
//! `e2 = p2 − p0` and `s = o − p0`: `det = −d · n`, `u = s · (d × e2) / det`, `v = d · (s × e1) / det`,
//! `t = s · n / det`, `n = e1 × e2`. The paper evaluates the same triple products around `d × e2` and `s × e1`;
//! here they are arranged around `n` and `r = d × s` (`u = −r · e2 / det`, `v = r · e1 / det`), the same two
//! cross and four dot products, so that a repeated vertex makes `n`, hence `det`, exactly 0 (the paper's `det`
//! from `d × e2` is rounding noise when `p1 = p2`, and reports false hits). Two-sided: only `det = 0` (a ray
//! parallel to the plane, or such a triangle) is rejected. Each triangle rounds its own edges, so a ray through
//! an edge shared by two triangles can slip between them.

use glam::Vec3;

use super::{Ray, Triangle, TriangleHit};

impl Triangle {
    /// Nearest hit with `t` in `(ray.t_min, t_max)` by Möller–Trumbore (see the module documentation).
    #[inline(always)]
    pub fn intersect_moller_trumbore(&self, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        let [p0, e1, e2, n] = self.moller_trumbore_frame();
        Self::moller_trumbore(p0, e1, e2, n, ray, t_max)
    }

    /// What the test reads of the triangle, computed the same way whether per ray or once for a SIMD block:
    /// `p0`, `e1 = p1 − p0`, `e2 = p2 − p0` and `n = e1 × e2`.
    #[inline(always)]
    pub fn moller_trumbore_frame(&self) -> [Vec3; 4] {
        let [p0, p1, p2] = self.p;
        let (e1, e2) = (p1 - p0, p2 - p0);
        [p0, e1, e2, e1.cross(e2)]
    }

    /// The test on a triangle given by [`Triangle::moller_trumbore_frame`].
    #[inline(always)]
    pub fn moller_trumbore(p0: Vec3, e1: Vec3, e2: Vec3, n: Vec3, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        let det = -ray.dir.dot(n);
        if det == 0.0 {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = ray.origin - p0;
        let r = ray.dir.cross(s);
        let u = -r.dot(e2) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let v = r.dot(e1) * inv_det;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = s.dot(n) * inv_det;
        (t > ray.t_min && t < t_max).then_some(TriangleHit { t, b1: u, b2: v })
    }
}
