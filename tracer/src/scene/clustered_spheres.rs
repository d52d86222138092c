//! Dense Gaussian clusters with radii over three decades: the case where split rules really differ.
//!
//! Six clusters, each drawn first: center (x, y in `[1, 7]`, z), spread `sigma in [0.3, 2.5]` and weight
//! in `[0.2, 1]`. Per sphere, in order: the cluster (by weight), three normal offsets (Irwin–Hall, see
//! [`SplitMix64::normal`]), the decade (`0.1`, `1` or `10` times `0.12 * cbrt(volume / n)`), a factor
//! `U(0.5, 1.5)` (radius capped at 3), then the material. Centers are lifted to `y >= r`.

use glam::Vec3;

use super::{Material, SCENE_BOX, Scene, radius_scale};
use crate::geometry::Sphere;
use crate::rng::SplitMix64;

/// Number of clusters.
const CLUSTERS: usize = 6;

/// Generates the scene.
pub fn generate(objects: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64::new(seed);
    let (lo, hi) = (SCENE_BOX.min, SCENE_BOX.max);
    let clusters: Vec<(Vec3, f64, f64)> = (0..CLUSTERS)
        .map(|_| {
            let c = Vec3::new(
                rng.range(lo.x as f64 + 1.0, hi.x as f64 - 1.0) as f32,
                rng.range(1.0, 7.0) as f32,
                rng.range(lo.z as f64 + 2.0, hi.z as f64 - 2.0) as f32,
            );
            (c, rng.range(0.3, 2.5), rng.range(0.2, 1.0))
        })
        .collect();
    let total_weight: f64 = clusters.iter().map(|c| c.2).sum();
    let base = 0.12 * radius_scale(objects);
    let mut spheres = Vec::with_capacity(objects);
    let mut materials = Vec::with_capacity(objects);
    for _ in 0..objects {
        let mut pick = rng.next_f64() * total_weight;
        let &(center, sigma, _) = clusters
            .iter()
            .find(|c| {
                pick -= c.2;
                pick < 0.0
            })
            .unwrap_or(&clusters[CLUSTERS - 1]);
        let offset = [rng.normal(), rng.normal(), rng.normal()].map(|v| (v * sigma) as f32);
        let decade = [0.1, 1.0, 10.0][rng.below(3) as usize];
        let r = (base * decade * rng.range(0.5, 1.5)).min(3.0) as f32;
        let mut p = center + Vec3::from(offset);
        p.y = p.y.max(r);
        spheres.push(Sphere::new(p, r));
        materials.push(Material::random(&mut rng));
    }
    Scene::in_scene_box(spheres, materials)
}
