//! The builder of [`Split::SpatialSah`](super::Split::SpatialSah): spatial splits (SBVH; Stich, Friedrich and
//! Dietrich 2009).
//!
//! Each node bins its references' centroids for the binned object SAH ([`binned_sah::best`]). Where the best object
//! split's two children overlap by more than `spatial_alpha` times the root's surface area, it also bins space:
//! `sah_bins` equal slabs of the node's box per axis, each reference clipped into every slab it crosses
//! ([`Referenced::halves`]: triangles clipped exactly, spheres by their box) and counted where it enters and
//! where it leaves. A spatial plane sends a straddling reference to both children, each with the box of its part on
//! that side; the cheaper split under the same [`CostModel`] as the other SAH rules wins (blocks of `block`, the leaf
//! test of `leaf_size`). While applying a spatial split, a straddling reference is unsplit (sent whole to one side)
//! when that costs less than duplicating it (the paper's reference unsplitting).
//!
//! References are duplicated at most `floor(DUPLICATE_BUDGET * n)` times in all (n primitives): a spatial split
//! that would need more than the budget left is not taken. So `prim_order` may name a primitive more than once, in
//! different leaves, never twice in one leaf.
//!
//! The build is serial (but for the binned object SAH's parallel binning of nodes of 65536 references or more);
//! the tree is the same whatever the thread count. The output is the shared builder's [`BuiltTree`].

use glam::Vec3A;

use super::params::BvhParams;
use super::sah::CostModel;
use super::split::clip::is_empty;
use super::split::{Box3A, BuildRef, NodeView, Referenced, binned_sah};
use super::tree::{BuiltTree, FlatNode, MAX_DEPTH, PLACEHOLDER, ceil_log2};
use crate::geometry::Aabb;

/// Most extra references a build makes, as a fraction of its primitives (Embree's and tinybvh's spatial builders
/// also allow a fixed fraction; 0.3 is within the range they use).
pub const DUPLICATE_BUDGET: f32 = 0.3;

/// A reference: the box of a primitive's part assigned to a node, and the primitive's id.
#[derive(Clone, Copy, Debug)]
struct SpatialRef {
    bounds: Box3A,
    id: u32,
}

impl BuildRef for SpatialRef {
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        (self.bounds.min + self.bounds.max) * 0.5
    }

    #[inline(always)]
    fn bounds(&self) -> Box3A {
        self.bounds
    }
}

/// Builds the tree of `prims` with spatial splits; nodes of at most `leaf_below` references are leaves.
pub fn build<P: Referenced>(prims: &[P], params: &BvhParams, block: u32, leaf_below: usize) -> BuiltTree<P> {
    build_with_boxes(prims, params, block, leaf_below).0
}

/// [`build`], also returning each leaf reference's box (same order as `prim_order`).
pub fn build_with_boxes<P: Referenced>(
    prims: &[P],
    params: &BvhParams,
    block: u32,
    leaf_below: usize,
) -> (BuiltTree<P>, Vec<Aabb>) {
    let refs: Vec<SpatialRef> =
        prims.iter().enumerate().map(|(i, p)| SpatialRef { bounds: p.reference().bounds(), id: i as u32 }).collect();
    let root = union(&refs);
    let mut b = Spatial {
        prims,
        params,
        costs: CostModel { costs: params.sah_costs, block },
        leaf_below,
        threshold: params.spatial_alpha.0 * root.surface_area(),
        budget: (prims.len() as f32 * DUPLICATE_BUDGET) as usize,
        nodes: vec![PLACEHOLDER],
        order: Vec::with_capacity(prims.len()),
        leaf_boxes: Vec::with_capacity(prims.len()),
        bins: binned_sah::Bins::default(),
        slabs: Slabs::default(),
        pool: Vec::new(),
    };
    b.node(0, refs, root, 0);
    let ordered = b.order.iter().map(|&id| P::from_ref(&prims[id as usize].reference(), prims, id)).collect();
    (BuiltTree { nodes: b.nodes, prim_order: b.order, ordered }, b.leaf_boxes)
}

fn union(refs: &[SpatialRef]) -> Box3A {
    let mut b = Box3A::EMPTY;
    refs.iter().for_each(|r| b.add(&r.bounds));
    b
}

/// One slab of the spatial binning: the union of the parts clipped into it, references entering and leaving in it.
#[derive(Clone, Copy)]
struct Slab {
    bounds: Box3A,
    enter: usize,
    exit: usize,
}

impl Slab {
    const EMPTY: Slab = Slab { bounds: Box3A::EMPTY, enter: 0, exit: 0 };
}

/// Scratch space of the spatial binning, kept between nodes.
#[derive(Default)]
struct Slabs {
    slabs: Vec<Slab>,
    right_bounds: Vec<Box3A>,
    right_count: Vec<usize>,
    /// Plane positions of the axis being binned, `bins + 1` of them (node box's ends included).
    planes: Vec<f32>,
}

/// The cheapest spatial plane: its cost, axis, position and the binning's child counts.
#[derive(Clone, Copy, Debug)]
struct SpatialPlane {
    cost: f32,
    axis: usize,
    pos: f32,
    /// The children's boxes and reference counts as binned.
    sides: [Box3A; 2],
    left: usize,
    right: usize,
}

/// How a node is divided.
enum Division {
    Leaf,
    Object(binned_sah::ObjectPlane),
    Spatial(SpatialPlane),
    Median,
}

struct Spatial<'a, P> {
    prims: &'a [P],
    params: &'a BvhParams,
    costs: CostModel,
    leaf_below: usize,
    /// `spatial_alpha * SA(root)`: object splits overlapping more than this try spatial ones.
    threshold: f32,
    /// Duplicates still allowed.
    budget: usize,
    nodes: Vec<FlatNode>,
    order: Vec<u32>,
    leaf_boxes: Vec<Aabb>,
    bins: binned_sah::Bins,
    slabs: Slabs,
    /// Emptied reference vectors, reused for children.
    pool: Vec<Vec<SpatialRef>>,
}

impl<P: Referenced> Spatial<'_, P> {
    /// Builds the node at `index` over `refs` (of union `bounds`), then its subtree.
    fn node(&mut self, index: usize, refs: Vec<SpatialRef>, bounds: Box3A, depth: usize) {
        match self.divide(refs, bounds, depth) {
            Ok([(left, lb), (right, rb)]) => {
                let first = self.nodes.len();
                self.nodes.extend([PLACEHOLDER, PLACEHOLDER]);
                self.nodes[index] =
                    FlatNode { bounds: bounds.aabb(), first: first as u32, prim_count: FlatNode::INTERIOR };
                self.node(first, left, lb, depth + 1);
                self.node(first + 1, right, rb, depth + 1);
            }
            Err(refs) => {
                let first = self.order.len() as u32;
                self.nodes[index] = FlatNode { bounds: bounds.aabb(), first, prim_count: refs.len() as u32 };
                self.order.extend(refs.iter().map(|r| r.id));
                self.leaf_boxes.extend(refs.iter().map(|r| r.bounds.aabb()));
                self.recycle(refs);
            }
        }
    }

    fn take(&mut self) -> Vec<SpatialRef> {
        self.pool.pop().unwrap_or_default()
    }

    fn recycle(&mut self, mut refs: Vec<SpatialRef>) {
        refs.clear();
        self.pool.push(refs);
    }

    /// The two children (references and bounds) of a split, or the references back for a leaf.
    #[allow(clippy::type_complexity)]
    fn divide(
        &mut self,
        mut refs: Vec<SpatialRef>,
        bounds: Box3A,
        depth: usize,
    ) -> Result<[(Vec<SpatialRef>, Box3A); 2], Vec<SpatialRef>> {
        let n = refs.len();
        let division = self.choose(&refs, bounds, depth);
        let mut right = self.take();
        match division {
            Division::Leaf => {
                self.recycle(right);
                return Err(refs);
            }
            Division::Spatial(plane) => {
                let mut left = self.take();
                if self.apply_spatial(&refs, &plane, &mut left, &mut right) {
                    self.recycle(refs);
                    return Ok(self.children(left, right));
                }
                // Floating-point classification left a side empty: divide by objects instead.
                self.recycle(left);
                right.clear();
                self.apply_object_or_median(&mut refs, bounds, &mut right);
            }
            Division::Object(plane) => {
                let mid = partition(&mut refs, |r| plane.goes_left(r.centroid()));
                if mid == 0 || mid == n {
                    self.median(&mut refs, &mut right);
                } else {
                    right.extend_from_slice(&refs[mid..]);
                    refs.truncate(mid);
                }
            }
            Division::Median => self.median(&mut refs, &mut right),
        }
        Ok(self.children(refs, right))
    }

    fn children(&self, left: Vec<SpatialRef>, right: Vec<SpatialRef>) -> [(Vec<SpatialRef>, Box3A); 2] {
        let (lb, rb) = (union(&left), union(&right));
        [(left, lb), (right, rb)]
    }

    /// What to do with a node of `refs` and box `bounds`.
    fn choose(&mut self, refs: &[SpatialRef], bounds: Box3A, depth: usize) -> Division {
        let n = refs.len();
        if n <= 1 || n <= self.leaf_below {
            return Division::Leaf;
        }
        if depth + ceil_log2(n) >= MAX_DEPTH - 1 {
            return Division::Median;
        }
        let may_be_leaf = n <= self.params.leaf_size as usize;
        let view = node_view(refs, bounds, may_be_leaf);
        let bins = self.params.sah_bins as usize;
        let object = binned_sah::best(&view, refs, bins, self.costs, &mut self.bins);
        let try_spatial = match &object {
            Some(o) => {
                let [l, r] = o.sides(&self.bins);
                let overlap = Box3A { min: l.min.max(r.min), max: l.max.min(r.max) };
                overlap.surface_area() > self.threshold
            }
            None => true,
        };
        let spatial = if try_spatial && self.budget > 0 { self.best_spatial(refs, bounds, bins) } else { None };
        let mut best = object.map_or(f32::INFINITY, |o| o.cost);
        let mut division = object.map_or(Division::Median, Division::Object);
        if let Some(s) = spatial
            && s.cost < best
        {
            (best, division) = (s.cost, Division::Spatial(s));
        }
        if may_be_leaf && (best.is_infinite() || self.costs.leaf_cost(n) <= best) {
            return Division::Leaf;
        }
        division
    }

    /// Position of the plane before slab `i` of `bins` over `[lo, lo + extent]`.
    #[inline(always)]
    fn plane(lo: f32, extent: f32, i: usize, bins: usize) -> f32 {
        if i == bins { lo + extent } else { lo + extent * (i as f32 / bins as f32) }
    }

    /// The cheapest spatial plane within the duplicate budget, if any.
    fn best_spatial(&mut self, refs: &[SpatialRef], bounds: Box3A, bins: usize) -> Option<SpatialPlane> {
        let n = refs.len();
        let parent_area = bounds.surface_area();
        let extent = bounds.max - bounds.min;
        let s = &mut self.slabs;
        s.slabs.resize(bins, Slab::EMPTY);
        s.right_bounds.resize(bins, Box3A::EMPTY);
        s.right_count.resize(bins, 0);
        let mut best: Option<SpatialPlane> = None;
        for axis in (0..3).filter(|&a| extent[a] > 0.0) {
            let (lo, ext) = (bounds.min[axis], extent[axis]);
            let scale = bins as f32 / ext;
            let slab_of = |x: f32| (((x - lo) * scale).max(0.0) as usize).min(bins - 1);
            s.slabs.fill(Slab::EMPTY);
            s.planes.clear();
            s.planes.extend((0..=bins).map(|i| Self::plane(lo, ext, i, bins)));
            for r in refs {
                let (entry, exit) = (slab_of(r.bounds.min[axis]), slab_of(r.bounds.max[axis]));
                let (mut first, mut last) = (usize::MAX, 0);
                let slabs = &mut s.slabs;
                let mut add = |i: usize, piece: Box3A| {
                    slabs[entry + i].bounds.add(&piece);
                    (first, last) = (first.min(entry + i), entry + i);
                };
                if entry == exit {
                    add(0, r.bounds);
                } else {
                    self.prims[r.id as usize].slab_parts(&r.bounds, axis, &s.planes[entry + 1..=exit], add);
                }
                if first != usize::MAX {
                    s.slabs[first].enter += 1;
                    s.slabs[last].exit += 1;
                }
            }
            let (mut acc, mut count) = (Box3A::EMPTY, 0);
            for i in (1..bins).rev() {
                acc.add(&s.slabs[i].bounds);
                count += s.slabs[i].exit;
                (s.right_bounds[i], s.right_count[i]) = (acc, count);
            }
            let (mut left, mut left_count) = (Box3A::EMPTY, 0);
            for i in 1..bins {
                left.add(&s.slabs[i - 1].bounds);
                left_count += s.slabs[i - 1].enter;
                let right_count = s.right_count[i];
                if left_count == 0 || right_count == 0 || (left_count + right_count).saturating_sub(n) > self.budget {
                    continue;
                }
                let right_area = s.right_bounds[i].surface_area();
                let cost = self.costs.split_cost(parent_area, left.surface_area(), left_count, right_area, right_count);
                if best.is_none_or(|b| cost < b.cost) {
                    let (pos, sides) = (Self::plane(lo, ext, i, bins), [left, s.right_bounds[i]]);
                    best = Some(SpatialPlane { cost, axis, pos, sides, left: left_count, right: right_count });
                }
            }
        }
        best
    }

    /// Divides `refs` at `plane` into `left` and `right`, clipping straddlers or unsplitting them; false (and the
    /// budget untouched) when a side came out empty.
    fn apply_spatial(
        &mut self,
        refs: &[SpatialRef],
        plane: &SpatialPlane,
        left: &mut Vec<SpatialRef>,
        right: &mut Vec<SpatialRef>,
    ) -> bool {
        let (axis, pos) = (plane.axis, plane.pos);
        // The children as the binning estimated them, updated as straddlers are unsplit (the paper's test).
        let [mut lbox, mut rbox] = plane.sides;
        let (mut nl, mut nr) = (plane.left, plane.right);
        let mut budget = self.budget;
        for r in refs {
            if r.bounds.max[axis] <= pos {
                left.push(*r);
                continue;
            }
            if r.bounds.min[axis] >= pos {
                right.push(*r);
                continue;
            }
            let [l, rr] = self.prims[r.id as usize].halves(&r.bounds, axis, pos);
            let (l_empty, r_empty) = (is_empty(&l), is_empty(&rr));
            if l_empty || r_empty {
                let (side, b) = if r_empty { (&mut *left, l) } else { (&mut *right, rr) };
                if !(l_empty && r_empty) {
                    side.push(SpatialRef { bounds: b, id: r.id });
                }
                continue;
            }
            let grown = |a: &Box3A| {
                let mut u = *a;
                u.add(&r.bounds);
                u.surface_area()
            };
            let c = &self.costs;
            let (la, ra) = (lbox.surface_area(), rbox.surface_area());
            let split = c.split_key(la, nl, ra, nr);
            let all_left = c.split_key(grown(&lbox), nl, ra, nr.saturating_sub(1));
            let all_right = c.split_key(la, nl.saturating_sub(1), grown(&rbox), nr);
            if budget > 0 && split <= all_left && split <= all_right {
                budget -= 1;
                left.push(SpatialRef { bounds: l, id: r.id });
                right.push(SpatialRef { bounds: rr, id: r.id });
            } else if all_left <= all_right {
                lbox.add(&r.bounds);
                nr = nr.saturating_sub(1);
                left.push(*r);
            } else {
                rbox.add(&r.bounds);
                nl = nl.saturating_sub(1);
                right.push(*r);
            }
        }
        if left.is_empty() || right.is_empty() {
            return false;
        }
        self.budget = budget;
        true
    }

    /// The object split of `refs` (or the median when it has none), the right side moved to `right`.
    fn apply_object_or_median(&mut self, refs: &mut Vec<SpatialRef>, bounds: Box3A, right: &mut Vec<SpatialRef>) {
        let view = node_view(refs, bounds, false);
        let bins = self.params.sah_bins as usize;
        let n = refs.len();
        let mid = match binned_sah::best(&view, refs, bins, self.costs, &mut self.bins) {
            Some(plane) => partition(refs, |r| plane.goes_left(r.centroid())),
            None => 0,
        };
        if mid == 0 || mid == n {
            self.median(refs, right);
        } else {
            right.extend_from_slice(&refs[mid..]);
            refs.truncate(mid);
        }
    }

    /// Half of `refs` on each side by centroid on the longest centroid axis (ties by id); the right half to `right`.
    fn median(&self, refs: &mut Vec<SpatialRef>, right: &mut Vec<SpatialRef>) {
        let mut centroids = Box3A::EMPTY;
        refs.iter().for_each(|r| centroids.grow(r.centroid()));
        let axis = centroids.aabb().longest_axis();
        let mid = refs.len() / 2;
        refs.select_nth_unstable_by(mid, |a, b| {
            a.centroid()[axis].total_cmp(&b.centroid()[axis]).then(a.id.cmp(&b.id))
        });
        right.extend_from_slice(&refs[mid..]);
        refs.truncate(mid);
    }
}

/// Moves the references for which `left` holds to the front (stable order of neither side needed); returns how many.
fn partition(refs: &mut [SpatialRef], mut left: impl FnMut(&SpatialRef) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..refs.len() {
        if left(&refs[i]) {
            refs.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

/// What the object split reads of a node: its box and its references' centroid bounds (no per-primitive arrays).
fn node_view(refs: &[SpatialRef], bounds: Box3A, may_be_leaf: bool) -> NodeView<'static> {
    let mut centroids = Box3A::EMPTY;
    refs.iter().for_each(|r| centroids.grow(r.centroid()));
    NodeView { boxes: &[], centroids: &[], bounds: bounds.aabb(), centroid_bounds: centroids.aabb(), may_be_leaf }
}
