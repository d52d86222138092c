//! The null backend: every ray misses, and nothing is read, neither the ray nor any structure. Traced through the
//! same ray set, executor and batch loop as every backend, its time is the harness's own cost per ray (one call
//! per ray that returns at once, and the answer written), as hyperfine measures its shell's start-up.

use super::{Accelerator, Hit, TreeStats};
use crate::counters::Counters;
use crate::geometry::Ray;

/// Answers "miss" to every query without touching memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Null;

impl Accelerator for Null {
    /// Never inlined: the loop keeps one call per ray, as every real backend has.
    #[inline(never)]
    fn intersect<C: Counters>(&self, _ray: &Ray, _counters: &mut C) -> Option<Hit> {
        None
    }

    #[inline(never)]
    fn occluded<C: Counters>(&self, _ray: &Ray, _counters: &mut C) -> bool {
        false
    }

    /// No structure: every count is 0.
    fn stats(&self) -> TreeStats {
        TreeStats::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::counters::WorkCounters;
    use crate::executor::Strategy;
    use crate::rays::{RayAnswers, RaySet, trace};
    use crate::render::PrimaryHits;
    use crate::scene::SceneKind;

    #[test]
    fn every_ray_misses_through_the_batch_path_and_counts_as_one_ray() {
        let mut scene = SceneKind::RandomSpheres.generate(50, 1);
        scene.camera = scene.camera.with_resolution(40, 30);
        let set = RaySet::primary(&scene);
        let (answers, c) = trace::<_, WorkCounters>(&Null, &set, &Strategy::SERIAL);
        assert_eq!(answers, RayAnswers::Closest(vec![PrimaryHits::MISS; 1200]));
        assert_eq!((c.rays, c.nodes_visited, c.box_tests, c.prim_tests), (1200, 0, 0, 0));
        let shadow = RaySet { kind: crate::rays::RayKind::Shadow, rays: set.rays.clone() };
        assert_eq!(
            trace::<_, WorkCounters>(&Null, &shadow, &Strategy::SERIAL).0,
            RayAnswers::Occluded(vec![false; 1200])
        );
    }
}
