//! The wide BVH: bit-identical answers to brute force for every width × leaf block × order × kernel this CPU has,
//! the same work counts whatever the kernel, deterministic trees, and clear refusals of kernels the CPU lacks.
//!
//! (Every wide configuration is also in `testing::every_tree`, so the agreement, degenerate and ray-set tests cover
//! it under their tolerance.)

use glam::Vec3;
use tracer::accel::bvh::builder;
use tracer::accel::wide::collapse::{PARALLEL_COLLAPSE_MIN_PRIMS, collapse};
use tracer::accel::wide::leaf::SphereBlock;
use tracer::accel::wide::{ChildOrdering, Kernel, WideBvh, WideParams};
use tracer::accel::{AccelKind, AccelParams, Accelerator, BuiltAccel, BvhParams, Hit, Split};
use tracer::agreement::Strictness;
use tracer::counters::{NoCounters, WorkCounters};
use tracer::executor::Strategy;
use tracer::geometry::{Ray, Sphere};
use tracer::rays::RaySet;
use tracer::render::{PrimaryHits, RenderSettings, render};
use tracer::scene::SceneKind;
use tracer::testing::{self, Reference};

/// Every wide configuration this CPU runs, built over `spheres`, with its parameters.
fn every_wide(spheres: &[Sphere]) -> impl Iterator<Item = (AccelParams, WideBvh)> + '_ {
    testing::every_wide().into_iter().map(|p| (p, WideBvh::build(spheres, &p.bvh, &p.wide)))
}

fn note_missing_kernels() {
    for kernel in [Kernel::Avx2, Kernel::Avx512] {
        if !kernel.is_available() {
            eprintln!("note: this CPU lacks {}; its kernel is not tested here", kernel.name());
        }
    }
}

/// Wide trees call no ray-sphere test of their own design: their `t` is brute force's, bit for bit.
#[test]
fn every_configuration_agrees_exactly_with_brute_force_on_the_test_scenes() {
    note_missing_kernels();
    for scene in testing::scenes() {
        let reference = Reference::new(&scene.spheres, &scene.rays);
        for (p, tree) in every_wide(&scene.spheres) {
            reference.assert_agrees(&format!("{} {:?} {:?}", scene.label, p.wide, p.bvh), &tree, Strictness::Identical);
        }
    }
}

#[test]
fn degenerate_scenes_agree_exactly() {
    let same: Vec<Sphere> = (0..100).map(|_| Sphere::new(Vec3::new(1.0, 2.0, 3.0), 0.5)).collect();
    let nested: Vec<Sphere> = (1..=100).map(|i| Sphere::new(Vec3::new(1.0, 2.0, 3.0), i as f32 * 0.1)).collect();
    let mut extreme: Vec<Sphere> =
        (0..50).map(|i| Sphere::new(Vec3::new(i as f32, 0.5, -10.0 - i as f32), 1e-5)).collect();
    extreme.push(Sphere::new(Vec3::ZERO, 1e6));
    extreme.push(Sphere::new(Vec3::new(3.0, 1e4, -2.0), 1e3));
    let deep: Vec<Sphere> = (0..120).map(|i| Sphere::new(Vec3::new(1.3f32.powi(i), 0.0, 0.0), 0.01)).collect();
    let cases: [(&str, Vec<Sphere>); 6] = [
        ("empty", vec![]),
        ("one sphere", vec![Sphere::new(Vec3::new(0.0, 1.0, -5.0), 1.0)]),
        ("coincident", same),
        ("concentric", nested),
        ("extreme radii", extreme),
        ("exponential", deep),
    ];
    for (label, spheres) in &cases {
        let rays = testing::sphere_ray_mix(spheres, 7, 400);
        let reference = Reference::new(spheres, &rays);
        for (p, tree) in every_wide(spheres) {
            reference.assert_agrees(&format!("{label} {:?} {:?}", p.wide, p.bvh), &tree, Strictness::Identical);
            if spheres.is_empty() {
                let s = tree.stats();
                assert_eq!((s.nodes, s.leaves, s.depth), (1, 0, 0), "an empty tree is a root without children");
            }
        }
    }
}

/// Answers and work counts of every ray, one at a time and in a batch (which must agree).
fn trace(tree: &WideBvh, rays: &[Ray]) -> Vec<(Option<Hit>, bool, WorkCounters, WorkCounters)> {
    let per_ray: Vec<_> = rays
        .iter()
        .map(|r| {
            let (mut closest, mut any) = (WorkCounters::default(), WorkCounters::default());
            let hit = tree.intersect(r, &mut closest);
            let occluded = tree.occluded(r, &mut any);
            (hit, occluded, closest, any)
        })
        .collect();
    let (mut hits, mut occluded) = (vec![PrimaryHits::MISS; rays.len()], vec![false; rays.len()]);
    let (mut closest, mut any) = (WorkCounters::default(), WorkCounters::default());
    tree.intersect_batch(rays, &mut hits, &mut closest);
    tree.occluded_batch(rays, &mut occluded, &mut any);
    let mut sum = (WorkCounters::default(), WorkCounters::default());
    for (i, (hit, occ, c, a)) in per_ray.iter().enumerate() {
        assert_eq!(hits[i], hit.unwrap_or(PrimaryHits::MISS), "batch answer of ray {i}");
        assert_eq!(occluded[i], *occ, "batch occlusion of ray {i}");
        sum.0 += *c;
        sum.1 += *a;
    }
    assert_eq!((closest.rays, any.rays), (rays.len() as u64, rays.len() as u64));
    assert_eq!(
        (closest.nodes_visited, closest.box_tests, closest.prim_tests),
        (sum.0.nodes_visited, sum.0.box_tests, sum.0.prim_tests)
    );
    assert_eq!(
        (any.nodes_visited, any.box_tests, any.prim_tests),
        (sum.1.nodes_visited, sum.1.box_tests, sum.1.prim_tests)
    );
    per_ray
}

#[test]
fn every_kernel_gives_the_same_hits_and_counts_on_the_same_tree() {
    note_missing_kernels();
    let kernels = Kernel::available();
    for scene in testing::scenes().into_iter().filter(|s| s.spheres.len() >= 50) {
        for width in WideParams::WIDTHS {
            for leaf_block in WideParams::LEAF_BLOCKS {
                for order in ChildOrdering::ALL {
                    let wide = WideParams { width, leaf_block, order, kernel: Kernel::Scalar, ..WideParams::default() };
                    let bvh = BvhParams { split: Split::BinnedSah, leaf_size: 8, ..BvhParams::default() };
                    let scalar = WideBvh::build(&scene.spheres, &bvh, &wide);
                    let want = trace(&scalar, &scene.rays);
                    assert!(want.iter().any(|w| w.2.prim_tests > 0));
                    for &kernel in &kernels[1..] {
                        let tree = scalar.clone().with_kernel(kernel).unwrap();
                        assert_eq!(tree.kernel(), kernel);
                        let got = trace(&tree, &scene.rays);
                        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                            assert!(g == w, "{} {wide:?} {kernel:?} ray {i}: {g:?} vs scalar {w:?}", scene.label);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn same_seed_same_tree_and_counts_in_any_thread_count() {
    // Enough spheres to collapse in parallel below the root.
    const SPHERES: usize = 12_000;
    const _: () = assert!(SPHERES >= PARALLEL_COLLAPSE_MIN_PRIMS);
    let spheres = SceneKind::RandomSpheres.generate(SPHERES, 5).spheres;
    let rays = testing::sphere_ray_mix(&spheres, 3, 500);
    let bvh = BvhParams { split: Split::BinnedSah, leaf_size: 4, ..BvhParams::default() };
    let pool = |t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
    for wide in [
        WideParams::default(),
        WideParams {
            width: 4,
            leaf_block: 16,
            kernel: Kernel::Scalar,
            order: ChildOrdering::Octant,
            packet: 8,
            ..WideParams::default()
        },
    ] {
        let trees: Vec<WideBvh> = [1, 2, 1].map(|t| pool(t).install(|| WideBvh::build(&spheres, &bvh, &wide))).into();
        let counts = |t: &WideBvh| {
            let mut c = WorkCounters::default();
            t.intersect_batch(&rays, &mut vec![PrimaryHits::MISS; rays.len()], &mut c);
            c
        };
        for t in &trees[1..] {
            assert_eq!(t.tree_hash(), trees[0].tree_hash(), "{wide:?}");
            assert_eq!(t.stats(), trees[0].stats());
            assert_eq!(counts(t), counts(&trees[0]));
        }
        let other = WideBvh::build(&SceneKind::RandomSpheres.generate(SPHERES, 6).spheres, &bvh, &wide);
        assert_ne!(other.tree_hash(), trees[0].tree_hash());
    }
}

#[test]
fn a_kernel_the_cpu_lacks_is_refused_at_validation_and_build() {
    let spheres = SceneKind::RandomSpheres.generate(100, 1).spheres;
    for kernel in [Kernel::Avx2, Kernel::Avx512] {
        let wide = WideParams { kernel, ..WideParams::default() };
        let built = WideBvh::try_build(&spheres, &BvhParams::default(), &wide);
        if kernel.is_available() {
            assert_eq!(built.unwrap().kernel_name(), kernel.name());
            continue;
        }
        eprintln!("note: checking that {} is refused (this CPU lacks it)", kernel.name());
        let e = built.unwrap_err();
        assert_eq!(e.key, "kernel");
        assert_eq!(wide.validate().unwrap_err(), e);
        let scalar = WideBvh::build(&spheres, &BvhParams::default(), &WideParams { kernel: Kernel::Scalar, ..wide });
        assert!(scalar.with_kernel(kernel).is_err());
        let params = AccelParams { kind: AccelKind::WideBvh, wide, ..AccelParams::default() };
        let panic = std::panic::catch_unwind(|| BuiltAccel::build(&spheres, &params)).unwrap_err();
        let message = panic.downcast_ref::<String>().unwrap();
        assert!(message.contains(&format!("kernel = {}", kernel.name())) && message.contains("lacks"), "{message}");
    }
}

#[test]
fn auto_runs_the_kernel_measured_fastest_for_its_leaf_block() {
    let spheres = SceneKind::RandomSpheres.generate(10, 1).spheres;
    let simd = |name: &str| Kernel::available().iter().any(|k| k.name() == name);
    for (leaf_block, want) in [(4, "avx2"), (8, "avx2"), (16, "avx512")] {
        let wide = WideParams { leaf_block, ..WideParams::default() };
        let tree =
            BuiltAccel::build(&spheres, &AccelParams { kind: AccelKind::WideBvh, wide, ..AccelParams::default() });
        // The widest kernel where it is measured fastest; AVX2 where the AVX-512 kernel is not; scalar without either.
        let ran = [want, "avx2", "scalar"].into_iter().find(|k| simd(k)).unwrap();
        assert_eq!(tree.kernel_name(), Some(ran), "blocks of {leaf_block}");
    }
    assert_eq!(BuiltAccel::build(&spheres, &AccelParams::default()).kernel_name(), None);
}

#[test]
fn a_scene_behind_the_ray_costs_the_root_only() {
    let spheres = SceneKind::RandomSpheres.generate(500, 2).spheres; // all at z < -7
    let ray = Ray::new(Vec3::new(0.0, 0.0, 10.0), Vec3::Z);
    for (p, tree) in every_wide(&spheres) {
        let mut c = WorkCounters::default();
        assert!(tree.intersect(&ray, &mut c).is_none());
        assert_eq!((c.nodes_visited, c.box_tests, c.prim_tests), (1, p.wide.width as u64, 0), "{p:?}");
    }
}

#[test]
fn counters_count_real_spheres_not_padding() {
    // Five spheres in a row along the ray: one leaf (five real lanes in one or two blocks); every sphere is tested.
    let spheres: Vec<Sphere> = (0..5).map(|i| Sphere::new(Vec3::new(0.0, 0.0, -3.0 * i as f32 - 5.0), 1.0)).collect();
    let ray = Ray::new(Vec3::ZERO, -Vec3::Z);
    for leaf_block in WideParams::LEAF_BLOCKS {
        let wide = WideParams { leaf_block, ..WideParams::default() };
        let tree = WideBvh::build(&spheres, &BvhParams { leaf_size: 8, ..BvhParams::default() }, &wide);
        let mut c = WorkCounters::default();
        assert_eq!(tree.intersect(&ray, &mut c), Some(Hit { t: 4.0, prim: 0 }));
        assert_eq!((c.nodes_visited, c.box_tests, c.prim_tests), (1, 1, 5), "block {leaf_block}");
        assert_eq!(tree.stats().leaves, 1);
    }
}

#[test]
fn wide_trees_render_the_same_image_as_brute_force() {
    let mut scene = SceneKind::ClusteredSpheres.generate(600, 11);
    scene.camera = scene.camera.with_resolution(72, 45);
    let list = tracer::accel::List::build(&scene.spheres);
    let (reference, _) = render::<_, NoCounters>(&scene, &list, &RenderSettings::default(), &Strategy::SERIAL);
    for (p, tree) in every_wide(&scene.spheres).step_by(5) {
        let (image, _) = render::<_, NoCounters>(&scene, &tree, &RenderSettings::default(), &Strategy::SERIAL);
        assert_eq!(image.hash(), reference.hash(), "{p:?}");
    }
}

/// Tile packets of primary rays (8×8 tiles, the order of `RaySet::primary`) answer each ray exactly as it answers
/// alone, count the same work with every kernel, and share it: the frustum and the ranged tests box-test fewer
/// boxes per ray than packets of 16 rays with a mask, which test every ray at every node.
#[test]
fn tile_packets_answer_like_single_rays_and_share_their_box_tests() {
    let mut scene = SceneKind::RandomSpheres.generate(2000, 5);
    scene.camera = scene.camera.with_resolution(256, 192);
    let rays = RaySet::primary(&scene).rays;
    let bvh = BvhParams { split: Split::BinnedSah, leaf_size: 4, ..BvhParams::default() };
    let batch = |wide: WideParams, kernel: Kernel| {
        let tree = WideBvh::build(&scene.spheres, &bvh, &WideParams { kernel, ..wide });
        let (mut hits, mut counters) = (vec![PrimaryHits::MISS; rays.len()], WorkCounters::default());
        tree.intersect_batch(&rays, &mut hits, &mut counters);
        let (mut occluded, mut any) = (vec![false; rays.len()], WorkCounters::default());
        tree.occluded_batch(&rays, &mut occluded, &mut any);
        (hits, occluded, counters, any)
    };
    let single = batch(WideParams::default(), Kernel::Scalar);
    assert!(single.0.iter().filter(|h| h.prim != PrimaryHits::MISS.prim).count() > rays.len() / 4);
    for width in WideParams::WIDTHS {
        let wide = |packet| WideParams { width, packet, ..WideParams::default() };
        let tiles = batch(wide(64), Kernel::Scalar);
        assert!(tiles.0 == single.0 && tiles.1 == single.1, "width {width}: tile packets answer as single rays");
        for &kernel in &Kernel::available()[1..] {
            let got = batch(wide(64), kernel);
            assert!(got == tiles, "width {width} {kernel:?}: the scalar kernel's answers and counts");
        }
        let packets = batch(wide(16), Kernel::Scalar);
        let per_ray = |c: &WorkCounters| c.box_tests as f64 / c.rays as f64;
        for (query, tile, packet) in [("closest", &tiles.2, &packets.2), ("any", &tiles.3, &packets.3)] {
            assert!(
                per_ray(tile) * 2.0 < per_ray(packet),
                "width {width} {query}: {:.1} box tests per ray in tiles, {:.1} in packets of 16",
                per_ray(tile),
                per_ray(packet)
            );
        }
    }
}

#[test]
fn wide_trees_visit_fewer_nodes_than_the_binary_tree() {
    let spheres = SceneKind::RandomSpheres.generate(5000, 3).spheres;
    let rays = testing::sphere_ray_mix(&spheres, 1, 2000);
    let bvh = BvhParams { split: Split::BinnedSah, leaf_size: 4, ..BvhParams::default() };
    let count = |a: &dyn Fn(&Ray, &mut WorkCounters)| {
        let mut c = WorkCounters::default();
        rays.iter().for_each(|r| a(r, &mut c));
        c
    };
    let flat = tracer::accel::FlatBvh::build(&spheres, &bvh);
    let binary = count(&|r, c| _ = flat.intersect(r, c));
    for width in WideParams::WIDTHS {
        let tree = WideBvh::build(&spheres, &bvh, &WideParams { width, ..WideParams::default() });
        let wide = count(&|r, c| _ = tree.intersect(r, c));
        assert!(wide.nodes_visited * 2 < binary.nodes_visited, "width {width}: {wide:?} vs binary {binary:?}");
    }
}

#[test]
fn the_sah_in_blocks_of_one_is_the_ordinary_sah_and_wider_blocks_make_bigger_leaves() {
    let spheres = SceneKind::ClusteredSpheres.generate(3000, 2).spheres;
    for split in [Split::BinnedSah, Split::SweepSah] {
        let bvh = BvhParams { split, leaf_size: 16, ..BvhParams::default() };
        let (plain, one) = (builder::build(&spheres, &bvh), builder::build_in_blocks(&spheres, &bvh, 1));
        assert!(plain.nodes == one.nodes && plain.prim_order == one.prim_order, "{split:?}");
        let leaves = |b: u32| builder::build_in_blocks(&spheres, &bvh, b).nodes.iter().filter(|n| n.is_leaf()).count();
        let (l1, l8) = (leaves(1), leaves(8));
        assert!(l8 * 2 < l1, "{split:?}: {l8} leaves with blocks of 8 vs {l1}");
    }
}

/// The wide tree collapsed from `build_for_blocks` (which stops splitting at one block) against the one collapsed
/// from the full `build_in_blocks` tree: the same nodes, and the same blocks but for the order of their lanes.
fn assert_same_wide_tree<const W: usize, const B: usize>(label: &str, spheres: &[Sphere], bvh: &BvhParams) {
    let full = collapse::<_, W, B>(&builder::build_in_blocks(spheres, bvh, B as u32));
    let stopped = collapse::<_, W, B>(&builder::build_for_blocks(spheres, bvh, B as u32));
    assert!(full.nodes == stopped.nodes, "{label} W={W} B={B} {bvh:?}: nodes differ");
    assert_eq!(full.blocks.len(), stopped.blocks.len(), "{label} W={W} B={B} {bvh:?}");
    let lanes = |b: &SphereBlock<B>| {
        let mut lanes: Vec<_> =
            (0..B).map(|l| (b.ids[l], [b.cx[l], b.cy[l], b.cz[l], b.r2[l]].map(f32::to_bits))).collect();
        lanes.sort();
        lanes
    };
    for (i, (f, s)) in full.blocks.iter().zip(&stopped.blocks).enumerate() {
        assert_eq!(lanes(f), lanes(s), "{label} W={W} B={B} {bvh:?}: block {i}");
    }
}

#[test]
fn stopping_the_binary_build_at_one_block_gives_the_same_wide_tree() {
    let mut scenes: Vec<(String, Vec<Sphere>)> =
        SceneKind::ALL.into_iter().map(|kind| (kind.name().to_string(), kind.generate(6000, 3).spheres)).collect();
    scenes.push(("coincident".into(), vec![Sphere::new(Vec3::new(1.0, 2.0, 3.0), 0.5); 100]));
    for (label, spheres) in &scenes {
        // Not spatial splits: splitting a node of one block further may duplicate references, so the full tree's
        // blocks are not the stopped tree's.
        for split in Split::ALL.into_iter().filter(|&s| s != Split::SpatialSah) {
            for leaf_size in [1, 4, 8, 16] {
                let bvh = BvhParams { split, leaf_size, ..BvhParams::default() };
                assert_same_wide_tree::<4, 4>(label, spheres, &bvh);
                assert_same_wide_tree::<8, 8>(label, spheres, &bvh);
                assert_same_wide_tree::<8, 16>(label, spheres, &bvh);
                assert_same_wide_tree::<4, 16>(label, spheres, &bvh);
            }
        }
    }
}

#[test]
fn serialized_params_of_other_kinds_are_unchanged_and_wide_params_round_trip() {
    let flat = AccelParams::default();
    let text = serde_json::to_string(&flat).unwrap();
    assert!(!text.contains("wide"), "{text}");
    assert_eq!(serde_json::from_str::<AccelParams>(&text).unwrap(), flat);
    let wide = AccelParams {
        kind: AccelKind::WideBvh,
        wide: WideParams {
            width: 4,
            leaf_block: 16,
            kernel: Kernel::Scalar,
            order: ChildOrdering::Octant,
            packet: 1,
            ..WideParams::default()
        },
        ..AccelParams::default()
    };
    let text = serde_json::to_string(&wide).unwrap();
    assert!(text.contains(r#""kind":"wide-bvh""#) && text.contains(r#""order":"octant""#), "{text}");
    assert_eq!(serde_json::from_str::<AccelParams>(&text).unwrap(), wide);
}
