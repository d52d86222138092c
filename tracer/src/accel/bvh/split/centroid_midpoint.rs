//! The paper's split: the plane through the middle of the centroid bounds' longest axis.

use super::{BuildRef, Decision, NodeView, partition, proper};

/// Splits at the midpoint of the longest centroid axis; nodes that may be leaves become leaves.
pub fn split<R: BuildRef>(node: &NodeView<'_>, prims: &mut [u32], refs: &mut [R]) -> Decision {
    if node.may_be_leaf {
        return Decision::Leaf;
    }
    let axis = node.centroid_bounds.longest_axis();
    let mid = node.centroid_bounds.center()[axis];
    let n = partition(prims, refs, |r| r.centroid()[axis] < mid);
    proper(n, prims.len())
}
