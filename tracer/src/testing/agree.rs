//! The agreement check in tests: an accelerator's answers against brute force's ([`List`]), ray by ray, under
//! the one definition ([`crate::agreement::check`]).

use crate::accel::wide::WidePrimitive;
use crate::accel::{AccelKind, AccelParams, AccelVisitor, Accelerator, BuiltAccel, BvhParams, Hit, List};
use crate::agreement::{Answer, BruteForce64, ExactPrimitive, Outcome, RayCandidates, Strictness, check, t_tolerance};
use crate::counters::NoCounters;
use crate::geometry::{Primitive, Ray, Sphere, Triangle, TrianglePrimitive};
use crate::render::PrimaryHits;
use rayon::prelude::*;

use super::every_tree;

/// Brute force's answers (closest hit and occlusion) to a ray set, computed once and compared with any
/// number of accelerators built over the same primitives (`X`: the f64 form that arbitrates, spheres or triangles).
#[derive(Clone, Debug)]
pub struct Reference<'a, X: ExactPrimitive = Sphere> {
    rays: &'a [Ray],
    closest: Vec<Option<Hit>>,
    occluded: Vec<bool>,
    brute: BruteForce64<X>,
    /// Per ray, the primitives f64 allows the f32 test to report (computed once, read by every comparison).
    candidates: Vec<RayCandidates>,
}

impl<'a> Reference<'a, Sphere> {
    /// Traces `rays` through a [`List`] of `spheres`.
    #[inline]
    pub fn new(spheres: &'a [Sphere], rays: &'a [Ray]) -> Self {
        Self::of(spheres, spheres, rays)
    }
}

impl<'a> Reference<'a, Triangle> {
    /// Traces `rays` through a [`List`] of `triangles` with the test of `T`.
    pub fn triangles<T: TrianglePrimitive>(triangles: &[Triangle], rays: &'a [Ray]) -> Self {
        Self::of(&T::all(triangles.iter().copied()), triangles, rays)
    }
}

impl<'a, X: ExactPrimitive> Reference<'a, X> {
    /// Traces `rays` through a [`List`] of `prims`, whose f64 forms (same order) are `exact`.
    pub fn of<P: Primitive>(prims: &[P], exact: &[X], rays: &'a [Ray]) -> Self {
        assert_eq!(prims.len(), exact.len());
        let list = List::build(prims);
        let closest = rays.iter().map(|r| list.intersect(r, &mut NoCounters)).collect();
        let occluded = rays.iter().map(|r| list.occluded(r, &mut NoCounters)).collect();
        let brute = BruteForce64::new(exact);
        let candidates = brute.candidates(rays);
        Self { rays, closest, occluded, brute, candidates }
    }

    /// Starts comparing answers to these rays; `what` names the backend in the failure message.
    #[inline]
    pub fn compare(&self, what: &str, strictness: Strictness) -> Comparison<'_, 'a, X> {
        Comparison {
            reference: self,
            what: what.to_owned(),
            strictness,
            bad: Vec::new(),
            excused: Vec::new(),
            answers: 0,
        }
    }

    /// Panics (listing the disagreements) unless `accel` answers every ray like brute force: closest hit and
    /// occlusion, under `strictness`, one ray at a time and as one batch (the path ray sets are traced and timed with:
    /// packets, where the structure has them). Returns the tally of the single-ray answers.
    #[track_caller]
    pub fn assert_agrees<A: Accelerator>(&self, what: &str, accel: &A, strictness: Strictness) -> Tally {
        let mut comparison = self.compare(what, strictness);
        for (i, ray) in self.rays.iter().enumerate() {
            comparison.closest(i, accel.intersect(ray, &mut NoCounters));
            comparison.occluded(i, accel.occluded(ray, &mut NoCounters));
        }
        let tally = comparison.finish();
        let mut batch = self.compare(&format!("{what} (batch)"), strictness);
        let mut hits = vec![PrimaryHits::MISS; self.rays.len()];
        accel.intersect_batch(self.rays, &mut hits, &mut NoCounters);
        let mut occluded = vec![false; self.rays.len()];
        accel.occluded_batch(self.rays, &mut occluded, &mut NoCounters);
        for (i, (hit, occluded)) in hits.into_iter().zip(occluded).enumerate() {
            batch.check(i, Answer::closest(hit));
            batch.occluded(i, occluded);
        }
        batch.finish();
        tally
    }

    /// [`Reference::assert_agrees`] for whichever structure `accel` holds.
    #[track_caller]
    pub fn assert_built_agrees<P: WidePrimitive>(&self, what: &str, accel: &BuiltAccel<P>, strictness: Strictness) {
        struct Check<'c, 'r, 'a, X: ExactPrimitive>(&'r Reference<'a, X>, &'c str, Strictness);
        impl<X: ExactPrimitive> AccelVisitor for Check<'_, '_, '_, X> {
            type Output = ();
            #[track_caller]
            fn visit<A: Accelerator>(self, accel: &A) {
                _ = self.0.assert_agrees(self.1, accel, self.2);
            }
        }
        accel.visit(Check(self, what, strictness));
    }
}

/// What a finished comparison counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Answers compared.
    pub answers: usize,
    /// Disagreements f64 tolerated (grazing rays, edge ties).
    pub tolerated: usize,
}

/// Answers being compared with a [`Reference`], one at a time (for backends answered in batches, e.g.
/// packets); [`Comparison::finish`] fails if any disagreed. Besides [`check`], a hit must name a primitive that f64
/// allows at its `t`.
#[must_use = "call `finish` to fail on disagreements"]
#[derive(Debug)]
pub struct Comparison<'r, 'a, X: ExactPrimitive = Sphere> {
    reference: &'r Reference<'a, X>,
    what: String,
    strictness: Strictness,
    bad: Vec<String>,
    excused: Vec<String>,
    answers: usize,
}

impl<X: ExactPrimitive> Comparison<'_, '_, X> {
    /// Compares `got` with brute force's closest hit of ray `i`.
    #[inline]
    pub fn closest(&mut self, i: usize, got: Option<Hit>) {
        self.check(i, Answer::Closest(got));
    }

    /// Compares `got` with brute force's occlusion of ray `i`.
    #[inline]
    pub fn occluded(&mut self, i: usize, got: bool) {
        self.check(i, Answer::Occluded(got));
    }

    /// Compares `got` with brute force's answer of the same kind to ray `i`.
    #[inline]
    pub fn check(&mut self, i: usize, got: Answer) {
        let (reference, ray) = (self.reference, &self.reference.rays[i]);
        self.answers += 1;
        let want = match got {
            Answer::Closest(_) => Answer::Closest(reference.closest[i]),
            Answer::Occluded(_) => Answer::Occluded(reference.occluded[i]),
        };
        let text = || format!("ray {i} {ray:?}: {got:?} vs brute force {want:?}");
        match check(&reference.brute, ray, &want, &got, self.strictness) {
            Outcome::Agree => {}
            Outcome::Tolerated(why) => self.excused.push(format!("{} ({why:?})", text())),
            Outcome::Mismatch(side) => self.bad.push(format!("{} (wrong: {side:?})", text())),
        }
        if let Answer::Closest(Some(hit)) = got {
            let named = reference.candidates[i].get(hit.prim).map(|c| c.exact.outcomes);
            if !named.is_some_and(|o| o.may_report(hit.t as f64, t_tolerance(ray, hit.t) as f64)) {
                self.bad.push(format!("{} (primitive {} cannot be hit at t = {})", text(), hit.prim, hit.t));
            }
        }
    }

    /// Prints the excused disagreements and panics with the others (the first 8 shown), if any.
    #[track_caller]
    #[inline]
    pub fn finish(self) -> Tally {
        let Self { what, strictness, bad, excused, reference, answers } = self;
        let tally = Tally { answers, tolerated: excused.len() };
        if !excused.is_empty() {
            eprintln!(
                "{what}: {} disagreement(s) f64 brute force tolerates (f32 cannot decide them):\n  {}",
                excused.len(),
                excused.join("\n  ")
            );
        }
        assert!(
            bad.is_empty(),
            "{what}: {} disagreement(s) with brute force over {} rays ({strictness:?}):\n{}",
            bad.len(),
            reference.rays.len(),
            bad[..bad.len().min(8)].join("\n")
        );
        tally
    }
}

/// Builds every tree configuration ([`every_tree`]) over `spheres` and checks each against brute force on
/// `rays` with [`Strictness::Identical`] (their leaves call [`Sphere::intersect`]); `label` starts the failure
/// message, followed by the configuration.
// `#[inline]`: compiled only where a test calls it, not into every build of the tracer (it builds and traverses
// every tree configuration).
#[inline]
#[track_caller]
pub fn assert_every_tree_agrees(label: &str, spheres: &[Sphere], rays: &[Ray]) {
    assert_every_tree_agrees_over(label, spheres, &Reference::new(spheres, rays), Strictness::Identical);
}

/// [`assert_every_tree_agrees`] over `triangles` with the test of `T` (brute force runs the same test), under
/// [`Strictness::Arbitrated`]: a ray through a vertex or edge may meet a triangle a few ulps before the box that
/// holds it, so a tree may return the neighbour that shares the vertex, one ulp later (an edge tie f64 tolerates).
#[track_caller]
pub fn assert_every_tree_agrees_on_triangles<T: TrianglePrimitive + WidePrimitive>(
    label: &str,
    triangles: &[Triangle],
    rays: &[Ray],
) {
    let prims = T::all(triangles.iter().copied());
    let reference = Reference::triangles::<T>(triangles, rays);
    assert_every_tree_agrees_over(&format!("{label} {}", T::NAME), &prims, &reference, Strictness::Arbitrated);
}

#[track_caller]
fn assert_every_tree_agrees_over<P: WidePrimitive, X: ExactPrimitive>(
    label: &str,
    prims: &[P],
    reference: &Reference<'_, X>,
    strictness: Strictness,
) {
    // `every_tree` varies the traversal innermost: a binary tree is built once and traversed in each order. The
    // trees are checked on rayon's threads.
    let same_tree = |a: &AccelParams, b: &AccelParams| {
        matches!(a.kind, AccelKind::Bvh | AccelKind::FlatBvh)
            && AccelParams { bvh: BvhParams { traversal: b.bvh.traversal, ..a.bvh }, ..*a } == *b
    };
    let trees = every_tree();
    let groups: Vec<&[AccelParams]> = trees.chunk_by(same_tree).collect();
    groups.into_par_iter().for_each(|group| {
        let mut accel = BuiltAccel::build(prims, &group[0]);
        for (k, params) in group.iter().enumerate() {
            accel = match accel {
                BuiltAccel::Bvh(tree) if k > 0 => BuiltAccel::Bvh(tree.with_traversal(params.bvh.traversal)),
                BuiltAccel::FlatBvh(tree) if k > 0 => BuiltAccel::FlatBvh(tree.with_traversal(params.bvh.traversal)),
                accel => accel,
            };
            reference.assert_built_agrees(&format!("{label} {params:?}"), &accel, strictness);
        }
    });
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::TreeStats;
    use crate::counters::Counters;
    use crate::testing::sphere_ray_mix;

    /// Brute force with its hit distances scaled and, optionally, every occlusion answer negated.
    struct Skewed {
        list: List,
        t_scale: f32,
        flip_occlusion: bool,
    }

    impl Accelerator for Skewed {
        fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
            self.list.intersect(ray, counters).map(|h| Hit { t: h.t * self.t_scale, ..h })
        }
        fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
            self.list.occluded(ray, counters) != self.flip_occlusion
        }
        fn stats(&self) -> TreeStats {
            self.list.stats()
        }
    }

    fn spheres() -> Vec<Sphere> {
        crate::scene::SceneKind::RandomSpheres.generate(40, 3).spheres
    }

    fn check(t_scale: f32, flip_occlusion: bool, strictness: Strictness) {
        let spheres = spheres();
        let rays = sphere_ray_mix(&spheres, 9, 200);
        let accel = Skewed { list: List::build(&spheres), t_scale, flip_occlusion };
        Reference::new(&spheres, &rays).assert_agrees("skewed", &accel, strictness);
    }

    #[test]
    fn brute_force_agrees_with_itself_under_either_strictness() {
        for strictness in [Strictness::Identical, Strictness::Arbitrated] {
            check(1.0, false, strictness);
        }
    }

    #[test]
    #[should_panic(expected = "disagreement(s) with brute force")]
    fn identical_rejects_one_ulp() {
        check(1.0 + f32::EPSILON, false, Strictness::Identical);
    }

    #[test]
    fn arbitrated_accepts_1e_5() {
        check(1.0 + 1e-5, false, Strictness::Arbitrated);
    }

    #[test]
    #[should_panic(expected = "Closest(Some")]
    fn arbitrated_rejects_1e_3() {
        check(1.0 + 1e-3, false, Strictness::Arbitrated);
    }

    #[test]
    #[should_panic(expected = "Occluded")]
    fn occlusion_must_match_where_f64_decides() {
        check(1.0, true, Strictness::Arbitrated);
    }

    /// A ray exactly tangent to a sphere: brute force hits it, a backend that misses is tolerated only by
    /// [`Strictness::Arbitrated`].
    #[test]
    fn only_arbitration_tolerates_grazing_rays() {
        let spheres = [Sphere::new(Vec3::ZERO, 1.0)];
        let rays = [Ray::new(Vec3::new(1.0, 0.0, -5.0), Vec3::Z)];
        let reference = Reference::new(&spheres, &rays);
        assert!(reference.closest[0].is_some() && reference.occluded[0]);
        let misses = |strictness| {
            let mut c = reference.compare("misses", strictness);
            c.closest(0, None);
            c.occluded(0, false);
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| c.finish())).is_ok()
        };
        assert!(misses(Strictness::Arbitrated));
        assert!(!misses(Strictness::Identical));
    }
}
