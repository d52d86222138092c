//! The binary tree every builder produces: the array layout's node ([`FlatNode`]), the built tree ([`BuiltTree`])
//! and the depth bound ([`MAX_DEPTH`]) the builders keep and the traversal stacks are sized by.

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
pub struct BuiltTree<P = Sphere> {
    /// Nodes; the root is `nodes[0]`.
    pub nodes: Vec<FlatNode>,
    /// Primitive ids in leaf order: a permutation, but for spatial splits, which may repeat an id (in other leaves).
    pub prim_order: Vec<u32>,
    /// The primitives of `prim_order`, in the same order (the builder's own copy, read in sequence).
    pub ordered: Vec<P>,
}

/// `ceil(log2(n))` (0 for n ≤ 1): the least depth of a binary tree with `n` leaves.
pub(super) fn ceil_log2(n: usize) -> usize {
    (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize
}

/// A node slot reserved before its subtree is built.
pub(super) const PLACEHOLDER: FlatNode = FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 };

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_log2_matches_definition() {
        assert_eq!([1, 2, 3, 4, 5, 8, 9].map(ceil_log2), [0, 1, 2, 2, 3, 3, 4]);
    }
}
