//! The reference a configuration is validated against, and f64 brute force's check of it.
//!
//! The reference is f32 brute force ([`List`]) for scenes of at most [`BRUTE_FORCE_MAX`] primitives, else the
//! tracer's flat BVH (binned SAH, front-to-back); over triangles both run the watertight test, and f64 brute force
//! is over the [`Triangle`]s (a ray within rounding of a shared edge or vertex is a tie there: tolerated, counted
//! as `grazing`). Neither is trusted blindly: before its first use, the reference's answers are checked against f64
//! brute force on every ray when rays × spheres ≤ [`ARBITRATION_BUDGET`], else on at least [`STRIDED_MIN`] rays
//! evenly strided over the set ([`strided`]); the count is recorded as `reference_checked`, and an answer f64 does
//! not accept fails every configuration validated against that reference (`wrong_side = reference`).
//!
//! A backend's answers are judged against the reference's ([`Reference::judge`]) by the tracer's one definition of
//! agreement ([`tracer::agreement`]: the distance tolerance and f64 brute force's arbitration). An answer that does
//! not agree with the reference's ([`Answer::agrees`]) is arbitrated ([`arbitrate`]): a tolerated disagreement
//! counts as `grazing`; a mismatch counts in `mismatches`, and `wrong_side` says whose answers f64 showed wrong
//! (`backend`, `reference` or `both`). More disagreements than one strided subset's worth are arbitrated on an
//! evenly strided subset of that size; the rest count as mismatches.

use std::sync::Arc;

use schema::WrongSide;
use tracer::accel::{AccelKind, BvhParams, FlatBvh, List, Split, Traversal};
use tracer::agreement::{self, Answer, BruteForce64, Outcome, RayCandidates, Strictness, Tolerated, arbitrate};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::geometry::{Ray, Sphere, Triangle, TrianglePrimitive, WatertightTriangle};
use tracer::rays::{RayAnswers, RaySet, trace};

use super::scenes::SceneData;

/// f64 brute force over a scene's primitives.
#[derive(Debug)]
pub enum Exact {
    Spheres(BruteForce64<Sphere>),
    Triangles(BruteForce64<Triangle>),
}

impl Exact {
    /// f64 brute force over the scene's primitives.
    pub fn of(scene: &SceneData) -> Self {
        match scene {
            SceneData::Spheres(s) => Exact::Spheres(BruteForce64::new(&s.spheres)),
            SceneData::Triangles(t) => Exact::Triangles(BruteForce64::new(&t.mesh.triangles().collect::<Vec<_>>())),
        }
    }

    /// True for a scene of nothing.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        match self {
            Exact::Spheres(b) => b.len(),
            Exact::Triangles(b) => b.len(),
        }
    }

    /// Every primitive each ray meets, in f64.
    pub fn candidates(&self, rays: &[Ray]) -> Vec<RayCandidates> {
        match self {
            Exact::Spheres(b) => b.candidates(rays),
            Exact::Triangles(b) => b.candidates(rays),
        }
    }
}

/// Largest scene validated against brute force.
pub const BRUTE_FORCE_MAX: usize = 10_000;

/// Rays × spheres up to which f64 brute force checks every ray of a set (about 2 s on one core).
pub const ARBITRATION_BUDGET: u64 = 2_000_000_000;

/// Fewest rays f64 brute force checks (or arbitrates) in a set, when not all of them.
pub const STRIDED_MIN: usize = 16_384;

/// The trusted tree for larger scenes.
pub(crate) fn reference_params() -> BvhParams {
    BvhParams { split: Split::BinnedSah, traversal: Traversal::FrontToBack, ..BvhParams::default() }
}

/// How many of `rays` rays f64 brute force over `spheres` spheres checks: all within [`ARBITRATION_BUDGET`],
/// else `max(STRIDED_MIN, budget / spheres)`.
pub fn checked_count(rays: usize, spheres: usize) -> usize {
    if rays as u64 * spheres as u64 <= ARBITRATION_BUDGET {
        rays
    } else {
        STRIDED_MIN.max((ARBITRATION_BUDGET / spheres.max(1) as u64) as usize).min(rays)
    }
}

/// `k` of the indices `0..n`, evenly strided (all of them when `k ≥ n`).
pub fn strided(n: usize, k: usize) -> Vec<usize> {
    let k = k.min(n);
    (0..k).map(|i| (i as u128 * n as u128 / k as u128) as usize).collect()
}

/// A ray set, the reference's answers, and what f64 brute force found of them.
#[derive(Debug)]
pub struct Reference {
    /// The rays.
    pub set: Arc<RaySet>,
    /// The reference's answers.
    pub answers: Arc<RayAnswers>,
    /// The reference's name (`list` or `flat-bvh`).
    pub name: &'static str,
    /// The scene's primitives, for f64 brute force.
    pub exact: Arc<Exact>,
    /// Rays whose reference answer f64 brute force checked.
    pub checked: usize,
    /// Those of them it did not accept.
    pub wrong: Vec<usize>,
}

impl Reference {
    /// Checks `answers` against f64 brute force on [`checked_count`] rays of `set`.
    pub fn check(set: Arc<RaySet>, answers: Arc<RayAnswers>, name: &'static str, exact: Arc<Exact>) -> Self {
        let picked = strided(set.rays.len(), checked_count(set.rays.len(), exact.len()));
        let rays: Vec<Ray> = picked.iter().map(|&i| set.rays[i]).collect();
        let found = exact.candidates(&rays);
        let wrong = picked
            .iter()
            .zip(&found)
            .filter(|(i, c)| !c.verdict(&Answer::of(&answers, **i)).acceptable())
            .map(|(i, _)| *i)
            .collect();
        Self { set, answers, name, exact, checked: picked.len(), wrong }
    }

    /// A backend's answers `got` judged against this reference, disagreements arbitrated by f64 brute force (see
    /// the module documentation).
    pub fn judge(&self, got: &RayAnswers) -> Judgement {
        let n = self.set.rays.len();
        let Some(disagree) = disagreements(&self.set, &self.answers, got) else {
            let wrong_side = WrongSide::of(true, !self.wrong.is_empty());
            return Judgement {
                mismatches: n.max(1),
                reference_checked: self.checked,
                wrong_side,
                ..Judgement::default()
            };
        };
        let cap = checked_count(n, self.exact.len());
        let (mut rays, unjudged) = if disagree.len() > cap {
            (strided(disagree.len(), cap).into_iter().map(|k| disagree[k]).collect(), disagree.len() - cap)
        } else {
            (disagree.clone(), 0)
        };
        rays.extend(&self.wrong);
        rays.sort_unstable();
        rays.dedup();
        let found = self.exact.candidates(&rays.iter().map(|&i| self.set.rays[i]).collect::<Vec<_>>());
        let mut judged = Judgement { mismatches: unjudged, reference_checked: self.checked, ..Judgement::default() };
        let (mut backend_wrong, mut reference_wrong) = (false, false);
        for (&i, c) in rays.iter().zip(&found) {
            match arbitrate(c, &Answer::of(&self.answers, i), &Answer::of(got, i)) {
                Outcome::Agree => {}
                Outcome::Tolerated(Tolerated::Grazing) => judged.grazing += 1,
                Outcome::Tolerated(Tolerated::Tie) => judged.ties += 1,
                Outcome::Tolerated(Tolerated::Leak) => judged.leaks += 1,
                Outcome::Mismatch(side) => {
                    judged.mismatches += 1;
                    backend_wrong |= side != agreement::WrongSide::Reference;
                    reference_wrong |= side != agreement::WrongSide::Backend;
                }
            }
        }
        judged.wrong_side = WrongSide::of(backend_wrong || (unjudged > 0 && !reference_wrong), reference_wrong);
        judged
    }
}

/// The reference's answers to `set` over `scene`'s primitives, and the reference's name.
pub fn answers(scene: &SceneData, set: &RaySet) -> (RayAnswers, &'static str) {
    match scene {
        SceneData::Spheres(s) => traced(&s.spheres, set),
        SceneData::Triangles(t) => traced(&WatertightTriangle::all(t.mesh.triangles()), set),
    }
}

/// The answers to `set` over `prims` of f32 brute force up to [`BRUTE_FORCE_MAX`] primitives, else of the flat BVH.
fn traced<P: tracer::accel::bvh::split::Referenced>(prims: &[P], set: &RaySet) -> (RayAnswers, &'static str) {
    if prims.len() <= BRUTE_FORCE_MAX {
        (trace::<_, NoCounters>(&List::build(prims), set, &Strategy::SERIAL).0, AccelKind::List.name())
    } else {
        let answers = trace::<_, NoCounters>(&FlatBvh::build(prims, &reference_params()), set, &Strategy::SERIAL).0;
        (answers, AccelKind::FlatBvh.name())
    }
}

/// Indices of the rays of `set` whose answers disagree or name different primitives (`None` when the answers
/// are not comparable: another kind or count).
pub fn disagreements(set: &RaySet, reference: &RayAnswers, got: &RayAnswers) -> Option<Vec<usize>> {
    let comparable = match (reference, got) {
        (RayAnswers::Closest(want), RayAnswers::Closest(got)) => want.len() == got.len(),
        (RayAnswers::Occluded(want), RayAnswers::Occluded(got)) => want.len() == got.len(),
        _ => false,
    };
    comparable.then(|| {
        (0..set.rays.len())
            .filter(|&i| {
                let (want, got) = (Answer::of(reference, i), Answer::of(got, i));
                !want.agrees(&set.rays[i], &got, Strictness::Arbitrated) || want.names_another(&got)
            })
            .collect()
    })
}

/// What validation found: disagreements with the reference that f64 brute force did not accept
/// (`mismatches`) and those it tolerated (`grazing`, `ties`, `leaks`: [`agreement::Tolerated`]), the reference's
/// own check, and who was wrong.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Judgement {
    pub mismatches: usize,
    pub grazing: usize,
    pub ties: usize,
    pub leaks: usize,
    pub reference_checked: usize,
    pub wrong_side: WrongSide,
}

#[cfg(test)]
mod tests {
    use tracer::accel::List;
    use tracer::counters::NoCounters;
    use tracer::executor::Strategy;
    use tracer::rays::{RayKind, trace};

    use std::sync::Arc;

    use super::*;
    use tracer::Vec3;
    use tracer::accel::Hit;
    use tracer::agreement::BruteForce64;
    use tracer::render::PrimaryHits;

    fn set(rays: Vec<Ray>) -> RaySet {
        RaySet { kind: RayKind::Primary, rays }
    }

    #[test]
    fn disagreements_are_hit_miss_distance_and_primitive_differences() {
        let rays = set(vec![Ray::new(Vec3::ZERO, Vec3::Z); 4]);
        let hit = |t| Hit { t, prim: 1 };
        let want = RayAnswers::Closest(vec![hit(10.0), hit(10.0), PrimaryHits::MISS, hit(10.0)]);
        let got = RayAnswers::Closest(vec![hit(10.0005), hit(10.01), hit(3.0), Hit { t: 10.0, prim: 7 }]);
        assert_eq!(
            disagreements(&rays, &want, &got),
            Some(vec![1, 2, 3]),
            "1e-4 relative passes, 1e-3 fails, hit vs miss fails, another id goes to f64 (a tie or a wrong id)"
        );
        let flags = |v: &[bool]| RayAnswers::Occluded(v.to_vec());
        assert_eq!(
            disagreements(&rays, &flags(&[true, false, true, true]), &flags(&[true, true, true, false])),
            Some(vec![1, 3])
        );
        assert_eq!(disagreements(&rays, &flags(&[true]), &want), None);
    }

    /// One sphere; ray 0 hits it squarely, ray 1 exactly tangent (f32 brute force hits it), ray 2 misses it by
    /// 1e-3 of its radius.
    fn tangent_case() -> (Arc<RaySet>, Arc<RayAnswers>, Arc<Exact>) {
        let spheres = [Sphere::new(Vec3::new(0.0, 0.0, -10.0), 1.0)];
        let rays = vec![
            Ray::new(Vec3::ZERO, -Vec3::Z),
            Ray::new(Vec3::new(1.0, 0.0, 0.0), -Vec3::Z),
            Ray::new(Vec3::new(1.001, 0.0, 0.0), -Vec3::Z),
        ];
        let set = set(rays);
        let answers = trace::<_, NoCounters>(&List::build(&spheres), &set, &Strategy::SERIAL).0;
        (Arc::new(set), Arc::new(answers), Arc::new(Exact::Spheres(BruteForce64::new(&spheres))))
    }

    #[test]
    fn f64_tolerates_grazing_disagreements_and_names_the_wrong_side() {
        let (set, answers, exact) = tangent_case();
        let reference = Reference::check(set, answers, "list", exact);
        assert_eq!((reference.checked, reference.wrong.len()), (3, 0));
        let hit = |t| Hit { t, prim: 0 };
        let miss = PrimaryHits::MISS;
        let judged = |got: Vec<Hit>| reference.judge(&RayAnswers::Closest(got));
        let ok = Judgement { reference_checked: 3, ..Judgement::default() };
        assert_eq!(judged(vec![hit(9.0), hit(10.0), miss]), ok);
        assert_eq!(judged(vec![hit(9.0), miss, miss]), Judgement { grazing: 1, ..ok.clone() }, "tangent: tolerated");
        let backend = Judgement { mismatches: 1, wrong_side: WrongSide::Backend, ..ok.clone() };
        assert_eq!(judged(vec![hit(9.0), hit(10.0), hit(10.0)]), backend, "a real miss");
        assert_eq!(judged(vec![hit(9.1), hit(10.0), miss]), backend, "a distance off by 1e-2");
        assert_eq!(judged(vec![miss, hit(10.0), miss]), backend);
        let flags = RayAnswers::Occluded(vec![true; 3]);
        assert_eq!(reference.judge(&flags).wrong_side, WrongSide::Backend, "not comparable");
    }

    /// Two triangles sharing an edge, one ray straight onto its midpoint: the other triangle is a tie, a miss a
    /// leak, an id f64 does not allow a mismatch.
    #[test]
    fn shared_edges_count_ties_and_leaks() {
        let v = Vec3::new;
        let a = Triangle::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let b = Triangle::new(v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), v(0.0, 1.0, 0.0));
        let rays = Arc::new(set(vec![Ray::new(v(0.5, 0.5, 1.0), -Vec3::Z), Ray::new(v(0.2, 0.2, 1.0), -Vec3::Z)]));
        let hits = |h: [Hit; 2]| RayAnswers::Closest(h.to_vec());
        let on = |prim| Hit { t: 1.0, prim };
        let exact = Arc::new(Exact::Triangles(BruteForce64::new(&[a, b])));
        let reference = Reference::check(rays, Arc::new(hits([on(0), on(0)])), "list", exact);
        assert_eq!((reference.checked, reference.wrong.len()), (2, 0));
        let judged = |got| reference.judge(&hits(got));
        assert_eq!(judged([on(0), on(0)]), Judgement { reference_checked: 2, ..Judgement::default() });
        assert_eq!((judged([on(1), on(0)]).ties, judged([on(1), on(0)]).mismatches), (1, 0));
        assert_eq!((judged([PrimaryHits::MISS, on(0)]).leaks, judged([PrimaryHits::MISS, on(0)]).mismatches), (1, 0));
        let wrong_id = judged([on(0), on(1)]);
        assert_eq!((wrong_id.mismatches, wrong_id.ties, wrong_id.wrong_side), (1, 0, WrongSide::Backend));
    }

    #[test]
    fn a_wrong_reference_fails_validation() {
        let (set, _, exact) = tangent_case();
        let wrong =
            Arc::new(RayAnswers::Closest(vec![Hit { t: 9.0, prim: 0 }, PrimaryHits::MISS, Hit { t: 10.0, prim: 0 }]));
        let reference = Reference::check(set, wrong, "list", exact);
        assert_eq!(reference.wrong, vec![2], "the tangent miss is acceptable, the hit by 1e-3 is not");
        let right = RayAnswers::Closest(vec![Hit { t: 9.0, prim: 0 }, Hit { t: 10.0, prim: 0 }, PrimaryHits::MISS]);
        let got = reference.judge(&right);
        assert_eq!((got.mismatches, got.grazing, got.wrong_side), (1, 1, WrongSide::Reference));
        let agrees = reference.judge(&reference.answers);
        assert_eq!((agrees.mismatches, agrees.wrong_side), (1, WrongSide::Both), "agreeing with a wrong reference");
    }

    #[test]
    fn checked_rays_are_all_within_the_budget_else_strided() {
        assert_eq!(checked_count(49_152, 10_000), 49_152);
        assert_eq!(checked_count(786_432, 10_000), 200_000);
        assert_eq!(checked_count(786_432, 1_000_000), STRIDED_MIN);
        assert_eq!(checked_count(100, 1_000_000), 100);
        assert_eq!(strided(10, 4), vec![0, 2, 5, 7]);
        assert_eq!(strided(3, 8), vec![0, 1, 2]);
    }
}
