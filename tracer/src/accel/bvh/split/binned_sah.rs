//! Binned surface area heuristic (Wald 2007): candidate planes between equal-width centroid bins.
//!
//! One pass over the node's [`PrimRef`]s bins every primitive on all three axes at once; the chosen axis's bins
//! then give the children's boxes, and the partition their centroid bounds, so children need no pass of their own.
//!
//! Nodes of [`PARALLEL_BIN_MIN_PRIMS`] or more, in a pool of more than one thread, bin chunks of their primitives
//! in parallel and merge the chunks' bins. Merging is exact whatever the chunks (counts add, boxes take minima and
//! maxima), so the bins, and the tree, are those of the serial pass: the top of the tree, whose nodes the builder
//! splits one at a time, then uses every thread too. The partition stays serial: its order (each match swapped
//! with the first non-match before it) is the tree's primitive order, which a parallel partition would change.

use glam::Vec3A;

use super::{Box3A, BuildRef, Decision, NodeBounds, NodeView, partition, proper};
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

    /// Adds the primitives of `other`.
    #[inline(always)]
    fn merge(&mut self, other: &Bin) {
        self.bounds.add(&other.bounds);
        self.count += other.count;
    }
}

/// Nodes of at least this many primitives bin in parallel (when the pool has more than one thread).
///
/// The builder splits the top nodes one at a time (the root alone, then one node per thread, ...), so binning
/// them in parallel is what keeps the other threads busy there; below the top, every thread has subtrees of its
/// own and parallel binning only adds the merge. 65536 lets the root of 1e5 spheres and the top four levels of 1e6
/// bin in parallel, in chunks of at least [`BIN_CHUNK`] (tens of microseconds each, far above a task's cost). On
/// two cores, 32768, 65536 and 262144 built 1e5 and 1e6 random spheres equally fast within noise (the root's
/// binning is a few percent of a build); 65536 leaves more threads something to do at the top.
pub const PARALLEL_BIN_MIN_PRIMS: usize = 1 << 16;

/// Fewest primitives per task of the parallel binning.
const BIN_CHUNK: usize = 1 << 13;

/// Scratch space kept between nodes so that binning allocates once per build.
#[derive(Default)]
pub struct Bins {
    /// `bin_count` bins per axis, x then y then z.
    bins: Vec<Bin>,
    right_area: Vec<f32>,
}

/// Bin of each axis for a centroid `c`: `((c - min) * scale) as usize`, at most `last` (NaN, from an infinite
/// scale on a zero offset, goes to bin 0, as `as usize` puts it).
#[inline(always)]
fn bin_index(c: Vec3A, min: Vec3A, scale: Vec3A, last: Vec3A) -> [usize; 3] {
    // Clamped in floats first (`max` returns its argument for NaN), the truncation needs no saturation.
    let f = ((c - min) * scale).max(Vec3A::ZERO).min(last);
    // SAFETY: every lane is finite and in [0, last], so it truncates to a u32 exactly.
    f.to_array().map(|x| unsafe { x.to_int_unchecked::<u32>() } as usize)
}

/// Bins every primitive on the three axes in one pass; axes of zero `scale` put everything in their first bin.
#[inline]
fn bin_all<R: BuildRef>(bins: &mut [Bin], bin_count: usize, refs: &[R], min: Vec3A, scale: Vec3A) {
    let (bx, rest) = bins.split_at_mut(bin_count);
    let (by, bz) = rest.split_at_mut(bin_count);
    let last = Vec3A::splat((bin_count - 1) as f32);
    for r in refs {
        let ([x, y, z], b) = (bin_index(r.centroid(), min, scale, last), r.bounds());
        bx[x].add(&b);
        by[y].add(&b);
        bz[z].add(&b);
    }
}

/// [`bin_all`] over chunks of `refs` in parallel, the chunks' bins merged into `bins`.
fn bin_all_parallel<R: BuildRef>(bins: &mut [Bin], bin_count: usize, refs: &[R], min: Vec3A, scale: Vec3A) {
    // Bins merge exactly (minima, maxima and counts), so the chunks' order does not matter.
    let merged = crate::parallel::map(refs.chunks(BIN_CHUNK).collect(), |chunk| {
        let mut acc = vec![Bin::EMPTY; bins.len()];
        bin_all(&mut acc, bin_count, chunk, min, scale);
        acc
    })
    .into_iter()
    .reduce(|mut a, b| {
        a.iter_mut().zip(&b).for_each(|(a, b)| a.merge(b));
        a
    });
    if let Some(merged) = merged {
        bins.copy_from_slice(&merged);
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
            area = acc.surface_area_of_nonempty();
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
        let key = costs.split_key(left.surface_area_of_nonempty(), left_count, right_area[b], right_count);
        // Only a key strictly below the best is evaluated further (a NaN key never is).
        if let Some(c) = best
            && key.partial_cmp(&c.key) != Some(std::cmp::Ordering::Less)
        {
            continue;
        }
        let cost = costs.split_cost_of_key(parent_area, key);
        if best.is_none_or(|c| cost < c.cost) {
            *best = Some(Candidate { cost, key, axis, first_right: b });
        }
    }
}

/// The cheapest plane of a node's binning, with what partitioning by it needs.
#[derive(Clone, Copy, Debug)]
pub struct ObjectPlane {
    /// The split's cost under the build's [`CostModel`].
    pub cost: f32,
    axis: usize,
    first_right: usize,
    min: Vec3A,
    scale: Vec3A,
    last: Vec3A,
}

impl ObjectPlane {
    /// True when a primitive of centroid `c` goes to the left child.
    #[inline(always)]
    pub fn goes_left(&self, c: Vec3A) -> bool {
        bin_index(c, self.min, self.scale, self.last)[self.axis] < self.first_right
    }

    /// The two children's boxes, from the bins `best` left in `scratch`.
    pub fn sides(&self, scratch: &Bins) -> [Box3A; 2] {
        let bin_count = scratch.bins.len() / 3;
        let bins = &scratch.bins[self.axis * bin_count..(self.axis + 1) * bin_count];
        let mut sides = [Box3A::EMPTY; 2];
        for (i, bin) in bins.iter().enumerate() {
            sides[(i >= self.first_right) as usize].add(&bin.bounds);
        }
        sides
    }
}

/// Bins `refs` and returns the cheapest of the `bin_count - 1` planes per axis (none when no axis has extent).
pub fn best<R: BuildRef>(
    node: &NodeView<'_>,
    refs: &[R],
    bin_count: usize,
    costs: CostModel,
    scratch: &mut Bins,
) -> Option<ObjectPlane> {
    let cb = node.centroid_bounds;
    let extent = cb.extent();
    let parent_area = node.bounds.surface_area();
    let scale =
        Vec3A::from_array(std::array::from_fn(|a| if extent[a] > 0.0 { bin_count as f32 / extent[a] } else { 0.0 }));
    let (min, last) = (Vec3A::from(cb.min), Vec3A::splat((bin_count - 1) as f32));
    if scratch.bins.len() != 3 * bin_count {
        scratch.bins.resize(3 * bin_count, Bin::EMPTY);
        scratch.right_area.resize(bin_count, 0.0);
    }
    scratch.bins.fill(Bin::EMPTY);
    if refs.len() >= PARALLEL_BIN_MIN_PRIMS && rayon::current_num_threads() > 1 {
        bin_all_parallel(&mut scratch.bins, bin_count, refs, min, scale);
    } else {
        bin_all(&mut scratch.bins, bin_count, refs, min, scale);
    }
    let mut best = None;
    for axis in (0..3).filter(|&a| extent[a] > 0.0) {
        let bins = &scratch.bins[axis * bin_count..(axis + 1) * bin_count];
        best_plane(bins, &mut scratch.right_area, refs.len(), parent_area, costs, axis, &mut best);
    }
    best.map(|Candidate { cost, axis, first_right, .. }| ObjectPlane { cost, axis, first_right, min, scale, last })
}

/// Chooses the cheapest plane among `bin_count - 1` per axis, or a leaf when that is cheaper and allowed.
///
/// On a split, also returns the two children's bounds.
pub fn split<R: BuildRef>(
    node: &NodeView<'_>,
    prims: &mut [u32],
    refs: &mut [R],
    bin_count: usize,
    costs: CostModel,
    scratch: &mut Bins,
) -> (Decision, Option<[NodeBounds; 2]>) {
    let Some(plane) = best(node, refs, bin_count, costs, scratch) else {
        return (if node.may_be_leaf { Decision::Leaf } else { Decision::NoSplit }, None);
    };
    if node.may_be_leaf && costs.leaf_cost(prims.len()) <= plane.cost {
        return (Decision::Leaf, None);
    }
    let sides = plane.sides(scratch);
    let mut centroids = [Box3A::EMPTY; 2];
    let n = partition(prims, refs, |r| {
        let c = r.centroid();
        let left = plane.goes_left(c);
        centroids[!left as usize].grow(c);
        left
    });
    let children = [0, 1].map(|i| NodeBounds { bounds: sides[i].aabb(), centroids: centroids[i].aabb() });
    (proper(n, prims.len()), Some(children))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bin_index_is_the_saturating_conversion_clamped_to_the_last_bin() {
        let (min, last) = (Vec3A::ZERO, Vec3A::splat(15.0));
        let reference = |f: f32| (f as usize).min(15);
        for f in [0.0, 0.99, 1.0, 7.5, 14.999, 15.0, 16.0, 1e30, f32::INFINITY, f32::NAN] {
            // Scale 1 gives `f` itself; a NaN or infinite product comes from an infinite scale.
            let got = bin_index(Vec3A::new(f, 0.0, 1.0), min, Vec3A::new(1.0, f32::INFINITY, f32::INFINITY), last);
            assert_eq!(got, [reference(f), reference(f32::NAN), reference(f32::INFINITY)], "{f}");
        }
    }
}
