//! The shared top-down builder: recursive splitting into the array layout both tree types start from.
//!
//! Nodes come out as sibling pairs in depth-first order: the root at index 0, the two children of an
//! interior node side by side at `first` and `first + 1`, and a node's whole subtree before its
//! sibling's. Leaves name a run of `prim_order`.
//!
//! The build uses the threads of the rayon pool it runs in (outside any pool: rayon's global pool). With more
//! than one thread, nodes of [`PARALLEL_MIN_PRIMS`] primitives or more build their two children with
//! `rayon::join`, each subtree into its own node vector with its own split scratch; the pieces are spliced
//! back in the serial order above, so the tree (nodes, their order, the primitive order) is identical
//! whatever the thread count. With one thread, and in subtrees below the threshold, it is the plain serial
//! recursion.

use glam::Vec3;

use super::params::{BvhParams, Split};
use super::sah::CostModel;
use super::split::{self, Decision, NodeView, binned_sah, object_median, sweep_sah};
use crate::geometry::{Aabb, Sphere};

/// Deepest level any builder produces; traversal stacks hold this many entries.
pub const MAX_DEPTH: usize = 64;

/// A node of the array layout: bounds, then either two children or a run of primitives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct FlatNode {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// Interior: index of the left child (the right child follows it). Leaf: first index into the primitive order.
    pub first: u32,
    /// Leaf: number of primitives. Interior: [`FlatNode::INTERIOR`].
    pub prim_count: u32,
}

const _: () = assert!(std::mem::size_of::<FlatNode>() == 32);

impl FlatNode {
    /// `prim_count` of interior nodes.
    pub const INTERIOR: u32 = u32::MAX;

    /// True for leaves.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.prim_count != Self::INTERIOR
    }
}

/// The builder's result: nodes in the array layout and the order of primitives their leaves refer to.
#[derive(Clone, Debug)]
pub struct BuiltTree {
    /// Nodes; the root is `nodes[0]`.
    pub nodes: Vec<FlatNode>,
    /// Primitive ids in leaf order.
    pub prim_order: Vec<u32>,
}

/// Nodes of at least this many primitives split in parallel (when the pool has more than one thread): each
/// builds its two children with `rayon::join`. Below it a subtree is built by one task with the serial code.
///
/// On two cores, thresholds from 1024 to 65536 built 1e5 and 1e6 random spheres equally fast within noise;
/// 4096 keeps tasks of a millisecond or more, far above a join's cost, and leaves enough of them (tens at
/// 1e5) to balance uneven SAH splits over more threads, where 65536 would split 1e5 spheres only once.
pub const PARALLEL_MIN_PRIMS: usize = 4096;

/// Builds a tree over `spheres` with the split rule and leaf size of `params`.
///
/// Builds with the threads of the current rayon pool (outside any pool: rayon's global pool); with one thread,
/// or fewer than [`PARALLEL_MIN_PRIMS`] spheres, it is the serial recursion. The tree is identical whatever the
/// thread count: same nodes in the same order, same primitive order.
pub fn build(spheres: &[Sphere], params: &BvhParams) -> BuiltTree {
    build_in_blocks(spheres, params, 1)
}

/// [`build`], with the SAH splits counting a leaf's spheres in SIMD blocks of `block` (see [`CostModel`]);
/// `block = 1` is [`build`] exactly. The other splits ignore `block`.
pub fn build_in_blocks(spheres: &[Sphere], params: &BvhParams, block: u32) -> BuiltTree {
    assert!(block >= 1, "a SIMD block holds at least one sphere");
    if let Err(e) = params.validate() {
        panic!("invalid BVH parameters: {e}");
    }
    let boxes: Vec<Aabb> = spheres.iter().map(Sphere::bounds).collect();
    let centroids: Vec<Vec3> = spheres.iter().map(|s| s.center).collect();
    let mut prims: Vec<u32> = (0..spheres.len() as u32).collect();
    let nodes = if spheres.len() >= PARALLEL_MIN_PRIMS && rayon::current_num_threads() > 1 {
        parallel::build(params, block, &boxes, &centroids, &mut prims)
    } else {
        let mut b = Builder::new(params, block, &boxes, &centroids, spheres.len());
        b.build_node(0, &mut prims, 0, 0);
        b.nodes
    };
    BuiltTree { nodes, prim_order: prims }
}

fn ceil_log2(n: usize) -> usize {
    (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize
}

const PLACEHOLDER: FlatNode = FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 };

/// What every node's split decision reads: the parameters and the per-primitive boxes and centroids.
#[derive(Clone, Copy)]
struct Inputs<'a> {
    params: &'a BvhParams,
    /// Spheres per SIMD leaf block the SAH splits count in (see [`CostModel`]).
    block: u32,
    boxes: &'a [Aabb],
    centroids: &'a [Vec3],
}

/// Split rules' scratch space; one per task.
#[derive(Default)]
struct Scratch {
    bins: binned_sah::Bins,
    sweep: sweep_sah::Sweep,
}

impl Inputs<'_> {
    /// The SAH cost model of this build.
    #[inline(always)]
    fn costs(&self) -> CostModel {
        CostModel { costs: self.params.sah_costs, block: self.block }
    }

    /// The node's bounds and what to do with it (leaf or split point, after reordering `prims`).
    #[inline(always)]
    fn decide(&self, prims: &mut [u32], depth: usize, scratch: &mut Scratch) -> (Aabb, Decision) {
        let mut bounds = Aabb::EMPTY;
        let mut centroid_bounds = Aabb::EMPTY;
        for &p in prims.iter() {
            bounds = bounds.union(&self.boxes[p as usize]);
            centroid_bounds.grow(self.centroids[p as usize]);
        }
        let n = prims.len();
        let view = NodeView {
            boxes: self.boxes,
            centroids: self.centroids,
            bounds,
            centroid_bounds,
            may_be_leaf: n <= self.params.leaf_size as usize,
        };
        let decision = if n <= 1 {
            Decision::Leaf
        } else if depth + ceil_log2(n) >= MAX_DEPTH - 1 {
            // Halving from here keeps every leaf within MAX_DEPTH, whatever the rule would have done.
            object_median::median(&view, prims)
        } else {
            let p = self.params;
            match p.split {
                Split::CentroidMidpoint => split::centroid_midpoint::split(&view, prims),
                Split::ObjectMedian => object_median::split(&view, prims),
                Split::BinnedSah => {
                    binned_sah::split(&view, prims, p.sah_bins as usize, self.costs(), &mut scratch.bins)
                }
                Split::SweepSah => sweep_sah::split(&view, prims, self.costs(), &mut scratch.sweep),
            }
        };
        let decision = match decision {
            Decision::NoSplit => object_median::median(&view, prims),
            d => d,
        };
        (bounds, decision)
    }
}

/// The serial recursion: appends a subtree's nodes to one vector, in the order the module doc describes.
struct Builder<'a> {
    inputs: Inputs<'a>,
    nodes: Vec<FlatNode>,
    scratch: Scratch,
}

impl<'a> Builder<'a> {
    /// A builder whose `nodes` hold the subtree root's slot (index 0) and room for a subtree of `prim_count`.
    fn new(params: &'a BvhParams, block: u32, boxes: &'a [Aabb], centroids: &'a [Vec3], prim_count: usize) -> Self {
        let mut nodes = Vec::with_capacity(2 * prim_count.max(1));
        nodes.push(PLACEHOLDER);
        Builder { inputs: Inputs { params, block, boxes, centroids }, nodes, scratch: Scratch::default() }
    }

    fn build_node(&mut self, index: usize, prims: &mut [u32], offset: usize, depth: usize) {
        let (bounds, decision) = self.inputs.decide(prims, depth, &mut self.scratch);
        match decision {
            Decision::Split(mid) => {
                let first = self.nodes.len();
                self.nodes.extend([PLACEHOLDER, PLACEHOLDER]);
                self.nodes[index] = FlatNode { bounds, first: first as u32, prim_count: FlatNode::INTERIOR };
                let (left, right) = prims.split_at_mut(mid);
                self.build_node(first, left, offset, depth + 1);
                self.build_node(first + 1, right, offset + mid, depth + 1);
            }
            _ => self.nodes[index] = FlatNode { bounds, first: offset as u32, prim_count: prims.len() as u32 },
        }
    }
}

/// The parallel top of the tree: nodes of [`PARALLEL_MIN_PRIMS`] or more split, then build their children
/// with `rayon::join`; smaller subtrees run [`Builder`] in their own vector. The pieces are spliced in the
/// serial build's order (children pair, whole left subtree, whole right subtree), so the tree is the same.
mod parallel {
    use super::*;

    /// Nodes whose interior `first` is `stored + shift` relative to the start of the enclosing descendant list
    /// (the shift is applied once, when the final array is assembled, so nodes are copied only once).
    struct Segment {
        nodes: Vec<FlatNode>,
        /// Leading nodes that are not part of the segment (a serial subtree's own root slot).
        skip: usize,
        shift: isize,
    }

    /// A node's descendants in serial order, as segments; `len` nodes in all.
    #[derive(Default)]
    struct Descendants {
        segments: Vec<Segment>,
        len: usize,
    }

    /// Builds the whole tree; `prims.len() >= PARALLEL_MIN_PRIMS`.
    pub(super) fn build(params: &BvhParams, block: u32, boxes: &[Aabb], centroids: &[Vec3], prims: &mut [u32]) -> Vec<FlatNode> {
        let inputs = Inputs { params, block, boxes, centroids };
        let (root, desc) = subtree(inputs, prims, 0, 0);
        let mut nodes = Vec::with_capacity(1 + desc.len);
        // Descendant-relative index i is array index 1 + i.
        nodes.push(shifted(root, 1));
        for seg in desc.segments {
            nodes.extend(seg.nodes[seg.skip..].iter().map(|&n| shifted(n, seg.shift + 1)));
        }
        debug_assert_eq!(nodes.len(), 1 + desc.len);
        nodes
    }

    #[inline(always)]
    fn shifted(mut node: FlatNode, shift: isize) -> FlatNode {
        if !node.is_leaf() {
            node.first = (node.first as isize + shift) as u32;
        }
        node
    }

    /// The subtree over `prims`: its root (an interior root's `first` relative to the start of its
    /// descendants) and its descendants.
    fn subtree(inputs: Inputs<'_>, prims: &mut [u32], offset: usize, depth: usize) -> (FlatNode, Descendants) {
        if prims.len() < PARALLEL_MIN_PRIMS {
            let mut b = Builder::new(inputs.params, inputs.block, inputs.boxes, inputs.centroids, prims.len());
            b.build_node(0, prims, offset, depth);
            // Array index i of `b.nodes` (i >= 1) is descendant index i - 1.
            let root = shifted(b.nodes[0], -1);
            let len = b.nodes.len() - 1;
            return (root, Descendants { segments: vec![Segment { nodes: b.nodes, skip: 1, shift: -1 }], len });
        }
        let (bounds, decision) = inputs.decide(prims, depth, &mut Scratch::default());
        let Decision::Split(mid) = decision else {
            let leaf = FlatNode { bounds, first: offset as u32, prim_count: prims.len() as u32 };
            return (leaf, Descendants::default());
        };
        let (left, right) = prims.split_at_mut(mid);
        let ((l, l_desc), (r, r_desc)) = rayon::join(
            || subtree(inputs, left, offset, depth + 1),
            || subtree(inputs, right, offset + mid, depth + 1),
        );
        // Descendants: the children pair, then the left child's descendants, then the right's.
        let (l_start, r_start) = (2, 2 + l_desc.len as isize);
        let mut segments = Vec::with_capacity(1 + l_desc.segments.len() + r_desc.segments.len());
        segments.push(Segment { nodes: vec![shifted(l, l_start), shifted(r, r_start)], skip: 0, shift: 0 });
        segments.extend(l_desc.segments.into_iter().map(|s| Segment { shift: s.shift + l_start, ..s }));
        segments.extend(r_desc.segments.into_iter().map(|s| Segment { shift: s.shift + r_start, ..s }));
        let root = FlatNode { bounds, first: 0, prim_count: FlatNode::INTERIOR };
        (root, Descendants { segments, len: 2 + l_desc.len + r_desc.len })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_log2_matches_definition() {
        assert_eq!([1, 2, 3, 4, 5, 8, 9].map(ceil_log2), [0, 1, 2, 2, 3, 3, 4]);
    }
}
