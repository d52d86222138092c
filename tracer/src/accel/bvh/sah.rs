//! The surface area heuristic's cost model, shared by the SAH splits and the tree statistics.
//!
//! Cost of a tree = `traversal * Σ_interior SA(n) / SA(root) + intersection * Σ_leaves count(l) * SA(l) /
//! SA(root)` (Goldsmith–Salmon, MacDonald–Booth). The SAH splits build with [`SahCosts`] (a parameter, unit
//! by default); the trees' reported SAH cost always uses unit costs, so that it compares across builds.

use std::hash::{Hash, Hasher};

use serde::{Deserialize, Serialize};

/// Cost of visiting one interior node in the reported SAH cost, relative to one ray-sphere test.
pub const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one ray-sphere test in the reported SAH cost.
pub const INTERSECTION_COST: f32 = 1.0;

/// The two constants of the cost model a SAH split builds with (positive and finite).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SahCosts {
    /// Cost of visiting one interior node.
    pub traversal: f32,
    /// Cost of one ray-sphere test.
    pub intersection: f32,
}

impl SahCosts {
    /// Both costs 1 (the reported SAH cost's model).
    pub const UNIT: SahCosts = SahCosts { traversal: TRAVERSAL_COST, intersection: INTERSECTION_COST };

    /// Expected cost of making a node of `count` spheres a leaf.
    pub fn leaf_cost(&self, count: usize) -> f32 {
        self.intersection * count as f32
    }

    /// Expected cost of splitting a node of surface area `parent_area` into two children whose term is
    /// `key = left_area * left_count + right_area * right_count`.
    ///
    /// Every step is monotone, so the cost is non-decreasing in `key`: a candidate whose key is not below another's
    /// cannot cost less, and a split search can skip computing its cost.
    #[inline(always)]
    pub fn split_cost_of_key(&self, parent_area: f32, key: f32) -> f32 {
        let parent_area = if parent_area > 0.0 { parent_area } else { 1.0 };
        self.traversal + self.intersection * key / parent_area
    }
}

impl Default for SahCosts {
    fn default() -> Self {
        SahCosts::UNIT
    }
}

// Costs are validated finite, so bitwise equality is equality.
impl Eq for SahCosts {}

impl Hash for SahCosts {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.traversal.to_bits().hash(state);
        self.intersection.to_bits().hash(state);
    }
}

/// The cost model a SAH split evaluates: [`SahCosts`] with spheres counted in SIMD blocks of `block` lanes.
///
/// A leaf of `n` spheres costs `intersection * ceil(n / block)` and a split counts each child's spheres the same
/// way (tinybvh rounds leaf sizes up to its SIMD width in the SAH). With `block = 1` (every tree but the wide
/// BVH) both costs are bit-identical to [`SahCosts::leaf_cost`] and [`SahCosts::split_cost_of_key`] of plain counts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    /// The cost constants.
    pub costs: SahCosts,
    /// Spheres a leaf tests at once (1: one by one).
    pub block: u32,
}

impl CostModel {
    /// Blocks needed for `count` spheres.
    #[inline(always)]
    pub fn blocks(&self, count: usize) -> usize {
        // Blocks of SIMD lanes come in powers of two: a shift, not a division, in the split search's inner loop.
        let block = self.block as usize;
        if block.is_power_of_two() { (count + block - 1) >> block.trailing_zeros() } else { count.div_ceil(block) }
    }

    /// Expected cost of making a node of `count` spheres a leaf.
    pub fn leaf_cost(&self, count: usize) -> f32 {
        self.costs.leaf_cost(self.blocks(count))
    }

    /// Expected cost of splitting a node of surface area `parent_area` into the two given children.
    pub fn split_cost(
        &self,
        parent_area: f32,
        left_area: f32,
        left_count: usize,
        right_area: f32,
        right_count: usize,
    ) -> f32 {
        self.split_cost_of_key(parent_area, self.split_key(left_area, left_count, right_area, right_count))
    }

    /// [`CostModel::split_cost`] from [`CostModel::split_key`]'s term.
    #[inline(always)]
    pub fn split_cost_of_key(&self, parent_area: f32, key: f32) -> f32 {
        self.costs.split_cost_of_key(parent_area, key)
    }

    /// The children's term of [`CostModel::split_cost`]; see [`SahCosts::split_cost_of_key`].
    #[inline(always)]
    pub fn split_key(&self, left_area: f32, left_count: usize, right_area: f32, right_count: usize) -> f32 {
        left_area * self.blocks(left_count) as f32 + right_area * self.blocks(right_count) as f32
    }
}

/// Expected cost of making a node of `count` spheres a leaf, with unit costs.
pub fn leaf_cost(count: usize) -> f32 {
    SahCosts::UNIT.leaf_cost(count)
}
