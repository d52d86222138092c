//! Median build time of the flat BVH's binned SAH (16 bins, leaf 4) over random spheres (seed 1), in 1- and 2-thread pools.
//!
//! `cargo run --release -p tracer --example build_time -- [repeats] [sizes...]` (default 7 repeats, 1e5 and 1e6 spheres).

use std::time::Instant;

use tracer::accel::bvh::builder::build;
use tracer::accel::{BvhParams, Split};
use tracer::scene::SceneKind;

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("numbers")).collect();
    let repeats = args.first().copied().unwrap_or(7);
    let sizes = if args.len() > 1 { args[1..].to_vec() } else { vec![100_000, 1_000_000] };
    let params = BvhParams { split: Split::BinnedSah, ..BvhParams::default() };
    for n in sizes {
        let spheres = SceneKind::RandomSpheres.generate(n, 1).spheres;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            let mut times: Vec<f64> = (0..repeats)
                .map(|_| {
                    let start = Instant::now();
                    std::hint::black_box(pool.install(|| build(&spheres, &params)));
                    start.elapsed().as_secs_f64()
                })
                .collect();
            times.sort_by(f64::total_cmp);
            let (min, med) = (times[0], times[times.len() / 2]);
            println!("n={n} threads={threads}: median {med:.4} s, min {min:.4} s ({repeats} builds)");
        }
    }
}
