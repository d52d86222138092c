//! Scenes: spheres with materials, point lights, a ground plane and a camera.
//!
//! Generated scenes are pure functions of `(kind, objects, seed)`: they draw from [`SplitMix64`] and use
//! only `+ - * /`, `sqrt` and comparisons, so the same seed gives bit-identical spheres on every machine.
//! [`Scene::fingerprint`] hashes a scene for tests and recorded rows.

mod camera;
mod clustered_spheres;
pub mod mesh;
mod mesh_scene;
mod random_spheres;
mod random_triangles;
pub mod sphere_file;
mod tessellate;
mod tiled;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::fingerprint::Fnv64;
use crate::geometry::{Aabb, Sphere};
use crate::rng::SplitMix64;

pub use camera::{Camera, CameraRays};
pub use mesh_scene::{MeshScene, View};
pub use random_triangles::random_triangles;
pub use sphere_file::SphereFileError;
pub use tessellate::tessellate;
pub use tiled::TILE_SEED;

/// Surface description of one sphere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Diffuse color, each channel in `[0, 1]`.
    pub albedo: Vec3,
    /// Weight of the Blinn–Phong highlight.
    pub specular: f32,
    /// Blinn–Phong exponent (an integer, so shading needs no `powf`).
    pub shininess: i32,
    /// Fraction of light from the mirror direction, `[0, 1]`.
    pub reflectivity: f32,
}

impl Material {
    /// A matte material of the given color.
    pub fn matte(albedo: Vec3) -> Self {
        Self { albedo, specular: 0.0, shininess: 1, reflectivity: 0.0 }
    }

    /// A random material: six draws (albedo r, g, b; specular; shininess; reflectivity).
    pub fn random(rng: &mut SplitMix64) -> Self {
        let albedo = Vec3::new(rng.range(0.2, 0.95) as f32, rng.range(0.2, 0.95) as f32, rng.range(0.2, 0.95) as f32);
        let specular = rng.range(0.0, 0.6) as f32;
        let shininess = 8 + rng.below(57) as i32;
        let r = rng.next_f64();
        let reflectivity = if r < 0.25 { (0.2 + 2.0 * r) as f32 } else { 0.0 };
        Self { albedo, specular, shininess, reflectivity }
    }
}

/// A point light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Brightness (white light, no falloff).
    pub intensity: f32,
}

/// The horizontal checkered plane `y = height` under the spheres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ground {
    /// Height of the plane.
    pub height: f32,
    /// Side of one checker square.
    pub square: f32,
    /// The two checker colors.
    pub albedo: [Vec3; 2],
    /// Mirror fraction.
    pub reflectivity: f32,
}

/// Everything the renderer needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The spheres the accelerators are built over.
    pub spheres: Vec<Sphere>,
    /// One material per sphere.
    pub materials: Vec<Material>,
    /// Point lights.
    pub lights: Vec<PointLight>,
    /// Ambient light level.
    pub ambient: f32,
    /// The ground plane, if any (not part of any accelerator).
    pub ground: Option<Ground>,
    /// The camera.
    pub camera: Camera,
}

/// The scene generators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SceneKind {
    /// The paper's scene: uniformly random spheres in a box in front of the camera.
    RandomSpheres,
    /// Dense Gaussian clusters with radii over three decades.
    ClusteredSpheres,
}

impl SceneKind {
    /// Both generators.
    pub const ALL: [SceneKind; 2] = [SceneKind::RandomSpheres, SceneKind::ClusteredSpheres];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::RandomSpheres => "random-spheres",
            SceneKind::ClusteredSpheres => "clustered-spheres",
        }
    }

    /// The scene of `objects` spheres drawn from `seed`.
    pub fn generate(self, objects: usize, seed: u64) -> Scene {
        match self {
            SceneKind::RandomSpheres => random_spheres::generate(objects, seed),
            SceneKind::ClusteredSpheres => clustered_spheres::generate(objects, seed),
        }
    }
}

/// The region generated spheres are placed in: x in [-8, 8], y in [0, 8], z in [-28, -8].
pub(crate) const SCENE_BOX: Aabb = Aabb { min: Vec3::new(-8.0, 0.0, -28.0), max: Vec3::new(8.0, 8.0, -8.0) };

/// Cube root by bisection: exact to the last bit of f64 on every machine (libm's `cbrt` is not specified so).
pub(crate) fn cube_root(x: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, x.max(1.0));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid * mid * mid < x { lo = mid } else { hi = mid }
    }
    hi
}

/// Radius scale for `objects` spheres in [`SCENE_BOX`]: keeps the filled fraction of the box fixed.
pub(crate) fn radius_scale(objects: usize) -> f64 {
    let e = SCENE_BOX.extent();
    cube_root((e.x * e.y * e.z) as f64 / objects.max(1) as f64)
}

impl Scene {
    /// The generated scenes' lights, ground and camera around the given spheres.
    pub(crate) fn in_scene_box(spheres: Vec<Sphere>, materials: Vec<Material>) -> Self {
        Scene {
            spheres,
            materials,
            lights: vec![
                PointLight { position: Vec3::new(-12.0, 22.0, 6.0), intensity: 0.65 },
                PointLight { position: Vec3::new(14.0, 16.0, -4.0), intensity: 0.45 },
            ],
            ambient: 0.08,
            ground: Some(Ground {
                height: 0.0,
                square: 2.0,
                albedo: [Vec3::splat(0.75), Vec3::new(0.3, 0.3, 0.36)],
                reflectivity: 0.2,
            }),
            camera: Camera {
                position: Vec3::new(0.0, 4.0, 4.0),
                look_at: Vec3::new(0.0, 3.0, -18.0),
                up: Vec3::Y,
                vfov_degrees: 55.0,
                width: 640,
                height: 480,
            },
        }
    }

    /// Stable hash of the geometry, materials, lights, ground and camera.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv64::default();
        let v3 = |h: &mut Fnv64, v: Vec3| {
            h.f32(v.x).f32(v.y).f32(v.z);
        };
        h.u32(self.spheres.len() as u32);
        for (s, m) in self.spheres.iter().zip(&self.materials) {
            v3(&mut h, s.center);
            h.f32(s.radius);
            v3(&mut h, m.albedo);
            h.f32(m.specular).u32(m.shininess as u32).f32(m.reflectivity);
        }
        for l in &self.lights {
            v3(&mut h, l.position);
            h.f32(l.intensity);
        }
        h.f32(self.ambient);
        if let Some(g) = &self.ground {
            h.f32(g.height).f32(g.square).f32(g.reflectivity);
            g.albedo.iter().for_each(|&a| v3(&mut h, a));
        }
        let c = &self.camera;
        v3(&mut h, c.position);
        v3(&mut h, c.look_at);
        v3(&mut h, c.up);
        h.f32(c.vfov_degrees).u32(c.width).u32(c.height);
        h.finish()
    }

    /// Bounds of all spheres.
    pub fn bounds(&self) -> Aabb {
        self.spheres.iter().fold(Aabb::EMPTY, |b, s| b.union(&s.bounds()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_root_is_exact_on_cubes() {
        for x in [1.0, 8.0, 27.0, 1000.0, 0.125] {
            let r = cube_root(x);
            assert!((r * r * r - x).abs() <= 1e-12 * x, "{x}: {r}");
        }
        assert!(cube_root(0.0) < 1e-50);
    }
}
