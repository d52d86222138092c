//! Every structure over triangles, with either test: the answers of brute force running the same test, bit for bit
//! (`t`), in every tree configuration, kernel, width, leaf block, order and packet shape; the same hits and work
//! counts whatever the kernel; deterministic trees. (Brute force itself against f64 is `agreement`'s to test.)

use tracer::accel::wide::{ChildOrdering, Kernel, WideBvh, WideParams, WidePrimitive};
use tracer::accel::{Accelerator, BvhParams, Hit, Split};
use tracer::counters::WorkCounters;
use tracer::geometry::{MollerTrumboreTriangle, Ray, Triangle, TrianglePrimitive, WatertightTriangle};
use tracer::render::PrimaryHits;
use tracer::testing::{self, TestMesh};

fn meshes() -> Vec<(TestMesh, Vec<Triangle>)> {
    testing::test_meshes()
        .into_iter()
        .map(|m| {
            let triangles = m.mesh.triangles().collect();
            (m, triangles)
        })
        .collect()
}

fn every_tree_agrees<T: TrianglePrimitive + WidePrimitive>() {
    for (mesh, triangles) in meshes() {
        testing::assert_every_tree_agrees_on_triangles::<T>(&mesh.label, &triangles, &mesh.rays);
    }
}

#[test]
fn every_structure_agrees_exactly_with_brute_force_moller_trumbore() {
    every_tree_agrees::<MollerTrumboreTriangle>();
}

#[test]
fn every_structure_agrees_exactly_with_brute_force_watertight() {
    every_tree_agrees::<WatertightTriangle>();
}

/// Answers and work counts of every ray, one at a time and in a batch (which must agree).
fn trace<P: WidePrimitive>(tree: &WideBvh<P>, rays: &[Ray]) -> Vec<(Option<Hit>, bool, WorkCounters, WorkCounters)> {
    let per_ray: Vec<_> = rays
        .iter()
        .map(|r| {
            let (mut closest, mut any) = (WorkCounters::default(), WorkCounters::default());
            (tree.intersect(r, &mut closest), tree.occluded(r, &mut any), closest, any)
        })
        .collect();
    let (mut hits, mut occluded) = (vec![PrimaryHits::MISS; rays.len()], vec![false; rays.len()]);
    tree.intersect_batch(rays, &mut hits, &mut WorkCounters::default());
    tree.occluded_batch(rays, &mut occluded, &mut WorkCounters::default());
    for (i, (hit, occ, ..)) in per_ray.iter().enumerate() {
        assert_eq!(hits[i], hit.unwrap_or(PrimaryHits::MISS), "batch answer of ray {i}");
        assert_eq!(occluded[i], *occ, "batch occlusion of ray {i}");
    }
    per_ray
}

fn kernels_agree<T: TrianglePrimitive + WidePrimitive>() {
    let kernels = Kernel::available();
    if kernels.len() == 1 {
        eprintln!("note: this CPU has neither AVX2 nor AVX-512; only the scalar kernel is tested");
    }
    for (mesh, triangles) in meshes().into_iter().filter(|(_, t)| t.len() > 100) {
        let prims = T::all(triangles);
        for width in WideParams::WIDTHS {
            for leaf_block in WideParams::LEAF_BLOCKS {
                for order in ChildOrdering::ALL {
                    let wide = WideParams { width, leaf_block, order, kernel: Kernel::Scalar, ..WideParams::default() };
                    let bvh = BvhParams { split: Split::BinnedSah, leaf_size: 8, ..BvhParams::default() };
                    let scalar = WideBvh::build(&prims, &bvh, &wide);
                    let want = trace(&scalar, &mesh.rays);
                    assert!(want.iter().filter(|w| w.0.is_some()).count() > mesh.rays.len() / 10, "{}", mesh.label);
                    for &kernel in &kernels[1..] {
                        let tree = scalar.clone().with_kernel(kernel).unwrap();
                        let got = trace(&tree, &mesh.rays);
                        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                            let label = &mesh.label;
                            assert!(g == w, "{label} {} {wide:?} {kernel:?} ray {i}: {g:?} vs scalar {w:?}", T::NAME);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn every_kernel_gives_the_same_hits_and_counts_moller_trumbore() {
    kernels_agree::<MollerTrumboreTriangle>();
}

#[test]
fn every_kernel_gives_the_same_hits_and_counts_watertight() {
    kernels_agree::<WatertightTriangle>();
}

/// The same mesh and parameters give the same tree, bit for bit.
#[test]
fn same_mesh_same_tree() {
    let (mesh, triangles) = meshes().swap_remove(0);
    let prims = WatertightTriangle::all(triangles);
    let (bvh, wide) = (BvhParams::default(), WideParams::default());
    let a = WideBvh::build(&prims, &bvh, &wide).tree_hash();
    let b = WideBvh::build(&prims, &bvh, &wide).tree_hash();
    assert_eq!(a, b, "{}", mesh.label);
}
