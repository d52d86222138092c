//! Build time and single-thread primary-ray throughput of every structure and split at 1e3, 1e4, 1e5 spheres.
//!
//! `cargo bench -p tracer --bench accel` (criterion reports primary throughput as elements/s = rays/s).
//! The scene is random-spheres seed 1; the primary image is 256×192 for trees and 64×48 for the list.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use tracer::accel::{AccelKind, AccelParams, AccelVisitor, Accelerator, BuiltAccel, BvhParams, Split, Traversal};
use tracer::counters::NoCounters;
use tracer::executor::Strategy;
use tracer::render::trace_primary;
use tracer::scene::{Camera, SceneKind};

const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

fn tree_params() -> Vec<AccelParams> {
    let mut all = Vec::new();
    for split in Split::ALL {
        all.push(AccelParams { kind: AccelKind::Bvh, bvh: BvhParams { split, ..BvhParams::default() } });
        for traversal in Traversal::ALL {
            all.push(AccelParams { kind: AccelKind::FlatBvh, bvh: BvhParams { split, traversal, ..BvhParams::default() } });
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

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    for n in SIZES {
        let scene = SceneKind::RandomSpheres.generate(n, 1);
        group.throughput(Throughput::Elements(n as u64));
        for p in tree_params().into_iter().filter(|p| p.bvh.traversal == Traversal::Fixed) {
            group.bench_with_input(BenchmarkId::new(label(&p), n), &p, |b, p| {
                b.iter(|| black_box(BuiltAccel::build(&scene.spheres, p)))
            });
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
            let camera = if p.kind == AccelKind::List { scene.camera.with_resolution(64, 48) } else { scene.camera.with_resolution(256, 192) };
            let accel = BuiltAccel::build(&scene.spheres, &p);
            group.throughput(Throughput::Elements(camera.width as u64 * camera.height as u64));
            group.bench_function(BenchmarkId::new(label(&p), n), |b| b.iter(|| black_box(accel.visit(Primary(&camera)))));
        }
    }
    group.finish();
}

criterion_group!(benches, build, primary);
criterion_main!(benches);
