//! Binned surface area heuristic (Wald 2007): candidate planes between equal-width centroid bins.

use super::{Decision, NodeView, partition, proper};
use crate::accel::bvh::sah::CostModel;
use crate::geometry::Aabb;

/// Scratch space kept between nodes so that binning allocates once per build.
#[derive(Default)]
pub struct Bins {
    bounds: Vec<Aabb>,
    counts: Vec<usize>,
    right_area: Vec<f32>,
}

/// Chooses the cheapest plane among `bin_count - 1` per axis, or a leaf when that is cheaper and allowed.
pub fn split(node: &NodeView<'_>, prims: &mut [u32], bin_count: usize, costs: CostModel, bins: &mut Bins) -> Decision {
    let cb = node.centroid_bounds;
    let extent = cb.extent();
    let parent_area = node.bounds.surface_area();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, first bin on the right)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = bin_count as f32 / extent[axis];
        let bin_of = |p: u32| (((node.centroids[p as usize][axis] - cb.min[axis]) * scale) as usize).min(bin_count - 1);
        bins.bounds.clear();
        bins.bounds.resize(bin_count, Aabb::EMPTY);
        bins.counts.clear();
        bins.counts.resize(bin_count, 0);
        for &p in prims.iter() {
            let b = bin_of(p);
            bins.bounds[b] = bins.bounds[b].union(&node.boxes[p as usize]);
            bins.counts[b] += 1;
        }
        bins.right_area.clear();
        bins.right_area.resize(bin_count, 0.0);
        let mut acc = Aabb::EMPTY;
        for b in (1..bin_count).rev() {
            acc = acc.union(&bins.bounds[b]);
            bins.right_area[b] = acc.surface_area();
        }
        let (mut left, mut left_count) = (Aabb::EMPTY, 0);
        for b in 1..bin_count {
            left = left.union(&bins.bounds[b - 1]);
            left_count += bins.counts[b - 1];
            let right_count = prims.len() - left_count;
            if left_count == 0 || right_count == 0 {
                continue;
            }
            let cost = costs.split_cost(parent_area, left.surface_area(), left_count, bins.right_area[b], right_count);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let Some((cost, axis, first_right)) = best else {
        return if node.may_be_leaf { Decision::Leaf } else { Decision::NoSplit };
    };
    if node.may_be_leaf && costs.leaf_cost(prims.len()) <= cost {
        return Decision::Leaf;
    }
    let scale = bin_count as f32 / extent[axis];
    let n = partition(prims, |p| {
        (((node.centroids[p as usize][axis] - cb.min[axis]) * scale) as usize).min(bin_count - 1) < first_right
    });
    proper(n, prims.len())
}
