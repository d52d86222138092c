//! The builder's output is pinned: FNV-1a hashes of nodes and primitive order for every split rule over random,
//! clustered and degenerate scenes, built in 1- and 2-thread pools. Speed work on the builder must keep every
//! tree bit-identical; a change that moves one bound's bits or one primitive fails here.
//!
//! The expected hashes were recorded from commit 397de82 (before the single-pass binning and the permuted
//! per-primitive data), with `PIN_PRINT=1 cargo test --release -p tracer --test build_pinned -- --nocapture`.

use glam::Vec3;
use rayon::ThreadPoolBuilder;
use tracer::accel::bvh::builder::build_in_blocks;
use tracer::accel::bvh::tree::BuiltTree;
use tracer::accel::{BvhParams, Split};
use tracer::fingerprint::Fnv64;
use tracer::geometry::Sphere;
use tracer::rng::SplitMix64;
use tracer::scene::SceneKind;

/// FNV-1a over every node's bounds bits, `first` and `prim_count`, then the primitive order.
fn tree_hash(tree: &BuiltTree) -> u64 {
    let mut h = Fnv64::default();
    for n in &tree.nodes {
        for v in [n.bounds.min, n.bounds.max] {
            h.f32(v.x).f32(v.y).f32(v.z);
        }
        h.u32(n.first).u32(n.prim_count);
    }
    for &p in &tree.prim_order {
        h.u32(p);
    }
    h.finish()
}

/// Named scenes: both generators at two sizes (the larger one splits in parallel), and degenerate inputs.
fn scenes() -> Vec<(String, Vec<Sphere>)> {
    let mut all = Vec::new();
    for kind in SceneKind::ALL {
        for (n, seed) in [(3_000, 5), (20_000, 11)] {
            all.push((format!("{} n={n}", kind.name()), kind.generate(n, seed).spheres));
        }
    }
    // Coincident centers (no split plane anywhere), and centers on a line with repeats (zero extent on two axes).
    all.push(("coincident".into(), vec![Sphere::new(Vec3::new(1.0, 2.0, 3.0), 0.5); 300]));
    let mut rng = SplitMix64::new(3);
    let line = (0..5_000)
        .map(|i| Sphere::new(Vec3::new((i % 37) as f32 * 0.25, -1.0, 2.0), 0.1 + rng.next_f64() as f32))
        .collect();
    all.push(("line".into(), line));
    all
}

/// Every split × leaf sizes 1, 4, 8; binned SAH also with 2 and 64 bins; the SAH splits also in blocks of 8. Spatial
/// splits (added after the recording, built by their own serial builder) are pinned by `tests/spatial.rs`'s
/// determinism test instead.
fn cases() -> Vec<(BvhParams, u32)> {
    let mut all = Vec::new();
    for split in Split::ALL.into_iter().filter(|&s| s != Split::SpatialSah) {
        for leaf_size in [1, 4, 8] {
            let bins: &[u32] = if split == Split::BinnedSah { &[2, 16, 64] } else { &[16] };
            for &sah_bins in bins {
                let p = BvhParams { split, leaf_size, sah_bins, ..BvhParams::default() };
                all.push((p, 1));
                if split.is_sah() && leaf_size == 8 {
                    all.push((p, 8));
                }
            }
        }
    }
    all
}

/// Combined hash per scene (over every case, in order), recorded at 397de82.
const EXPECTED: [u64; 6] = [
    0xd1ca2b53cfad3da0,
    0x6b7e974686d8e37c,
    0xffa79d69180458f7,
    0x5b8d9cf6f09c9594,
    0x04d3885a94b99e0d,
    0x1c233038cda7d02e,
];

#[test]
fn every_tree_is_bit_identical_to_the_recorded_one() {
    let pools = [1, 2].map(|t| ThreadPoolBuilder::new().num_threads(t).build().unwrap());
    let print = std::env::var_os("PIN_PRINT").is_some();
    let mut failures = Vec::new();
    for ((label, spheres), expected) in scenes().into_iter().zip(EXPECTED) {
        let mut combined = Fnv64::default();
        for (params, block) in cases() {
            let serial = pools[0].install(|| tree_hash(&build_in_blocks(&spheres, &params, block)));
            let parallel = pools[1].install(|| tree_hash(&build_in_blocks(&spheres, &params, block)));
            assert_eq!(serial, parallel, "{label} {params:?} block {block}: 1 and 2 threads differ");
            combined.bytes(&serial.to_le_bytes());
        }
        if print {
            println!("{label}: {:#018x}", combined.finish());
        } else if combined.finish() != expected {
            failures.push(format!("{label}: {:#018x}, recorded {expected:#018x}", combined.finish()));
        }
    }
    assert!(failures.is_empty(), "trees changed:\n{}", failures.join("\n"));
}
