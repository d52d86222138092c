//! Arbitration by f64 brute force: whether an answer to a ray is acceptable, and what a disagreement is.
//!
//! The exact answer is the nearest exact hit in `(t_min, t_max)` of any primitive (closest hit) or whether there
//! is one (occlusion). An answer is *acceptable* when it is the exact one (a hit's `t` within [`t_tolerance`]), or
//! when it differs only in ways the f32 test's rounding bound allows ([`crate::geometry::F32Outcomes`]): a
//! closest-hit answer at `t` iff some primitive may be reported at `t` (within the tolerance) and none must be
//! reported before it; a miss iff none must be reported; an occlusion answer `true` iff some primitive may be
//! reported, `false` iff none must. A hit must also name a primitive that may be reported at its `t`.
//!
//! A tolerated disagreement is one of three kinds ([`Tolerated`]): a *tie* (the same distance, another primitive:
//! an edge or vertex shared by two triangles), a *leak* (the exact hit lies on an edge or vertex shared by two or
//! more primitives, and the answer slipped between them: a miss or a later hit) or, otherwise, a *grazing* ray.

use super::{Answer, RayCandidates, Strictness, t_tolerance};

/// How one answer compares with f64 brute force.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The f64 answer (a hit's `t` within the tolerance).
    Exact,
    /// Not the f64 answer, but one the f32 rounding bound allows (a grazing ray, or `t` within the root bound).
    Grazing,
    /// Neither.
    Wrong,
}

impl Verdict {
    /// True unless [`Verdict::Wrong`].
    pub fn acceptable(self) -> bool {
        self != Verdict::Wrong
    }
}

/// What the agreement check found of a backend's answer to one ray against the reference's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The answers agree ([`Answer::agrees`]).
    Agree,
    /// They disagree, and f64 accepts both: tolerated, and counted.
    Tolerated(Tolerated),
    /// f64 rejects one answer or both.
    Mismatch(WrongSide),
}

/// Why a disagreement was tolerated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tolerated {
    /// The ray grazes a primitive, or the distance lies within the root bound, where f32 cannot decide.
    Grazing,
    /// The same distance, another primitive, both allowed there: an edge or vertex shared by two triangles.
    Tie,
    /// The backend's answer slipped between primitives that share the exact hit's edge or vertex: a miss or a
    /// later hit, which the f32 rounding bound allows for each primitive alone (what a watertight test prevents).
    Leak,
}

/// Whose answer f64 showed wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WrongSide {
    /// The backend's.
    Backend,
    /// The reference's.
    Reference,
    /// Both.
    Both,
}

impl RayCandidates {
    /// `answer` judged against f64.
    pub fn verdict(&self, answer: &Answer) -> Verdict {
        match *answer {
            Answer::Closest(Some(hit)) if !self.may_name(hit.prim, hit.t) => Verdict::Wrong,
            Answer::Closest(hit) => self.closest(hit.map(|h| h.t)),
            Answer::Occluded(flag) => self.occluded(flag),
        }
    }

    /// True when primitive `prim` may be reported at `t`.
    fn may_name(&self, prim: u32, t: f32) -> bool {
        let slack = t_tolerance(&self.ray, t) as f64;
        self.get(prim).is_some_and(|c| c.exact.outcomes.may_report(t as f64, slack))
    }

    /// True when `answer` misses the exact hit (a miss, a later hit, not occluded) where the ray crosses an
    /// edge or vertex shared by two or more primitives: the ray slipped between them.
    fn slipped_through(&self, answer: &Answer) -> bool {
        let Some((_, t)) = self.exact_closest() else { return false };
        let slack = t_tolerance(&self.ray, t as f32) as f64;
        let missed = match *answer {
            Answer::Closest(hit) => hit.is_none_or(|h| h.t as f64 > t + slack),
            Answer::Occluded(flag) => !flag,
        };
        missed && self.crosses_shared
    }

    /// A closest-hit answer (`None` for a miss) judged against f64.
    fn closest(&self, answer: Option<f32>) -> Verdict {
        let slack = |t: f64| t_tolerance(&self.ray, t as f32) as f64;
        let exact = self.exact_closest();
        match (answer, exact) {
            (None, None) => return Verdict::Exact,
            (Some(t), Some((_, want))) if (t as f64 - want).abs() <= slack(want) => return Verdict::Exact,
            _ => {}
        }
        let mut outcomes = self.list.iter().map(|c| c.exact.outcomes);
        let acceptable = match answer {
            None => outcomes.all(|o| o.must.is_none()),
            Some(t) => {
                let (t, slack) = (t as f64, slack(t as f64));
                outcomes.clone().any(|o| o.may_report(t, slack))
                    && outcomes.all(|o| o.must.is_none_or(|latest| t <= latest + slack))
            }
        };
        if acceptable { Verdict::Grazing } else { Verdict::Wrong }
    }

    /// An occlusion answer judged against f64.
    fn occluded(&self, answer: bool) -> Verdict {
        let acceptable = if answer == self.exact_closest().is_some() {
            return Verdict::Exact;
        } else if answer {
            // Every listed candidate may be reported.
            !self.list.is_empty()
        } else {
            self.list.iter().all(|c| c.exact.outcomes.must.is_none())
        };
        if acceptable { Verdict::Grazing } else { Verdict::Wrong }
    }
}

/// The backend's answer `got` against the reference's `want` to the ray of `c`, by f64: both acceptable and
/// agreeing, [`Outcome::Agree`] (or [`Tolerated::Tie`] when they name different primitives); both acceptable,
/// [`Tolerated::Leak`] or [`Tolerated::Grazing`]; else a mismatch, naming the wrong side.
pub fn arbitrate(c: &RayCandidates, want: &Answer, got: &Answer) -> Outcome {
    match (c.verdict(got).acceptable(), c.verdict(want).acceptable()) {
        (true, true) if want.agrees(&c.ray, got, Strictness::Arbitrated) => {
            if want.names_another(got) {
                Outcome::Tolerated(Tolerated::Tie)
            } else {
                Outcome::Agree
            }
        }
        (true, true) if c.slipped_through(got) => Outcome::Tolerated(Tolerated::Leak),
        (true, true) => Outcome::Tolerated(Tolerated::Grazing),
        (false, true) => Outcome::Mismatch(WrongSide::Backend),
        (true, false) => Outcome::Mismatch(WrongSide::Reference),
        (false, false) => Outcome::Mismatch(WrongSide::Both),
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::{Accelerator, BvhParams, FlatBvh, Hit, Split, Traversal};
    use crate::agreement::BruteForce64;
    use crate::counters::NoCounters;
    use crate::geometry::{ExactTest, Ray, Sphere};
    use crate::scene::SceneKind;

    #[test]
    fn a_disagreement_is_tolerated_when_f64_accepts_both_answers() {
        let exact = BruteForce64::new(&[Sphere::new(Vec3::new(0.0, 0.0, -10.0), 1.0)]);
        let hit = |t| Answer::Closest(Some(Hit { t, prim: 0 }));
        let miss = Answer::Closest(None);
        let tangent = &exact.candidates_of(&Ray::new(Vec3::new(1.0, 0.0, 0.0), -Vec3::Z));
        assert_eq!(arbitrate(tangent, &hit(10.0), &miss), Outcome::Tolerated(Tolerated::Grazing));
        assert_eq!(arbitrate(tangent, &hit(10.0), &hit(10.0005)), Outcome::Agree);
        assert_eq!(arbitrate(tangent, &hit(10.0), &hit(11.0)), Outcome::Mismatch(WrongSide::Backend));
        let square = &exact.candidates_of(&Ray::new(Vec3::ZERO, -Vec3::Z));
        assert_eq!(arbitrate(square, &miss, &hit(9.0)), Outcome::Mismatch(WrongSide::Reference));
        assert_eq!(arbitrate(square, &miss, &hit(9.5)), Outcome::Mismatch(WrongSide::Both));
        assert_eq!(
            arbitrate(square, &Answer::Occluded(true), &Answer::Occluded(false)),
            Outcome::Mismatch(WrongSide::Backend)
        );
    }

    /// Two triangles sharing the edge from (1, 0, 0) to (0, 1, 0), and a ray straight down onto its midpoint:
    /// either triangle is a tie, a miss or the floor behind is a leak, another primitive's id is wrong; one
    /// triangle alone, the miss is a grazing ray.
    #[test]
    fn shared_edges_give_ties_and_leaks_and_lone_edges_graze() {
        use crate::geometry::Triangle;
        let v = |x, y, z| Vec3::new(x, y, z);
        let a = Triangle::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let b = Triangle::new(v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0));
        let floor = Triangle::new(v(-9.0, -9.0, -1.0), v(9.0, -9.0, -1.0), v(0.0, 9.0, -1.0));
        let ray = Ray::new(v(0.5, 0.5, 1.0), -Vec3::Z);
        let hit = |t, prim| Answer::Closest(Some(Hit { t, prim }));
        let c = &BruteForce64::new(&[a, b, floor]).candidates_of(&ray);
        assert_eq!(c.exact_closest().map(|(_, t)| t), Some(1.0));
        assert_eq!(arbitrate(c, &hit(1.0, 0), &hit(1.0, 0)), Outcome::Agree);
        assert_eq!(arbitrate(c, &hit(1.0, 0), &hit(1.0, 1)), Outcome::Tolerated(Tolerated::Tie));
        assert_eq!(arbitrate(c, &hit(1.0, 0), &hit(2.0, 2)), Outcome::Tolerated(Tolerated::Leak));
        assert_eq!(arbitrate(c, &hit(1.0, 0), &hit(1.0, 2)), Outcome::Mismatch(WrongSide::Backend), "floor at 1");
        let occluded = |f| Answer::Occluded(f);
        let lone = &BruteForce64::new(&[a, b]).candidates_of(&ray);
        assert_eq!(arbitrate(lone, &hit(1.0, 1), &Answer::Closest(None)), Outcome::Tolerated(Tolerated::Leak));
        assert_eq!(arbitrate(lone, &occluded(true), &occluded(false)), Outcome::Tolerated(Tolerated::Leak));
        let one = &BruteForce64::new(&[a]).candidates_of(&ray);
        assert_eq!(arbitrate(one, &hit(1.0, 0), &Answer::Closest(None)), Outcome::Tolerated(Tolerated::Grazing));
        assert_eq!(arbitrate(one, &hit(1.0, 0), &hit(1.0, 1)), Outcome::Mismatch(WrongSide::Backend), "no such id");
    }

    #[test]
    fn verdicts_on_a_plain_sphere() {
        let spheres = [Sphere::new(Vec3::new(0.0, 0.0, -10.0), 1.0)];
        let exact = BruteForce64::new(&spheres);
        let hit = Ray::new(Vec3::ZERO, -Vec3::Z);
        let c = &exact.candidates(&[hit])[0];
        assert_eq!(c.exact_closest().map(|(p, t)| (p, t as f32)), Some((0, 9.0)));
        assert_eq!(c.closest(Some(9.0)), Verdict::Exact);
        assert_eq!(c.closest(Some(9.0005)), Verdict::Exact);
        assert_eq!(c.closest(Some(9.01)), Verdict::Wrong);
        assert_eq!(c.closest(Some(11.0)), Verdict::Wrong, "the far root behind a must-hit near root");
        assert_eq!(c.closest(None), Verdict::Wrong);
        assert_eq!((c.occluded(true), c.occluded(false)), (Verdict::Exact, Verdict::Wrong));
        let miss = Ray::new(Vec3::new(1.01, 0.0, 0.0), -Vec3::Z);
        let c = &exact.candidates(&[miss])[0];
        assert!(c.list.is_empty());
        assert_eq!(c.closest(None), Verdict::Exact);
        assert_eq!(c.closest(Some(10.0)), Verdict::Wrong);
        assert_eq!((c.occluded(false), c.occluded(true)), (Verdict::Exact, Verdict::Wrong));
        // Exactly tangent: f64 hits (g = 0); a miss is within the bound.
        let tangent = Ray::new(Vec3::new(1.0, 0.0, 0.0), -Vec3::Z);
        let c = &exact.candidates(&[tangent])[0];
        assert_eq!(c.closest(Some(10.0)), Verdict::Exact);
        assert_eq!(c.closest(None), Verdict::Grazing);
        assert_eq!(c.occluded(false), Verdict::Grazing);
        // From inside: the far root.
        let inside = Ray::new(Vec3::new(0.0, 0.0, -10.0), -Vec3::Z);
        let c = &exact.candidates(&[inside])[0];
        assert_eq!(c.closest(Some(1.0)), Verdict::Exact);
        assert_eq!(c.closest(None), Verdict::Wrong);
    }

    /// Issue #9: random-spheres, 1e6 spheres, seed 1, 1024×768 primary rays. On rays 456464 and 505152 our
    /// BVH hits a sphere that the ray passes just outside of in f64 (Embree returns the f64 answer): both
    /// answers are acceptable, ours as grazing; a ray moved so that the same sphere is missed by
    /// `g ≈ −1e-3` is not.
    #[test]
    fn embree_disagreements_at_a_million_spheres_are_grazing() {
        let scene = SceneKind::RandomSpheres.generate(1_000_000, 1);
        let camera = scene.camera.with_resolution(1024, 768);
        let eye = camera.rays();
        let rays: Vec<Ray> = [456_464u32, 505_152].iter().map(|&i| eye.ray(i % 1024, i / 1024)).collect();
        let params = BvhParams { split: Split::BinnedSah, traversal: Traversal::FrontToBack, ..BvhParams::default() };
        let tree = FlatBvh::build(&scene.spheres, &params);
        let exact = BruteForce64::new(&scene.spheres);
        let found = exact.candidates(&rays);
        let cases = [(309_135, 152_110, 2.8e-6), (75_983, 144_986, 5.0e-6)];
        for ((ray, c), (ours, embree, g)) in rays.iter().zip(&found).zip(cases) {
            let hit = tree.intersect(ray, &mut NoCounters).expect("our BVH hits");
            assert_eq!(hit.prim, ours);
            let (prim, t_exact) = c.exact_closest().expect("f64 hits another sphere behind");
            assert_eq!(prim, embree);
            assert!(c.get(ours).is_some(), "a candidate");
            let test = ExactTest::new(&scene.spheres[ours as usize], ray);
            eprintln!("sphere {ours}: g = {:.3e}, B = {:.3e}, T = {:.1e}", test.g, test.g_bound, test.t_bound);
            assert!((test.g + g).abs() < 0.1 * g, "g = {:e}, expected about -{g:e}", test.g);
            assert!(test.is_grazing() && test.g_bound < 1e-3);
            assert!(t_exact > hit.t as f64 + 1e-3, "the f64 hit lies behind ours");
            assert_eq!(c.closest(Some(hit.t)), Verdict::Grazing, "our answer is tolerated");
            assert_eq!(c.closest(Some(t_exact as f32)), Verdict::Exact, "Embree's answer is exact");
            assert_eq!(c.occluded(true), Verdict::Exact);

            // Move the origin sideways, away from the sphere's center, so that g ≈ −1e-3.
            let s = scene.spheres[ours as usize];
            let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
            let f = o - s.center.as_dvec3();
            let away = (f - d * (f.dot(d) / d.dot(d))).normalize();
            let shift = s.radius as f64 * ((1.0 + 1e-3f64).sqrt() - (1.0 - test.g).sqrt());
            let moved = Ray { origin: (o + away * shift).as_vec3(), ..*ray };
            let m = &exact.candidates(&[moved])[0];
            let miss = ExactTest::new(&s, &moved);
            assert!((miss.g + 1e-3).abs() < 1e-4 && !miss.may_cross(), "g = {:e}", miss.g);
            assert!(m.get(ours).is_none());
            let t_ours = s.intersect(ray, f32::INFINITY).unwrap();
            assert_eq!(m.closest(Some(t_ours)), Verdict::Wrong, "a real miss is not tolerated");
        }
    }
}
