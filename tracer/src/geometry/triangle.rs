use glam::Vec3;

use super::{Aabb, Ray, TriangleTest};

/// A triangle given by its three vertices; rays hit it from either side.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Triangle {
    /// The vertices `p0, p1, p2`.
    pub p: [Vec3; 3],
}

/// Where a ray meets a triangle: its parameter and the barycentric weights `b1`, `b2` of `p1` and `p2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of `p1`.
    pub b1: f32,
    /// Barycentric weight of `p2` (`p0`'s is `1 − b1 − b2`).
    pub b2: f32,
}

impl Triangle {
    /// The triangle `p0, p1, p2`.
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Self {
        Self { p: [p0, p1, p2] }
    }

    /// Relative widening of [`Triangle::bounds`]: the largest vertex coordinate magnitude times this on every side.
    pub const BOUNDS_PAD: f32 = 4.0 * f32::EPSILON;

    /// Bounding box, widened by a few ulps so that rounding never puts a surface point outside it.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::point(self.p[0]);
        b.grow(self.p[1]);
        b.grow(self.p[2]);
        let pad = b.min.abs().max(b.max.abs()) * Self::BOUNDS_PAD;
        Aabb { min: b.min - pad, max: b.max + pad }
    }

    /// The mean of the vertices.
    pub fn centroid(&self) -> Vec3 {
        (self.p[0] + self.p[1] + self.p[2]) * (1.0 / 3.0)
    }

    /// Unit normal of the triangle's plane on the side of `toward` (`(p1 − p0) × (p2 − p0)`, flipped if needed).
    pub fn normal_toward(&self, toward: Vec3) -> Vec3 {
        let n = (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0]).normalize_or_zero();
        if n.dot(toward) < 0.0 { -n } else { n }
    }

    /// Nearest hit with `t` in `(ray.t_min, t_max)` by the chosen test; both cull nothing.
    #[inline(always)]
    pub fn intersect(&self, test: TriangleTest, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        match test {
            TriangleTest::MollerTrumbore => self.intersect_moller_trumbore(ray, t_max),
            TriangleTest::Watertight => self.intersect_watertight(ray, t_max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_contain_the_vertices_and_centroid_is_their_mean() {
        let tri = Triangle::new(Vec3::new(1.0e3, -2.0, 3.5), Vec3::new(-1.0, 0.25, 7.0), Vec3::new(0.5, 9.0, -4.0));
        let b = tri.bounds();
        assert!(tri.p.iter().all(|&p| b.contains(p)));
        assert!(b.min.x < -1.0 && b.max.x > 1.0e3);
        let c = tri.centroid();
        assert!((c - Vec3::new(999.5 / 3.0, 7.25 / 3.0, 6.5 / 3.0)).abs().max_element() < 1e-4);
    }

    /// Both tests find a plain hit from either side at the same `t` and barycentrics, and respect `t_min`, `t_max`.
    #[test]
    fn both_tests_hit_either_side_within_t_min_and_t_max() {
        let tri = Triangle::new(Vec3::new(0.0, 0.0, -4.0), Vec3::new(2.0, 0.0, -4.0), Vec3::new(0.0, 2.0, -4.0));
        for test in TriangleTest::ALL {
            let front = Ray::new(Vec3::new(0.5, 0.25, 0.0), -Vec3::Z);
            let hit = tri.intersect(test, &front, f32::INFINITY).unwrap_or_else(|| panic!("{}", test.name()));
            assert_eq!((hit.t, hit.b1, hit.b2), (4.0, 0.25, 0.125), "{}", test.name());
            let back = Ray::new(Vec3::new(0.5, 0.25, -6.0), Vec3::new(0.0, 0.0, 2.0));
            assert_eq!(tri.intersect(test, &back, f32::INFINITY).map(|h| h.t), Some(1.0), "{}", test.name());
            assert_eq!(tri.intersect(test, &front, 4.0), None, "t_max is exclusive: {}", test.name());
            let late = Ray { t_min: 4.0, ..front };
            assert_eq!(tri.intersect(test, &late, f32::INFINITY), None, "t_min is exclusive: {}", test.name());
            let away = Ray::new(Vec3::new(0.5, 0.25, 0.0), Vec3::Z);
            assert_eq!(tri.intersect(test, &away, f32::INFINITY), None, "{}", test.name());
            let outside = Ray::new(Vec3::new(1.5, 1.5, 0.0), -Vec3::Z);
            assert_eq!(tri.intersect(test, &outside, f32::INFINITY), None, "{}", test.name());
        }
    }

    /// Zero-area triangles (a vertex repeated, or all three) are never hit by either test, even by rays aimed at
    /// their vertices: a repeated vertex makes the watertight test's edge functions one exactly 0 and the others
    /// exact opposites, and Möller–Trumbore's `det` exactly 0. Nothing panics or comes out NaN.
    #[test]
    fn degenerate_triangles_are_never_hit() {
        let mut rng = crate::rng::SplitMix64::new(4);
        let mut point = |s: f64| Vec3::new(rng.range(-s, s) as f32, rng.range(-s, s) as f32, rng.range(-s, s) as f32);
        for i in 0..20_000 {
            let (p, q) = (point(10.0), point(10.0));
            let origin = point(30.0);
            let aim = [p, q, p.lerp(q, 0.5), p + point(1e-3)][i % 4];
            let ray = Ray::new(origin, aim - origin);
            for tri in [[p, p, p], [p, p, q], [p, q, p], [q, p, p]].map(|[a, b, c]| Triangle::new(a, b, c)) {
                for test in TriangleTest::ALL {
                    assert_eq!(tri.intersect(test, &ray, f32::INFINITY), None, "{}: {tri:?} {ray:?}", test.name());
                }
            }
        }
    }
}
