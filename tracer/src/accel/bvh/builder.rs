//! The shared top-down builder: recursive splitting into the array layout both tree types start from.
//!
//! Nodes come out as sibling pairs in depth-first order: the root at index 0, the two children of an
//! interior node side by side at `first` and `first + 1`, and a node's whole subtree before its
//! sibling's. Leaves name a run of `prim_order`. [`Split::SpatialSah`] is built by [`super::spatial`] into the same
//! layout; only there may `prim_order` name a primitive more than once (in different leaves).
//!
//! The build uses the threads of the rayon pool it runs in (outside any pool: rayon's global pool). With more
//! than one thread, nodes of [`PARALLEL_MIN_PRIMS`] primitives or more build their two children with
//! `rayon::join`, each subtree into its own node vector with its own split scratch; the pieces are spliced
//! back in the serial order above, so the tree (nodes, their order, the primitive order) is identical
//! whatever the thread count. With one thread, and in subtrees below the threshold, it is the plain serial
//! recursion.
//!
//! The top nodes, split one at a time before their subtrees run in parallel, would leave the other threads idle:
//! so with more than one thread the O(n) passes before and after the recursion (the per-primitive arrays, the
//! root's bounds) run in parallel, and the binned SAH bins large nodes in parallel (see [`binned_sah`]).

use glam::Vec3;

use super::params::{BvhParams, Split};
use super::reinsertion;
use super::sah::CostModel;
use super::split::{self, Decision, NodeBounds, NodeView, Referenced, binned_sah, object_median, prim_ref, sweep_sah};
use super::tree::{BuiltTree, FlatNode, MAX_DEPTH, PLACEHOLDER, ceil_log2};
use crate::geometry::Aabb;

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
pub fn build<P: Referenced>(spheres: &[P], params: &BvhParams) -> BuiltTree<P> {
    build_in_blocks(spheres, params, 1)
}

/// [`build`], with the SAH splits counting a leaf's spheres in SIMD blocks of `block` (see [`CostModel`]);
/// `block = 1` is [`build`] exactly. The other splits ignore `block`.
pub fn build_in_blocks<P: Referenced>(spheres: &[P], params: &BvhParams, block: u32) -> BuiltTree<P> {
    build_with(spheres, params, block, 0)
}

/// The binary tree a wide BVH with leaf blocks of `block` spheres collapses: [`build_in_blocks`], except that nodes
/// of at most `block` spheres are leaves, whatever `leaf_size` says.
///
/// The collapse never opens such a node: its whole subtree becomes one leaf of one block. So splitting it is work
/// thrown away (on random spheres with leaves of 4 and blocks of 8, half of the build's time), and the wide tree
/// collapsed from this tree is the one collapsed from [`build_in_blocks`]'s, but for the order of the spheres
/// inside a block. Embree's wide builders stop at their leaf block the same way.
pub fn build_for_blocks<P: Referenced>(spheres: &[P], params: &BvhParams, block: u32) -> BuiltTree<P> {
    build_with(spheres, params, block, block as usize)
}

/// The build of [`build_in_blocks`], with nodes of at most `leaf_below` spheres made leaves without a decision, then
/// `params.reinsertion` rounds of [`reinsertion`].
fn build_with<P: Referenced>(spheres: &[P], params: &BvhParams, block: u32, leaf_below: usize) -> BuiltTree<P> {
    assert!(block >= 1, "a SIMD block holds at least one sphere");
    if let Err(e) = params.validate() {
        panic!("invalid BVH parameters: {e}");
    }
    let tree = if params.split == Split::SpatialSah {
        super::spatial::build(spheres, params, block, leaf_below)
    } else {
        build_top_down(spheres, params, block, leaf_below)
    };
    reinsertion::optimize(tree, params.reinsertion)
}

/// The top-down recursion of [`build_with`], serial or parallel.
fn build_top_down<P: Referenced>(spheres: &[P], params: &BvhParams, block: u32, leaf_below: usize) -> BuiltTree<P> {
    if spheres.len() >= PARALLEL_MIN_PRIMS && rayon::current_num_threads() > 1 {
        return parallel::build_with(spheres, params, block, leaf_below);
    }
    // Only the sweep reads boxes by id; the other rules read a node's spheres through its `PrimRef`s.
    let boxes: Vec<Aabb> =
        if params.split == Split::SweepSah { spheres.iter().map(P::bounds).collect() } else { Vec::new() };
    let centroids: Vec<Vec3> = spheres.iter().map(P::centroid).collect();
    let inputs = Inputs { params, block, leaf_below, spheres, boxes: &boxes, centroids: &centroids };
    let mut prims: Vec<u32> = (0..spheres.len() as u32).collect();
    let mut refs: Vec<P::Ref> = spheres.iter().map(P::reference).collect();
    let root = NodeBounds::of(&refs);
    let mut b = Builder::new(inputs, spheres.len());
    b.build_node(0, &mut prims, &mut refs, root, 0, 0);
    let ordered = refs.iter().zip(&prims).map(|(r, &id)| P::from_ref(r, spheres, id)).collect();
    BuiltTree { nodes: b.nodes, prim_order: prims, ordered }
}

/// What every node's split decision reads: the parameters and the per-primitive spheres, boxes and centroids.
struct Inputs<'a, P> {
    params: &'a BvhParams,
    /// Spheres per SIMD leaf block the SAH splits count in (see [`CostModel`]).
    block: u32,
    /// Nodes of at most this many spheres are leaves, without a split decision (0: none are).
    leaf_below: usize,
    spheres: &'a [P],
    /// Boxes by primitive id; empty unless the split is the sweep, the one rule that reads them.
    boxes: &'a [Aabb],
    centroids: &'a [Vec3],
}

/// Split rules' scratch space; one per task.
#[derive(Default)]
struct Scratch {
    bins: binned_sah::Bins,
    sweep: sweep_sah::Sweep,
}

impl<P> Clone for Inputs<'_, P> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<P> Copy for Inputs<'_, P> {}

impl<P: Referenced> Inputs<'_, P> {
    /// The SAH cost model of this build.
    #[inline(always)]
    fn costs(&self) -> CostModel {
        CostModel { costs: self.params.sah_costs, block: self.block }
    }

    /// What to do with the node of bounds `nb` (leaf, or split point after reordering `prims` and `refs`), and on a
    /// split the children's bounds.
    #[inline(always)]
    fn decide(
        &self,
        prims: &mut [u32],
        refs: &mut [P::Ref],
        nb: NodeBounds,
        depth: usize,
        scratch: &mut Scratch,
    ) -> (Decision, Option<[NodeBounds; 2]>) {
        let n = prims.len();
        let view = NodeView {
            boxes: self.boxes,
            centroids: self.centroids,
            bounds: nb.bounds,
            centroid_bounds: nb.centroids,
            may_be_leaf: n <= self.params.leaf_size as usize,
        };
        // Rules that reorder `prims` alone leave `refs` to be gathered again.
        let (mut decision, mut children, mut gather) = (Decision::Leaf, None, false);
        if n <= 1 || n <= self.leaf_below {
            // A leaf, as initialized.
        } else if depth + ceil_log2(n) >= MAX_DEPTH - 1 {
            // Halving from here keeps every leaf within MAX_DEPTH, whatever the rule would have done.
            (decision, gather) = (object_median::median(&view, prims), true);
        } else {
            let p = self.params;
            match p.split {
                Split::CentroidMidpoint => decision = split::centroid_midpoint::split(&view, prims, refs),
                Split::ObjectMedian => (decision, gather) = (object_median::split(&view, prims), true),
                Split::BinnedSah => {
                    let bins = &mut scratch.bins;
                    (decision, children) =
                        binned_sah::split(&view, prims, refs, p.sah_bins as usize, self.costs(), bins);
                }
                Split::SweepSah => {
                    (decision, gather) = (sweep_sah::split(&view, prims, self.costs(), &mut scratch.sweep), true)
                }
                Split::SpatialSah => unreachable!("spatial splits are built by `spatial::build`"),
            }
        }
        if decision == Decision::NoSplit {
            (decision, children, gather) = (object_median::median(&view, prims), None, true);
        }
        if gather {
            prim_ref::gather(refs, prims, self.spheres);
        }
        if let (Decision::Split(mid), None) = (decision, children) {
            children = Some([NodeBounds::of(&refs[..mid]), NodeBounds::of(&refs[mid..])]);
        }
        (decision, children)
    }
}

/// The serial recursion: appends a subtree's nodes to one vector, in the order the module doc describes.
struct Builder<'a, P> {
    inputs: Inputs<'a, P>,
    nodes: Vec<FlatNode>,
    scratch: Scratch,
}

impl<'a, P: Referenced> Builder<'a, P> {
    /// A builder whose `nodes` hold the subtree root's slot (index 0) and room for a subtree of `prim_count`.
    fn new(inputs: Inputs<'a, P>, prim_count: usize) -> Self {
        let mut nodes = Vec::with_capacity(2 * prim_count.max(1));
        nodes.push(PLACEHOLDER);
        Builder { inputs, nodes, scratch: Scratch::default() }
    }

    /// Builds the node at `index` over `prims` (with their `refs`, of bounds `nb`), then its subtree.
    fn build_node(
        &mut self,
        index: usize,
        prims: &mut [u32],
        refs: &mut [P::Ref],
        nb: NodeBounds,
        offset: usize,
        depth: usize,
    ) {
        let bounds = nb.bounds;
        match self.inputs.decide(prims, refs, nb, depth, &mut self.scratch) {
            (Decision::Split(mid), Some([l, r])) => {
                let first = self.nodes.len();
                self.nodes.extend([PLACEHOLDER, PLACEHOLDER]);
                self.nodes[index] = FlatNode { bounds, first: first as u32, prim_count: FlatNode::INTERIOR };
                let (left, right) = prims.split_at_mut(mid);
                let (left_refs, right_refs) = refs.split_at_mut(mid);
                self.build_node(first, left, left_refs, l, offset, depth + 1);
                self.build_node(first + 1, right, right_refs, r, offset + mid, depth + 1);
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

    /// Primitives per task of the O(n) passes around the recursion (the per-primitive arrays, the root's bounds).
    const PASS_CHUNK: usize = 1 << 14;

    /// [`super::build_with`] with the per-primitive arrays, the root's bounds and the recursion in parallel.
    pub(super) fn build_with<P: Referenced>(
        spheres: &[P],
        params: &BvhParams,
        block: u32,
        leaf_below: usize,
    ) -> BuiltTree<P> {
        use crate::parallel::map_indices;
        let n = spheres.len();
        let boxes: Vec<Aabb> = match params.split {
            Split::SweepSah => map_indices(n, PASS_CHUNK, |i| spheres[i].bounds()),
            _ => Vec::new(),
        };
        let centroids: Vec<Vec3> = map_indices(n, PASS_CHUNK, |i| spheres[i].centroid());
        let inputs = Inputs { params, block, leaf_below, spheres, boxes: &boxes, centroids: &centroids };
        let mut prims: Vec<u32> = map_indices(n, PASS_CHUNK, |i| i as u32);
        let mut refs: Vec<P::Ref> = map_indices(n, PASS_CHUNK, |i| P::reference(&spheres[i]));
        // The union of the chunks' bounds is that of the serial pass: minima and maxima in any order.
        let root = crate::parallel::map(refs.chunks(PASS_CHUNK).collect(), NodeBounds::of)
            .into_iter()
            .reduce(NodeBounds::union);
        let nodes = build(inputs, &mut prims, &mut refs, root.unwrap_or(NodeBounds::EMPTY));
        let ordered = map_indices(n, PASS_CHUNK, |i| P::from_ref(&refs[i], spheres, prims[i]));
        BuiltTree { nodes, prim_order: prims, ordered }
    }

    /// Builds the whole tree; `prims.len() >= PARALLEL_MIN_PRIMS`.
    fn build<P: Referenced>(
        inputs: Inputs<'_, P>,
        prims: &mut [u32],
        refs: &mut [P::Ref],
        nb: NodeBounds,
    ) -> Vec<FlatNode> {
        let (root, desc) = subtree(inputs, prims, refs, nb, 0, 0);
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
    fn subtree<P: Referenced>(
        inputs: Inputs<'_, P>,
        prims: &mut [u32],
        refs: &mut [P::Ref],
        nb: NodeBounds,
        offset: usize,
        depth: usize,
    ) -> (FlatNode, Descendants) {
        if prims.len() < PARALLEL_MIN_PRIMS {
            let mut b = Builder::new(inputs, prims.len());
            b.build_node(0, prims, refs, nb, offset, depth);
            // Array index i of `b.nodes` (i >= 1) is descendant index i - 1.
            let root = shifted(b.nodes[0], -1);
            let len = b.nodes.len() - 1;
            return (root, Descendants { segments: vec![Segment { nodes: b.nodes, skip: 1, shift: -1 }], len });
        }
        let bounds = nb.bounds;
        let (Decision::Split(mid), Some([l_nb, r_nb])) = inputs.decide(prims, refs, nb, depth, &mut Scratch::default())
        else {
            let leaf = FlatNode { bounds, first: offset as u32, prim_count: prims.len() as u32 };
            return (leaf, Descendants::default());
        };
        let (left, right) = prims.split_at_mut(mid);
        let (left_refs, right_refs) = refs.split_at_mut(mid);
        let ((l, l_desc), (r, r_desc)) = rayon::join(
            || subtree(inputs, left, left_refs, l_nb, offset, depth + 1),
            || subtree(inputs, right, right_refs, r_nb, offset + mid, depth + 1),
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
