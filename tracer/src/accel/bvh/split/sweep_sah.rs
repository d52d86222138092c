//! Full-sweep surface area heuristic: every split position in centroid order on every axis.

use super::{Decision, NodeView, proper};
use crate::accel::bvh::sah::CostModel;
use crate::geometry::Aabb;

/// Scratch space kept between nodes.
#[derive(Default)]
pub struct Sweep {
    order: Vec<u32>,
    right_area: Vec<f32>,
}

fn sort_on_axis(order: &mut [u32], node: &NodeView<'_>, axis: usize) {
    order.sort_unstable_by(|&a, &b| {
        node.centroids[a as usize][axis].total_cmp(&node.centroids[b as usize][axis]).then(a.cmp(&b))
    });
}

/// Chooses the cheapest split position on any axis, or a leaf when that is cheaper and allowed.
pub fn split(node: &NodeView<'_>, prims: &mut [u32], costs: CostModel, sweep: &mut Sweep) -> Decision {
    let n = prims.len();
    let parent_area = node.bounds.surface_area();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, left count)
    for axis in 0..3 {
        sweep.order.clear();
        sweep.order.extend_from_slice(prims);
        sort_on_axis(&mut sweep.order, node, axis);
        sweep.right_area.clear();
        sweep.right_area.resize(n, 0.0);
        let mut acc = Aabb::EMPTY;
        for i in (1..n).rev() {
            acc = acc.union(&node.boxes[sweep.order[i] as usize]);
            sweep.right_area[i] = acc.surface_area();
        }
        let mut left = Aabb::EMPTY;
        for i in 1..n {
            left = left.union(&node.boxes[sweep.order[i - 1] as usize]);
            let cost = costs.split_cost(parent_area, left.surface_area(), i, sweep.right_area[i], n - i);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, i));
            }
        }
    }
    let Some((cost, axis, left_count)) = best else {
        return if node.may_be_leaf { Decision::Leaf } else { Decision::NoSplit };
    };
    if node.may_be_leaf && costs.leaf_cost(n) <= cost {
        return Decision::Leaf;
    }
    sort_on_axis(prims, node, axis);
    proper(left_count, n)
}
