//! Flat shading of triangle scenes (or any primitives): one primary ray per pixel; a hit is grey, lit by one point
//! light through a hard shadow ray plus an ambient term, with the primitive's normal turned toward the viewer; a
//! miss is the sphere renderer's sky gradient along the camera's up.

use glam::Vec3;

use super::Image;
use super::shade::{sky_at, to_srgb8};
use crate::accel::Accelerator;
use crate::counters::Counters;
use crate::executor::Strategy;
use crate::geometry::{Primitive, Ray};
use crate::scene::Camera;

/// Grey albedo of every surface.
const ALBEDO: f32 = 0.8;
/// Fraction of the albedo lit without the light (shadowed and back-facing surfaces).
const AMBIENT: f32 = 0.2;

/// Renders `camera`'s image of `prims` (`accel` is built over them and returns their indices), lit from `light`;
/// returns the image and merged counters.
pub fn render_mesh<P: Primitive, A: Accelerator, C: Counters>(
    prims: &[P],
    camera: &Camera,
    light: Vec3,
    accel: &A,
    strategy: &Strategy,
) -> (Image, C) {
    let (width, height) = (camera.width, camera.height);
    let rays = camera.rays();
    let up = camera.up.try_normalize().unwrap_or(Vec3::Y);
    let shade = |ray: &Ray, counters: &mut C| -> Vec3 {
        counters.ray();
        let Some(hit) = accel.intersect(ray, counters) else { return sky_at(ray.dir.dot(up)) };
        let point = ray.at(hit.t);
        let normal = prims[hit.prim as usize].normal(point, -ray.dir);
        let origin = point + normal * (1e-4 * point.abs().max_element().max(1.0));
        let to_light = light - origin;
        let distance = to_light.length();
        let l = to_light / distance.max(f32::MIN_POSITIVE);
        let n_dot_l = normal.dot(l);
        let lit = n_dot_l > 0.0 && {
            counters.ray();
            !accel.occluded(&Ray::segment(origin, l, distance), counters)
        };
        let direct = if lit { (1.0 - AMBIENT) * n_dot_l } else { 0.0 };
        Vec3::splat(ALBEDO * (AMBIENT + direct))
    };
    let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
    let counters = strategy.run_rows(width as usize, &mut pixels, |y, row, counters: &mut C| {
        for (x, px) in row.iter_mut().enumerate() {
            *px = to_srgb8(shade(&rays.ray(x as u32, y as u32), counters));
        }
    });
    (Image { width, height, pixels }, counters)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{AccelKind, AccelParams, AccelVisitor, BuiltAccel, List};
    use crate::counters::WorkCounters;
    use crate::executor::StrategyKind;
    use crate::geometry::{MollerTrumboreTriangle, Triangle, TrianglePrimitive, WatertightTriangle};
    use crate::scene::{MeshScene, SceneKind, View, tessellate};

    /// The flat-shaded image of a visited structure.
    struct Draw<'a, P>(&'a [P], &'a MeshScene, Strategy);

    impl<P: Primitive> AccelVisitor for Draw<'_, P> {
        type Output = (Image, WorkCounters);
        fn visit<A: Accelerator>(self, a: &A) -> Self::Output {
            render_mesh(self.0, &self.1.camera, self.1.light, a, &self.2)
        }
    }

    fn scene(up: Vec3) -> MeshScene {
        let spheres = SceneKind::RandomSpheres.generate(20, 7).spheres;
        let s = MeshScene::new(tessellate(&spheres, 16), View::Overview, up);
        MeshScene { camera: s.camera.with_resolution(48, 32), ..s }
    }

    /// The sky is blue-ish; surfaces are grey.
    fn sky_pixel(p: &[u8; 3]) -> bool {
        p[2] > p[0]
    }

    #[test]
    fn a_tessellated_scene_renders_the_same_image_with_every_structure_and_strategy() {
        for up in [Vec3::Y, Vec3::Z] {
            let scene = scene(up);
            let tris = WatertightTriangle::all(scene.mesh.triangles());
            let listed = || {
                render_mesh::<_, _, WorkCounters>(
                    &tris,
                    &scene.camera,
                    scene.light,
                    &List::build(&tris),
                    &Strategy::SERIAL,
                )
            };
            let reference = listed();
            let (image, counters) = &reference;
            let sky = image.pixels.iter().filter(|p| sky_pixel(p)).count();
            assert!(sky > 0 && sky < image.pixels.len(), "some pixels hit, some are sky: {sky}");
            let shades: std::collections::HashSet<_> = image.pixels.iter().filter(|p| !sky_pixel(p)).collect();
            assert!(shades.len() > 10, "lit, shadowed and turned faces differ: {}", shades.len());
            assert!(counters.rays > u64::from(image.width * image.height), "shadow rays are counted");
            let again = listed();
            assert_eq!(again.0.hash(), image.hash(), "deterministic");
            for kind in [AccelKind::Bvh, AccelKind::FlatBvh, AccelKind::WideBvh] {
                let params = AccelParams { kind, ..Default::default() };
                let built = BuiltAccel::build(&tris, &params);
                for strategy in [Strategy::SERIAL, Strategy::new(StrategyKind::RayonBands, 3)] {
                    let (other, c) = built.visit(Draw(&tris, &scene, strategy));
                    assert_eq!(other.hash(), image.hash(), "{kind:?} {strategy}");
                    assert_eq!(c.rays, counters.rays, "{kind:?} {strategy}");
                }
            }
            // The other triangle test's structure, shaded with the same normals.
            let mt = MollerTrumboreTriangle::all(scene.mesh.triangles());
            let built = BuiltAccel::build(&mt, &AccelParams::default());
            let strategy = Strategy::new(StrategyKind::MpscThreads, 2);
            let (other, _) = built.visit(Draw(&tris, &scene, strategy));
            let differing = other.pixels.iter().zip(&image.pixels).filter(|(a, b)| a != b).count();
            assert!(differing * 100 <= image.pixels.len(), "Möller–Trumbore: {differing} pixels differ");
        }
    }

    #[test]
    fn a_square_above_a_floor_is_lit_and_casts_a_hard_shadow() {
        // A floor (y = 0) and a square above it (y = 1), lit from the side: the shadow falls at x in [-2.2, 0].
        let quad = |y: f32, s: f32| {
            let [a, b, c, d] = [(-s, -s), (s, -s), (s, s), (-s, s)].map(|(x, z)| Vec3::new(x, y, z));
            [Triangle::new(a, b, c), Triangle::new(a, c, d)]
        };
        let tris = WatertightTriangle::all(quad(0.0, 10.0).into_iter().chain(quad(1.0, 1.0)));
        let camera = Camera {
            position: Vec3::new(-6.0, 6.0, 0.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_degrees: 90.0,
            width: 32,
            height: 32,
        };
        let light = Vec3::new(10.0, 10.0, 0.0);
        let (image, _) =
            render_mesh::<_, _, WorkCounters>(&tris, &camera, light, &List::build(&tris), &Strategy::SERIAL);
        let rays = camera.rays();
        let pixel_toward = |target: Vec3| {
            let toward = (target - camera.position).normalize();
            let pixels = (0..32u32).flat_map(|y| (0..32u32).map(move |x| (x, y)));
            let along = |&(x, y): &(u32, u32)| rays.ray(x, y).dir.dot(toward);
            let (x, y) = pixels.max_by(|a, b| along(a).total_cmp(&along(b))).unwrap();
            image.pixels[(y * 32 + x) as usize]
        };
        let shadow = pixel_toward(Vec3::new(-1.5, 0.0, 0.0));
        let floor = pixel_toward(Vec3::new(-1.5, 0.0, 4.0));
        let top = pixel_toward(Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(shadow, to_srgb8(Vec3::splat(ALBEDO * AMBIENT)), "in the shadow: ambient only");
        assert!(floor[0] > shadow[0] + 50 && top[0] > shadow[0] + 50, "lit: {floor:?} {top:?}");
        assert!([shadow, floor, top].iter().all(|p| p[0] == p[1] && p[1] == p[2]), "grey");
    }
}
