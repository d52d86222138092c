//! f64 brute force: for each ray, every primitive the f32 test may report, evaluated exactly.

use rayon::prelude::*;

use super::{ExactAnswer, ExactPrimitive};
use crate::geometry::Ray;

/// A scene's primitives laid out for f64 brute force.
#[derive(Clone, Debug)]
pub struct BruteForce64<P: ExactPrimitive> {
    prims: Vec<P>,
    layout: P::Layout,
}

/// A primitive the f32 test may report for a ray: its index and its f64 evaluation.
#[derive(Clone, Copy, Debug)]
pub struct Candidate {
    /// Index of the primitive in the scene.
    pub prim: u32,
    /// The ray against the primitive in f64.
    pub exact: ExactAnswer,
}

/// Every primitive the f32 test may report for one ray (all others it surely misses).
#[derive(Clone, Debug)]
pub struct RayCandidates {
    /// The ray.
    pub ray: Ray,
    /// Its candidates, by primitive index.
    pub list: Vec<Candidate>,
}

impl<P: ExactPrimitive> BruteForce64<P> {
    /// Lays out `prims` for brute force.
    pub fn new(prims: &[P]) -> Self {
        Self { prims: prims.to_vec(), layout: P::layout(prims) }
    }

    /// Number of primitives.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// The candidates of every ray (in order), rays in parallel.
    pub fn candidates(&self, rays: &[Ray]) -> Vec<RayCandidates> {
        rays.par_iter().map(|ray| self.candidates_of(ray)).collect()
    }

    /// The candidates of one ray: the screened primitives that the f32 test may report.
    pub fn candidates_of(&self, ray: &Ray) -> RayCandidates {
        let list = P::screen(&self.layout, ray)
            .into_iter()
            .filter_map(|prim| {
                let exact = self.prims[prim as usize].exact(ray);
                exact.outcomes.may_hit().then_some(Candidate { prim, exact })
            })
            .collect();
        RayCandidates { ray: *ray, list }
    }
}

impl RayCandidates {
    /// The exact closest hit: primitive and `t`.
    pub fn exact_closest(&self) -> Option<(u32, f64)> {
        self.list.iter().filter_map(|c| c.exact.hit.map(|t| (c.prim, t))).min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The candidate for primitive `prim`, if the f32 test may report it.
    pub fn get(&self, prim: u32) -> Option<&Candidate> {
        self.list.iter().find(|c| c.prim == prim)
    }
}
