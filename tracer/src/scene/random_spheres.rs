//! The paper's scene: `n` spheres uniformly placed in the scene box in front of the camera.
//!
//! Radii are `s * U(0.5, 1.5)` with `s = 0.3 * cbrt(volume / n)` (capped at 3), so the filled fraction of the
//! box stays near 14% from 1 to 10^6 spheres. Per sphere, in order: radius, x, z, y (in `[r, 8]`, above the
//! ground), then the six material draws of [`Material::random`]. The RNG is seeded with the seed itself.

use glam::Vec3;

use super::{Material, SCENE_BOX, Scene, radius_scale};
use crate::geometry::Sphere;
use crate::rng::SplitMix64;

/// Generates the scene.
pub fn generate(objects: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64::new(seed);
    let scale = 0.3 * radius_scale(objects);
    let (lo, hi) = (SCENE_BOX.min, SCENE_BOX.max);
    let mut spheres = Vec::with_capacity(objects);
    let mut materials = Vec::with_capacity(objects);
    for _ in 0..objects {
        let r = (scale * rng.range(0.5, 1.5)).min(3.0);
        let x = rng.range(lo.x as f64, hi.x as f64);
        let z = rng.range(lo.z as f64, hi.z as f64);
        let y = rng.range(r, (hi.y as f64).max(r));
        spheres.push(Sphere::new(Vec3::new(x as f32, y as f32, z as f32), r as f32));
        materials.push(Material::random(&mut rng));
    }
    Scene::in_scene_box(spheres, materials)
}
