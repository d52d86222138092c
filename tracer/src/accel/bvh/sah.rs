//! The surface area heuristic's cost model, shared by the SAH splits and the tree statistics.
//!
//! Cost of a tree = `TRAVERSAL_COST * Σ_interior SA(n) / SA(root) + INTERSECTION_COST * Σ_leaves
//! count(l) * SA(l) / SA(root)` (Goldsmith–Salmon, MacDonald–Booth), with both constants 1.

/// Cost of visiting one interior node, relative to one ray-sphere test.
pub const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one ray-sphere test.
pub const INTERSECTION_COST: f32 = 1.0;

/// Expected cost of making a node of `count` spheres a leaf.
pub fn leaf_cost(count: usize) -> f32 {
    INTERSECTION_COST * count as f32
}

/// Expected cost of splitting a node of surface area `parent_area` into the two given children.
pub fn split_cost(parent_area: f32, left_area: f32, left_count: usize, right_area: f32, right_count: usize) -> f32 {
    let parent_area = if parent_area > 0.0 { parent_area } else { 1.0 };
    TRAVERSAL_COST
        + INTERSECTION_COST * (left_area * left_count as f32 + right_area * right_count as f32) / parent_area
}
