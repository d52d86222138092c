//! Equal counts on both sides, by centroid order on the longest centroid axis.

use super::{Decision, NodeView};

/// Splits at the median centroid; also the builder's fallback, so it always splits nodes of two or more.
pub fn split(node: &NodeView<'_>, prims: &mut [u32]) -> Decision {
    if node.may_be_leaf {
        return Decision::Leaf;
    }
    median(node, prims)
}

/// Splits at the median without asking whether the node may be a leaf.
pub fn median(node: &NodeView<'_>, prims: &mut [u32]) -> Decision {
    let axis = node.centroid_bounds.longest_axis();
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |&a, &b| {
        let (ca, cb) = (node.centroids[a as usize][axis], node.centroids[b as usize][axis]);
        ca.total_cmp(&cb).then(a.cmp(&b))
    });
    Decision::Split(mid)
}
