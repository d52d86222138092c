//! Embree's `rtcIntersect1` in a plain loop against the same library, rays and order traced through the harness's
//! path (the ray set, the executor's rows, the batch loop, the answers), and the `null` backend through that path:
//! how much the harness adds per ray.
//!
//! `cargo run --release -p harness --example embree_loop -- [rounds] [spheres...]` (default 7 rounds; 1e3, 1e5
//! and 1e6 random spheres, seed 1; 1024×768 primary rays in the harness's tile order; one thread). Needs Embree 4
//! (`python3 -m pip install embreex==4.4.0.post1`). Each round times every path once, in turn; the minimum and the
//! median over rounds are printed.

use std::time::Instant;

use harness::peers::embree::abi::RTC_INVALID_GEOMETRY_ID;
use harness::peers::embree::scene::ray_hit;
use harness::peers::{EmbreeConfig, EmbreeDevice, EmbreeSpheres};
use schema::EmbreeQuality;
use tracer::accel::Null;
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::geometry::Ray;
use tracer::rays::{RayAnswers, RaySet, trace};
use tracer::scene::SceneKind;

/// `rtcIntersect1` on every ray in order, written as a C user would: one `RTCRayHit` on the stack per ray (the
/// binding's conversion), the hit distance and primitive stored per ray (a miss as infinity and `u32::MAX`).
fn plain_loop(scene: &EmbreeSpheres, rays: &[Ray], out: &mut [(f32, u32)]) {
    let (handle, api) = scene.raw();
    for (ray, o) in rays.iter().zip(out.iter_mut()) {
        let mut rh = ray_hit(ray);
        // SAFETY: a committed scene that outlives the call, an initialized 16-byte aligned RTCRayHit (its type's
        // alignment), NULL arguments (the defaults).
        unsafe { (api.intersect1)(handle, &mut rh, std::ptr::null_mut()) };
        *o = if rh.hit.geomID == RTC_INVALID_GEOMETRY_ID {
            (f32::INFINITY, u32::MAX)
        } else {
            (rh.ray.tfar, rh.hit.primID)
        };
    }
}

/// Minimum and median of `times`.
fn min_median(times: &mut [f64]) -> (f64, f64) {
    times.sort_by(f64::total_cmp);
    (times[0], times[times.len() / 2])
}

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("numbers")).collect();
    let rounds = args.first().copied().unwrap_or(7).max(1);
    let sizes = if args.len() > 1 { args[1..].to_vec() } else { vec![1_000, 100_000, 1_000_000] };
    let device = EmbreeDevice::new(&EmbreeConfig { threads: Some(1), ..EmbreeConfig::default() }).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    // The harness traces in a one-thread pool it starts before timing; so does this.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a one-thread pool");
    println!("{}", device.info().config);
    for n in sizes {
        let mut scene = SceneKind::RandomSpheres.generate(n, 1);
        scene.camera = scene.camera.with_resolution(1024, 768);
        let set = RaySet::primary(&scene);
        let embree = EmbreeSpheres::build(&device, &scene.spheres, EmbreeQuality::Medium).expect("an Embree scene");
        let mut out = vec![(0.0f32, 0u32); set.rays.len()];
        let (mut plain, mut harness, mut null) = (vec![], vec![], vec![]);
        let mut answers = None;
        for _ in 0..rounds {
            let t = Instant::now();
            pool.install(|| plain_loop(&embree, &set.rays, &mut out));
            plain.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let (a, _) = pool.install(|| trace::<_, NoCounters>(&embree, &set, &Strategy::SERIAL));
            harness.push(t.elapsed().as_secs_f64());
            answers = Some(a);
            let t = Instant::now();
            std::hint::black_box(pool.install(|| trace::<_, NoCounters>(&Null, &set, &Strategy::SERIAL)));
            null.push(t.elapsed().as_secs_f64());
        }
        // Both paths give the same answers.
        let Some(RayAnswers::Closest(hits)) = answers else { unreachable!("primary rays ask for closest hits") };
        let same = hits.iter().zip(&out).all(|(h, &(t, prim))| (h.t, h.prim) == (t, prim));
        assert!(same, "the plain loop and the harness's path disagree");
        let rays = set.rays.len() as f64;
        let ((pmin, pmed), (hmin, hmed), (nmin, nmed)) =
            (min_median(&mut plain), min_median(&mut harness), min_median(&mut null));
        let ns = |s: f64| s / rays * 1e9;
        println!(
            "{n} spheres, {} rays: plain loop {:.2} Mrays/s ({:.1} ns/ray, median {:.1}); harness path {:.2} Mrays/s \
             ({:.1} ns/ray, median {:.1}): {:.3} of the plain loop; null backend {:.2} ns/ray (median {:.2})",
            rays,
            rays / pmin / 1e6,
            ns(pmin),
            ns(pmed),
            rays / hmin / 1e6,
            ns(hmin),
            ns(hmed),
            pmin / hmin,
            ns(nmin),
            ns(nmed),
        );
    }
}
