//! Ray mixes for agreement tests: ordinary rays plus the families where traversal and intersection go wrong.
//!
//! Every family draws from one [`SplitMix64`] stream, so a mix is a pure function of its inputs and seed.

use glam::Vec3;

use crate::accel::{Accelerator, List};
use crate::counters::NoCounters;
use crate::geometry::{Aabb, Ray, Sphere};
use crate::rays::RaySet;
use crate::rng::SplitMix64;
use crate::scene::{PointLight, Scene};

/// `count` rays over `spheres`, cycling through seven families (ray `i` is of family `i % 7`):
///
/// 0. random lines through the box around the spheres and the origin (grown by half its extent per side);
/// 1. rays starting inside a sphere (half its radius from the center), in a random direction;
/// 2. rays from a random point aimed at a sphere's center (unit direction);
/// 3. grazing rays: lines tangent to a sphere at relative offset `1 ± 1e-5` from its center (hit or near miss);
/// 4. grazing rays tangent where a sphere touches its bounding box, tilted by up to `2e-5` to cross that face;
/// 5. finite segments between two random points (`t_max` is the segment's length);
/// 6. non-unit directions: aimed at a sphere's center, 0.1 to 3 times the distance long.
///
/// With no spheres every ray is a random line.
#[inline]
pub fn sphere_ray_mix(spheres: &[Sphere], seed: u64, count: usize) -> Vec<Ray> {
    let mut draw = Families::new(spheres, seed, Vec3::ZERO, 0.5);
    (0..count)
        .map(|i| match (i % 7, spheres.is_empty()) {
            (_, true) | (0, _) => draw.line(),
            (1, _) => draw.starting_inside(),
            (2, _) => draw.at_center(),
            (3, _) => draw.tangent(),
            (4, _) => draw.tangent_at_box(),
            (5, _) => draw.segment(),
            _ => draw.at_center_non_unit(),
        })
        .collect()
}

/// The rays a renderer traces in `scene`, plus the hard families, in this order:
///
/// - the camera's primary rays at 40 × 30, in the tile order of [`RaySet::primary`];
/// - 300 × (a random line, a finite segment), points drawn from the box around the spheres and the camera
///   (grown by a quarter of its extent per side);
/// - with spheres, 200 × (a ray from inside a sphere, a grazing ray tangent at `1 ± 1e-5`, a grazing ray
///   tangent where a sphere touches its box, a non-unit direction at a sphere's center);
/// - from every camera ray's brute-force hit, offset along the normal like the shader does: a shadow segment
///   to each light and a bounce in a random direction around the normal.
#[inline]
pub fn scene_ray_mix(scene: &Scene, seed: u64) -> Vec<Ray> {
    let spheres = &scene.spheres;
    let mut draw = Families::new(spheres, seed, scene.camera.position, 0.25);
    let camera = scene.camera.with_resolution(40, 30);
    let cam = camera.rays();
    let mut rays: Vec<Ray> = RaySet::tile_order(camera.width, camera.height).map(|(x, y)| cam.ray(x, y)).collect();
    for _ in 0..300 {
        rays.push(draw.line());
        rays.push(draw.segment());
    }
    if spheres.is_empty() {
        return rays;
    }
    for _ in 0..200 {
        rays.push(draw.starting_inside());
        rays.push(draw.tangent());
        rays.push(draw.tangent_at_box());
        rays.push(draw.at_center_non_unit());
    }
    let reference = List::build(spheres);
    let primaries: Vec<Ray> = rays[..(camera.width * camera.height) as usize].to_vec();
    let hit_normal = |ray: &Ray| {
        let hit = reference.intersect(ray, &mut NoCounters)?;
        Some((hit.t, spheres[hit.prim as usize].normal_at(ray.at(hit.t))))
    };
    rays.extend(secondary_rays(&primaries, &scene.lights, hit_normal, || draw.unit_vector()));
    rays
}

/// From every primary ray's hit (`hit_normal`: its `t` and the surface normal there, either side), offset along
/// the normal like the shader does: a shadow segment to each light and a bounce around the normal (`unit` draws
/// the random unit vector added to it).
#[inline]
pub fn secondary_rays(
    primaries: &[Ray],
    lights: &[PointLight],
    mut hit_normal: impl FnMut(&Ray) -> Option<(f32, Vec3)>,
    mut unit: impl FnMut() -> Vec3,
) -> Vec<Ray> {
    let mut rays = Vec::new();
    for ray in primaries {
        let Some((t, mut n)) = hit_normal(ray) else { continue };
        let p = ray.at(t);
        if n.dot(ray.dir) > 0.0 {
            n = -n;
        }
        let origin = p + n * (1e-4 * p.abs().max_element().max(1.0));
        for light in lights {
            let to_light = light.position - origin;
            let distance = to_light.length();
            rays.push(Ray::segment(origin, to_light / distance, distance));
        }
        rays.push(Ray::new(origin, (n + unit()).normalize_or(n)));
    }
    rays
}

/// One random stream drawing rays of each family over `spheres`; points come from a box around them.
struct Families<'a> {
    rng: SplitMix64,
    spheres: &'a [Sphere],
    lo: Vec3,
    hi: Vec3,
}

impl<'a> Families<'a> {
    /// Points are drawn from the box around `around` and the spheres, grown by `margin` × its extent per side.
    fn new(spheres: &'a [Sphere], seed: u64, around: Vec3, margin: f32) -> Self {
        let bounds = spheres.iter().fold(Aabb::point(around), |b, s| b.union(&s.bounds()));
        let (lo, hi) = (bounds.min - bounds.extent() * margin, bounds.max + bounds.extent() * margin);
        Self { rng: SplitMix64::new(seed), spheres, lo, hi }
    }

    /// A uniformly random unit vector (rejection sampling in the unit ball).
    fn unit_vector(&mut self) -> Vec3 {
        let rng = &mut self.rng;
        loop {
            let v = Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }

    /// A uniformly random point in the box.
    fn point(&mut self) -> Vec3 {
        let (lo, hi, rng) = (self.lo, self.hi, &mut self.rng);
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    }

    /// A random sphere (there must be one).
    fn sphere(&mut self) -> Sphere {
        self.spheres[self.rng.below(self.spheres.len() as u64) as usize]
    }

    /// A random line through the box.
    fn line(&mut self) -> Ray {
        let origin = self.point();
        Ray::new(origin, self.unit_vector())
    }

    /// From inside a sphere (half its radius from the center) in a random direction.
    fn starting_inside(&mut self) -> Ray {
        let s = self.sphere();
        let origin = s.center + self.unit_vector() * (s.radius * 0.5);
        Ray::new(origin, self.unit_vector())
    }

    /// From a random point at a sphere's center, unit direction.
    fn at_center(&mut self) -> Ray {
        let s = self.sphere();
        let origin = self.point();
        Ray::new(origin, (s.center - origin).normalize_or(Vec3::X))
    }

    /// From a random point at a sphere's center, direction 0.1 to 3 times the distance: `t` is in units of its length.
    fn at_center_non_unit(&mut self) -> Ray {
        let s = self.sphere();
        let origin = self.point();
        Ray::new(origin, (s.center - origin) * self.rng.range(0.1, 3.0) as f32)
    }

    /// A line tangent to a sphere at relative offset `1 ± 1e-5` from its center: a grazing hit or a near miss.
    fn tangent(&mut self) -> Ray {
        let s = self.sphere();
        let d = self.unit_vector();
        let offset = 1.0 + self.rng.range(-1e-5, 1e-5) as f32;
        let origin = s.center + d.any_orthonormal_vector() * (s.radius * offset) - d * (s.radius * 3.0 + 1.0);
        Ray::new(origin, d)
    }

    /// Tangent at the point where a sphere touches its box (`±1e-7` relative), tilted by up to `2e-5` to cross that face.
    fn tangent_at_box(&mut self) -> Ray {
        let s = self.sphere();
        let axis = Vec3::AXES[self.rng.below(3) as usize] * if self.rng.below(2) == 0 { 1.0 } else { -1.0 };
        let d = (axis.any_orthonormal_vector() + axis * self.rng.range(-2e-5, 2e-5) as f32).normalize();
        let touch = s.center + axis * (s.radius * (1.0 + self.rng.range(-1e-7, 1e-7) as f32));
        Ray::new(touch - d * (s.radius * self.rng.range(0.5, 4.0) as f32), d)
    }

    /// A finite segment between two random points, unit direction, `t_max` its length.
    fn segment(&mut self) -> Ray {
        let (a, b) = (self.point(), self.point());
        let len = (b - a).length().max(1e-6);
        Ray::segment(a, (b - a) / len, len)
    }
}
