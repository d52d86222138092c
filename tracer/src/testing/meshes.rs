//! Test meshes and their ray mix: procedural triangle meshes (closed tessellated spheres, random triangles, one
//! triangle, none) with rays aimed at what breaks triangle tests: shared vertices and edges.

use glam::Vec3;

use super::sphere_ray_mix;
use crate::geometry::{Aabb, Ray, Triangle};
use crate::rng::SplitMix64;
use crate::scene::mesh::Mesh;
use crate::scene::{SceneKind, random_triangles, tessellate};

/// A triangle mesh with its ray mix, named for failure messages.
#[derive(Clone, Debug)]
pub struct TestMesh {
    /// What the mesh is, e.g. `"tessellated 40 spheres ×8"`.
    pub label: String,
    /// The mesh.
    pub mesh: Mesh,
    /// [`mesh_ray_mix`] of it (plus the spheres' [`sphere_ray_mix`] for tessellated spheres).
    pub rays: Vec<Ray>,
}

/// The procedural test meshes: random spheres tessellated coarsely and finely (closed meshes: shared edges and
/// vertices), random triangles (3000, seed 5), one triangle and an empty mesh, each with its rays.
#[inline]
pub fn test_meshes() -> Vec<TestMesh> {
    let tessellated = |n: usize, segments: u32, seed: u64| {
        let spheres = SceneKind::RandomSpheres.generate(n, seed).spheres;
        let mesh = tessellate(&spheres, segments);
        let mut rays = mesh_ray_mix(&mesh, seed ^ 0x5eed, 2_100);
        rays.extend(sphere_ray_mix(&spheres, seed ^ 0xface, 700));
        TestMesh { label: format!("tessellated {n} spheres ×{segments} seed={seed}"), mesh, rays }
    };
    let plain = |label: &str, mesh: Mesh, count: usize| {
        let rays = mesh_ray_mix(&mesh, 11, count);
        TestMesh { label: label.to_owned(), mesh, rays }
    };
    // Tilted, so that its box has volume and random points lie off its plane.
    let one = Mesh {
        positions: vec![Vec3::new(-1.0, -1.0, 0.3), Vec3::new(1.0, -0.8, -0.2), Vec3::new(0.1, 1.0, 0.5)],
        indices: vec![[0, 1, 2]],
    };
    vec![
        tessellated(40, 8, 3),
        tessellated(6, 32, 4),
        plain("random triangles n=3000 seed=5", random_triangles(3_000, 5), 2_800),
        plain("one triangle", one, 700),
        plain("empty mesh", Mesh::default(), 70),
    ]
}

/// `count` rays at `mesh`, cycling through seven families (ray `i` is of family `i % 7`); points are drawn from
/// the mesh's box grown by half its extent per side:
///
/// 0. random lines through the box;
/// 1. from a random point through a random vertex (shared by several triangles in a closed mesh);
/// 2. from a random point through a random point of a random edge;
/// 3. from a random point through a random interior point of a random triangle;
/// 4. finite segments between two random points (`t_max` is the segment's length);
/// 5. non-unit directions through an interior point, 0.1 to 3 times the distance long;
/// 6. leaving a surface like a bounce: from an interior point moved off the plane by `1e-4` of its magnitude,
///    in a random direction.
///
/// With no triangles every ray is a random line around the origin.
#[inline]
pub fn mesh_ray_mix(mesh: &Mesh, seed: u64, count: usize) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    let bounds = if mesh.positions.is_empty() { Aabb { min: -Vec3::ONE, max: Vec3::ONE } } else { mesh.bounds() };
    let (lo, hi) = (bounds.min - bounds.extent() * 0.5, bounds.max + bounds.extent() * 0.5);
    let unit = |rng: &mut SplitMix64| loop {
        let v = Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    };
    let point = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    };
    let interior = |rng: &mut SplitMix64, t: &Triangle| {
        let (mut b1, mut b2) = (rng.next_f64() as f32, rng.next_f64() as f32);
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        t.p[0] + (t.p[1] - t.p[0]) * b1 + (t.p[2] - t.p[0]) * b2
    };
    let n = mesh.triangle_count() as u64;
    (0..count)
        .map(|i| {
            let family = if n == 0 { 0 } else { i % 7 };
            let tri = if n == 0 {
                Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)
            } else {
                mesh.triangle(rng.below(n) as usize)
            };
            let through = |rng: &mut SplitMix64, aim: Vec3| {
                let origin = point(rng);
                Ray::new(origin, (aim - origin).normalize_or(Vec3::X))
            };
            match family {
                0 => Ray::new(point(&mut rng), unit(&mut rng)),
                1 => {
                    let aim = tri.p[rng.below(3) as usize];
                    through(&mut rng, aim)
                }
                2 => {
                    let e = rng.below(3) as usize;
                    let aim = tri.p[e].lerp(tri.p[(e + 1) % 3], rng.next_f64() as f32);
                    through(&mut rng, aim)
                }
                3 => {
                    let aim = interior(&mut rng, &tri);
                    through(&mut rng, aim)
                }
                4 => {
                    let (a, b) = (point(&mut rng), point(&mut rng));
                    let length = (b - a).length().max(1e-3);
                    Ray::segment(a, (b - a) / length, length)
                }
                5 => {
                    let aim = interior(&mut rng, &tri);
                    let origin = point(&mut rng);
                    Ray::new(origin, (aim - origin) * rng.range(0.1, 3.0) as f32)
                }
                _ => {
                    let p = interior(&mut rng, &tri);
                    let normal = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize_or(Vec3::Y);
                    let side = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                    let n = normal * side;
                    let origin = p + n * (1e-4 * p.abs().max_element().max(1.0));
                    Ray::new(origin, (n + unit(&mut rng)).normalize_or(n))
                }
            }
        })
        .collect()
}
