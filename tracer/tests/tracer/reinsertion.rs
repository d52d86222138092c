//! Reinsertion (`BvhParams::reinsertion`): every structure built from the optimized tree answers like brute force
//! on spheres and triangles; the SAH cost never increases and drops on the centroid-midpoint split's trees; the
//! result is a valid tree in the builder's layout with the same leaves; the pass is deterministic whatever the
//! thread count.

use rayon::ThreadPoolBuilder;
use tracer::accel::bvh::builder;
use tracer::accel::bvh::tree::{BuiltTree, MAX_DEPTH};
use tracer::accel::{AccelKind, AccelParams, BuiltAccel, BvhParams, Split};
use tracer::agreement::Strictness;
use tracer::geometry::{Aabb, Primitive, Sphere, Triangle, TrianglePrimitive, WatertightTriangle};
use tracer::scene::SceneKind;
use tracer::testing::{self, Reference};

/// Rounds the agreement tests build with.
const ROUNDS: u32 = 2;

/// Binary trees of every split × leaf sizes 1 and 4, both layouts, and every wide configuration, all with `rounds`.
fn configurations(rounds: u32) -> Vec<AccelParams> {
    let mut all = Vec::new();
    for kind in [AccelKind::Bvh, AccelKind::FlatBvh] {
        for split in Split::ALL {
            for leaf_size in [1, 4] {
                let bvh = BvhParams { split, leaf_size, reinsertion: rounds, ..BvhParams::default() };
                all.push(AccelParams { kind, bvh, ..AccelParams::default() });
            }
        }
    }
    for mut wide in testing::every_wide() {
        wide.bvh.reinsertion = rounds;
        all.push(wide);
    }
    all
}

#[test]
fn every_structure_with_reinsertion_agrees_with_brute_force_on_spheres() {
    for scene in testing::scenes() {
        let reference = Reference::new(&scene.spheres, &scene.rays);
        for params in configurations(ROUNDS) {
            let accel = BuiltAccel::build(&scene.spheres, &params);
            reference.assert_built_agrees(&format!("{} {params:?}", scene.label), &accel, Strictness::Identical);
        }
    }
}

#[test]
fn every_structure_with_reinsertion_agrees_with_brute_force_on_triangles() {
    for mesh in testing::test_meshes() {
        let triangles: Vec<Triangle> = mesh.mesh.triangles().collect();
        let prims = WatertightTriangle::all(triangles.iter().copied());
        let reference = Reference::triangles::<WatertightTriangle>(&triangles, &mesh.rays);
        for params in configurations(ROUNDS) {
            let accel = BuiltAccel::build(&prims, &params);
            reference.assert_built_agrees(&format!("{} {params:?}", mesh.label), &accel, Strictness::Arbitrated);
        }
    }
}

/// The flat BVH's reported SAH cost of `prims` under `bvh`.
fn sah_cost<P: tracer::accel::wide::WidePrimitive>(prims: &[P], bvh: BvhParams) -> f64 {
    BuiltAccel::build(prims, &AccelParams { kind: AccelKind::FlatBvh, bvh, ..AccelParams::default() }).stats().sah_cost
}

#[test]
fn the_sah_cost_never_increases_and_drops_on_midpoint_trees() {
    let mesh: Vec<Triangle> = testing::test_meshes().swap_remove(0).mesh.triangles().collect();
    let triangles = WatertightTriangle::all(mesh.iter().copied());
    for kind in SceneKind::ALL {
        let spheres = kind.generate(3000, 5).spheres;
        for split in Split::ALL {
            for leaf_size in [1, 4, 8] {
                let label = format!("{} {split:?} leaf {leaf_size}", kind.name());
                let bvh = BvhParams { split, leaf_size, ..BvhParams::default() };
                let costs: Vec<f64> =
                    [0, 1, 2, 8].map(|reinsertion| sah_cost(&spheres, BvhParams { reinsertion, ..bvh })).into();
                assert!(costs.windows(2).all(|w| w[1] <= w[0]), "{label}: costs by rounds {costs:?}");
                if split == Split::CentroidMidpoint {
                    assert!(costs[1] < costs[0], "{label}: a round lowers the cost: {costs:?}");
                    if leaf_size == 1 {
                        // Leaves stay as they are, so the gain is largest where interior nodes weigh most.
                        assert!(costs[2] < 0.97 * costs[0], "{label}: two rounds lower the cost by 3%: {costs:?}");
                    }
                }
                let on_mesh = [0, 2].map(|reinsertion| sah_cost(&triangles, BvhParams { reinsertion, ..bvh }));
                assert!(on_mesh[1] <= on_mesh[0], "{label} on triangles: {on_mesh:?}");
            }
        }
    }
}

/// Panics unless `tree` is laid out as the builder lays trees out, over every primitive of `prims` once (at least
/// once where `split` repeats primitives in several leaves: spatial splits), with boxes that hold their children and
/// primitives; returns its leaves as (primitive ids, box), sorted.
fn check_layout<P: Primitive + PartialEq>(
    label: &str,
    split: Split,
    tree: &BuiltTree<P>,
    prims: &[P],
) -> Vec<(Vec<u32>, [u32; 6])> {
    let nodes = &tree.nodes;
    let repeats = split == Split::SpatialSah;
    assert!(tree.prim_order.len() == prims.len() || repeats && tree.prim_order.len() > prims.len(), "{label}");
    assert_eq!(tree.ordered.len(), tree.prim_order.len(), "{label}");
    let mut seen = vec![false; prims.len()];
    for (k, &id) in tree.prim_order.iter().enumerate() {
        assert!(!std::mem::replace(&mut seen[id as usize], true) || repeats, "{label}: primitive {id} twice");
        assert!(tree.ordered[k] == prims[id as usize], "{label}: ordered[{k}] is not primitive {id}");
    }
    assert!(seen.iter().all(|&s| s), "{label}: every primitive in some leaf");
    // Replays the builder's allocation: children pairs handed out in depth-first order, runs in leaf order.
    let (mut next_pair, mut next_prim, mut leaves) = (1usize, 0u32, Vec::new());
    let mut stack = vec![(0usize, 0usize)];
    while let Some((index, depth)) = stack.pop() {
        let node = nodes[index];
        assert!(depth < MAX_DEPTH, "{label}: node {index} at depth {depth}");
        if node.is_leaf() {
            assert_eq!(node.first, next_prim, "{label}: leaf {index}'s run is not next in leaf order");
            next_prim += node.prim_count;
            let ids = tree.prim_order[node.first as usize..next_prim as usize].to_vec();
            if repeats {
                // A spatial split's leaf holds the parts of its primitives clipped to it: it meets each one's box.
                for &id in &ids {
                    let b = prims[id as usize].bounds();
                    let meets = b.min.cmple(node.bounds.max).all() && node.bounds.min.cmple(b.max).all();
                    assert!(meets, "{label}: leaf {index} does not meet primitive {id}");
                }
            } else {
                let held = ids.iter().map(|&id| prims[id as usize].bounds()).fold(Aabb::EMPTY, |a, b| a.union(&b));
                assert_eq!(node.bounds.union(&held), node.bounds, "{label}: leaf {index} does not hold its primitives");
            }
            let mut sorted = ids;
            sorted.sort_unstable();
            let b = node.bounds;
            leaves.push((sorted, [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits)));
        } else {
            let first = node.first as usize;
            assert_eq!(first, next_pair, "{label}: node {index}'s children are not the next pair");
            next_pair += 2;
            let union = nodes[first].bounds.union(&nodes[first + 1].bounds);
            // A spatial split's node keeps the box it was split in, which holds its children's clipped boxes.
            let holds = if repeats { node.bounds.union(&union) == node.bounds } else { node.bounds == union };
            assert!(holds, "{label}: node {index}'s box {:?} is not its children's {union:?}", node.bounds);
            stack.push((first + 1, depth + 1));
            stack.push((first, depth + 1));
        }
    }
    assert_eq!(next_pair, nodes.len(), "{label}: every node reached once");
    assert_eq!(next_prim as usize, tree.prim_order.len(), "{label}: every reference in a leaf");
    leaves.sort_unstable();
    leaves
}

#[test]
fn the_optimized_tree_is_a_valid_layout_with_the_same_leaves() {
    let mesh: Vec<Triangle> = testing::test_meshes().swap_remove(2).mesh.triangles().collect();
    let triangles = WatertightTriangle::all(mesh.iter().copied());
    for kind in SceneKind::ALL {
        let spheres = kind.generate(2000, 9).spheres;
        for split in Split::ALL {
            for leaf_size in [1, 4] {
                let label = format!("{} {split:?} leaf {leaf_size}", kind.name());
                let bvh = BvhParams { split, leaf_size, ..BvhParams::default() };
                let optimized = BvhParams { reinsertion: 4, ..bvh };
                let before = check_layout(&label, split, &builder::build(&spheres, &bvh), &spheres);
                let tree = builder::build(&spheres, &optimized);
                assert_eq!(check_layout(&label, split, &tree, &spheres), before, "{label}: the same leaves");
                let blocks = builder::build_for_blocks(&triangles, &optimized, 8);
                let before = check_layout(&label, split, &builder::build_for_blocks(&triangles, &bvh, 8), &triangles);
                assert_eq!(
                    check_layout(&label, split, &blocks, &triangles),
                    before,
                    "{label} triangles: the same leaves"
                );
            }
        }
    }
}

#[test]
fn reinsertion_moves_subtrees_of_midpoint_trees() {
    let spheres = SceneKind::ClusteredSpheres.generate(3000, 2).spheres;
    let bvh = BvhParams { leaf_size: 4, ..BvhParams::default() };
    let (plain, optimized) =
        (builder::build(&spheres, &bvh), builder::build(&spheres, &BvhParams { reinsertion: 1, ..bvh }));
    assert_eq!(plain.nodes.len(), optimized.nodes.len());
    assert_ne!(plain.prim_order, optimized.prim_order, "the leaf order changes");
    let zero = builder::build(&spheres, &BvhParams { reinsertion: 0, ..bvh });
    assert_eq!((zero.nodes, zero.prim_order), (plain.nodes, plain.prim_order), "0 rounds: the builder's tree");
}

#[test]
fn reinsertion_is_deterministic_whatever_the_thread_count() {
    let spheres: Vec<Sphere> = SceneKind::RandomSpheres.generate(3 * builder::PARALLEL_MIN_PRIMS, 4).spheres;
    for split in [Split::CentroidMidpoint, Split::BinnedSah] {
        let bvh = BvhParams { split, leaf_size: 4, reinsertion: 3, ..BvhParams::default() };
        let trees: Vec<BuiltTree> = [1, 2, 1]
            .map(|threads| {
                let pool = ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| builder::build(&spheres, &bvh))
            })
            .into();
        for t in &trees[1..] {
            assert_eq!(t.nodes, trees[0].nodes, "{split:?}: nodes");
            assert_eq!(t.prim_order, trees[0].prim_order, "{split:?}: primitive order");
        }
    }
}

#[test]
fn rounds_outside_the_range_are_refused() {
    let with = |reinsertion| BvhParams { reinsertion, ..BvhParams::default() }.validate();
    let last = *BvhParams::REINSERTION_ROUNDS.end();
    assert_eq!(with(last + 1).unwrap_err().key, "reinsertion");
    assert!(with(0).is_ok() && with(1).is_ok() && with(last).is_ok());
}
