//! Binned surface area heuristic (Wald 2007): candidate planes between equal-width centroid bins.
//!
//! One pass over the node's [`PrimRef`]s bins every primitive on all three axes at once; the chosen axis's bins
//! then give the children's boxes, and the partition their centroid bounds, so children need no pass of their own.

use glam::Vec3A;

use super::{Box3A, Decision, NodeBounds, NodeView, PrimRef, partition, proper};
use crate::accel::bvh::sah::CostModel;

/// One bin: the union of its primitives' boxes and their number.
#[derive(Clone, Copy)]
struct Bin {
    bounds: Box3A,
    count: usize,
}

impl Bin {
    const EMPTY: Bin = Bin { bounds: Box3A::EMPTY, count: 0 };

    #[inline(always)]
    fn add(&mut self, b: &Box3A) {
        self.bounds.add(b);
        self.count += 1;
    }
}

/// Scratch space kept between nodes so that binning allocates once per build.
#[derive(Default)]
pub struct Bins {
    /// `bin_count` bins per axis, x then y then z.
    bins: Vec<Bin>,
    right_area: Vec<f32>,
}

/// Bins every primitive on the three axes in one pass; axes of zero `scale` put everything in their first bin.
#[inline]
fn bin_all(bins: &mut [Bin], bin_count: usize, refs: &[PrimRef], min: Vec3A, scale: Vec3A) {
    let (bx, rest) = bins.split_at_mut(bin_count);
    let (by, bz) = rest.split_at_mut(bin_count);
    let last = bin_count - 1;
    for r in refs {
        let f = (r.centroid - min) * scale;
        bx[(f.x as usize).min(last)].add(&r.bounds);
        by[(f.y as usize).min(last)].add(&r.bounds);
        bz[(f.z as usize).min(last)].add(&r.bounds);
    }
}

/// The cheapest plane so far.
#[derive(Clone, Copy)]
struct Candidate {
    cost: f32,
    /// The children's term of the cost ([`CostModel::split_key`]); the cost is non-decreasing in it.
    key: f32,
    axis: usize,
    /// First bin on the right.
    first_right: usize,
}

/// Updates `best` with the planes of one axis's `bins` that cost strictly less, in bin order.
///
/// Exactly the candidates and comparisons of evaluating every plane: a plane after an empty bin has the children
/// of the plane before it, so the same cost, and a plane whose key is not below the best's cannot cost less.
#[inline]
fn best_plane(
    bins: &[Bin],
    right_area: &mut [f32],
    n: usize,
    parent_area: f32,
    costs: CostModel,
    axis: usize,
    best: &mut Option<Candidate>,
) {
    let right_area = &mut right_area[..bins.len()];
    let mut acc = Box3A::EMPTY;
    let mut area = 0.0;
    for b in (1..bins.len()).rev() {
        if bins[b].count > 0 {
            acc.add(&bins[b].bounds);
            area = acc.surface_area();
        }
        right_area[b] = area;
    }
    let (mut left, mut left_count) = (Box3A::EMPTY, 0);
    for b in 1..bins.len() {
        if bins[b - 1].count == 0 {
            continue;
        }
        left.add(&bins[b - 1].bounds);
        left_count += bins[b - 1].count;
        let right_count = n - left_count;
        if right_count == 0 {
            break;
        }
        let key = costs.split_key(left.surface_area(), left_count, right_area[b], right_count);
        if let Some(c) = best
            && !(key < c.key)
        {
            continue;
        }
        let cost = costs.split_cost_of_key(parent_area, key);
        if best.is_none_or(|c| cost < c.cost) {
            *best = Some(Candidate { cost, key, axis, first_right: b });
        }
    }
}

/// Chooses the cheapest plane among `bin_count - 1` per axis, or a leaf when that is cheaper and allowed.
///
/// On a split, also returns the two children's bounds.
pub fn split(
    node: &NodeView<'_>,
    prims: &mut [u32],
    refs: &mut [PrimRef],
    bin_count: usize,
    costs: CostModel,
    scratch: &mut Bins,
) -> (Decision, Option<[NodeBounds; 2]>) {
    let cb = node.centroid_bounds;
    let extent = cb.extent();
    let parent_area = node.bounds.surface_area();
    let scale =
        Vec3A::from_array(std::array::from_fn(|a| if extent[a] > 0.0 { bin_count as f32 / extent[a] } else { 0.0 }));
    if scratch.bins.len() != 3 * bin_count {
        scratch.bins.resize(3 * bin_count, Bin::EMPTY);
        scratch.right_area.resize(bin_count, 0.0);
    }
    scratch.bins.fill(Bin::EMPTY);
    bin_all(&mut scratch.bins, bin_count, refs, cb.min.into(), scale);
    let mut best = None;
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        let bins = &scratch.bins[axis * bin_count..(axis + 1) * bin_count];
        best_plane(bins, &mut scratch.right_area, prims.len(), parent_area, costs, axis, &mut best);
    }
    let Some(Candidate { cost, axis, first_right, .. }) = best else {
        return (if node.may_be_leaf { Decision::Leaf } else { Decision::NoSplit }, None);
    };
    if node.may_be_leaf && costs.leaf_cost(prims.len()) <= cost {
        return (Decision::Leaf, None);
    }
    let bins = &scratch.bins[axis * bin_count..(axis + 1) * bin_count];
    let mut sides = [Box3A::EMPTY; 2];
    for (i, bin) in bins.iter().enumerate() {
        sides[(i >= first_right) as usize].add(&bin.bounds);
    }
    let (min, s, last) = (cb.min[axis], scale[axis], bin_count - 1);
    let mut centroids = [Box3A::EMPTY; 2];
    let n = partition(prims, refs, |r| {
        let c = r.centroid[axis];
        let left = (((c - min) * s) as usize).min(last) < first_right;
        centroids[!left as usize].grow(r.centroid);
        left
    });
    let children = [0, 1].map(|i| NodeBounds { bounds: sides[i].aabb(), centroids: centroids[i].aabb() });
    (proper(n, prims.len()), Some(children))
}
