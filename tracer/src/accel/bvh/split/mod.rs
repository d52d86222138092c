//! Split rules, one file each. Each reorders a node's primitive indices and says where the left child ends.

pub mod binned_sah;
pub mod centroid_midpoint;
pub mod clip;
pub mod object_median;
pub mod prim_ref;
pub mod sweep_sah;

use glam::Vec3;

use crate::geometry::Aabb;
pub use prim_ref::{Box3A, BoxRef, BuildRef, PrimRef, Referenced};

/// What a split rule decided for a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    /// Make the node a leaf (only when it may be one).
    Leaf,
    /// The first `n` primitives (after reordering) form the left child; `0 < n < len`.
    Split(usize),
    /// The rule found no useful split; the builder falls back to the object median.
    NoSplit,
}

/// What a split rule sees of a node: per-primitive boxes and centroids (indexed by primitive id),
/// the node's bounds and centroid bounds, and whether the node may become a leaf.
pub struct NodeView<'a> {
    /// Box of every primitive.
    pub boxes: &'a [Aabb],
    /// Centroid of every primitive.
    pub centroids: &'a [Vec3],
    /// Bounds of the node's primitives.
    pub bounds: Aabb,
    /// Bounds of the node's primitive centroids.
    pub centroid_bounds: Aabb,
    /// True when the node holds few enough primitives to be a leaf.
    pub may_be_leaf: bool,
}

/// A node's box and the box of its primitives' centroids.
#[derive(Clone, Copy, Debug)]
pub struct NodeBounds {
    /// Union of the primitives' boxes.
    pub bounds: Aabb,
    /// Bounds of the primitives' centroids.
    pub centroids: Aabb,
}

impl NodeBounds {
    /// Bounds of nothing.
    pub const EMPTY: NodeBounds = NodeBounds { bounds: Aabb::EMPTY, centroids: Aabb::EMPTY };

    /// The bounds of `refs`.
    #[inline]
    pub fn of<R: BuildRef>(refs: &[R]) -> Self {
        let (mut bounds, mut centroids) = (Box3A::EMPTY, Box3A::EMPTY);
        for r in refs {
            bounds.add(&r.bounds());
            centroids.grow(r.centroid());
        }
        NodeBounds { bounds: bounds.aabb(), centroids: centroids.aabb() }
    }

    /// The bounds of both nodes' primitives together.
    pub fn union(self, other: Self) -> Self {
        NodeBounds { bounds: self.bounds.union(&other.bounds), centroids: self.centroids.union(&other.centroids) }
    }
}

/// Moves the primitives (ids and their [`PrimRef`]s alike) for which `left` holds to the front; returns how many
/// there are. The order is that of swapping each match with the first non-match before it.
#[inline]
pub fn partition<R: BuildRef>(prims: &mut [u32], refs: &mut [R], mut left: impl FnMut(&R) -> bool) -> usize {
    assert_eq!(prims.len(), refs.len());
    let mut mid = 0;
    for i in 0..prims.len() {
        // Without a branch: a match swaps places `i` and `mid`, a non-match rewrites both in place.
        let l = left(&refs[i]);
        let (from_i, from_mid) = if l { (mid, i) } else { (i, mid) };
        let (p, q) = (prims[from_i], prims[from_mid]);
        let (r, s) = (refs[from_i], refs[from_mid]);
        (prims[i], refs[i]) = (p, r);
        (prims[mid], refs[mid]) = (q, s);
        mid += l as usize;
    }
    mid
}

/// `Split(mid)` when both sides are non-empty, else `NoSplit`.
pub fn proper(mid: usize, len: usize) -> Decision {
    if mid == 0 || mid == len { Decision::NoSplit } else { Decision::Split(mid) }
}
