//! A ray against a triangle in f64, and how far the f32 tests ([`Triangle::intersect_moller_trumbore`],
//! [`Triangle::intersect_watertight`]) can stray from it.
//!
//! [`ExactTriangleTest::new`] takes the f32 ray and triangle exactly and evaluates the watertight formulation in
//! f64 (see `watertight.rs`): the ray-space coordinates `(xᵢ, yᵢ)` and depths `zᵢ = aᵢ[kz] / d[kz]` of the
//! vertices (`aᵢ = pᵢ − o`), the edge functions `E = (U, V, W)` and `t = Σ Eᵢ·zᵢ / Σ Eᵢ`. The ray pierces the
//! triangle iff the `Eᵢ` share a sign and `det = Σ Eᵢ ≠ 0`. Each f32 test moves each edge's line in ray space by
//! at most `εₑ` and reports `t` within `T` of the f64 one; so f32 and f64 can disagree on hit/miss only where the
//! ray passes within `εₑ` of an edge's line (an *edge tie*: near an edge or vertex, or grazing the plane) or where
//! `t` lies within `T` of `t_min` or `t_max`. [`ExactTriangleTest::f32_outcomes`] turns that into what either test
//! may and must report: it may pierce where every edge function has one sign or is tied, and must where the f64
//! line pierces and no edge is tied.
//!
//! # The bounds
//!
//! With `u` the unit roundoff, `M = Σᵢ |aᵢ|₁`, `L` the longest edge (`|pⱼ − pₖ|₁`), `ℓₑ` edge `e`'s length in ray
//! space and `p`, `q` its ends there:
//! - watertight: each sheared coordinate `a[kx] − Sx·a[kz]` is off by at most about `4u·|aᵢ|₁` (`|Sx| ≤ 1`), which
//!   moves the edge's line by as much; the edge function's own products add `2u·|p|·|q|`, i.e. `2u·|p|·|q| / ℓₑ`
//!   of distance;
//! - Möller–Trumbore: its numerators `(o − p0)·(d × e2)` and `(d × (o − p0))·e1` and `det` equal the edge functions
//!   times `d[kz]` (up to sign) and err by a small multiple of `u·|o − p0|·|e|·|d|`, with `|d| ≤ √3·|d[kz]|`: a
//!   small multiple of `u·M·L` in edge-function units, `u·M·L / ℓₑ` of distance (large for an edge seen end-on).
//!
//! So `εₑ = K·(u₃₂ + u₆₄)·M·(1 + L / ℓₑ) + 4u·|p|·|q| / ℓₑ` with [`ExactTriangleTest::K`] covering both (the f64
//! evaluation's own error is the same analysis with `u₆₄`). For `t`, in edge-function units
//! `Δ = K·(u₃₂ + u₆₄)·M·(P + L)` (`P = Σᵢ |xᵢ| + |yᵢ|`) bounds either test's error on any `Eᵢ`; the derivative of
//! `Σ Eᵢzᵢ / Σ Eᵢ` in `Eᵢ` is `(zᵢ − t) / det`, and Möller–Trumbore's `t = (o − p0)·n / det` errs by a multiple of
//! `u·M·L² / (|d[kz]|·|det|)`: `T = (Δ·Σ|zᵢ − t| + K·u·M·L² / |d[kz]|) / (|det| − 3Δ) + K·u·(maxᵢ |zᵢ| + |t|)`,
//! infinite when `|det| ≤ 3Δ` (a ray in the plane, or a triangle of no projected area). These are first-order
//! estimates with a safety factor, not a proof as for spheres: the tests below check both against both f32 tests
//! on rays aimed at edges and vertices, and print how close they come (about 1/25 of `εₑ` and 1/10 of `T`).

use glam::DVec3;

use super::{F32Outcomes, Ray, Triangle, U_F32, U_F64};

/// A ray against a triangle evaluated in f64, with the rounding bounds of the f32 tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactTriangleTest {
    /// The edge functions `U, V, W` in ray space (module documentation): the barycentrics times `det`.
    pub edges: [f64; 3],
    /// `Δ`: bound on how far either f32 test's edge functions can stray from [`ExactTriangleTest::edges`] (for `T`).
    pub edge_bound: f64,
    /// Per edge (opposite `p0`, `p1`, `p2`): the distance in ray space from the ray to its line, and `εₑ`, how
    /// far either f32 test may move that line; a ray within `εₑ` of it is tied on that edge.
    pub sides: [(f64, f64); 3],
    /// Ray parameter where the line crosses the triangle's plane (not finite where `det = 0`).
    pub t: f64,
    /// `T`: bound on the error of `t` as either f32 test computes it, whenever it reports a hit.
    pub t_bound: f64,
}

impl ExactTriangleTest {
    /// The safety factor of the bounds (module documentation).
    pub const K: f64 = 2.0;

    /// Evaluates `ray` against `tri` in f64 (see the module documentation).
    pub fn new(tri: &Triangle, ray: &Ray) -> Self {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let kz = d.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (sx, sy) = (d[kx] / d[kz], d[ky] / d[kz]);
        let p = tri.p.map(|p| p.as_dvec3());
        let a = p.map(|p| p - o);
        let xy = a.map(|a| (a[kx] - sx * a[kz], a[ky] - sy * a[kz]));
        let z = a.map(|a| a[kz] / d[kz]);
        let edge = |p: (f64, f64), q: (f64, f64)| q.0 * p.1 - q.1 * p.0;
        let edges = [edge(xy[1], xy[2]), edge(xy[2], xy[0]), edge(xy[0], xy[1])];
        let det = edges.iter().sum::<f64>();
        let t = (edges[0] * z[0] + edges[1] * z[1] + edges[2] * z[2]) / det;

        let l1 = |v: DVec3| v.abs().element_sum();
        let m = a.iter().map(|&a| l1(a)).sum::<f64>();
        let projected = xy.iter().map(|(x, y)| x.abs() + y.abs()).sum::<f64>();
        let longest = l1(p[1] - p[2]).max(l1(p[2] - p[0])).max(l1(p[0] - p[1]));
        let ku = Self::K * (U_F32 + U_F64);
        let edge_bound = ku * m * (projected + longest);
        let spread = z.iter().map(|zi| (zi - t).abs()).sum::<f64>();
        let z_max = z.iter().fold(0.0f64, |acc, zi| acc.max(zi.abs()));
        let slack = det.abs() - 3.0 * edge_bound;
        let t_bound = if slack > 0.0 && t.is_finite() {
            (edge_bound * spread + ku * m * longest * longest / d[kz].abs()) / slack + ku * (z_max + t.abs())
        } else {
            f64::INFINITY
        };
        // Per edge: the distance from the ray to its line in ray space, and how far the f32 tests may move it.
        let side = |e: f64, p: (f64, f64), q: (f64, f64)| {
            let length = (q.0 - p.0).hypot(q.1 - p.1);
            let moved = ku * m * (1.0 + longest / length) + 4.0 * U_F32 * p.0.hypot(p.1) * q.0.hypot(q.1) / length;
            (if length > 0.0 { e.abs() / length } else { 0.0 }, if moved.is_nan() { f64::INFINITY } else { moved })
        };
        let sides = [side(edges[0], xy[1], xy[2]), side(edges[1], xy[2], xy[0]), side(edges[2], xy[0], xy[1])];
        Self { edges, edge_bound, sides, t, t_bound }
    }

    /// True when the f64 edge functions share a sign and `det ≠ 0`: the ray's line pierces the triangle.
    pub fn pierces(&self) -> bool {
        let det = self.edges.iter().sum::<f64>();
        det != 0.0 && (self.edges.iter().all(|&e| e >= 0.0) || self.edges.iter().all(|&e| e <= 0.0))
    }

    /// True when the ray passes within `εₑ` of the line of edge `e` (index of the opposite vertex).
    fn tied(&self, e: usize) -> bool {
        self.sides[e].0 <= self.sides[e].1
    }

    /// True when an f32 test may find the line piercing the triangle: every edge function has one sign, or is
    /// tied.
    pub fn may_cross(&self) -> bool {
        let side_of =
            |positive: bool| (0..3).all(|e| (self.edges[e] >= 0.0) == positive || self.edges[e] == 0.0 || self.tied(e));
        side_of(true) || side_of(false)
    }

    /// True when both f32 tests surely find it piercing: it does, and no edge is tied.
    pub fn must_cross(&self) -> bool {
        self.pierces() && !(0..3).any(|e| self.tied(e))
    }

    /// True when f32 and f64 may decide hit/miss differently: an edge tie, the ray passing within rounding of an
    /// edge or vertex (or grazing the plane).
    pub fn is_edge_tie(&self) -> bool {
        self.may_cross() && !self.must_cross()
    }

    /// The hit the f64 evaluation finds in `(t_min, t_max)`.
    pub fn exact_hit(&self, t_min: f64, t_max: f64) -> Option<f64> {
        (self.pierces() && self.t > t_min && self.t < t_max).then_some(self.t)
    }

    /// What either f32 test may and must report for a ray with this `(t_min, t_max)`.
    pub fn f32_outcomes(&self, t_min: f64, t_max: f64) -> F32Outcomes {
        let none = F32Outcomes { may: [None, None], must: None };
        if !self.may_cross() {
            return none;
        }
        let (lo, hi) = if self.t_bound.is_finite() {
            (self.t - self.t_bound, self.t + self.t_bound)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        };
        let may = (hi > t_min && lo < t_max).then(|| (lo.max(t_min), hi.min(t_max)));
        let must = (self.must_cross() && lo > t_min && hi < t_max).then_some(hi);
        F32Outcomes { may: [may, None], must }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::TriangleTest;
    use crate::rng::SplitMix64;

    fn point(rng: &mut SplitMix64, scale: f64) -> Vec3 {
        Vec3::new(rng.range(-scale, scale) as f32, rng.range(-scale, scale) as f32, rng.range(-scale, scale) as f32)
    }

    /// A random triangle and a ray at it: aimed inside, at an edge or a vertex (nudged by 1e-9 to 1e-3 of the
    /// triangle's size, or not at all), or nearly in its plane; at scales from 1 to 1e3 off the origin.
    fn triangle_and_ray(rng: &mut SplitMix64, i: usize) -> (Triangle, Ray) {
        let center = point(rng, [1.0, 30.0, 1e3][i % 3]);
        let size = rng.range(0.01, 3.0);
        let tri = Triangle::new(center + point(rng, size), center + point(rng, size), center + point(rng, size));
        let [p0, p1, p2] = tri.p.map(|p| p.as_dvec3());
        let (b1, b2) = (rng.next_f64(), rng.next_f64());
        let aim = match i % 4 {
            0 => {
                let (b1, b2) = if b1 + b2 > 1.0 { (1.0 - b1, 1.0 - b2) } else { (b1, b2) };
                p0 + (p1 - p0) * b1 + (p2 - p0) * b2
            }
            1 => [p0, p1, p2][rng.below(3) as usize].lerp([p1, p2, p0][rng.below(3) as usize], b1),
            _ => [p0, p1, p2][rng.below(3) as usize],
        };
        let nudge = if rng.below(4) == 0 { 0.0 } else { size * 10f64.powf(rng.range(-9.0, -3.0)) };
        let aim = aim + point(rng, 1.0).as_dvec3() * nudge;
        let origin = if i.is_multiple_of(7) {
            let normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
            (aim + (aim - p0) * rng.range(1.0, 5.0) + normal * size * 10f64.powf(rng.range(-8.0, -1.0))).as_vec3()
        } else {
            center + point(rng, 10.0 * size.max(1.0))
        };
        let mut ray = Ray::new(origin, ((aim - origin.as_dvec3()) * rng.range(0.3, 3.0)).as_vec3());
        if i.is_multiple_of(5) {
            let t = rng.range(0.0, 2.0) as f32;
            (ray.t_min, ray.t_max) = (t * rng.next_f64() as f32, t);
        }
        (tri, ray)
    }

    /// Both f32 tests report a hit only where f64 allows one, always where f64 insists, within `T` of its `t`;
    /// every hit/miss flip is an edge tie (or `t` at a range end). Prints how close the bounds come.
    #[test]
    fn both_tests_agree_with_f64_except_within_the_rounding_bound() {
        for test in TriangleTest::ALL {
            let mut rng = SplitMix64::new(11);
            let (mut flips, mut ties, mut worst_flip, mut worst_t) = (0, 0, 0.0f64, 0.0f64);
            for i in 0..300_000 {
                let (tri, ray) = triangle_and_ray(&mut rng, i);
                let e = ExactTriangleTest::new(&tri, &ray);
                let (t_min, t_max) = (ray.t_min as f64, ray.t_max as f64);
                let out = e.f32_outcomes(t_min, t_max);
                let hit = tri.intersect(test, &ray, ray.t_max);
                ties += e.is_edge_tie() as usize;
                match hit {
                    Some(h) => {
                        assert!(h.t.is_finite() && h.b1.is_finite() && h.b2.is_finite(), "{h:?}");
                        let t = h.t as f64;
                        assert!(
                            out.may_report(t, 0.0),
                            "{}: {t} outside {out:?} for {tri:?} {ray:?} ({e:?})",
                            test.name()
                        );
                        if e.t_bound.is_finite() {
                            worst_t = worst_t.max((t - e.t).abs() / e.t_bound);
                        }
                    }
                    None => assert!(
                        out.must.is_none(),
                        "{}: missed, f64 says {out:?} for {tri:?} {ray:?} ({e:?})",
                        test.name()
                    ),
                }
                if hit.is_some() != e.exact_hit(t_min, t_max).is_some() {
                    flips += 1;
                    let range_end = (e.t - t_min).abs() <= e.t_bound || (e.t - t_max).abs() <= e.t_bound;
                    assert!(e.is_edge_tie() || range_end, "{}: flip on {tri:?} {ray:?} ({e:?})", test.name());
                    if !range_end {
                        let nearest = e.sides.iter().fold(f64::INFINITY, |m, &(d, moved)| m.min(d / moved));
                        worst_flip = worst_flip.max(nearest);
                    }
                }
                if let Some(t) = e.exact_hit(t_min, t_max) {
                    assert!(out.may_report(t, 0.0), "f64's own hit {t} outside {out:?}");
                }
            }
            eprintln!(
                "{}: {flips} hit/miss flips, {ties} edge ties; max min distance/εₑ over flips {worst_flip:.3}; \
                 max |t32 - t|/T {worst_t:.3}",
                test.name()
            );
            assert!(flips > 100, "{}: the rays must exercise the decision ({flips} flips)", test.name());
            assert!(worst_flip > 1e-3 && worst_t > 1e-3, "{}: the bounds are far too loose", test.name());
        }
    }

    #[test]
    fn a_ray_through_the_middle_is_no_edge_tie_and_its_bounds_are_small() {
        let tri = Triangle::new(Vec3::new(-1.0, -1.0, -10.0), Vec3::new(1.0, -1.0, -10.0), Vec3::new(0.0, 1.0, -10.0));
        let e = ExactTriangleTest::new(&tri, &Ray::new(Vec3::ZERO, -Vec3::Z));
        assert!(e.must_cross() && !e.is_edge_tie());
        assert_eq!(e.exact_hit(0.0, f64::INFINITY), Some(10.0));
        assert!(e.t_bound < 1e-4 && e.edge_bound < 1e-3, "{e:?}");
        let out = e.f32_outcomes(0.0, f64::INFINITY);
        assert!(out.must.is_some() && out.may_report(10.0, 0.0));
        assert_eq!(e.f32_outcomes(0.0, 5.0).must, None);
    }
}
