//! Degenerate inputs: empty and single-sphere scenes, coincident spheres, extreme radii, deep trees.

use glam::Vec3;
use tracer::accel::{AccelKind, AccelParams, Accelerator, BuiltAccel, BvhParams, Split};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::geometry::{Ray, Sphere};
use tracer::render::{RenderSettings, render};
use tracer::scene::SceneKind;
use tracer::testing;

#[test]
fn empty_scene_misses_everything_and_renders() {
    let rays = testing::sphere_ray_mix(&[], 3, 60);
    testing::assert_every_tree_agrees("empty", &[], &rays);
    for params in testing::every_tree().into_iter().take(8) {
        let accel = BuiltAccel::<Sphere>::build(&[], &params);
        assert!(rays.iter().all(|r| accel.visit(MissesAll(*r))));
        assert_eq!(accel.stats().nodes, 1);
    }
    let scene = SceneKind::RandomSpheres.generate(0, 1);
    let mut scene = scene;
    scene.camera = scene.camera.with_resolution(16, 12);
    let accel = tracer::accel::FlatBvh::build(&scene.spheres, &BvhParams::default());
    let (image, _) = render::<_, NoCounters>(&scene, &accel, &RenderSettings::default(), &Strategy::SERIAL);
    assert_eq!(image.pixels.len(), 16 * 12);
}

struct MissesAll(Ray);
impl tracer::accel::AccelVisitor for MissesAll {
    type Output = bool;
    fn visit<A: Accelerator>(self, a: &A) -> bool {
        a.intersect(&self.0, &mut NoCounters).is_none() && !a.occluded(&self.0, &mut NoCounters)
    }
}

#[test]
fn single_sphere() {
    let spheres = [Sphere::new(Vec3::new(0.0, 1.0, -5.0), 1.0)];
    testing::assert_every_tree_agrees("one sphere", &spheres, &testing::sphere_ray_mix(&spheres, 4, 300));
    let accel = BuiltAccel::build(&spheres, &AccelParams::default());
    let hit = accel.visit(Closest(Ray::new(Vec3::new(0.0, 1.0, 0.0), -Vec3::Z))).unwrap();
    assert_eq!((hit.t, hit.prim), (4.0, 0));
}

struct Closest(Ray);
impl tracer::accel::AccelVisitor for Closest {
    type Output = Option<tracer::accel::Hit>;
    fn visit<A: Accelerator>(self, a: &A) -> Self::Output {
        a.intersect(&self.0, &mut NoCounters)
    }
}

#[test]
fn all_spheres_at_one_point() {
    let same: Vec<Sphere> = (0..100).map(|_| Sphere::new(Vec3::new(1.0, 2.0, 3.0), 0.5)).collect();
    testing::assert_every_tree_agrees("coincident", &same, &testing::sphere_ray_mix(&same, 5, 300));
    let nested: Vec<Sphere> = (1..=100).map(|i| Sphere::new(Vec3::new(1.0, 2.0, 3.0), i as f32 * 0.1)).collect();
    testing::assert_every_tree_agrees("concentric", &nested, &testing::sphere_ray_mix(&nested, 6, 300));
}

#[test]
fn huge_and_tiny_radii() {
    let mut spheres: Vec<Sphere> =
        (0..50).map(|i| Sphere::new(Vec3::new(i as f32, 0.5, -10.0 - i as f32), 1e-5)).collect();
    spheres.push(Sphere::new(Vec3::ZERO, 1e6)); // contains every ray origin below
    spheres.push(Sphere::new(Vec3::new(3.0, 1e4, -2.0), 1e3));
    testing::assert_every_tree_agrees("extreme radii", &spheres, &testing::sphere_ray_mix(&spheres, 7, 400));
}

#[test]
fn exponentially_spaced_spheres_stay_within_the_traversal_stack() {
    // Midpoint splits peel one sphere per level here: without the depth guard the tree would be 120 deep.
    let spheres: Vec<Sphere> = (0..120).map(|i| Sphere::new(Vec3::new(1.3f32.powi(i), 0.0, 0.0), 0.01)).collect();
    for split in Split::ALL {
        for kind in [AccelKind::Bvh, AccelKind::FlatBvh] {
            let params = AccelParams {
                kind,
                bvh: BvhParams { split, leaf_size: 1, ..BvhParams::default() },
                ..AccelParams::default()
            };
            let depth = BuiltAccel::build(&spheres, &params).stats().depth;
            assert!(depth < tracer::accel::bvh::tree::MAX_DEPTH, "{split:?}: depth {depth}");
        }
    }
    let rays: Vec<Ray> = (0..120).map(|i| Ray::new(Vec3::new(1.3f32.powi(i), 5.0, 0.0), -Vec3::Y)).collect();
    testing::assert_every_tree_agrees("exponential", &spheres, &rays);
}
