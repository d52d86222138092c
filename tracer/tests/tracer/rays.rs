//! Ray sets are deterministic, sized as promised, and every tree and strategy answers them like brute force.

use tracer::accel::{AccelParams, AccelVisitor, Accelerator, BuiltAccel, FlatBvh, List};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::executor::{Strategy, StrategyKind};
use tracer::rays::{RayAnswers, RayKind, RaySet, trace};
use tracer::scene::{Scene, SceneKind};
use tracer::testing;

fn scene(kind: SceneKind) -> Scene {
    let mut s = kind.generate(700, 5);
    s.camera = s.camera.with_resolution(48, 36);
    s
}

struct Trace<'a>(&'a RaySet, Strategy);
impl AccelVisitor for Trace<'_> {
    type Output = RayAnswers;
    fn visit<A: Accelerator>(self, a: &A) -> RayAnswers {
        trace::<_, NoCounters>(a, self.0, &self.1).0
    }
}

#[test]
fn ray_sets_are_deterministic_and_sized_by_primary_hits() {
    for kind in SceneKind::ALL {
        let s = scene(kind);
        let reference = FlatBvh::build(&s.spheres, &Default::default());
        let primary = RaySet::generate(RayKind::Primary, &s, &reference, 1);
        assert_eq!(primary.rays.len(), 48 * 36);
        let hits = trace::<_, NoCounters>(&reference, &primary, &Strategy::SERIAL).0.hit_count();
        assert!(hits > 0);
        for k in [RayKind::Shadow, RayKind::Diffuse] {
            let a = RaySet::generate(k, &s, &reference, 1);
            assert_eq!(a, RaySet::generate(k, &s, &reference, 1));
            assert_eq!(a.rays.len(), hits, "{k:?}: one ray per primary hit");
        }
        assert_ne!(
            RaySet::generate(RayKind::Diffuse, &s, &reference, 1),
            RaySet::generate(RayKind::Diffuse, &s, &reference, 2)
        );
    }
}

#[test]
fn every_tree_and_strategy_answers_ray_sets_like_brute_force() {
    for kind in SceneKind::ALL {
        let s = scene(kind);
        let list = List::build(&s.spheres);
        for k in RayKind::ALL {
            let set = RaySet::generate(k, &s, &list, 7);
            testing::assert_every_tree_agrees(&format!("{kind:?} {k:?}"), &s.spheres, &set.rays);
            let (want, counters) = trace::<_, WorkCounters>(&list, &set, &Strategy::SERIAL);
            assert_eq!(counters.rays as usize, set.rays.len());
            let flat = BuiltAccel::build(&s.spheres, &AccelParams::default());
            for strategy in [
                Strategy::SERIAL,
                Strategy::new(StrategyKind::RayonBands, 3),
                Strategy::new(StrategyKind::MpscThreads, 2),
            ] {
                assert_eq!(flat.visit(Trace(&set, strategy)).hash(), want.hash(), "{kind:?} {k:?} {strategy}");
            }
        }
    }
}
