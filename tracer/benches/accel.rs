//! Single-thread build time and primary-ray throughput of every structure and split at 1e3, 1e4, 1e5 spheres,
//! the flat BVH's build time in 1- and 2-thread pools at 1e5 and 1e6 spheres, and (group `wide`) primary rays
//! through the flat BVH against the wide BVH's widths and kernels.
//!
//! `cargo bench -p tracer --bench accel` (criterion reports primary throughput as elements/s = rays/s).
//! The scene is random-spheres seed 1; the primary image is 256×192 for trees and 64×48 for the list.
//! Builds use the threads of the rayon pool they run in: `build` runs in a 1-thread pool, `build-threads`
//! in pools of the thread count its ids name.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use tracer::accel::wide::Kernel;
use tracer::accel::{
    AccelKind, AccelParams, AccelVisitor, Accelerator, BuiltAccel, BvhParams, Split, Traversal, WideBvh, WideParams,
};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::render::trace_primary;
use tracer::scene::{Camera, SceneKind};

const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

fn tree_params() -> Vec<AccelParams> {
    let mut all = Vec::new();
    for split in Split::ALL {
        all.push(AccelParams {
            kind: AccelKind::Bvh,
            bvh: BvhParams { split, ..BvhParams::default() },
            ..AccelParams::default()
        });
        for traversal in Traversal::ALL {
            all.push(AccelParams {
                kind: AccelKind::FlatBvh,
                bvh: BvhParams { split, traversal, ..BvhParams::default() },
                ..AccelParams::default()
            });
        }
    }
    all
}

fn label(p: &AccelParams) -> String {
    match p.kind {
        AccelKind::List => AccelKind::List.name().into(),
        k => format!("{}/{}/{}", k.name(), p.bvh.split.name(), p.bvh.traversal.name()),
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

/// Serial build time: every tree in a 1-thread pool.
fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    let serial = pool(1);
    for n in SIZES {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        group.throughput(Throughput::Elements(n as u64));
        for p in tree_params().into_iter().filter(|p| p.bvh.traversal == Traversal::Fixed) {
            group.bench_with_input(BenchmarkId::new(label(&p), n), &p, |b, p| {
                b.iter(|| black_box(serial.install(|| BuiltAccel::build(&scene.spheres, p))))
            });
        }
    }
    group.finish();
}

/// Parallel build: the flat BVH with the paper's split and binned SAH in 1- and 2-thread pools
/// (ids `flat-bvh/{split}/threads={t}/{spheres}`).
fn build_threads(c: &mut Criterion) {
    let mut group = c.benchmark_group("build-threads");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    let pools = [1, 2].map(|t| (t, pool(t)));
    for n in [100_000, 1_000_000] {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        group.throughput(Throughput::Elements(n as u64));
        for split in [Split::CentroidMidpoint, Split::BinnedSah] {
            let p = AccelParams {
                kind: AccelKind::FlatBvh,
                bvh: BvhParams { split, ..BvhParams::default() },
                ..AccelParams::default()
            };
            for (threads, pool) in &pools {
                let id = BenchmarkId::new(format!("flat-bvh/{}/threads={threads}", split.name()), n);
                group.bench_function(id, |b| {
                    b.iter(|| black_box(pool.install(|| BuiltAccel::build(&scene.spheres, &p))))
                });
            }
        }
    }
    group.finish();
}

struct Primary<'a>(&'a Camera);
impl AccelVisitor for Primary<'_> {
    type Output = usize;
    fn visit<A: Accelerator>(self, a: &A) -> usize {
        trace_primary::<_, NoCounters>(self.0, a, &Strategy::SERIAL).0.hit_count()
    }
}

fn primary(c: &mut Criterion) {
    let mut group = c.benchmark_group("primary");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    for n in SIZES {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        let list = AccelParams { kind: AccelKind::List, ..AccelParams::default() };
        for p in std::iter::once(list).chain(tree_params()) {
            let camera = if p.kind == AccelKind::List {
                scene.camera.with_resolution(64, 48)
            } else {
                scene.camera.with_resolution(256, 192)
            };
            let accel = BuiltAccel::build(&scene.spheres, &p);
            group.throughput(Throughput::Elements(camera.width as u64 * camera.height as u64));
            group.bench_function(BenchmarkId::new(label(&p), n), |b| {
                b.iter(|| black_box(accel.visit(Primary(&camera))))
            });
        }
    }
    group.finish();
}

/// Primary rays through the flat BVH (binned SAH, front to back) and the wide BVH (widths 4 and 8, leaf blocks of 8,
/// distance order, scalar and AVX2 kernels) at 1e3 and 1e5 spheres; ids `{structure}/{…}/{spheres}`.
///
/// The wide BVH's binary tree is the same binned SAH with leaves of up to 8 spheres (one block), its SAH counting
/// blocks. `cargo bench -p tracer --bench accel -- wide`.
fn wide(c: &mut Criterion) {
    let mut group = c.benchmark_group("wide");
    group.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    for n in [1_000, 100_000] {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        let camera = scene.camera.with_resolution(256, 192);
        group.throughput(Throughput::Elements(camera.width as u64 * camera.height as u64));
        let flat = BvhParams { split: Split::BinnedSah, traversal: Traversal::FrontToBack, ..BvhParams::default() };
        let accel = BuiltAccel::build(
            &scene.spheres,
            &AccelParams { kind: AccelKind::FlatBvh, bvh: flat, ..AccelParams::default() },
        );
        group.bench_function(BenchmarkId::new("flat-bvh/binned-sah/front-to-back", n), |b| {
            b.iter(|| black_box(accel.visit(Primary(&camera))))
        });
        let bvh = BvhParams { leaf_size: 8, ..flat };
        for width in WideParams::WIDTHS {
            let tree = WideBvh::build(
                &scene.spheres,
                &bvh,
                &WideParams { width, kernel: Kernel::Scalar, ..WideParams::default() },
            );
            for kernel in [Kernel::Scalar, Kernel::Avx2].into_iter().filter(|k| k.is_available()) {
                let tree = tree.clone().with_kernel(kernel).expect("available");
                let id = BenchmarkId::new(format!("wide-bvh/w{width}/b8/{}", kernel.name()), n);
                group.bench_function(id, |b| b.iter(|| black_box(Primary(&camera).visit(&tree))));
            }
        }
    }
    group.finish();
}

criterion_group!(benches, build, build_threads, primary, wide);
criterion_main!(benches);
