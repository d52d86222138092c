//! Closest-hit and any-hit traversal of a wide tree, generic over kernel, child order and counters.
//!
//! A node's children are box-tested at once; a single hit child is visited directly, several are pushed in the
//! [`Order`]'s order with their entry distances and the first popped. Popped entries whose entry distance is not
//! below the current closest hit are skipped. A leaf tests its blocks one after the other.
//!
//! Counters: one `node_visit` per wide node taken (leaves are not nodes here; their work is the sphere tests),
//! `box_tests` of the node's children in use (not the padding lanes the SIMD test also computes), one `prim_test`
//! per real sphere of every block tested (not padding lanes). They depend only on the tree and the ray, not on
//! the kernel, since every kernel computes the same distances.

use super::collapse::Tree;
use super::kernel::{Ops, Query};
use super::leaf::{LeafBlock, PAD, WidePrimitive};
use super::node::ChildRef;
use super::order::Order;
use super::ray::RayLanes;
use super::stack::Stack;
use crate::accel::Hit;
use crate::counters::Counters;
use crate::geometry::Ray;
use crate::render::PrimaryHits;

/// Where the traversal goes next: into `ChildRef`, or back to the stack.
#[inline(always)]
unsafe fn enter<K: Ops, O: Order, C: Counters, Prim: WidePrimitive, const W: usize, const B: usize>(
    tree: &Tree<W, B, Prim>,
    node: ChildRef,
    r: &RayLanes,
    t_max: f32,
    stack: &mut Stack,
    counters: &mut C,
) -> Option<ChildRef> {
    debug_assert!(node.index() < tree.nodes.len());
    // SAFETY: node references come from the collapse, which emits every node it refers to.
    let node = unsafe { tree.nodes.get_unchecked(node.index()) };
    counters.node_visit();
    if C::ENABLED {
        counters.box_tests(node.len() as u32);
    }
    let mut dist = [0.0f32; W];
    // SAFETY: the caller runs inside `K`'s `run`.
    let hits = unsafe { K::boxes(node, r, t_max, &mut dist) };
    if hits == 0 {
        None
    } else if hits & (hits - 1) == 0 {
        Some(node.children[hits.trailing_zeros() as usize])
    } else {
        O::push(node, hits, &dist, r.octant, stack);
        stack.pop().map(|e| e.0)
    }
}

/// The next entry on the stack entered before `t_max`, if any.
#[inline(always)]
fn next(stack: &mut Stack, t_max: f32) -> Option<ChildRef> {
    while let Some((child, t)) = stack.pop() {
        if t < t_max {
            return Some(child);
        }
    }
    None
}

/// The nearest hit of `ray`.
///
/// # Safety
/// The CPU supports `K`'s instructions.
#[inline(always)]
pub unsafe fn closest<K: Ops, O: Order, C: Counters, Prim: WidePrimitive, const W: usize, const B: usize>(
    tree: &Tree<W, B, Prim>,
    ray: &Ray,
    counters: &mut C,
) -> Option<Hit> {
    let r = RayLanes::for_leaves::<Prim>(ray);
    let mut t_max = ray.t_max;
    let mut best = PAD;
    let mut stack = Stack::new();
    let mut at = Some(ChildRef::ROOT);
    while let Some(child) = at {
        if child.is_node() {
            // SAFETY: forwarded from the caller.
            at = unsafe { enter::<K, O, C, Prim, W, B>(tree, child, &r, t_max, &mut stack, counters) };
            if at.is_some() {
                continue;
            }
        } else {
            debug_assert!(child.blocks().end <= tree.blocks.len());
            // SAFETY: leaf references name blocks the collapse emitted.
            for block in unsafe { tree.blocks.get_unchecked(child.blocks()) } {
                if C::ENABLED {
                    (0..block.len()).for_each(|_| counters.prim_test());
                }
                // SAFETY: forwarded from the caller.
                if let Some((t, lane)) = unsafe { K::closest(block, &r, t_max) } {
                    t_max = t;
                    best = block.ids()[lane];
                }
            }
        }
        at = next(&mut stack, t_max);
    }
    (best != PAD).then_some(Hit { t: t_max, prim: best })
}

/// True when `ray` hits anything (stops at the first hit).
///
/// # Safety
/// The CPU supports `K`'s instructions.
#[inline(always)]
pub unsafe fn any<K: Ops, O: Order, C: Counters, Prim: WidePrimitive, const W: usize, const B: usize>(
    tree: &Tree<W, B, Prim>,
    ray: &Ray,
    counters: &mut C,
) -> bool {
    let r = RayLanes::for_leaves::<Prim>(ray);
    let mut stack = Stack::new();
    let mut at = Some(ChildRef::ROOT);
    while let Some(child) = at {
        if child.is_node() {
            // SAFETY: forwarded from the caller.
            at = unsafe { enter::<K, O, C, Prim, W, B>(tree, child, &r, ray.t_max, &mut stack, counters) };
            if at.is_some() {
                continue;
            }
        } else {
            // SAFETY: as in `closest`.
            for block in unsafe { tree.blocks.get_unchecked(child.blocks()) } {
                if C::ENABLED {
                    (0..block.len()).for_each(|_| counters.prim_test());
                }
                // SAFETY: forwarded from the caller.
                if unsafe { K::any(block, &r, ray.t_max) } {
                    return true;
                }
            }
        }
        at = next(&mut stack, ray.t_max);
    }
    false
}

/// The nearest hit of one ray.
pub struct Closest<'a, C> {
    /// The ray.
    pub ray: &'a Ray,
    /// Where its work is counted.
    pub counters: &'a mut C,
}

/// Whether one ray hits anything.
pub struct Any<'a, C> {
    /// The ray.
    pub ray: &'a Ray,
    /// Where its work is counted.
    pub counters: &'a mut C,
}

/// Nearest hits of a batch ([`PrimaryHits::MISS`] for misses), one `ray` count per ray.
pub struct ClosestBatch<'a, C> {
    /// The rays.
    pub rays: &'a [Ray],
    /// One answer per ray.
    pub out: &'a mut [Hit],
    /// Where their work is counted.
    pub counters: &'a mut C,
}

/// Occlusion of a batch, one `ray` count per ray.
pub struct AnyBatch<'a, C> {
    /// The rays.
    pub rays: &'a [Ray],
    /// One answer per ray.
    pub out: &'a mut [bool],
    /// Where their work is counted.
    pub counters: &'a mut C,
}

impl<C: Counters> Query for Closest<'_, C> {
    type Out = Option<Hit>;
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) -> Option<Hit> {
        // SAFETY: forwarded from the caller.
        unsafe { closest::<K, O, C, Prim, W, B>(tree, self.ray, self.counters) }
    }
}

impl<C: Counters> Query for Any<'_, C> {
    type Out = bool;
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) -> bool {
        // SAFETY: forwarded from the caller.
        unsafe { any::<K, O, C, Prim, W, B>(tree, self.ray, self.counters) }
    }
}

impl<C: Counters> Query for ClosestBatch<'_, C> {
    type Out = ();
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) {
        for (ray, out) in self.rays.iter().zip(self.out) {
            self.counters.ray();
            // SAFETY: forwarded from the caller.
            *out = unsafe { closest::<K, O, C, Prim, W, B>(tree, ray, self.counters) }.unwrap_or(PrimaryHits::MISS);
        }
    }
}

impl<C: Counters> Query for AnyBatch<'_, C> {
    type Out = ();
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) {
        for (ray, out) in self.rays.iter().zip(self.out) {
            self.counters.ray();
            // SAFETY: forwarded from the caller.
            *out = unsafe { any::<K, O, C, Prim, W, B>(tree, ray, self.counters) };
        }
    }
}
