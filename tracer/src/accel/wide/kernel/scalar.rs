//! The portable kernel: one lane at a time, the same arithmetic as the binary trees' box and sphere tests.

use super::{Ops, Query};
use crate::accel::wide::collapse::Tree;
use crate::accel::wide::leaf::{LeafBlock, WidePrimitive};
use crate::accel::wide::node::WideNode;
use crate::accel::wide::order::Order;
use crate::accel::wide::ray::{FrustumLanes, RayLanes};
use crate::geometry::RayBoxTester;

/// The portable kernel.
pub struct Scalar;

/// Runs `query` with the portable kernel.
#[inline(never)]
pub fn run<Q: Query, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
    query: Q,
    tree: &Tree<W, B, P>,
) -> Q::Out {
    // SAFETY: the scalar kernel uses no optional instructions.
    unsafe { query.run::<Scalar, O, P, W, B>(tree) }
}

/// Entry distance into child `lane` of `node` before `t_max`, or `None` when missed: [`RayBoxTester::entry`]
/// with the entry plane chosen by the direction's sign (the same value, as `lo`/`hi` there pick it).
#[inline(always)]
fn entry<const W: usize>(node: &WideNode<W>, r: &RayLanes, t_max: f32, lane: usize) -> Option<f32> {
    let slab = |axis: usize| {
        let row = r.near_rows[axis];
        let near = (node.bounds[row][lane] - r.origin[axis]) * r.inv[axis];
        let far = (node.bounds[row ^ 1][lane] - r.origin[axis]) * r.inv[axis];
        (near, far)
    };
    let hi = |a: f32, b: f32| if a > b { a } else { b };
    let lo = |a: f32, b: f32| if a < b { a } else { b };
    let ((x0, x1), (y0, y1), (z0, z1)) = (slab(0), slab(1), slab(2));
    let near = hi(hi(x0, y0), hi(z0, r.t_min));
    let far = lo(lo(x1, y1), z1) * RayBoxTester::FAR_SCALE;
    (near <= far && near <= t_max).then_some(near)
}

/// A lower bound on the entry distance of every ray of `f` into child `lane` of `node`, if some ray may enter it
/// before `t_max` (see [`FrustumLanes`]); `None` for empty lanes.
#[inline(always)]
fn frustum_entry<const W: usize>(node: &WideNode<W>, f: &FrustumLanes, t_max: f32, lane: usize) -> Option<f32> {
    let hi = |a: f32, b: f32| if a > b { a } else { b };
    let lo = |a: f32, b: f32| if a < b { a } else { b };
    let (mut near, mut far) = (f.t_min, f32::INFINITY);
    for axis in (0..3).filter(|&axis| f.used[axis]) {
        let row = f.near_rows[axis];
        let x = node.bounds[row][lane] - f.origin_near[axis];
        let y = node.bounds[row ^ 1][lane] - f.origin_far[axis];
        near = hi(near, lo(x * f.inv_lo[axis], x * f.inv_hi[axis]));
        far = lo(far, hi(y * f.inv_lo[axis], y * f.inv_hi[axis]));
    }
    let occupied = node.bounds[0][lane] <= node.bounds[1][lane];
    (occupied && near <= far * RayBoxTester::FAR_SCALE && near <= t_max).then_some(near)
}

impl Ops for Scalar {
    #[inline(always)]
    unsafe fn run_apart<Q: Query, O: Order, P: WidePrimitive, const W: usize, const B: usize>(
        query: Q,
        tree: &Tree<W, B, P>,
    ) -> Q::Out {
        run::<Q, O, P, W, B>(query, tree)
    }

    #[inline(always)]
    unsafe fn boxes<const W: usize>(node: &WideNode<W>, r: &RayLanes, t_max: f32, dist: &mut [f32; W]) -> u32 {
        let mut mask = 0;
        for (lane, d) in dist.iter_mut().enumerate() {
            if let Some(t) = entry(node, r, t_max, lane) {
                *d = t;
                mask |= 1 << lane;
            }
        }
        mask
    }

    #[inline(always)]
    unsafe fn frustum_boxes<const W: usize>(
        node: &WideNode<W>,
        f: &FrustumLanes,
        t_max: f32,
        dist: &mut [f32; W],
    ) -> u32 {
        let mut mask = 0;
        for (lane, d) in dist.iter_mut().enumerate() {
            if let Some(t) = frustum_entry(node, f, t_max, lane) {
                *d = t;
                mask |= 1 << lane;
            }
        }
        mask
    }

    #[inline(always)]
    unsafe fn closest<L: LeafBlock<B>, const B: usize>(block: &L, r: &RayLanes, t_max: f32) -> Option<(f32, usize)> {
        let mut best: Option<(f32, usize)> = None;
        for lane in 0..B {
            let t = block.lane(r, t_max, lane);
            if t < best.map_or(t_max, |b| b.0) {
                best = Some((t, lane));
            }
        }
        best
    }

    #[inline(always)]
    unsafe fn any<L: LeafBlock<B>, const B: usize>(block: &L, r: &RayLanes, t_max: f32) -> bool {
        (0..B).any(|lane| block.lane(r, t_max, lane) < t_max)
    }
}
