//! A ray against a sphere in f64, and how far [`Sphere::intersect`]'s f32 arithmetic can stray from it.
//!
//! [`ExactTest::new`] takes the f32 ray and sphere exactly (every f32 is an f64) and evaluates the same robust
//! formula as [`Sphere::intersect`] in f64: the grazing measure `g = (r² − p²) / r²` (`p` the distance of the
//! center from the ray's line; the line crosses the sphere iff `g ≥ 0`), the roots, and two rounding bounds of
//! the f32 test for that ray and sphere: `B ≥ |g₃₂ − g|` and `T ≥ |t₃₂ − t|` for either root. f32 and f64 can
//! disagree on hit/miss only where `|g| ≤ B` (a *grazing* ray) or where a root lies within `T` of `t_min` or
//! `t_max`; [`ExactTest::f32_outcomes`] turns that into what `Sphere::intersect` may and must report.
//!
//! # Derivation
//!
//! Standard error analysis (Higham, *Accuracy and Stability of Numerical Algorithms*, ch. 3): every f32
//! operation is `fl(x ∘ y) = (x ∘ y)(1 + δ)`, `|δ| ≤ u = 2⁻²⁴`, and `γₙ = n·u / (1 − n·u)`. Write
//! `F = |f|` with `f = o − c`, `P = |p|`, `D = |d|`, `a = D²`, `b = f·d`, `s = b / a`, `p = f − d·s` (so `p ⊥ d`).
//! No overflow or underflow is assumed (scene coordinates and radii of ordinary size).
//!
//! 1. `f̂ = fl(o − c)`: one rounding per component, `|f̂ − f| ≤ u·F`. (No `|o| + |c|` term: `o` and `c` are
//!    exact, only their difference is rounded, relative to itself.)
//! 2. `â = fl(d·d) = a(1 + θ)`, `|θ| ≤ γ₃`; `|b̂ − b| ≤ u·F·D + γ₃·|f̂|·D =: β·F·D`, `β = u + γ₃(1 + u)`.
//! 3. `ŝ = fl(b̂ / â)`: `|ŝ − s|·D ≤ σ·F` with `σ = ((1 + u)β + u + γ₃) / (1 − γ₃) ≈ 8u`, and `|ŝ|·D ≤ (1 + σ)F`.
//! 4. The offset `p̂ = fl(f̂ − fl(d·ŝ))` against `q = f − d·ŝ`: `|p̂ − q| ≤ ε := (1 + u)(2 + σ)·u·F + u·|q|`
//!    (the error of `f̂`, of the product `d·ŝ` and of the subtraction). Since `p ⊥ d`,
//!    `|q|² = P² + D²(ŝ − s)²`: the error of `ŝ` enters only to second order, and `|q| ≤ P + σF`.
//! 5. `P̂ = fl(p̂·p̂) = |p̂|²(1 + θ')`, `|θ'| ≤ γ₃`, and `|p̂|² − P² = D²(ŝ − s)² + 2q·(p̂ − q) + |p̂ − q|²`, so
//!    `|P̂ − P²| ≤ ΔP := σ²F² + 2|q|ε + ε² + γ₃(|q| + ε)²`.
//! 6. `r̂² = fl(r·r)`, `|r̂² − r²| ≤ u·r²`. The test rejects iff `fl(â·fl(r̂² − P̂)) < 0`, i.e. iff
//!    `g₃₂ := (r̂² − P̂) / r² < 0` (rounding keeps signs, `â > 0`). Hence
//!
//!    **`B = u + ΔP / r² ≈ 4u·(F / r)·(P / r) + 6u`** — at a grazing ray (`P ≈ r`) `4u·F/r + 6u`: the f32
//!    ulp of `|f|` relative to the radius. Where f32 and f64 decide differently, `g` and `g₃₂` straddle 0, so
//!    `|g| ≤ B`.
//!
//! 7. Roots, when the f32 test goes on (`disc₃₂ ≥ 0`): `|disc₃₂ − max(a·r²·g, 0)| ≤ Δdisc := a·r²·(B + (|g| + B)γ₅)`;
//!    with `h = √max(disc, 0)`, `|ĥ − h| ≤ Δh := (1 + u)·min(√Δdisc, Δdisc / h) + u·h` (the square root of a
//!    near-zero discriminant amplifies its error: at a grazing ray `Δh ≈ D·r·√B`).
//!    `c = F² − r²`: `|ĉ − c| ≤ Δc := (1 + u)(κF² + u·r²) + u|c|`, `κ = (1 + u)²(1 + γ₃) − 1`.
//!    `q = −(b + sign(b)·h)`: `|q̂ − q| ≤ Δq := (1 + u)(β·F·D + Δh) + u(|b| + h)`, and `|q| ≥ Q = |b| + h` (or
//!    `||b| − h|` when `|b| ≤ β·F·D`, where f32 may take the other sign: the pair of roots is the same).
//!    The roots `c / q` and `q / a` then err by at most
//!    `T₀ = (1 + u)(Δc + |t₀|Δq) / (Q − Δq) + u|t₀|` and `T₁ = ((1 + u)Δq + (u + γ₃)|q|) / (a(1 − γ₃))`;
//!    **`T = max(T₀, T₁)`** (infinite when `Q ≤ Δq`: an origin on the surface with a tangent ray). Away from
//!    grazing `T ≈ 8u·(F + |t|·D)/D`-ish; at grazing `T ≈ r·√B / D`. Where `g < 0` the reference roots are
//!    those of `h = 0` (both within `r²|g| / |b|` of the closest approach).
//!
//! The f64 evaluation obeys the same analysis with `u = 2⁻⁵³`; those bounds are added to the f32 ones, so the
//! comparison is between the f32 result and the f64 *value*, rigorously (the bounds' own inputs are f64
//! values, whose relative error of order 1e-16 changes them negligibly).

use super::{Ray, Sphere};

/// Unit roundoff of f32, `2⁻²⁴`.
pub const U_F32: f64 = 1.0 / (1u64 << 24) as f64;
/// Unit roundoff of f64, `2⁻⁵³`.
pub const U_F64: f64 = f64::EPSILON / 2.0;

fn gamma(n: f64, u: f64) -> f64 {
    n * u / (1.0 - n * u)
}

/// A ray against a sphere evaluated in f64, with the rounding bounds of the f32 [`Sphere::intersect`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactTest {
    /// Grazing measure `(r² − p²) / r²`: positive where the ray's line crosses the sphere, negative where it
    /// passes outside (`p` the distance of the center from the line).
    pub g: f64,
    /// `B`: bound on `|g₃₂ − g|`, so that f32 and f64 decide hit/miss alike unless `|g| ≤ B`.
    pub g_bound: f64,
    /// Parameter of the line's closest approach to the center.
    pub t_closest: f64,
    /// The roots, nearer first (where `g < 0`, those f32 would compute from a zero discriminant).
    pub roots: (f64, f64),
    /// `T`: bound on the error of either root as f32 computes it, whenever f32 gets that far.
    pub t_bound: f64,
}

/// What [`Sphere::intersect`] (with the ray's own `t_max`) may report for one ray and sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct F32Outcomes {
    /// Intervals that hold every `t` it may report (near root, far root); `None` where it cannot report that root.
    pub may: [Option<(f64, f64)>; 2],
    /// `Some(latest)` when it surely reports a hit, at `t ≤ latest`.
    pub must: Option<f64>,
}

impl F32Outcomes {
    /// True when f32 may report a hit.
    pub fn may_hit(&self) -> bool {
        self.may.iter().any(Option::is_some)
    }

    /// True when `t` lies within `slack` of an interval of [`F32Outcomes::may`].
    pub fn may_report(&self, t: f64, slack: f64) -> bool {
        self.may.iter().flatten().any(|&(lo, hi)| t >= lo - slack && t <= hi + slack)
    }
}

/// Bounds `(B, T)` of the module documentation for unit roundoff `u`.
#[allow(clippy::too_many_arguments)]
fn bounds(u: f64, f: f64, p: f64, d: f64, b: f64, h: f64, c: f64, r2: f64, g: f64, t0: f64) -> (f64, f64) {
    let (g3, g5) = (gamma(3.0, u), gamma(5.0, u));
    let beta = u + g3 * (1.0 + u);
    let sigma = ((1.0 + u) * beta + u + g3) / (1.0 - g3);
    let q_off = p + sigma * f;
    let eps = (1.0 + u) * (2.0 + sigma) * u * f + u * q_off;
    let dp = sigma * sigma * f * f + 2.0 * q_off * eps + eps * eps + g3 * (q_off + eps) * (q_off + eps);
    let big_b = u + dp / r2;

    let a = d * d;
    let (b, c) = (b.abs(), c.abs());
    let d_disc = a * r2 * (big_b + (g.abs() + big_b) * g5);
    let dh = (1.0 + u) * if h > 0.0 { d_disc.sqrt().min(d_disc / h) } else { d_disc.sqrt() } + u * h;
    let kappa = (1.0 + u) * (1.0 + u) * (1.0 + g3) - 1.0;
    let dc = (1.0 + u) * (kappa * f * f + u * r2) + u * c;
    let db = beta * f * d;
    let dq = (1.0 + u) * (db + dh) + u * (b + h);
    let q_low = if b > db { b + h } else { (h - b).abs() };
    let t0 = t0.abs();
    let err0 = if q_low > dq { (1.0 + u) * (dc + t0 * dq) / (q_low - dq) + u * t0 } else { f64::INFINITY };
    let err1 = ((1.0 + u) * dq + (u + g3) * (b + h)) / (a * (1.0 - g3));
    (big_b, err0.max(err1))
}

impl ExactTest {
    /// Evaluates `ray` against `sphere` in f64 (see the module documentation).
    pub fn new(sphere: &Sphere, ray: &Ray) -> Self {
        let (o, d, c) = (ray.origin.as_dvec3(), ray.dir.as_dvec3(), sphere.center.as_dvec3());
        let r = sphere.radius as f64;
        let f = o - c;
        let a = d.dot(d);
        let b = f.dot(d);
        let r2 = r * r;
        let p = f - d * (b / a);
        let p2 = p.dot(p);
        let g = (r2 - p2) / r2;
        let h = (a * (r2 - p2)).max(0.0).sqrt();
        let cc = f.dot(f) - r2;
        let q = -(b + h.copysign(b));
        let (t0, t1) = (cc / q, q / a);
        let roots = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        let (fl, pl, dl) = (f.length(), p2.sqrt(), a.sqrt());
        let (b32, t32) = bounds(U_F32, fl, pl, dl, b, h, cc, r2, g, t0);
        let (b64, t64) = bounds(U_F64, fl, pl, dl, b, h, cc, r2, g, t0);
        let t_bound = if roots.0.is_finite() && roots.1.is_finite() { t32 + t64 } else { f64::INFINITY };
        Self { g, g_bound: b32 + b64, t_closest: -b / a, roots, t_bound }
    }

    /// True when f32 may find the discriminant non-negative (`g ≥ −B`).
    pub fn may_cross(&self) -> bool {
        self.g >= -self.g_bound
    }

    /// True when f32 surely finds the discriminant non-negative (`g > B`).
    pub fn must_cross(&self) -> bool {
        self.g > self.g_bound
    }

    /// True when f32 and f64 may decide hit/miss of the line differently (`|g| ≤ B`).
    pub fn is_grazing(&self) -> bool {
        self.g.abs() <= self.g_bound
    }

    /// The hit the f64 evaluation finds in `(t_min, t_max)`, with `Sphere::intersect`'s logic: the near root
    /// if in range, else the far one.
    pub fn exact_hit(&self, t_min: f64, t_max: f64) -> Option<f64> {
        if self.g < 0.0 {
            return None;
        }
        let (near, far) = self.roots;
        [near, far].into_iter().find(|&t| t > t_min && t < t_max)
    }

    /// What the f32 test may and must report for a ray with this `(t_min, t_max)`.
    pub fn f32_outcomes(&self, t_min: f64, t_max: f64) -> F32Outcomes {
        let none = F32Outcomes { may: [None, None], must: None };
        if !self.may_cross() {
            return none;
        }
        let tb = if self.t_bound.is_nan() { f64::INFINITY } else { self.t_bound };
        let near = (self.roots.0 - tb, self.roots.0 + tb);
        let far = (self.roots.1 - tb, self.roots.1 + tb);
        let (near, far) = if near.0.is_nan() || far.0.is_nan() {
            ((f64::NEG_INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::INFINITY))
        } else {
            (near, far)
        };
        let clip = |(lo, hi): (f64, f64)| (hi > t_min && lo < t_max).then(|| (lo.max(t_min), hi.min(t_max)));
        let inside = |(lo, hi): (f64, f64)| lo > t_min && hi < t_max;
        let near_surely_in = inside(near);
        let may = [clip(near), if near_surely_in { None } else { clip(far) }];
        let must = if !self.must_cross() {
            None
        } else if near_surely_in {
            Some(near.1)
        } else if inside(far) {
            Some(far.1)
        } else {
            None
        };
        F32Outcomes { may, must }
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};

    use super::*;
    use crate::rng::SplitMix64;

    /// `Sphere::intersect`'s discriminant and roots, step for step (the test checks it decides alike).
    fn f32_parts(s: &Sphere, ray: &Ray) -> (f32, Option<(f32, f32)>) {
        let d = ray.dir;
        let f = ray.origin - s.center;
        let a = d.dot(d);
        let b = f.dot(d);
        let r2 = s.radius * s.radius;
        let offset = f - d * (b / a);
        let w = r2 - offset.dot(offset);
        let disc = a * w;
        if disc < 0.0 {
            return (w, None);
        }
        let c = f.dot(f) - r2;
        let q = -(b + disc.sqrt().copysign(b));
        let (r0, r1) = (c / q, q / a);
        (w, Some(if r0 <= r1 { (r0, r1) } else { (r1, r0) }))
    }

    fn unit(rng: &mut SplitMix64) -> DVec3 {
        loop {
            let v = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
            if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    fn point(rng: &mut SplitMix64, scale: f64) -> Vec3 {
        Vec3::new(rng.range(-scale, scale) as f32, rng.range(-scale, scale) as f32, rng.range(-scale, scale) as f32)
    }

    /// A ray from a random origin aimed at a point `(1 + offset)·r` from a random sphere's center, perpendicular
    /// to the line of sight (so `g ≈ −2·offset`), with a direction of random length.
    fn near_tangent(rng: &mut SplitMix64) -> (Sphere, Ray) {
        loop {
            let sphere = Sphere::new(point(rng, 30.0), rng.range(0.01, 1.0) as f32);
            let origin = point(rng, 30.0);
            let f = (sphere.center - origin).as_dvec3();
            if f.length() < 4.0 * sphere.radius as f64 + 0.5 {
                continue;
            }
            let side = unit(rng).reject_from(f).normalize();
            let offset = rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-8.0, -3.0));
            let aim = sphere.center.as_dvec3() + side * (sphere.radius as f64 * (1.0 + offset));
            let dir = ((aim - origin.as_dvec3()).normalize() * rng.range(0.5, 4.0)).as_vec3();
            return (sphere, Ray::new(origin, dir));
        }
    }

    /// Many near-tangent rays: wherever f32 and f64 decide differently, `|g| ≤ B`; `|g₃₂ − g|` never exceeds
    /// `B`, and comes within a small factor of it (the bound is not wildly loose).
    #[test]
    fn the_grazing_bound_covers_every_f32_decision_and_is_not_loose() {
        let mut rng = SplitMix64::new(17);
        let (mut flips, mut worst_flip, mut worst_err) = (0, 0.0f64, 0.0f64);
        for _ in 0..500_000 {
            let (s, ray) = near_tangent(&mut rng);
            let e = ExactTest::new(&s, &ray);
            let (w, roots) = f32_parts(&s, &ray);
            let mirrored = roots.and_then(|(n, f)| [n, f].into_iter().find(|&t| t > 0.0 && t < f32::INFINITY));
            let hit = s.intersect(&ray, f32::INFINITY);
            assert_eq!(mirrored, hit, "f32_parts must mirror Sphere::intersect");
            let g32 = (w as f64) / (s.radius as f64 * s.radius as f64);
            let err = (g32 - e.g).abs() / e.g_bound;
            assert!(err <= 1.0, "|g32 - g| = {:e} > B = {:e} for {s:?} {ray:?}", (g32 - e.g).abs(), e.g_bound);
            worst_err = worst_err.max(err);
            if hit.is_some() != e.exact_hit(0.0, f64::INFINITY).is_some() {
                flips += 1;
                assert!(
                    e.is_grazing(),
                    "f32 and f64 disagree on {s:?} {ray:?} with g = {:e}, B = {:e}",
                    e.g,
                    e.g_bound
                );
                worst_flip = worst_flip.max(e.g.abs() / e.g_bound);
            }
            if let Some((n, f)) = roots {
                for (t32, t) in [(n, e.roots.0), (f, e.roots.1)] {
                    assert!(
                        (t32 as f64 - t).abs() <= e.t_bound,
                        "t {t32} vs {t}: > T = {:e} for {s:?} {ray:?}",
                        e.t_bound
                    );
                }
            }
        }
        eprintln!("{flips} hit/miss flips; max |g|/B over flips {worst_flip:.3}; max |g32 - g|/B {worst_err:.3}");
        assert!(flips > 100, "the rays must exercise the decision ({flips} flips)");
        assert!(worst_flip > 1e-3 && worst_err > 1e-2, "B is far too loose: {worst_flip:e}, {worst_err:e}");
    }

    /// General rays (origins inside and outside, segments): f32 reports a hit only where f64 allows one,
    /// always when f64 insists, and within `T` of a root.
    #[test]
    fn f32_outcomes_hold_every_report_of_sphere_intersect() {
        let mut rng = SplitMix64::new(5);
        for i in 0..200_000 {
            let (s, mut ray) = if i % 2 == 0 {
                near_tangent(&mut rng)
            } else {
                let s = Sphere::new(point(&mut rng, 30.0), rng.range(0.01, 2.0) as f32);
                let origin = s.center + point(&mut rng, 3.0);
                (s, Ray::new(origin, (s.center + point(&mut rng, 2.0) - origin) * rng.range(0.3, 3.0) as f32))
            };
            if i % 3 == 0 {
                ray.t_min = rng.range(0.0, 1.0) as f32;
                ray.t_max = rng.range(0.0, 40.0) as f32;
            }
            let e = ExactTest::new(&s, &ray);
            let out = e.f32_outcomes(ray.t_min as f64, ray.t_max as f64);
            match s.intersect(&ray, ray.t_max) {
                Some(t) => assert!(out.may_report(t as f64, 0.0), "{t} outside {out:?} for {s:?} {ray:?} ({e:?})"),
                None => assert!(out.must.is_none(), "missed, but f64 says {out:?} for {s:?} {ray:?} ({e:?})"),
            }
            if let (Some(t), Some(latest)) = (s.intersect(&ray, ray.t_max), out.must) {
                assert!(t as f64 <= latest);
            }
            if let Some(t) = e.exact_hit(ray.t_min as f64, ray.t_max as f64) {
                assert!(out.may_report(t, 0.0), "f64's own hit {t} outside {out:?}");
            }
        }
    }

    #[test]
    fn bounds_scale_with_distance_over_radius() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -13.0), 0.05);
        let tangent = ExactTest::new(&s, &Ray::new(Vec3::new(0.05, 0.0, 0.0), -Vec3::Z));
        assert!(tangent.is_grazing() && tangent.g.abs() < 1e-6);
        let expect = 4.0 * U_F32 * 13.0 / 0.05;
        assert!(tangent.g_bound > expect && tangent.g_bound < 1.2 * expect, "{:e} vs {expect:e}", tangent.g_bound);
        assert!(tangent.g_bound > 5.0e-6 && tangent.g_bound < 1e-3);
        let centered = ExactTest::new(&s, &Ray::new(Vec3::ZERO, -Vec3::Z));
        assert!((centered.g - 1.0).abs() < 1e-15);
        assert!((centered.roots.0 - 12.95).abs() < 1e-6 && (centered.roots.1 - 13.05).abs() < 1e-6);
        assert!(centered.t_bound < 1e-5 && centered.must_cross());
    }
}
