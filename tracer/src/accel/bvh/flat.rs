//! The tree in one contiguous array: 32-byte nodes, primitives copied into leaf order.

use super::builder;
use super::params::{BvhParams, Traversal};
use super::split::Referenced;
use super::stats::TreeStats;
use super::traverse::{self, ChildOrder, OrderedQueries, TreeView, traverse};
use super::tree::FlatNode;
use crate::accel::{Accelerator, Hit};
use crate::counters::Counters;
use crate::geometry::{Aabb, Ray, Sphere};

/// A BVH stored as one array of [`FlatNode`]s (sibling pairs, depth-first) with primitives in leaf order.
#[derive(Clone, Debug)]
pub struct FlatBvh<P = Sphere> {
    nodes: Vec<FlatNode>,
    prims: Vec<P>,
    prim_ids: Vec<u32>,
    params: BvhParams,
}

impl<P: Referenced> FlatBvh<P> {
    /// Builds the tree and lays it out.
    ///
    /// Builds with the threads of the current rayon pool (outside any pool: rayon's global pool); the tree is
    /// identical whatever the thread count (see [`builder`]).
    pub fn build(prims: &[P], params: &BvhParams) -> Self {
        let built = builder::build(prims, params);
        Self { nodes: built.nodes, prims: built.ordered, prim_ids: built.prim_order, params: *params }
    }

    /// The same tree traversed in `traversal` order (the order does not change the tree: nothing is rebuilt).
    pub fn with_traversal(mut self, traversal: Traversal) -> Self {
        self.params.traversal = traversal;
        self
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &BvhParams {
        &self.params
    }

    /// The nodes; the root is first.
    pub fn nodes(&self) -> &[FlatNode] {
        &self.nodes
    }

    /// The node at `index`, which came from the root or a parent's `first` (always in range).
    #[inline(always)]
    fn node(&self, index: u32) -> &FlatNode {
        debug_assert!((index as usize) < self.nodes.len());
        // SAFETY: indices come from the root (0; the builder always emits a root) or from an interior
        // node's `first`/`first + 1`, which the builder allocates before recording them.
        unsafe { self.nodes.get_unchecked(index as usize) }
    }
}

impl<P: Referenced> OrderedQueries for FlatBvh<P> {
    #[inline(always)]
    fn traversal(&self) -> Traversal {
        self.params.traversal
    }

    #[inline(always)]
    fn closest<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best = u32::MAX;
        let mut best_t = ray.t_max;
        traverse::<_, O, C, _>(self, ray, counters, |node, t_max, counters| {
            let n = self.node(node);
            // SAFETY: the builder makes every leaf's run lie inside `prims` (one primitive per entry of `prim_ids`).
            let leaf = unsafe { self.prims.get_unchecked(n.first as usize..(n.first + n.prim_count) as usize) };
            for (i, s) in (n.first..).zip(leaf) {
                counters.prim_test();
                if let Some(t) = s.intersect(ray, *t_max) {
                    *t_max = t;
                    best_t = t;
                    best = i;
                }
            }
            false
        });
        (best != u32::MAX).then(|| Hit { t: best_t, prim: self.prim_ids[best as usize] })
    }

    #[inline(always)]
    fn any<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let mut found = false;
        traverse::<_, O, C, _>(self, ray, counters, |node, t_max, counters| {
            let n = self.node(node);
            // SAFETY: as in `closest`.
            let leaf = unsafe { self.prims.get_unchecked(n.first as usize..(n.first + n.prim_count) as usize) };
            found = leaf.iter().any(|s| {
                counters.prim_test();
                s.intersect(ray, *t_max).is_some()
            });
            found
        });
        found
    }
}

impl<P: Referenced> TreeView for FlatBvh<P> {
    type Node<'a> = u32;

    #[inline(always)]
    fn root(&self) -> u32 {
        0
    }

    #[inline(always)]
    fn bounds(&self, node: u32) -> &Aabb {
        &self.node(node).bounds
    }

    #[inline(always)]
    fn children(&self, node: u32) -> Option<[u32; 2]> {
        let n = self.node(node);
        (!n.is_leaf()).then(|| [n.first, n.first + 1])
    }

    fn leaf_len(&self, node: u32) -> usize {
        self.nodes[node as usize].prim_count as usize
    }
}

impl<P: Referenced> Accelerator for FlatBvh<P> {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        traverse::intersect(self, ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        traverse::occluded(self, ray, counters)
    }

    fn stats(&self) -> TreeStats {
        let bytes = std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.prims.as_slice())
            + std::mem::size_of_val(self.prim_ids.as_slice());
        TreeStats::of_tree(self, bytes)
    }
}
