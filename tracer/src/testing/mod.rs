//! Test support shared by the tracer's tests and the harness's peer tests.
//!
//! Every backend's tests check it against brute force with the one definition of agreement
//! ([`crate::agreement`]), on shared configurations and rays:
//! - [`every_tree`]: every BVH configuration the tracer can build ([`every_wide`]: the wide ones this CPU runs);
//! - [`sphere_ray_mix`] and [`scene_ray_mix`]: ray sets that mix ordinary rays with the cases where traversal
//!   and intersection go wrong (grazing, inside, finite, non-unit rays and secondary rays);
//! - [`scenes`]: the generated scenes, each with its [`scene_ray_mix`]; [`test_meshes`]: procedural triangle
//!   meshes, each with its [`mesh_ray_mix`];
//! - [`Reference`]: brute force's answers to a ray set, compared with an accelerator's under a
//!   [`crate::agreement::Strictness`]; [`assert_every_tree_agrees`] checks every tree configuration at once;
//! - [`threads`]: where a strategy's worker threads may run (distinct CPUs, or all of them).
//!
//! Always compiled, at no cost to a release build: every function here is generic or `#[inline]`, so it is compiled
//! only into the tests that call it.

mod agree;
mod meshes;
mod rays;
pub mod threads;

pub use agree::{Comparison, Reference, Tally, assert_every_tree_agrees, assert_every_tree_agrees_on_triangles};
pub use meshes::{TestMesh, mesh_ray_mix, test_meshes};
pub use rays::{scene_ray_mix, secondary_rays, sphere_ray_mix};

use crate::accel::wide::{AnyHitOrdering, ChildOrdering, Kernel};
use crate::accel::{AccelKind, AccelParams, BvhParams, Split, Traversal, WideParams};
use crate::geometry::{Ray, Sphere};
use crate::scene::SceneKind;

/// Every tree configuration: both binary layouts × every split × leaf sizes `1..=16` × both traversal orders (16
/// SAH bins), then [`every_wide`].
#[inline]
pub fn every_tree() -> Vec<AccelParams> {
    let mut all = Vec::new();
    for kind in [AccelKind::Bvh, AccelKind::FlatBvh] {
        for split in Split::ALL {
            for leaf_size in 1..=BvhParams::MAX_LEAF_SIZE {
                for traversal in Traversal::ALL {
                    let bvh = BvhParams { leaf_size, split, traversal, sah_bins: 16, ..BvhParams::default() };
                    all.push(AccelParams { kind, bvh, ..AccelParams::default() });
                }
            }
        }
    }
    all.extend(every_wide());
    all
}

/// Every wide BVH configuration this CPU can run: every kernel it has ([`Kernel::available`]: scalar, AVX2,
/// AVX-512) × width × leaf block × child order. The binary tree each is collapsed from cycles through every split ×
/// leaf sizes 1, 16, 4 and 8 (so leaves of one block, of several blocks and merged subtrees all occur), the
/// batch packet size through 1, 8, 16 and 64 (so every kernel, width and block runs in packets of every size), and
/// the any-hit order through both (so with 3 child orders each child order meets each).
#[inline]
pub fn every_wide() -> Vec<AccelParams> {
    let mut all = Vec::new();
    let mut binary = Split::ALL.into_iter().flat_map(|split| [1, 16, 4, 8].map(|leaf_size| (split, leaf_size))).cycle();
    let mut packets = WideParams::PACKETS.into_iter().cycle();
    let mut any_hit_orders = AnyHitOrdering::ALL.into_iter().cycle();
    for kernel in Kernel::available() {
        for width in WideParams::WIDTHS {
            for leaf_block in WideParams::LEAF_BLOCKS {
                for order in ChildOrdering::ALL {
                    let (split, leaf_size) = binary.next().expect("cycle");
                    let bvh = BvhParams { split, leaf_size, traversal: Traversal::FrontToBack, ..BvhParams::default() };
                    let packet = packets.next().expect("cycle");
                    let any_hit_order = any_hit_orders.next().expect("cycle");
                    let sah_block = if leaf_block == 16 && order == ChildOrdering::Distance { 4 } else { 16 };
                    let wide = WideParams { width, leaf_block, kernel, order, any_hit_order, packet, sah_block };
                    all.push(AccelParams { kind: AccelKind::WideBvh, bvh, wide });
                }
            }
        }
    }
    all
}

/// A generated scene's spheres with its ray mix, named for failure messages.
#[derive(Clone, Debug)]
pub struct TestScene {
    /// `"{kind} n={spheres} seed={seed}"`.
    pub label: String,
    /// The scene's spheres.
    pub spheres: Vec<Sphere>,
    /// [`scene_ray_mix`] of the scene with seed `seed ^ 0x5eed`.
    pub rays: Vec<Ray>,
}

/// Every test scene: both scene kinds × 0, 1, 50 and 2000 spheres × seeds 1 and 2 (16 scenes), in that order.
#[inline]
pub fn scenes() -> Vec<TestScene> {
    let mut all = Vec::new();
    for kind in SceneKind::ALL {
        for n in [0, 1, 50, 2000] {
            for seed in [1u64, 2] {
                let scene = kind.generate(n, seed);
                let rays = scene_ray_mix(&scene, seed ^ 0x5eed);
                all.push(TestScene {
                    label: format!("{} n={n} seed={seed}", kind.name()),
                    spheres: scene.spheres,
                    rays,
                });
            }
        }
    }
    all
}
