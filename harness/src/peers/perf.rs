//! Single-thread primary-ray throughput of every peer against the tracer's FlatBvh (run by hand, `--ignored`).

use std::time::Instant;

use tracer::accel::{Accelerator, BvhParams, FlatBvh, Split, Traversal};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::render::trace_primary;
use tracer::scene::{Camera, SceneKind};

use super::*;

/// Best of `reps` runs of the primary-ray kernel, in Mrays/s, and the hit count.
fn mrays<A: Accelerator>(camera: &Camera, accel: &A, reps: usize) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..reps {
        let start = Instant::now();
        let (h, _) = trace_primary::<_, NoCounters>(camera, accel, &Strategy::SERIAL);
        best = best.min(start.elapsed().as_secs_f64());
        hits = h.hit_count();
    }
    ((camera.width * camera.height) as f64 / best / 1e6, hits)
}

/// Packets of 16 consecutive pixels of a row through `intersect16`, in Mrays/s, and the hit count.
fn mrays_packets(camera: &Camera, accel: &EmbreeSpheres, reps: usize) -> (f64, usize) {
    let rays = camera.rays();
    let mut best = f64::INFINITY;
    let mut hits = 0;
    let mut row = Vec::with_capacity(camera.width as usize);
    for _ in 0..reps {
        let start = Instant::now();
        hits = 0;
        for y in 0..camera.height {
            row.clear();
            row.extend((0..camera.width).map(|x| rays.ray(x, y)));
            for chunk in row.chunks(16) {
                hits += accel.intersect16(chunk).iter().flatten().count();
            }
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    ((camera.width * camera.height) as f64 / best / 1e6, hits)
}

#[test]
#[ignore = "timing: run by hand with --release -- --ignored --nocapture"]
fn primary_ray_throughput() {
    let loadavg = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("loadavg before: {}", loadavg.trim());
    let device = EmbreeDevice::new(&EmbreeConfig { threads: Some(1), ..EmbreeConfig::default() }).ok();
    if let Some(d) = &device {
        println!("embree: {:?}", d.info());
    }
    println!("{:>8} {:>16} {:>9} {:>9} {:>8}", "spheres", "backend", "build ms", "Mrays/s", "hits");
    for n in [1_000usize, 100_000, 1_000_000] {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        let camera = scene.camera.with_resolution(512, 384);
        let reps = if n >= 1_000_000 { 3 } else { 5 };
        let report = |name: &str, build: f64, (m, hits): (f64, usize)| {
            println!("{n:>8} {name:>16} {:>9.1} {m:>9.2} {hits:>8}", build * 1e3);
        };
        let t = Instant::now();
        let params = BvhParams { split: Split::BinnedSah, traversal: Traversal::FrontToBack, ..Default::default() };
        let flat = FlatBvh::build(&scene.spheres, &params);
        report("flat-bvh", t.elapsed().as_secs_f64(), mrays(&camera, &flat, reps));
        drop(flat);
        let t = Instant::now();
        let b2 = ObvhsBvh2::build(&scene.spheres, ObvhsQuality::Medium);
        report("obvhs-bvh2", t.elapsed().as_secs_f64(), mrays(&camera, &b2, reps));
        drop(b2);
        let t = Instant::now();
        let cw = ObvhsCwbvh::build(&scene.spheres, ObvhsQuality::Medium);
        report("obvhs-cwbvh", t.elapsed().as_secs_f64(), mrays(&camera, &cw, reps));
        drop(cw);
        if let Some(d) = &device {
            let t = Instant::now();
            let e = EmbreeSpheres::build(d, &scene.spheres, EmbreeQuality::Medium).expect("embree build");
            let build = t.elapsed().as_secs_f64();
            report("embree", build, mrays(&camera, &e, reps));
            report("embree-packets", build, mrays_packets(&camera, &e, reps));
        }
    }
    let loadavg = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("loadavg after: {}", loadavg.trim());
}
