//! Shared helpers for the integration tests: every tree configuration, ray sets and the agreement check.
#![allow(dead_code)]

use glam::Vec3;
use tracer::accel::{AccelKind, AccelParams, Accelerator, BuiltAccel, BvhParams, List, Split, Traversal};
use tracer::counters::NoCounters;
use tracer::geometry::{Ray, Sphere};
use tracer::rng::SplitMix64;

/// Every tree configuration: both layouts × every split × leaf sizes 1..=16 × both traversal orders.
pub fn every_tree() -> Vec<AccelParams> {
    let mut all = Vec::new();
    for kind in [AccelKind::Bvh, AccelKind::FlatBvh] {
        for split in Split::ALL {
            for max_leaf_size in 1..=BvhParams::MAX_LEAF_SIZE {
                for traversal in Traversal::ALL {
                    let bvh = BvhParams { max_leaf_size, split, traversal, sah_bins: 16 };
                    all.push(AccelParams { kind, bvh });
                }
            }
        }
    }
    all
}

fn unit_vector(rng: &mut SplitMix64) -> Vec3 {
    loop {
        let v = Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// A mix of rays over `spheres`: random lines through the scene, rays starting inside spheres, rays aimed
/// at centers, grazing rays tangent to a sphere (just inside and just outside), and finite segments.
pub fn ray_mix(spheres: &[Sphere], seed: u64, count: usize) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    let bounds = spheres.iter().fold(tracer::geometry::Aabb::point(Vec3::ZERO), |b, s| b.union(&s.bounds()));
    let (lo, hi) = (bounds.min - bounds.extent() * 0.5, bounds.max + bounds.extent() * 0.5);
    let point = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    };
    (0..count)
        .map(|i| {
            let pick = |rng: &mut SplitMix64| spheres[rng.below(spheres.len() as u64) as usize];
            match (i % 7, spheres.is_empty()) {
                (_, true) | (0, _) => Ray::new(point(&mut rng), unit_vector(&mut rng)),
                (1, _) => {
                    let s = pick(&mut rng);
                    Ray::new(s.center + unit_vector(&mut rng) * (s.radius * 0.5), unit_vector(&mut rng))
                }
                (2, _) => {
                    let s = pick(&mut rng);
                    let o = point(&mut rng);
                    Ray::new(o, (s.center - o).normalize_or(Vec3::X))
                }
                (3, _) => {
                    // Tangent line at relative offset 1 ± 1e-5 from the center: a grazing hit or a near miss.
                    let s = pick(&mut rng);
                    let d = unit_vector(&mut rng);
                    let perp = d.any_orthonormal_vector();
                    let offset = 1.0 + rng.range(-1e-5, 1e-5) as f32;
                    let o = s.center + perp * (s.radius * offset) - d * (s.radius * 3.0 + 1.0);
                    Ray::new(o, d)
                }
                (4, _) => {
                    // Tangent at the point where the sphere touches its box, tilted to cross that face.
                    let s = pick(&mut rng);
                    let axis = Vec3::AXES[rng.below(3) as usize] * if rng.below(2) == 0 { 1.0 } else { -1.0 };
                    let along = axis.any_orthonormal_vector();
                    let tilt = rng.range(-2e-5, 2e-5) as f32;
                    let d = (along + axis * tilt).normalize();
                    let touch = s.center + axis * (s.radius * (1.0 + rng.range(-1e-7, 1e-7) as f32));
                    Ray::new(touch - d * (s.radius * rng.range(0.5, 4.0) as f32), d)
                }
                (5, _) => {
                    let (a, b) = (point(&mut rng), point(&mut rng));
                    let d = b - a;
                    let len = d.length().max(1e-6);
                    Ray::segment(a, d / len, len)
                }
                _ => {
                    // Non-unit direction: t is in units of the direction's length.
                    let s = pick(&mut rng);
                    let o = point(&mut rng);
                    Ray::new(o, (s.center - o) * rng.range(0.1, 3.0) as f32)
                }
            }
        })
        .collect()
}

/// Asserts that `accel` agrees with brute force on every ray: hit/miss exactly, `t` within 1e-4 relative,
/// occlusion exactly. `what` names the configuration in the failure message.
pub fn assert_agrees(what: &str, accel: &BuiltAccel, reference: &List, rays: &[Ray]) {
    struct Check<'a> {
        what: &'a str,
        reference: &'a List,
        rays: &'a [Ray],
    }
    impl tracer::accel::AccelVisitor for Check<'_> {
        type Output = ();
        fn visit<A: Accelerator>(self, accel: &A) {
            for (i, ray) in self.rays.iter().enumerate() {
                let want = self.reference.intersect(ray, &mut NoCounters);
                let got = accel.intersect(ray, &mut NoCounters);
                match (want, got) {
                    (None, None) => {}
                    (Some(w), Some(g)) => assert!(
                        (g.t - w.t).abs() <= 1e-4 * w.t.abs() + 1e-7,
                        "{}: ray {i} {ray:?}: t {} vs brute force {}",
                        self.what,
                        g.t,
                        w.t
                    ),
                    _ => panic!("{}: ray {i} {ray:?}: hit {got:?} vs brute force {want:?}", self.what),
                }
                assert_eq!(
                    accel.occluded(ray, &mut NoCounters),
                    self.reference.occluded(ray, &mut NoCounters),
                    "{}: ray {i} {ray:?}: occlusion differs from brute force",
                    self.what
                );
            }
        }
    }
    accel.visit(Check { what, reference, rays });
}

/// Builds every tree over `spheres` and checks each against brute force on `rays`.
pub fn assert_every_tree_agrees(label: &str, spheres: &[Sphere], rays: &[Ray]) {
    let reference = List::build(spheres);
    for params in every_tree() {
        let accel = BuiltAccel::build(spheres, &params);
        assert_agrees(&format!("{label} {params:?}"), &accel, &reference, rays);
    }
}
