//! The BVH build uses the threads of the rayon pool it runs in, and the tree is the same whatever their number:
//! built in 1-, 2- and 4-thread pools, every split rule × leaf sizes 1 and 4 × both layouts gives the same
//! nodes in the same order, the same primitive order, the same statistics and the same answers.
//!
//! The flat layout's nodes are the builder's nodes as they are; the pointer tree's leaves, in depth-first
//! order, are its primitive order. So the two tests together compare the builder's whole output.
//!
//! Nodes large enough to bin in parallel ([`PARALLEL_BIN_MIN_PRIMS`]) take a scene larger still: the binned SAH
//! alone builds one, and its whole output (nodes, primitive order, ordered spheres) is compared, and so is the
//! wide BVH collapsed from it (whose parallel collapse then has a top of several levels).

use rayon::{ThreadPool, ThreadPoolBuilder};
use tracer::accel::bvh::builder::{self, PARALLEL_MIN_PRIMS};
use tracer::accel::bvh::pointer::{BvhNode, BvhNodeKind};
use tracer::accel::bvh::split::binned_sah::PARALLEL_BIN_MIN_PRIMS;
use tracer::accel::wide::collapse::PARALLEL_COLLAPSE_MIN_PRIMS;
use tracer::accel::{Accelerator, Bvh, BvhParams, FlatBvh, Hit, Split, WideBvh, WideParams};
use tracer::counters::NoCounters;
use tracer::geometry::{Ray, Sphere};
use tracer::scene::SceneKind;
use tracer::testing::sphere_ray_mix;

/// Spheres per scene: several times the parallel threshold, so that the top levels split in parallel.
const SPHERES: usize = 40_000;
const _: () = assert!(SPHERES >= 8 * PARALLEL_MIN_PRIMS, "the scenes must be large enough to build in parallel");
const LEAF_SIZES: [u32; 2] = [1, 4];
/// The first pool (one thread) builds the reference.
const THREADS: [usize; 3] = [1, 2, 4];

fn pools() -> Vec<ThreadPool> {
    THREADS.iter().map(|&t| ThreadPoolBuilder::new().num_threads(t).build().unwrap()).collect()
}

struct Case {
    label: String,
    spheres: Vec<Sphere>,
    rays: Vec<Ray>,
}

fn cases() -> Vec<Case> {
    SceneKind::ALL
        .into_iter()
        .map(|kind| {
            let spheres = kind.generate(SPHERES, 3).spheres;
            let rays = sphere_ray_mix(&spheres, 9, 700);
            Case { label: kind.name().to_owned(), spheres, rays }
        })
        .collect()
}

fn every_params() -> Vec<BvhParams> {
    let mut all = Vec::new();
    for split in Split::ALL {
        for leaf_size in LEAF_SIZES {
            all.push(BvhParams { split, leaf_size, ..BvhParams::default() });
        }
    }
    all
}

fn answers<A: Accelerator>(accel: &A, rays: &[Ray]) -> Vec<(Option<Hit>, bool)> {
    rays.iter().map(|r| (accel.intersect(r, &mut NoCounters), accel.occluded(r, &mut NoCounters))).collect()
}

/// First difference between two pointer trees (bounds, shape, leaf primitives), by path from the root.
fn pointer_difference(a: &BvhNode, b: &BvhNode) -> Option<String> {
    let mut stack = vec![(a, b, String::from("root"))];
    while let Some((a, b, path)) = stack.pop() {
        if a.bounds != b.bounds {
            return Some(format!("{path}: bounds {:?} vs {:?}", a.bounds, b.bounds));
        }
        match (&a.kind, &b.kind) {
            (BvhNodeKind::Leaf { prims: pa }, BvhNodeKind::Leaf { prims: pb }) => {
                if pa != pb {
                    return Some(format!("{path}: leaf {pa:?} vs {pb:?}"));
                }
            }
            (BvhNodeKind::Interior { left: la, right: ra }, BvhNodeKind::Interior { left: lb, right: rb }) => {
                stack.push((ra, rb, format!("{path}.R")));
                stack.push((la, lb, format!("{path}.L")));
            }
            _ => return Some(format!("{path}: leaf vs interior")),
        }
    }
    None
}

#[test]
fn flat_bvh_is_the_same_in_1_2_and_4_thread_pools() {
    let pools = pools();
    for case in cases() {
        for params in every_params() {
            let what = format!("{} {params:?}", case.label);
            let built: Vec<_> = pools.iter().map(|p| p.install(|| FlatBvh::build(&case.spheres, &params))).collect();
            let reference = answers(&built[0], &case.rays);
            for (tree, threads) in built.iter().zip(THREADS).skip(1) {
                assert!(tree.nodes() == built[0].nodes(), "{what}: nodes differ with {threads} threads");
                assert_eq!(tree.stats(), built[0].stats(), "{what}: stats differ with {threads} threads");
                assert!(answers(tree, &case.rays) == reference, "{what}: answers differ with {threads} threads");
            }
        }
    }
}

#[test]
fn pointer_bvh_is_the_same_in_1_2_and_4_thread_pools() {
    let pools = pools();
    for case in cases() {
        for params in every_params() {
            let what = format!("{} {params:?}", case.label);
            let built: Vec<_> = pools.iter().map(|p| p.install(|| Bvh::build(&case.spheres, &params))).collect();
            let reference = answers(&built[0], &case.rays);
            for (tree, threads) in built.iter().zip(THREADS).skip(1) {
                if let Some(diff) = pointer_difference(tree.root(), built[0].root()) {
                    panic!("{what}: trees differ with {threads} threads at {diff}");
                }
                assert_eq!(tree.stats(), built[0].stats(), "{what}: stats differ with {threads} threads");
                assert!(answers(tree, &case.rays) == reference, "{what}: answers differ with {threads} threads");
            }
        }
    }
}

#[test]
fn binned_sah_is_the_same_when_large_nodes_bin_in_parallel() {
    // Twice the parallel binning threshold: the root bins in parallel in the 2- and 4-thread pools.
    let spheres = SceneKind::RandomSpheres.generate(2 * PARALLEL_BIN_MIN_PRIMS, 11).spheres;
    let params = BvhParams { split: Split::BinnedSah, leaf_size: 4, ..BvhParams::default() };
    let pools = pools();
    for block in [1, 8] {
        let built: Vec<_> =
            pools.iter().map(|p| p.install(|| builder::build_for_blocks(&spheres, &params, block))).collect();
        for (tree, threads) in built.iter().zip(THREADS).skip(1) {
            assert!(tree.nodes == built[0].nodes, "blocks of {block}: nodes differ with {threads} threads");
            assert!(tree.prim_order == built[0].prim_order, "blocks of {block}: order differs with {threads} threads");
            assert!(tree.ordered == built[0].ordered, "blocks of {block}: {threads} threads");
        }
    }
    // The wide tree over it collapses in parallel with a top several levels deep.
    const _: () = assert!(2 * PARALLEL_BIN_MIN_PRIMS >= 8 * PARALLEL_COLLAPSE_MIN_PRIMS);
    let wide = WideParams::default();
    let hashes: Vec<u64> =
        pools.iter().map(|p| p.install(|| WideBvh::build(&spheres, &params, &wide).tree_hash())).collect();
    assert!(hashes.iter().all(|&h| h == hashes[0]), "wide tree hashes {hashes:x?} in {THREADS:?}-thread pools");
}
