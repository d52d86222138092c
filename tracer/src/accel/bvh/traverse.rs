//! One traversal for every layout: generic over the tree view, child order, counters and leaf test.

use std::mem::MaybeUninit;

use super::params::Traversal;
use super::tree::MAX_DEPTH;
use crate::accel::Hit;
use crate::counters::Counters;
use crate::geometry::{Aabb, Ray, RayBoxTester};

/// Read access to a binary tree of boxes, whatever its memory layout.
pub trait TreeView {
    /// A cheap handle to one node.
    type Node<'a>: Copy
    where
        Self: 'a;
    /// The root.
    fn root(&self) -> Self::Node<'_>;
    /// A node's bounds.
    fn bounds<'a>(&'a self, node: Self::Node<'a>) -> &'a Aabb;
    /// The two children of an interior node; `None` for a leaf.
    fn children<'a>(&'a self, node: Self::Node<'a>) -> Option<[Self::Node<'a>; 2]>;
    /// Number of primitives in a leaf.
    fn leaf_len<'a>(&'a self, node: Self::Node<'a>) -> usize;
}

/// Which child of an entered node is visited first.
pub trait ChildOrder {
    /// True to visit the child with the smaller entry distance first.
    const NEAR_FIRST: bool;
}

/// Left child first, always (the paper's order).
pub struct Fixed;
impl ChildOrder for Fixed {
    const NEAR_FIRST: bool = false;
}

/// Nearer child first, by entry distance.
pub struct FrontToBack;
impl ChildOrder for FrontToBack {
    const NEAR_FIRST: bool = true;
}

/// A tree whose queries are compiled once per child order; [`intersect`] and [`occluded`] run the order it was
/// built with.
pub trait OrderedQueries {
    /// The child order chosen at build time.
    fn traversal(&self) -> Traversal;
    /// The nearest hit, visiting children in order `O`.
    fn closest<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit>;
    /// Whether anything is hit, visiting children in order `O`.
    fn any<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool;
}

/// The nearest hit in `tree`, in its chosen child order (a branch per ray; each order is its own compiled loop).
#[inline(always)]
pub fn intersect<T: OrderedQueries, C: Counters>(tree: &T, ray: &Ray, counters: &mut C) -> Option<Hit> {
    match tree.traversal() {
        Traversal::Fixed => tree.closest::<Fixed, C>(ray, counters),
        Traversal::FrontToBack => tree.closest::<FrontToBack, C>(ray, counters),
    }
}

/// Whether anything in `tree` is hit, in its chosen child order.
#[inline(always)]
pub fn occluded<T: OrderedQueries, C: Counters>(tree: &T, ray: &Ray, counters: &mut C) -> bool {
    match tree.traversal() {
        Traversal::Fixed => tree.any::<Fixed, C>(ray, counters),
        Traversal::FrontToBack => tree.any::<FrontToBack, C>(ray, counters),
    }
}

/// Visits every leaf whose box the ray enters before the current `t_max`, in the order `O` gives.
///
/// Both children of an entered node are tested from the parent; the nearer (or left) one is descended
/// and the other pushed with its entry distance, which is compared with `t_max` again when popped
/// (closest-hit culling). `leaf` may shrink `t_max` and returns true to stop (any-hit queries).
#[inline(always)]
pub fn traverse<'a, T, O, C, L>(tree: &'a T, ray: &Ray, counters: &mut C, mut leaf: L)
where
    T: TreeView,
    O: ChildOrder,
    C: Counters,
    L: FnMut(T::Node<'a>, &mut f32, &mut C) -> bool,
{
    let tester = RayBoxTester::new(ray);
    let mut t_max = ray.t_max;
    let mut node = tree.root();
    counters.node_visit();
    counters.box_tests(1);
    let root_bounds = tree.bounds(node);
    if root_bounds.is_empty() || tester.entry(root_bounds, t_max) == f32::INFINITY {
        return;
    }
    let mut stack: [MaybeUninit<(T::Node<'a>, f32)>; MAX_DEPTH] = [const { MaybeUninit::uninit() }; MAX_DEPTH];
    let mut len = 0;
    'nodes: loop {
        match tree.children(node) {
            Some([left, right]) => {
                counters.box_tests(2);
                let t_left = tester.entry(tree.bounds(left), t_max);
                let t_right = tester.entry(tree.bounds(right), t_max);
                let (near, t_near, far, t_far) = if O::NEAR_FIRST && t_right < t_left {
                    (right, t_right, left, t_left)
                } else {
                    (left, t_left, right, t_right)
                };
                if t_near != f32::INFINITY {
                    if t_far != f32::INFINITY {
                        debug_assert!(len < MAX_DEPTH);
                        // SAFETY: at most one entry is pushed per level descended, and builders keep every
                        // tree under MAX_DEPTH levels (tested), so `len < MAX_DEPTH` here.
                        unsafe { stack.get_unchecked_mut(len) }.write((far, t_far));
                        len += 1;
                    }
                    node = near;
                    counters.node_visit();
                    continue 'nodes;
                }
                if t_far != f32::INFINITY {
                    node = far;
                    counters.node_visit();
                    continue 'nodes;
                }
            }
            None => {
                if leaf(node, &mut t_max, counters) {
                    return;
                }
            }
        }
        while len > 0 {
            len -= 1;
            // SAFETY: entries below `len` were written above and each is read once.
            let (next, t_entry) = unsafe { stack.get_unchecked(len).assume_init_read() };
            if t_entry < t_max {
                node = next;
                counters.node_visit();
                continue 'nodes;
            }
        }
        return;
    }
}
