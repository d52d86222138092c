//! f64 brute force: for each ray, every primitive the f32 test may report, evaluated exactly.

use rayon::prelude::*;

use super::{ExactAnswer, ExactPrimitive, t_tolerance};
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
    /// True when the ray crosses an edge or vertex shared by its candidates at the exact closest hit (see
    /// [`BruteForce64::crosses_shared`]): an answer that misses them there slipped between them.
    pub crosses_shared: bool,
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
            .collect::<Vec<_>>();
        let crosses_shared = self.crosses_shared(ray, &list);
        RayCandidates { ray: *ray, list, crosses_shared }
    }

    /// True when two or more of `list` may be reported at the exact closest hit and the surface they make covers
    /// the hit point: rays parallel to `ray`, moved sideways from it by [`CROSSING_ULPS`] ulps of the hit point in
    /// eight directions, each hit one of them in f64. A ray that only touches them (a silhouette edge or vertex)
    /// does not cross.
    fn crosses_shared(&self, ray: &Ray, list: &[Candidate]) -> bool {
        let Some(t) = list.iter().filter_map(|c| c.exact.hit).min_by(f64::total_cmp) else { return false };
        let slack = t_tolerance(ray, t as f32) as f64;
        let near: Vec<&P> = list
            .iter()
            .filter(|c| c.exact.outcomes.may_report(t, slack))
            .map(|c| &self.prims[c.prim as usize])
            .collect();
        if near.len() < 2 {
            return false;
        }
        let point = ray.at(t as f32);
        let step = CROSSING_ULPS * f32::EPSILON * point.abs().max_element().max(f32::MIN_POSITIVE);
        let back = (1.0 / 16.0f32).min(t as f32);
        let (u, v) = ray.dir.normalize().any_orthonormal_pair();
        (0..8).all(|k| {
            let (sin, cos) = (k as f32 * std::f32::consts::FRAC_PI_4).sin_cos();
            let moved = Ray::new(point - ray.dir * back + (u * cos + v * sin) * step, ray.dir);
            near.iter().any(|p| p.exact(&moved).hit.is_some_and(|h| h < 2.0 * back as f64))
        })
    }
}

/// How far [`BruteForce64`]'s crossing test moves a ray sideways, in ulps of the hit point's largest coordinate:
/// far beyond the f32 tests' rounding, far within any triangle of the meshes measured here.
pub const CROSSING_ULPS: f32 = 256.0;

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
