//! Median build times over random spheres (seed 1), in 1- and 2-thread pools: the flat BVH's binned SAH (16 bins,
//! leaf 4), and the phases of the wide BVH of `experiments/peers.toml`'s `wide-best` (the binary tree for blocks of
//! 8, its collapse into 8-wide nodes, and the whole [`WideBvh::build`]).
//!
//! `cargo run --release -p tracer --example build_time -- [repeats] [sizes...]` (default 7 repeats, 1e5 and 1e6 spheres).

use std::time::Instant;

use tracer::accel::bvh::builder::{build, build_for_blocks};
use tracer::accel::wide::collapse::collapse;
use tracer::accel::{BvhParams, Split, WideBvh, WideParams};
use tracer::scene::SceneKind;

/// Median and minimum of `repeats` timings of `f`.
fn time<R>(repeats: usize, mut f: impl FnMut() -> R) -> (f64, f64) {
    let mut times: Vec<f64> = (0..repeats)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], times[0])
}

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("numbers")).collect();
    let repeats = args.first().copied().unwrap_or(7);
    let sizes = if args.len() > 1 { args[1..].to_vec() } else { vec![100_000, 1_000_000] };
    let params = BvhParams { split: Split::BinnedSah, ..BvhParams::default() };
    let wide = WideParams { width: 8, leaf_block: 8, ..WideParams::default() };
    for n in sizes {
        let spheres = SceneKind::RandomSpheres.generate(n, 1).spheres;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            let report = |what: &str, (med, min): (f64, f64)| {
                println!("n={n} threads={threads} {what}: median {med:.4} s, min {min:.4} s ({repeats} builds)");
            };
            report("binary", pool.install(|| time(repeats, || build(&spheres, &params))));
            report("binary for blocks of 8", pool.install(|| time(repeats, || build_for_blocks(&spheres, &params, 8))));
            let built = pool.install(|| build_for_blocks(&spheres, &params, 8));
            report("collapse 8-wide", pool.install(|| time(repeats, || collapse::<_, 8, 8>(&built))));
            report("wide 8x8 (all)", pool.install(|| time(repeats, || WideBvh::build(&spheres, &params, &wide))));
        }
    }
}
