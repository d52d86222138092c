//! The SAH cost constants are a build parameter: they change the tree the SAH splits build, and every such
//! tree still agrees with brute force.

use tracer::accel::bvh::SahCosts;
use tracer::accel::{AccelKind, AccelParams, BuiltAccel, BvhParams, Split};
use tracer::agreement::Strictness;
use tracer::scene::SceneKind;
use tracer::testing::{Reference, sphere_ray_mix};

fn params(split: Split, traversal: f32, intersection: f32) -> BvhParams {
    BvhParams { split, leaf_size: 16, sah_costs: SahCosts { traversal, intersection }, ..BvhParams::default() }
}

#[test]
fn dearer_node_visits_build_bigger_leaves_that_still_agree_with_brute_force() {
    let scene = SceneKind::RandomSpheres.generate(3000, 7);
    let rays = sphere_ray_mix(&scene.spheres, 11, 4000);
    let reference = Reference::new(&scene.spheres, &rays);
    for split in [Split::BinnedSah, Split::SweepSah] {
        let mut leaves = Vec::new();
        for (traversal, intersection) in [(0.5, 1.0), (1.0, 1.0), (4.0, 1.0), (1.0, 0.25)] {
            let params = AccelParams {
                kind: AccelKind::FlatBvh,
                bvh: params(split, traversal, intersection),
                ..AccelParams::default()
            };
            let tree = BuiltAccel::build(&scene.spheres, &params);
            reference.assert_built_agrees(
                &format!("{} costs {traversal}/{intersection}", split.name()),
                &tree,
                Strictness::Identical,
            );
            leaves.push(tree.stats().leaves);
        }
        assert!(
            leaves[0] > leaves[1] && leaves[1] > leaves[2],
            "{split:?}: leaves {leaves:?} shrink as visits get dearer"
        );
        assert_eq!(leaves[2], leaves[3], "{split:?}: only the ratio of the costs matters: {leaves:?}");
    }
}

#[test]
fn midpoint_and_median_ignore_the_costs() {
    let scene = SceneKind::ClusteredSpheres.generate(2000, 3);
    for split in [Split::CentroidMidpoint, Split::ObjectMedian] {
        let build = |t| {
            BuiltAccel::build(
                &scene.spheres,
                &AccelParams { kind: AccelKind::FlatBvh, bvh: params(split, t, 1.0), ..AccelParams::default() },
            )
            .stats()
        };
        assert_eq!(build(1.0), build(8.0), "{split:?}");
    }
}

#[test]
fn costs_outside_the_range_are_refused() {
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e4] {
        let e = params(Split::BinnedSah, bad, 1.0).validate().unwrap_err();
        assert_eq!(e.key, "sah_traversal_cost");
        assert!(params(Split::BinnedSah, 1.0, bad).validate().is_err());
    }
    assert!(params(Split::BinnedSah, 1e-3, 1e3).validate().is_ok());
}
