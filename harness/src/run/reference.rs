//! The reference a configuration is validated against, and f64 brute force's check of it.
//!
//! The reference is f32 brute force ([`List`]) for scenes of at most [`BRUTE_FORCE_MAX`] primitives, else the
//! tracer's flat BVH (binned SAH, front-to-back); over triangles both run the watertight test, and f64 brute force
//! is over the [`Triangle`]s (a ray within rounding of a shared edge or vertex is a tie there: tolerated, counted
//! as `grazing`). Neither is trusted blindly: before its first use, the reference's answers are checked against f64
//! brute force on every ray when rays × spheres ≤ [`ARBITRATION_BUDGET`], else on at least [`STRIDED_MIN`] rays
//! evenly strided over the set ([`strided`]); the count is recorded as `reference_checked`, and an answer f64 does
//! not accept fails every configuration validated against that reference (`wrong_side = reference`).

use std::sync::Arc;

use tracer::accel::{AccelKind, BvhParams, FlatBvh, List, Split, Traversal};
use tracer::agreement::{Answer, BruteForce64, RayCandidates};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::geometry::{Ray, Sphere, Triangle};
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
}

/// The reference's answers to `set` over `prims`: f32 brute force up to [`BRUTE_FORCE_MAX`], else the flat BVH.
pub fn answers<P: tracer::accel::bvh::split::Referenced>(
    prims: &[P],
    set: RaySet,
) -> (RaySet, RayAnswers, &'static str) {
    if prims.len() <= BRUTE_FORCE_MAX {
        let answers = trace::<_, NoCounters>(&List::build(prims), &set, &Strategy::SERIAL).0;
        (set, answers, AccelKind::List.name())
    } else {
        let answers = trace::<_, NoCounters>(&FlatBvh::build(prims, &reference_params()), &set, &Strategy::SERIAL).0;
        (set, answers, AccelKind::FlatBvh.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
