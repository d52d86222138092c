//! Split rules, one file each. Each reorders a node's primitive indices and says where the left child ends.

pub mod binned_sah;
pub mod centroid_midpoint;
pub mod object_median;
pub mod sweep_sah;

use glam::Vec3;

use crate::geometry::Aabb;

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

/// Moves the primitives for which `left` holds to the front; returns how many there are.
pub fn partition(prims: &mut [u32], mut left: impl FnMut(u32) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..prims.len() {
        if left(prims[i]) {
            prims.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

/// `Split(mid)` when both sides are non-empty, else `NoSplit`.
pub fn proper(mid: usize, len: usize) -> Decision {
    if mid == 0 || mid == len { Decision::NoSplit } else { Decision::Split(mid) }
}
