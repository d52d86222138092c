//! Every accelerator × split × leaf size × traversal order returns the same answers as brute force.

use glam::Vec3;
use proptest::prelude::*;
use tracer::geometry::Sphere;
use tracer::scene::SceneKind;
use tracer::testing;

fn arbitrary_spheres() -> impl Strategy<Value = Vec<Sphere>> {
    let coord = -50.0f32..50.0;
    let sphere = (coord.clone(), coord.clone(), coord, 0.001f32..8.0)
        .prop_map(|(x, y, z, r)| Sphere::new(Vec3::new(x, y, z), r));
    prop::collection::vec(sphere, 0..160)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn generated_scenes_agree_with_brute_force(clustered in any::<bool>(), objects in 0usize..400, seed in any::<u64>()) {
        let kind = if clustered { SceneKind::ClusteredSpheres } else { SceneKind::RandomSpheres };
        let scene = kind.generate(objects, seed);
        let rays = testing::sphere_ray_mix(&scene.spheres, seed ^ 0x5eed, 240);
        testing::assert_every_tree_agrees(kind.name(), &scene.spheres, &rays);
    }

    #[test]
    fn arbitrary_spheres_agree_with_brute_force(spheres in arbitrary_spheres(), ray_seed in any::<u64>()) {
        let rays = testing::sphere_ray_mix(&spheres, ray_seed, 240);
        testing::assert_every_tree_agrees("arbitrary", &spheres, &rays);
    }
}

#[test]
fn camera_rays_agree_on_the_papers_scene() {
    let scene = SceneKind::RandomSpheres.generate(1000, 1);
    let cam = scene.camera.with_resolution(40, 30).rays();
    let rays: Vec<_> = (0..30).flat_map(|y| (0..40).map(move |x| (x, y))).map(|(x, y)| cam.ray(x, y)).collect();
    testing::assert_every_tree_agrees("paper scene camera rays", &scene.spheres, &rays);
}

#[test]
fn every_tree_agrees_on_the_peer_test_scenes() {
    // The scenes and ray mix (camera, grazing, secondary rays) the peers are checked on.
    for scene in testing::scenes() {
        testing::assert_every_tree_agrees(&scene.label, &scene.spheres, &scene.rays);
    }
}
