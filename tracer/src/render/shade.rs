//! Whitted-style shading: primary rays, hard shadows to every light, mirror reflections to a maximum depth,
//! Lambert diffuse plus Blinn–Phong specular, a checkered ground plane and a sky gradient.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::Image;
use crate::accel::Accelerator;
use crate::counters::Counters;
use crate::executor::Strategy;
use crate::geometry::Ray;
use crate::scene::{Material, Scene};

/// Settings of a full render.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RenderSettings {
    /// Reflection bounces after the primary hit (0 = no reflections).
    pub max_depth: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { max_depth: 3 }
    }
}

struct Shader<'a, A> {
    scene: &'a Scene,
    accel: &'a A,
    max_depth: u32,
}

fn sky(dir: Vec3) -> Vec3 {
    sky_at(dir.y)
}

/// The sky gradient at `height`, a unit direction's component along up: white straight down, blue straight up.
pub(super) fn sky_at(height: f32) -> Vec3 {
    let t = 0.5 * (height + 1.0);
    Vec3::ONE * (1.0 - t) + Vec3::new(0.5, 0.7, 1.0) * t
}

impl<A: Accelerator> Shader<'_, A> {
    fn radiance<C: Counters>(&self, ray: &Ray, depth: u32, counters: &mut C) -> Vec3 {
        counters.ray();
        let hit = self.accel.intersect(ray, counters);
        let sphere_t = hit.map_or(f32::INFINITY, |h| h.t);
        let ground_t = self.scene.ground.as_ref().and_then(|g| {
            let t = (g.height - ray.origin.y) / ray.dir.y;
            (t > ray.t_min && t < sphere_t).then_some((t, g))
        });
        let (point, mut normal, material) = match (ground_t, hit) {
            (Some((t, g)), _) => {
                let p = ray.at(t);
                let cell = (p.x / g.square).floor() as i64 + (p.z / g.square).floor() as i64;
                let m = Material { reflectivity: g.reflectivity, ..Material::matte(g.albedo[(cell & 1) as usize]) };
                (p, Vec3::Y, m)
            }
            (None, Some(h)) => {
                let p = ray.at(h.t);
                let s = &self.scene.spheres[h.prim as usize];
                (p, s.normal_at(p), self.scene.materials[h.prim as usize])
            }
            (None, None) => return sky(ray.dir),
        };
        if normal.dot(ray.dir) > 0.0 {
            normal = -normal;
        }
        let origin = point + normal * (1e-4 * point.abs().max_element().max(1.0));
        let mut color = material.albedo * self.scene.ambient;
        for light in &self.scene.lights {
            let to_light = light.position - origin;
            let distance = to_light.length();
            let l = to_light / distance;
            let n_dot_l = normal.dot(l);
            if n_dot_l <= 0.0 {
                continue;
            }
            counters.ray();
            if self.accel.occluded(&Ray::segment(origin, l, distance), counters) {
                continue;
            }
            color += material.albedo * (n_dot_l * light.intensity);
            if material.specular > 0.0 {
                let h = (l - ray.dir).normalize();
                color +=
                    Vec3::splat(material.specular * normal.dot(h).max(0.0).powi(material.shininess) * light.intensity);
            }
        }
        if material.reflectivity > 0.0 && depth < self.max_depth {
            let reflected = (ray.dir - normal * (2.0 * ray.dir.dot(normal))).normalize();
            let bounce = self.radiance(&Ray::new(origin, reflected), depth + 1, counters);
            color = color * (1.0 - material.reflectivity) + bounce * material.reflectivity;
        }
        color
    }
}

pub(super) fn to_srgb8(c: Vec3) -> [u8; 3] {
    let c = c.clamp(Vec3::ZERO, Vec3::ONE);
    [c.x, c.y, c.z].map(|v| (v.sqrt() * 255.0 + 0.5) as u8)
}

/// Renders the scene's camera image with `accel` under `strategy`; returns the image and merged counters.
pub fn render<A: Accelerator, C: Counters>(
    scene: &Scene,
    accel: &A,
    settings: &RenderSettings,
    strategy: &Strategy,
) -> (Image, C) {
    let (width, height) = (scene.camera.width, scene.camera.height);
    let rays = scene.camera.rays();
    let shader = Shader { scene, accel, max_depth: settings.max_depth };
    let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
    let counters = strategy.run_rows(width as usize, &mut pixels, |y, row, counters: &mut C| {
        for (x, px) in row.iter_mut().enumerate() {
            *px = to_srgb8(shader.radiance(&rays.ray(x as u32, y as u32), 0, counters));
        }
    });
    (Image { width, height, pixels }, counters)
}
