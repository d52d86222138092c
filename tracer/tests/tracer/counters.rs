//! Work counters count what they promise; `NoCounters` is free.

use glam::Vec3;
use tracer::accel::{Accelerator, Bvh, BvhParams, FlatBvh, List, Traversal};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::executor::Strategy;
use tracer::render::trace_primary;
use tracer::scene::SceneKind;

#[test]
fn list_tests_every_sphere_for_every_ray() {
    let scene = SceneKind::RandomSpheres.generate(137, 9);
    let camera = scene.camera.with_resolution(20, 10);
    let (hits, c) = trace_primary::<_, WorkCounters>(&camera, &List::build(&scene.spheres), &Strategy::SERIAL);
    assert_eq!(c.rays, 200);
    assert_eq!(c.prim_tests, 137 * 200);
    assert_eq!((c.nodes_visited, c.box_tests), (0, 0));
    assert!(hits.hit_count() > 0);
}

#[test]
fn a_scene_behind_the_camera_costs_one_node_per_ray() {
    let mut scene = SceneKind::RandomSpheres.generate(500, 2);
    scene.camera.look_at = scene.camera.position + Vec3::Z; // the spheres are all at z < -7
    let camera = scene.camera.with_resolution(24, 16);
    for traversal in Traversal::ALL {
        let params = BvhParams { traversal, ..BvhParams::default() };
        for c in [
            trace_primary::<_, WorkCounters>(&camera, &Bvh::build(&scene.spheres, &params), &Strategy::SERIAL).1,
            trace_primary::<_, WorkCounters>(&camera, &FlatBvh::build(&scene.spheres, &params), &Strategy::SERIAL).1,
        ] {
            assert_eq!(c, WorkCounters { rays: 384, nodes_visited: 384, box_tests: 384, prim_tests: 0 });
        }
    }
}

#[test]
fn bvh_does_far_less_work_than_the_list_on_many_spheres() {
    let scene = SceneKind::RandomSpheres.generate(5000, 3);
    let camera = scene.camera.with_resolution(32, 24);
    let list = trace_primary::<_, WorkCounters>(&camera, &List::build(&scene.spheres), &Strategy::SERIAL).1;
    let bvh = trace_primary::<_, WorkCounters>(
        &camera,
        &FlatBvh::build(&scene.spheres, &BvhParams::default()),
        &Strategy::SERIAL,
    )
    .1;
    assert!(bvh.prim_tests * 50 < list.prim_tests, "bvh {bvh:?} vs list {list:?}");
}

#[test]
fn no_counters_is_zero_sized() {
    assert_eq!(std::mem::size_of::<NoCounters>(), 0);
    let scene = SceneKind::RandomSpheres.generate(10, 1);
    let r = tracer::geometry::Ray::new(scene.camera.position, Vec3::NEG_Z);
    let a = List::build(&scene.spheres);
    assert_eq!(a.intersect(&r, &mut NoCounters), a.intersect(&r, &mut WorkCounters::default()));
}
