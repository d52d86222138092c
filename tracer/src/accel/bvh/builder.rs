//! The shared top-down builder: recursive splitting into the array layout both tree types start from.
//!
//! Nodes come out as sibling pairs in depth-first order: the root at index 0, the two children of an
//! interior node side by side at `first` and `first + 1`, and a node's whole subtree before its
//! sibling's. Leaves name a run of `prim_order`.

use glam::Vec3;

use super::params::{BvhParams, Split};
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

struct Builder<'a> {
    params: &'a BvhParams,
    boxes: Vec<Aabb>,
    centroids: Vec<Vec3>,
    nodes: Vec<FlatNode>,
    bins: binned_sah::Bins,
    sweep: sweep_sah::Sweep,
}

/// Builds a tree over `spheres` with the split rule and leaf size of `params`.
pub fn build(spheres: &[Sphere], params: &BvhParams) -> BuiltTree {
    if let Err(e) = params.validate() {
        panic!("invalid BVH parameters: {e}");
    }
    let boxes: Vec<Aabb> = spheres.iter().map(Sphere::bounds).collect();
    let centroids: Vec<Vec3> = spheres.iter().map(|s| s.center).collect();
    let mut prims: Vec<u32> = (0..spheres.len() as u32).collect();
    let mut b = Builder {
        params,
        boxes,
        centroids,
        nodes: Vec::with_capacity(2 * spheres.len().max(1)),
        bins: Default::default(),
        sweep: Default::default(),
    };
    b.nodes.push(FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 });
    b.build_node(0, &mut prims, 0, 0);
    BuiltTree { nodes: b.nodes, prim_order: prims }
}

fn ceil_log2(n: usize) -> usize {
    (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize
}

impl Builder<'_> {
    fn build_node(&mut self, index: usize, prims: &mut [u32], offset: usize, depth: usize) {
        let mut bounds = Aabb::EMPTY;
        let mut centroid_bounds = Aabb::EMPTY;
        for &p in prims.iter() {
            bounds = bounds.union(&self.boxes[p as usize]);
            centroid_bounds.grow(self.centroids[p as usize]);
        }
        let n = prims.len();
        let view = NodeView {
            boxes: &self.boxes,
            centroids: &self.centroids,
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
            match self.params.split {
                Split::CentroidMidpoint => split::centroid_midpoint::split(&view, prims),
                Split::ObjectMedian => object_median::split(&view, prims),
                Split::BinnedSah => {
                    binned_sah::split(&view, prims, self.params.sah_bins as usize, self.params.sah_costs, &mut self.bins)
                }
                Split::SweepSah => sweep_sah::split(&view, prims, self.params.sah_costs, &mut self.sweep),
            }
        };
        let decision = match decision {
            Decision::NoSplit => object_median::median(&view, prims),
            d => d,
        };
        match decision {
            Decision::Split(mid) => {
                let first = self.nodes.len();
                let placeholder = FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 };
                self.nodes.extend([placeholder, placeholder]);
                self.nodes[index] = FlatNode { bounds, first: first as u32, prim_count: FlatNode::INTERIOR };
                let (left, right) = prims.split_at_mut(mid);
                self.build_node(first, left, offset, depth + 1);
                self.build_node(first + 1, right, offset + mid, depth + 1);
            }
            _ => self.nodes[index] = FlatNode { bounds, first: offset as u32, prim_count: n as u32 },
        }
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
