//! Test helpers for the peers: scenes, a ray mix like the renderers' and the agreement check against brute force.

use std::io::Write;

use tracer::Vec3;
use tracer::accel::{Accelerator, Hit, List};
use tracer::counters::NoCounters;
use tracer::geometry::{Aabb, Ray, Sphere};
use tracer::rng::SplitMix64;
use tracer::scene::{Scene, SceneKind};

use super::embree::{EmbreeConfig, EmbreeDevice, EmbreeLibrary};

fn unit_vector(rng: &mut SplitMix64) -> Vec3 {
    loop {
        let v = Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// Every test scene (both kinds; 0, 1, 50 and 2000 spheres; two seeds) with its ray mix.
pub fn scenes() -> Vec<(String, Vec<Sphere>, Vec<Ray>)> {
    let mut all = Vec::new();
    for kind in SceneKind::ALL {
        for n in [0, 1, 50, 2000] {
            for seed in [1u64, 2] {
                let scene = kind.generate(n, seed);
                let rays = ray_mix(&scene, seed ^ 0x5eed);
                all.push((format!("{} n={n} seed={seed}", kind.name()), scene.spheres, rays));
            }
        }
    }
    all
}

/// Camera rays, random lines, rays from inside spheres, grazing rays (tangent ± 1e-5 and tangent where a sphere
/// touches its box), random segments, and from camera hits: shadow segments to the lights and cosine-ish bounces.
pub fn ray_mix(scene: &Scene, seed: u64) -> Vec<Ray> {
    let spheres = &scene.spheres;
    let mut rng = SplitMix64::new(seed);
    let bounds = spheres.iter().fold(Aabb::point(scene.camera.position), |b, s| b.union(&s.bounds()));
    let (lo, hi) = (bounds.min - bounds.extent() * 0.25, bounds.max + bounds.extent() * 0.25);
    let point = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    };
    let camera = scene.camera.with_resolution(40, 30);
    let cam = camera.rays();
    let mut rays: Vec<Ray> = (0..camera.height).flat_map(|y| (0..camera.width).map(move |x| cam.ray(x, y))).collect();
    for _ in 0..300 {
        rays.push(Ray::new(point(&mut rng), unit_vector(&mut rng)));
        let (a, b) = (point(&mut rng), point(&mut rng));
        let len = (b - a).length().max(1e-6);
        rays.push(Ray::segment(a, (b - a) / len, len));
    }
    if spheres.is_empty() {
        return rays;
    }
    let pick = |rng: &mut SplitMix64| spheres[rng.below(spheres.len() as u64) as usize];
    for _ in 0..200 {
        let s = pick(&mut rng);
        rays.push(Ray::new(s.center + unit_vector(&mut rng) * (s.radius * 0.5), unit_vector(&mut rng)));
        // Tangent line at relative offset 1 ± 1e-5 from the center: a grazing hit or a near miss.
        let s = pick(&mut rng);
        let d = unit_vector(&mut rng);
        let offset = 1.0 + rng.range(-1e-5, 1e-5) as f32;
        let o = s.center + d.any_orthonormal_vector() * (s.radius * offset) - d * (s.radius * 3.0 + 1.0);
        rays.push(Ray::new(o, d));
        // Tangent where the sphere touches its box, tilted to cross that face.
        let s = pick(&mut rng);
        let axis = Vec3::AXES[rng.below(3) as usize] * if rng.below(2) == 0 { 1.0 } else { -1.0 };
        let d = (axis.any_orthonormal_vector() + axis * rng.range(-2e-5, 2e-5) as f32).normalize();
        let touch = s.center + axis * (s.radius * (1.0 + rng.range(-1e-7, 1e-7) as f32));
        rays.push(Ray::new(touch - d * (s.radius * rng.range(0.5, 4.0) as f32), d));
        // Non-unit direction at a center.
        let s = pick(&mut rng);
        let o = point(&mut rng);
        rays.push(Ray::new(o, (s.center - o) * rng.range(0.1, 3.0) as f32));
    }
    // Secondary rays from the camera rays' hits, offset like the shader's.
    let reference = List::build(spheres);
    let primaries: Vec<Ray> = rays[..(camera.width * camera.height) as usize].to_vec();
    for ray in primaries {
        let Some(hit) = reference.intersect(&ray, &mut NoCounters) else { continue };
        let p = ray.at(hit.t);
        let mut n = spheres[hit.prim as usize].normal_at(p);
        if n.dot(ray.dir) > 0.0 {
            n = -n;
        }
        let origin = p + n * (1e-4 * p.abs().max_element().max(1.0));
        for light in &scene.lights {
            let to_light = light.position - origin;
            let distance = to_light.length();
            rays.push(Ray::segment(origin, to_light / distance, distance));
        }
        rays.push(Ray::new(origin, (n + unit_vector(&mut rng)).normalize_or(n)));
    }
    rays
}

/// How closely a backend's hit distances must match brute force's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tolerance {
    /// Bit-identical `t` (backends that call our own `Sphere::intersect`).
    Exact,
    /// Within 1e-4 relative to the larger of `t` and the hit sphere's distance scale `(|o - c| + r) / |d|`:
    /// a ray-sphere root's rounding error scales with the operands, not with `t` (for backends with their own test).
    Relative,
}

/// True when `got` matches brute force's `want` for `ray`: hit/miss equal and `t` within `tol`.
pub fn same_hit(spheres: &[Sphere], ray: &Ray, want: Option<Hit>, got: Option<Hit>, tol: Tolerance) -> bool {
    match (want, got, tol) {
        (None, None, _) => true,
        (Some(w), Some(g), Tolerance::Exact) => g.t.to_bits() == w.t.to_bits(),
        (Some(w), Some(g), Tolerance::Relative) => {
            let s = &spheres[w.prim as usize];
            let scale = ((ray.origin - s.center).length() + s.radius) / ray.dir.length();
            (g.t - w.t).abs() <= 1e-4 * w.t.abs().max(scale)
        }
        _ => false,
    }
}

/// How near tangent (`|perp / r - 1|`, about two f32 ulps of the radius) f32 cannot tell a hit from a miss.
pub const GRAZING: f64 = 2.5e-7;

/// How far from tangent the ray's line passes sphere `s`, `|perp / r - 1|` in f64, if it grazes it ahead of
/// the origin within [`GRAZING`].
pub fn grazing_offset(s: &Sphere, ray: &Ray) -> Option<f64> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let f = o - s.center.as_dvec3();
    let t_closest = -f.dot(d) / d.dot(d);
    let rel = ((f + d * t_closest).length() / s.radius as f64 - 1.0).abs();
    (rel < GRAZING && t_closest > ray.t_min as f64).then_some(rel)
}

/// The first sphere the ray grazes (see [`grazing_offset`]) and its offset from tangent.
pub fn grazes(spheres: &[Sphere], ray: &Ray) -> Option<(usize, f64)> {
    spheres.iter().enumerate().find_map(|(i, s)| grazing_offset(s, ray).map(|rel| (i, rel)))
}

/// For a closest-hit disagreement: a sphere of either answer that the ray grazes, and its offset.
pub fn hit_grazes(spheres: &[Sphere], ray: &Ray, want: Option<Hit>, got: Option<Hit>) -> Option<(usize, f64)> {
    [want, got].into_iter().flatten().find_map(|h| grazing_offset(&spheres[h.prim as usize], ray).map(|rel| (h.prim as usize, rel)))
        .or_else(|| if want.is_none() || got.is_none() { grazes(spheres, ray) } else { None })
}

/// Panics with every disagreement (up to 8 shown) between `accel` and brute force over `rays`.
///
/// With [`Tolerance::Relative`] (a backend with its own ray-sphere test), a disagreement caused by a sphere the
/// ray grazes within [`GRAZING`] of tangent (below f32's resolution of the radius) is printed and excused; any
/// other disagreement fails. With [`Tolerance::Exact`] nothing is excused.
pub fn assert_agrees<A: Accelerator>(what: &str, accel: &A, spheres: &[Sphere], rays: &[Ray], tol: Tolerance) {
    let reference = List::build(spheres);
    let mut bad = Vec::new();
    let mut excused = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let want = reference.intersect(ray, &mut NoCounters);
        let got = accel.intersect(ray, &mut NoCounters);
        let (want_occ, got_occ) = (reference.occluded(ray, &mut NoCounters), accel.occluded(ray, &mut NoCounters));
        let relative = tol == Tolerance::Relative;
        if !same_hit(spheres, ray, want, got, tol) {
            let text = format!("closest {got:?} vs brute force {want:?}");
            match hit_grazes(spheres, ray, want, got).filter(|_| relative) {
                Some((s, rel)) => excused.push(format!("ray {i} {ray:?} grazes sphere {s} ({rel:.1e}): {text}")),
                None => bad.push(format!("ray {i} {ray:?}: {text}")),
            }
        }
        if want_occ != got_occ {
            let text = format!("occluded {got_occ} vs brute force {want_occ}");
            match grazes(spheres, ray).filter(|_| relative) {
                Some((s, rel)) => excused.push(format!("ray {i} {ray:?} grazes sphere {s} ({rel:.1e}): {text}")),
                None => bad.push(format!("ray {i} {ray:?}: {text}")),
            }
        }
    }
    if !excused.is_empty() {
        eprintln!("{what}: {} hit/miss disagreement(s) on rays within {GRAZING:e} of tangent (excused):\n  {}", excused.len(), excused.join("\n  "));
    }
    assert!(bad.is_empty(), "{what}: {} disagreements of {} rays:\n{}", bad.len(), rays.len(), bad[..bad.len().min(8)].join("\n"));
}

/// The Embree device for a test, or `None` (after saying so) when Embree is missing and not required.
/// With `BVHLAB_REQUIRE_EMBREE=1` a missing Embree fails the test.
pub fn embree_device(test: &str) -> Option<EmbreeDevice> {
    let required = std::env::var("BVHLAB_REQUIRE_EMBREE").is_ok_and(|v| v == "1");
    match EmbreeLibrary::shared() {
        Ok(_) => Some(EmbreeDevice::new(&EmbreeConfig { threads: Some(2), ..EmbreeConfig::default() }).expect("Embree device")),
        Err(e) if required => panic!("{test}: BVHLAB_REQUIRE_EMBREE=1 but {e}"),
        Err(e) => {
            // Straight to stderr, past libtest's output capture, so the skip is always visible.
            let _ = writeln!(std::io::stderr(), "{test}: skipped: {e}");
            None
        }
    }
}
