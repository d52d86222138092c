//! Validation before timing, planned → validated or rejected: one counted pass of a configuration, and its answers
//! judged against the reference's ([`super::reference`]) by the tracer's one definition of agreement
//! ([`tracer::agreement`]: the distance tolerance and f64 brute force's arbitration), counted into a row.
//!
//! A backend's answer that does not agree with the reference's ([`Answer::agrees`]) is arbitrated
//! ([`arbitrate`]): a tolerated disagreement counts as `grazing`; a mismatch counts in `mismatches`, and
//! `wrong_side` says whose answers f64 showed wrong (`backend`, `reference` or `both`). Validation passes
//! (`exact`) when `mismatches` is 0. More disagreements than one strided subset's worth are arbitrated on an
//! evenly strided subset of that size; the rest count as mismatches.

use schema::{ValidationStatus, WrongSide};
use tracer::agreement::{self, Answer, Outcome, Strictness, Tolerated, arbitrate};
use tracer::counters::WorkCounters;
use tracer::rays::{RayAnswers, RaySet};

use super::rays::{RayBank, workload_rays};
use super::reference::{Reference, checked_count, strided};
use super::trial::counted;
use crate::error::Error;
use crate::plan::{Configuration, Plan};

/// What validating one configuration found: the counted pass's counters and output hash, and the judgement of its
/// answers against the reference's (no reference and no judgement for a backend that gives no answers).
#[derive(Clone, Debug)]
pub struct Findings {
    pub status: ValidationStatus,
    pub counters: WorkCounters,
    pub output_hash: u64,
    pub reference: &'static str,
    /// Mismatches, tolerated disagreements by kind, the reference's own check and whose answers were wrong.
    pub judged: Judgement,
    pub rays: usize,
}

/// A planned configuration after validation: cleared for timing, or rejected (recorded once, never timed).
#[derive(Clone, Debug)]
pub enum Validation {
    /// Its answers agree with the reference's (`exact`), or its backend gives none to check (`unchecked`).
    Validated(Findings),
    /// Its answers disagree with the reference's beyond f64 brute force's tolerance.
    Rejected(Findings),
}

impl Findings {
    /// Why a configuration (`what`) was rejected, in one line.
    pub fn failure(&self, what: &str) -> String {
        format!(
            "VALIDATION FAILED: {what}: {} of {} rays disagree with {} beyond f64 brute force's tolerance ({} grazing, \
             {} ties, {} leaks tolerated); f64 shows the {} answers wrong; this configuration is not timed",
            self.judged.mismatches,
            self.rays,
            self.reference,
            self.judged.grazing,
            self.judged.ties,
            self.judged.leaks,
            match self.judged.wrong_side {
                WrongSide::Both => "backend's and the reference's",
                WrongSide::Reference => "reference's",
                WrongSide::Backend | WrongSide::Neither => "backend's",
            }
        )
    }
}

/// Validates configuration `c` before its first timed run: one counted pass over its workload's rays (its counters
/// and output hash), and its answers to its validation ray set judged against the reference's (a backend that gives
/// no answers is recorded `unchecked`).
pub fn validate(plan: &Plan, c: &Configuration, bank: &mut RayBank) -> Result<Validation, Error> {
    let (settings, file) = (&c.settings, plan.scene_file());
    let rays = workload_rays(plan, settings, bank);
    let rays = rays.as_deref();
    let reference = bank.reference_for(settings, file);
    let Some(reference) = reference else {
        let (counters, output_hash, _) = counted(settings, file, rays, None)?;
        let judged = Judgement::default();
        let status = ValidationStatus::Unchecked;
        return Ok(Validation::Validated(Findings { status, counters, output_hash, reference: "-", judged, rays: 0 }));
    };
    let (counters, output_hash, answers) = counted(settings, file, rays, Some(&reference.set))?;
    let judged = judge(&reference, &answers.expect("answers were asked for"));
    let exact = judged.mismatches == 0;
    let status = if exact { ValidationStatus::Exact } else { ValidationStatus::Failed };
    let findings =
        Findings { status, counters, output_hash, reference: reference.name, judged, rays: reference.set.rays.len() };
    Ok(if exact { Validation::Validated(findings) } else { Validation::Rejected(findings) })
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

/// A backend's answers `got` judged against `reference`, disagreements arbitrated by f64 brute force (see the
/// module documentation).
pub fn judge(reference: &Reference, got: &RayAnswers) -> Judgement {
    let n = reference.set.rays.len();
    let Some(disagree) = disagreements(&reference.set, &reference.answers, got) else {
        let wrong_side = WrongSide::of(true, !reference.wrong.is_empty());
        return Judgement {
            mismatches: n.max(1),
            reference_checked: reference.checked,
            wrong_side,
            ..Judgement::default()
        };
    };
    let cap = checked_count(n, reference.exact.len());
    let (mut rays, unjudged) = if disagree.len() > cap {
        (strided(disagree.len(), cap).into_iter().map(|k| disagree[k]).collect(), disagree.len() - cap)
    } else {
        (disagree.clone(), 0)
    };
    rays.extend(&reference.wrong);
    rays.sort_unstable();
    rays.dedup();
    let found = reference.exact.candidates(&rays.iter().map(|&i| reference.set.rays[i]).collect::<Vec<_>>());
    let mut judged = Judgement { mismatches: unjudged, reference_checked: reference.checked, ..Judgement::default() };
    let (mut backend_wrong, mut reference_wrong) = (false, false);
    for (&i, c) in rays.iter().zip(&found) {
        match arbitrate(c, &Answer::of(&reference.answers, i), &Answer::of(got, i)) {
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

#[cfg(test)]
mod tests {
    use tracer::accel::List;
    use tracer::counters::NoCounters;
    use tracer::executor::Strategy;
    use tracer::rays::{RayKind, trace};

    use std::sync::Arc;

    use super::super::reference::Exact;
    use super::*;
    use tracer::Vec3;
    use tracer::accel::Hit;
    use tracer::agreement::BruteForce64;
    use tracer::geometry::{Ray, Sphere, Triangle};
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
        let judged = |got: Vec<Hit>| judge(&reference, &RayAnswers::Closest(got));
        let ok = Judgement { reference_checked: 3, ..Judgement::default() };
        assert_eq!(judged(vec![hit(9.0), hit(10.0), miss]), ok);
        assert_eq!(judged(vec![hit(9.0), miss, miss]), Judgement { grazing: 1, ..ok.clone() }, "tangent: tolerated");
        let backend = Judgement { mismatches: 1, wrong_side: WrongSide::Backend, ..ok.clone() };
        assert_eq!(judged(vec![hit(9.0), hit(10.0), hit(10.0)]), backend, "a real miss");
        assert_eq!(judged(vec![hit(9.1), hit(10.0), miss]), backend, "a distance off by 1e-2");
        assert_eq!(judged(vec![miss, hit(10.0), miss]), backend);
        let flags = RayAnswers::Occluded(vec![true; 3]);
        assert_eq!(judge(&reference, &flags).wrong_side, WrongSide::Backend, "not comparable");
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
        let judged = |got| judge(&reference, &hits(got));
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
        let got = judge(&reference, &right);
        assert_eq!((got.mismatches, got.grazing, got.wrong_side), (1, 1, WrongSide::Reference));
        let agrees = judge(&reference, &reference.answers);
        assert_eq!((agrees.mismatches, agrees.wrong_side), (1, WrongSide::Both), "agreeing with a wrong reference");
    }
}
