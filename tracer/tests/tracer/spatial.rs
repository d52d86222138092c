//! Spatial splits (`spatial-sah`): every structure built with them answers like f64-arbitrated brute force on the
//! test meshes and on long thin triangles; they duplicate references there (within the budget), never with
//! alpha = 1; the tree is deterministic; every leaf reference's box lies in its node's box, and the leaves' boxes
//! cover every triangle.

use glam::Vec3;
use rayon::ThreadPoolBuilder;
use tracer::accel::bvh::builder;
use tracer::accel::bvh::spatial::{self, DUPLICATE_BUDGET};
use tracer::accel::bvh::tree::{BuiltTree, FlatNode};
use tracer::accel::bvh::{SpatialAlpha, TreeStats};
use tracer::accel::wide::{WideBvh, WideParams};
use tracer::accel::{Accelerator, Bvh, BvhParams, FlatBvh, Split, Traversal};
use tracer::agreement::Strictness;
use tracer::geometry::{Aabb, Triangle, TrianglePrimitive, WatertightTriangle};
use tracer::rng::SplitMix64;
use tracer::scene::mesh::Mesh;
use tracer::testing::{self, Reference};

fn spatial(alpha: f32, leaf_size: u32) -> BvhParams {
    BvhParams {
        split: Split::SpatialSah,
        leaf_size,
        spatial_alpha: SpatialAlpha(alpha),
        traversal: Traversal::FrontToBack,
        ..BvhParams::default()
    }
}

/// `n` small triangles (side 0.1) in a box of side 10, every 20th replaced by a long thin one (length 12, width
/// 0.02) across the box in a random direction: the city-like case spatial splits are for.
fn thin_triangles(n: usize, seed: u64) -> Mesh {
    let mut rng = SplitMix64::new(seed);
    let mut f = |lo: f64, hi: f64| rng.range(lo, hi) as f32;
    let mut mesh = Mesh::default();
    for i in 0..n {
        let c = Vec3::new(f(0.0, 10.0), f(0.0, 10.0), f(0.0, 10.0));
        let d = Vec3::new(f(-1.0, 1.0), f(-1.0, 1.0), f(-1.0, 1.0)).normalize_or(Vec3::X);
        let (half, width) = if i % 20 == 0 { (6.0, 0.02) } else { (0.05, 0.1) };
        let side = d.any_orthonormal_vector() * width;
        mesh.positions.extend([c - d * half, c + d * half, c - d * half + side]);
        let v = 3 * i as u32;
        mesh.indices.push([v, v + 1, v + 2]);
    }
    mesh
}

fn prims(mesh: &Mesh) -> (Vec<Triangle>, Vec<WatertightTriangle>) {
    let triangles: Vec<Triangle> = mesh.triangles().collect();
    let prims = WatertightTriangle::all(triangles.iter().copied());
    (triangles, prims)
}

/// Flat, pointer and wide trees built with spatial splits against brute force.
fn assert_structures_agree(label: &str, mesh: &Mesh, rays: &[tracer::geometry::Ray], alpha: f32) {
    let (triangles, prims) = prims(mesh);
    let reference = Reference::triangles::<WatertightTriangle>(&triangles, rays);
    for leaf_size in [1, 4, 8] {
        let bvh = spatial(alpha, leaf_size);
        let what = format!("{label} alpha={alpha} leaf_size={leaf_size}");
        _ = reference.assert_agrees(&format!("{what} flat"), &FlatBvh::build(&prims, &bvh), Strictness::Arbitrated);
        _ = reference.assert_agrees(&format!("{what} pointer"), &Bvh::build(&prims, &bvh), Strictness::Arbitrated);
        for (width, leaf_block) in [(4, 4), (8, 8), (8, 16)] {
            let wide = WideParams { width, leaf_block, ..WideParams::default() };
            let tree = WideBvh::build(&prims, &bvh, &wide);
            _ = reference.assert_agrees(&format!("{what} wide {width}x{leaf_block}"), &tree, Strictness::Arbitrated);
        }
    }
}

#[test]
fn every_structure_agrees_with_brute_force_on_the_test_meshes() {
    for mesh in testing::test_meshes() {
        for alpha in [0.0, 1e-5] {
            assert_structures_agree(&mesh.label, &mesh.mesh, &mesh.rays, alpha);
        }
    }
}

#[test]
fn every_structure_agrees_with_brute_force_on_thin_triangles() {
    let mesh = thin_triangles(1_500, 3);
    let rays = testing::mesh_ray_mix(&mesh, 21, 3_000);
    for alpha in [0.0, 1e-5] {
        assert_structures_agree("thin triangles", &mesh, &rays, alpha);
    }
}

/// How often each primitive occurs in the tree.
fn occurrences<P>(tree: &BuiltTree<P>, n: usize) -> Vec<usize> {
    let mut seen = vec![0; n];
    tree.prim_order.iter().for_each(|&id| seen[id as usize] += 1);
    seen
}

#[test]
fn thin_triangles_are_duplicated_within_the_budget_and_lower_the_sah_cost() {
    let (_, prims) = prims(&thin_triangles(3_000, 5));
    let n = prims.len();
    let tree = builder::build(&prims, &spatial(1e-5, 4));
    let seen = occurrences(&tree, n);
    assert!(seen.iter().all(|&k| k >= 1), "every triangle in some leaf");
    let extra = tree.prim_order.len() - n;
    assert!(extra > n / 20, "only {extra} duplicates of {n} thin triangles");
    assert!(extra <= (n as f32 * DUPLICATE_BUDGET) as usize, "{extra} duplicates exceed the budget");
    for node in tree.nodes.iter().filter(|n| n.is_leaf()) {
        let mut ids = tree.prim_order[node.first as usize..(node.first + node.prim_count) as usize].to_vec();
        ids.sort_unstable();
        assert!(ids.windows(2).all(|w| w[0] != w[1]), "a leaf names a triangle twice: {ids:?}");
    }
    let cost = |split| -> TreeStats { FlatBvh::build(&prims, &BvhParams { split, ..spatial(1e-5, 4) }).stats() };
    let (binned, spatial) = (cost(Split::BinnedSah).sah_cost, cost(Split::SpatialSah).sah_cost);
    assert!(spatial < 0.8 * binned, "SAH cost {spatial} with spatial splits vs {binned} binned");
}

#[test]
fn alpha_one_makes_only_object_splits_the_binned_sahs() {
    let (_, prims) = prims(&thin_triangles(3_000, 5));
    for block in [1, 8] {
        let tree = builder::build_for_blocks(&prims, &spatial(1.0, 4), block);
        let mut order = tree.prim_order.clone();
        order.sort_unstable();
        assert!(order == (0..prims.len() as u32).collect::<Vec<_>>(), "alpha = 1 duplicated references");
        let binned =
            builder::build_for_blocks(&prims, &BvhParams { split: Split::BinnedSah, ..spatial(1.0, 4) }, block);
        assert!(tree.nodes == binned.nodes, "blocks of {block}: alpha = 1 is not the binned SAH's tree");
    }
}

#[test]
fn the_tree_is_deterministic_whatever_the_thread_count() {
    let (_, prims) = prims(&thin_triangles(5_000, 7));
    let pools = [1, 2].map(|t| ThreadPoolBuilder::new().num_threads(t).build().unwrap());
    let [a, b] = [&pools[0], &pools[1]].map(|p| p.install(|| builder::build_for_blocks(&prims, &spatial(1e-5, 4), 8)));
    let again = builder::build_for_blocks(&prims, &spatial(1e-5, 4), 8);
    assert!(a.nodes == b.nodes && a.prim_order == b.prim_order, "1 and 2 threads differ");
    assert!(a.nodes == again.nodes && a.prim_order == again.prim_order, "two builds differ");
}

fn inside(inner: &Aabb, outer: &Aabb) -> bool {
    inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all()
}

#[test]
fn reference_boxes_lie_in_their_nodes_and_leaves_cover_every_triangle() {
    let (triangles, prims) = prims(&thin_triangles(800, 9));
    for alpha in [0.0, 1e-5] {
        let (tree, boxes) = spatial::build_with_boxes(&prims, &spatial(alpha, 2), 1, 0);
        assert!(tree.prim_order.len() > prims.len(), "alpha {alpha}: no duplicates");
        for (i, node) in tree.nodes.iter().enumerate() {
            if node.prim_count == FlatNode::INTERIOR {
                for c in [node.first, node.first + 1] {
                    assert!(inside(&tree.nodes[c as usize].bounds, &node.bounds), "child {c} outside node {i}");
                }
                continue;
            }
            for b in &boxes[node.first as usize..(node.first + node.prim_count) as usize] {
                assert!(inside(b, &node.bounds), "reference box {b:?} outside leaf {i} {:?}", node.bounds);
            }
        }
        // Points of each triangle lie in the box of one of its references.
        let mut refs_of = vec![Vec::new(); prims.len()];
        for (k, &id) in tree.prim_order.iter().enumerate() {
            refs_of[id as usize].push(boxes[k]);
        }
        let mut rng = SplitMix64::new(1);
        for (id, t) in triangles.iter().enumerate() {
            for _ in 0..64 {
                let (mut b1, mut b2) = (rng.next_f64() as f32, rng.next_f64() as f32);
                if b1 + b2 > 1.0 {
                    (b1, b2) = (1.0 - b1, 1.0 - b2);
                }
                let p = t.p[0] + (t.p[1] - t.p[0]) * b1 + (t.p[2] - t.p[0]) * b2;
                assert!(refs_of[id].iter().any(|b| b.contains(p)), "alpha {alpha}: {p} of triangle {id} in no box");
            }
        }
    }
}
