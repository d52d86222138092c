//! tinybvh against f64-arbitrated brute force, on every ISA variant this CPU runs × every layout it has × both
//! builders, plus the ABI, the degenerate meshes and rays, and the mapping of `t_min` and `t_max`.

use tracer::Vec3;
use tracer::accel::{Accelerator, Hit};
use tracer::agreement::{Answer, Strictness};
use tracer::counters::NoCounters;
use tracer::geometry::{Ray, Triangle, TriangleTest};
use tracer::render::PrimaryHits;
use tracer::rng::SplitMix64;
use tracer::scene::mesh::Mesh;
use tracer::scene::{SceneKind, random_triangles, tessellate};

use super::*;
use crate::peers::testing::triangle_reference;
use tracer::testing::secondary_rays;

/// Every (ISA, layout, builder) this CPU runs; fails if the shim is missing on x86-64 Linux.
fn configurations() -> Vec<(TinyIsa, TinyLayout, TinyQuality)> {
    let isas: Vec<TinyIsa> = TinyIsa::ALL.into_iter().filter(|isa| isa.supported()).collect();
    assert!(!isas.is_empty(), "no tinybvh variant runs here: {}", unavailable_reason());
    let mut all = Vec::new();
    for isa in isas {
        for layout in TinyLayout::ALL.into_iter().filter(|&l| isa.has(l)) {
            for quality in [TinyQuality::Default, TinyQuality::High] {
                all.push((isa, layout, quality));
            }
        }
    }
    all
}

/// f32 brute force with the watertight test: the closest hit in `(t_min, t_max)`.
fn brute_closest(triangles: &[Triangle], ray: &Ray) -> Option<Hit> {
    triangles
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            t.intersect(TriangleTest::Watertight, ray, ray.t_max).map(|h| Hit { t: h.t, prim: i as u32 })
        })
        .min_by(|a, b| a.t.total_cmp(&b.t))
}

/// The rays of a test: the camera's at 40 × 30, random lines and segments through the mesh's box, rays aimed at
/// random points inside triangles (a third with non-unit directions), at vertices and edges (edge ties), rays
/// with `t_min > 0` around a triangle, and from the camera rays' hits a bounce and a shadow segment per light.
fn ray_mix(mesh: &Mesh, scene: &tracer::scene::Scene, seed: u64) -> Vec<Ray> {
    let triangles: Vec<Triangle> = mesh.triangles().collect();
    let mut rng = SplitMix64::new(seed);
    let camera = scene.camera.with_resolution(40, 30);
    let cam = camera.rays();
    let mut rays: Vec<Ray> =
        (0..camera.height).flat_map(|y| (0..camera.width).map(move |x| (x, y))).map(|(x, y)| cam.ray(x, y)).collect();
    let b = mesh.bounds().union(&tracer::geometry::Aabb::point(scene.camera.position));
    let (lo, hi) = (b.min - b.extent() * 0.25, b.max + b.extent() * 0.25);
    let point = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    };
    for _ in 0..300 {
        let (a, c) = (point(&mut rng), point(&mut rng));
        rays.push(Ray::new(a, (c - a).normalize()));
        let len = (c - a).length().max(1e-6);
        rays.push(Ray::segment(a, (c - a) / len, len));
    }
    if triangles.is_empty() {
        return rays;
    }
    for i in 0..1200 {
        let tri = triangles[rng.below(triangles.len() as u64) as usize];
        let (b1, b2) = (rng.next_f64() as f32, rng.next_f64() as f32);
        let (b1, b2) = if b1 + b2 > 1.0 { (1.0 - b1, 1.0 - b2) } else { (b1, b2) };
        let inside = tri.p[0] + (tri.p[1] - tri.p[0]) * b1 + (tri.p[2] - tri.p[0]) * b2;
        let origin = point(&mut rng);
        let to = inside - origin;
        match i % 6 {
            0 | 1 => rays.push(Ray::new(origin, to.normalize())),
            2 => rays.push(Ray::new(origin, to * rng.range(0.1, 3.0) as f32)),
            3 => rays.push(Ray::new(origin, tri.p[rng.below(3) as usize] - origin)),
            4 => rays.push(Ray::new(origin, tri.p[0].lerp(tri.p[1], b1) - origin)),
            _ => {
                // t_min on either side of the aimed point (in units of `to`: the point is at t = 1).
                let t_min = [0.5f32, 0.999, 1.001, 1.5][rng.below(4) as usize];
                rays.push(Ray { origin, dir: to, t_min, t_max: f32::INFINITY });
            }
        }
    }
    let primaries = rays[..(camera.width * camera.height) as usize].to_vec();
    let hit_normal = |ray: &Ray| {
        let hit = brute_closest(&triangles, ray)?;
        let tri = triangles[hit.prim as usize];
        Some((hit.t, (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize_or(Vec3::Y)))
    };
    let unit = || Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
    rays.extend(secondary_rays(&primaries, &scene.lights, hit_normal, unit));
    rays
}

/// Panics unless `accel`'s batches answer every ray as its single-ray queries do.
#[track_caller]
fn assert_batches_are_single_rays(what: &str, accel: &TinyBvh, rays: &[Ray]) {
    let mut hits = vec![PrimaryHits::MISS; rays.len()];
    accel.intersect_batch(rays, &mut hits, &mut NoCounters);
    let mut occluded = vec![false; rays.len()];
    accel.occluded_batch(rays, &mut occluded, &mut NoCounters);
    for (i, ray) in rays.iter().enumerate() {
        let closest = accel.intersect(ray, &mut NoCounters);
        assert_eq!(Answer::closest(hits[i]), Answer::Closest(closest), "{what}: batch vs single, ray {i}");
        assert_eq!(occluded[i], accel.occluded(ray, &mut NoCounters), "{what}: batch vs single occlusion, ray {i}");
    }
}

/// Builds every configuration over `mesh` and checks it against brute force on `rays`.
#[track_caller]
fn assert_every_configuration_agrees(label: &str, mesh: &Mesh, rays: Vec<Ray>) {
    let reference = triangle_reference(mesh, &rays);
    for (isa, layout, quality) in configurations() {
        let accel = TinyBvh::build_with(mesh, layout, quality, isa).expect("build");
        assert_eq!((accel.isa(), accel.layout(), accel.kernel()), (isa, layout, isa.name()));
        let stats = accel.stats();
        assert!(stats.nodes > 0 && stats.leaves > 0 && stats.bytes > 0, "{label}: {stats:?}");
        let what = format!("{label} {} {layout:?} {quality:?}", isa.name());
        assert_batches_are_single_rays(&what, &accel, &rays);
        let tally = reference.assert_agrees(&what, &accel, Strictness::Arbitrated);
        eprintln!("{what}: {} rays, {} answers tolerated by f64, {stats:?}", rays.len(), tally.tolerated);
    }
}

/// The sizes both sides were compiled with agree, tinybvh's own `Ray` is the 128 bytes the wrapper gets wrong,
/// and each variant has exactly the layouts its ISA gives tinybvh.
#[test]
fn the_abi_agrees_on_both_sides_and_variants_have_their_layouts() {
    for isa in TinyIsa::ALL.into_iter().filter(|isa| isa.supported()) {
        let abi = isa.abi().expect("abi");
        let want = TbAbi {
            ray_size: size_of::<TbRay>() as u32,
            ray_align: align_of::<TbRay>() as u32,
            hit_size: size_of::<TbHit>() as u32,
            hit_align: align_of::<TbHit>() as u32,
            stats_size: size_of::<TbStats>() as u32,
            stats_align: align_of::<TbStats>() as u32,
            tiny_ray_size: 128,
            tiny_ray_align: 64,
            version: 10608,
        };
        assert_eq!(abi, want, "{}", isa.name());
        let layouts: Vec<TinyLayout> = TinyLayout::ALL.into_iter().filter(|&l| isa.has(l)).collect();
        let want = match isa {
            TinyIsa::V2 => vec![TinyLayout::Bvh, TinyLayout::Bvh4Cpu],
            _ => TinyLayout::ALL.to_vec(),
        };
        assert_eq!(layouts, want, "{}", isa.name());
        assert!(TinyLayout::ALL.iter().all(|&l| !isa.has(l) || TinyIsa::lowest_for(l) <= isa));
    }
    let best = TinyIsa::best().expect("a variant runs here");
    let mesh = random_triangles(10, 1);
    assert_eq!(TinyBvh::build(&mesh, TinyLayout::Bvh, TinyQuality::Default).unwrap().kernel(), best.name());
    eprintln!("tinybvh runs {} here", best.name());
}

/// The paper's random-sphere scene tessellated into closed meshes (rays through shared edges and vertices).
#[test]
fn every_layout_agrees_with_brute_force_on_tessellated_spheres() {
    for (n, segments, seed) in [(60, 8, 1), (200, 5, 2)] {
        let scene = SceneKind::RandomSpheres.generate(n, seed);
        let mesh = tessellate(&scene.spheres, segments);
        let rays = ray_mix(&mesh, &scene, seed ^ 0x5eed);
        assert_every_configuration_agrees(&format!("tessellated n={n} segments={segments}"), &mesh, rays);
    }
}

/// Free random triangles (overlapping, any orientation) in the paper's scene box.
#[test]
fn every_layout_agrees_with_brute_force_on_random_triangles() {
    for (n, seed) in [(3000, 4), (40, 5)] {
        let scene = SceneKind::RandomSpheres.generate(0, seed);
        let mesh = random_triangles(n, seed);
        let rays = ray_mix(&mesh, &scene, seed ^ 0x5eed);
        assert_every_configuration_agrees(&format!("random triangles n={n}"), &mesh, rays);
    }
}

/// An empty mesh builds and misses everything; one triangle is hit where it is, not outside it, not at or
/// beyond `t_max` (exclusive) and not at or before `t_min`; a second triangle behind it is found past `t_min`.
#[test]
fn degenerate_meshes_and_rays() {
    let scene = SceneKind::RandomSpheres.generate(0, 1);
    let empty = Mesh::default();
    let tri = Mesh {
        positions: vec![Vec3::new(0.0, 0.0, -4.0), Vec3::new(2.0, 0.0, -4.0), Vec3::new(0.0, 2.0, -4.0)],
        indices: vec![[0, 1, 2]],
    };
    let mut two = tri.clone();
    two.append(Mesh {
        positions: tri.positions.iter().map(|p| *p - Vec3::Z * 2.0).collect(),
        indices: vec![[0, 1, 2]],
    });
    let down = Ray::new(Vec3::new(0.5, 0.25, 0.0), -Vec3::Z);
    for (isa, layout, quality) in configurations() {
        let what = format!("{} {layout:?} {quality:?}", isa.name());
        let build = |mesh: &Mesh| TinyBvh::build_with(mesh, layout, quality, isa).expect("build");
        let none = build(&empty);
        assert_eq!(none.stats().nodes, 0, "{what}");
        for ray in ray_mix(&empty, &scene, 3) {
            assert_eq!(none.intersect(&ray, &mut NoCounters), None, "{what}");
            assert!(!none.occluded(&ray, &mut NoCounters), "{what}");
        }
        let one = build(&tri);
        let t = |a: &TinyBvh, ray: Ray| a.intersect(&ray, &mut NoCounters).map(|h| (h.t, h.prim));
        let occ = |a: &TinyBvh, ray: Ray| a.occluded(&ray, &mut NoCounters);
        let hit = t(&one, down).unwrap_or_else(|| panic!("{what}: no hit"));
        assert!((hit.0 - 4.0).abs() < 1e-5 && hit.1 == 0, "{what}: {hit:?}");
        assert!(occ(&one, down), "{what}");
        let long = Ray { dir: -Vec3::Z * 2.0, ..down };
        assert!(t(&one, long).is_some_and(|h| (h.0 - 2.0).abs() < 1e-5), "{what}: non-unit direction");
        assert_eq!(t(&one, Ray::new(Vec3::new(1.5, 1.5, 0.0), -Vec3::Z)), None, "{what}: outside");
        assert_eq!(t(&one, Ray { dir: Vec3::Z, ..down }), None, "{what}: away");
        // Exactly at the hit (t = 4) only the plain layout's arithmetic is exact; BVH4_CPU and BVH8_CPU divide
        // by an approximate reciprocal (their t may be an ulp off), so they are checked off the boundary.
        let exact = layout == TinyLayout::Bvh;
        for t_max in [4.0, 3.999, 3.9].into_iter().filter(|&t| exact || t != 4.0) {
            assert_eq!(t(&one, Ray { t_max, ..down }), None, "{what}: t_max {t_max} is exclusive");
            assert!(!occ(&one, Ray { t_max, ..down }), "{what}: occlusion, t_max {t_max}");
        }
        assert!(occ(&one, Ray { t_max: 4.001, ..down }) && t(&one, Ray { t_max: 4.001, ..down }).is_some(), "{what}");
        for t_min in [4.0, 4.001, 4.5].into_iter().filter(|&t| exact || t != 4.0) {
            assert_eq!(t(&one, Ray { t_min, ..down }), None, "{what}: t_min {t_min}");
            assert!(!occ(&one, Ray { t_min, ..down }), "{what}: occlusion, t_min {t_min}");
        }
        assert!(t(&one, Ray { t_min: 3.999, ..down }).is_some_and(|h| (h.0 - 4.0).abs() < 1e-5), "{what}");
        assert!(t(&one, Ray { t_min: 3.5, ..down }).is_some_and(|h| (h.0 - 4.0).abs() < 1e-5), "{what}");
        assert_eq!(t(&one, Ray { dir: Vec3::ZERO, ..down }), None, "{what}: zero direction");
        assert_eq!(t(&one, Ray { origin: Vec3::NAN, ..down }), None, "{what}: NaN origin");
        assert!(!occ(&one, Ray { t_max: f32::NAN, ..down }), "{what}: NaN t_max");
        let both = build(&two);
        assert!(t(&both, down).is_some_and(|h| (h.0 - 4.0).abs() < 1e-5 && h.1 == 0), "{what}");
        let past = Ray { t_min: 5.0, ..down };
        assert!(t(&both, past).is_some_and(|h| (h.0 - 6.0).abs() < 1e-5 && h.1 == 1), "{what}: t_min 5");
        assert!(occ(&both, past) && !occ(&both, Ray { t_min: 6.5, ..down }), "{what}: occlusion past t_min");
    }
}

/// Meshes the shim must not see are refused before C++ runs; a layout missing from a variant is named.
#[test]
fn bad_meshes_and_missing_layouts_are_errors() {
    let bad = Mesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y], indices: vec![[0, 1, 3]] };
    assert!(matches!(TinyBvh::build(&bad, TinyLayout::Bvh, TinyQuality::Default), Err(TinyBvhError::BadMesh(_))));
    let nan = Mesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::NAN], indices: vec![[0, 1, 2]] };
    assert!(matches!(TinyBvh::build(&nan, TinyLayout::Bvh, TinyQuality::Default), Err(TinyBvhError::BadMesh(_))));
    if TinyIsa::V2.supported() {
        let mesh = random_triangles(5, 1);
        let err = TinyBvh::build_with(&mesh, TinyLayout::Bvh8Cpu, TinyQuality::Default, TinyIsa::V2).unwrap_err();
        assert_eq!(err, TinyBvhError::LayoutNeedsIsa(TinyLayout::Bvh8Cpu, TinyIsa::V2));
        assert_eq!(err.to_string(), "tinybvh BVH8_CPU is not compiled for x86-64-v2");
    }
}
