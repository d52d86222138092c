//! Collapsing the binary tree into `W`-wide nodes (tinybvh's `BVH8_CPU::ConvertFrom`, Embree's wide builders).
//!
//! A wide node's children are a cut of its binary node's subtree: at most `W` descendants that together hold all
//! its spheres. The cut is chosen bottom-up for the least SAH cost (Ylitie, Karras and Laine 2017's collapse, with
//! the leaves fixed as below): every wide node costs its box's surface area, and leaves cost the same whatever the
//! cut, so for each binary node and each number of children k ≤ `W` the cheapest way to cover its subtree with k
//! children is either the node itself (a leaf, or a wide node of its own best cut) or the cheapest split of k
//! between its two children. A binary node can be opened when it is interior and holds more than `B` spheres: a
//! subtree of at most `B` spheres becomes one leaf of one block (Embree makes subtrees of at most 8 spheres one
//! leaf), and a binary leaf of more than `B` spheres (`leaf_size > B`) becomes one leaf of several blocks. So
//! whatever the binary `leaf_size`, leaves fill their blocks: a leaf holds at most `max(leaf_size, B)` spheres, and
//! only its last block is padded.
//! Children keep the binary tree's left-to-right order; wide nodes and leaf blocks come out in depth-first order.
//!
//! Trees of [`PARALLEL_COLLAPSE_MIN_PRIMS`] spheres or more, in a pool of more than one thread, collapse in
//! parallel: the wide nodes of at least that many spheres (the top of the tree) are gathered first to find the
//! subtrees below them, which collapse as independent tasks. Leaves are the binary subtrees that cannot be opened,
//! whatever the gathering, so each task's blocks are counted beforehand and it writes them in place, in its run of
//! the tree's blocks; its nodes go to a vector of its own. The top is then emitted in the serial order, with the
//! tasks' nodes spliced in where the serial recursion would have emitted them, their references shifted. So the
//! tree is the serial one whatever the thread count.

use super::leaf::{LeafBlock, WidePrimitive};
use super::node::{ChildRef, WideNode};
use crate::accel::bvh::tree::BuiltTree;
use crate::geometry::{Aabb, Sphere};
use crate::parallel;

/// Trees of at least this many spheres collapse in parallel (when the pool has more than one thread), and their
/// wide nodes of at least this many spheres are the serial top above the parallel tasks.
///
/// A wide level divides a subtree's spheres by up to `W`, so a task holds about 1000 to 8191 spheres: 50 to 400
/// microseconds of serial collapse, far above a task's cost, and there are hundreds of them at 1e6 spheres (tens
/// at 1e5) to balance over the threads, below a top of tens of wide nodes. On two cores, 2048, 8192 and 32768
/// collapsed 1e5 and 1e6 random spheres equally fast within noise (1e6: 45 ms serial, 19-21 ms in parallel).
pub const PARALLEL_COLLAPSE_MIN_PRIMS: usize = 1 << 13;

/// Blocks per task when the parallel collapse lays out its padding blocks.
const PADDING_CHUNK: usize = 1 << 12;

/// A wide tree: nodes (the root first, depth-first) and the blocks their leaves refer to.
#[derive(Clone, Debug)]
pub struct Tree<const W: usize, const B: usize, P: WidePrimitive = Sphere> {
    /// Wide nodes; the root is `nodes[0]`, and a tree always has one (without children when empty).
    pub nodes: Vec<WideNode<W>>,
    /// Leaf blocks, each leaf's blocks contiguous.
    pub blocks: Vec<P::Block<B>>,
}

/// Collapses `built` into a `W`-wide tree with leaves in blocks of `B`.
///
/// Collapses with the threads of the current rayon pool; the tree is identical whatever the thread count.
pub fn collapse<P: WidePrimitive, const W: usize, const B: usize>(built: &BuiltTree<P>) -> Tree<W, B, P> {
    let c = Collapser::<P, W, B>::new(built);
    let spheres = built.prim_order.len();
    if spheres >= PARALLEL_COLLAPSE_MIN_PRIMS && rayon::current_num_threads() > 1 {
        return c.parallel();
    }
    let mut blocks = Vec::with_capacity(spheres.div_ceil(B) + spheres / 2);
    let mut nodes = Vec::new();
    c.node(&mut nodes, &mut blocks, 0);
    Tree { nodes, blocks }
}

/// Where a collapse puts its leaf blocks: the tree's vector, or a parallel task's run of it.
trait Blocks<P: WidePrimitive, const B: usize> {
    /// Blocks put so far.
    fn len(&self) -> usize;
    /// Puts the blocks of `prims` (whose scene indices are `ids`) after the others; returns how many.
    fn append(&mut self, prims: &[P], ids: &[u32]) -> usize;
}

impl<P: WidePrimitive, const B: usize> Blocks<P, B> for Vec<P::Block<B>> {
    fn len(&self) -> usize {
        self.len()
    }

    fn append(&mut self, prims: &[P], ids: &[u32]) -> usize {
        P::Block::<B>::append(self, prims, ids)
    }
}

/// A run of the tree's blocks (made as padding), filled from its start.
struct Run<'a, P: WidePrimitive, const B: usize> {
    blocks: &'a mut [P::Block<B>],
    len: usize,
}

impl<P: WidePrimitive, const B: usize> Blocks<P, B> for Run<'_, P, B> {
    fn len(&self) -> usize {
        self.len
    }

    fn append(&mut self, prims: &[P], ids: &[u32]) -> usize {
        let n = P::Block::<B>::write(&mut self.blocks[self.len..], prims, ids);
        self.len += n;
        n
    }
}

/// The binary tree and its subtrees' sphere counts and first positions, shared by every task.
struct Collapser<'a, P, const W: usize, const B: usize> {
    built: &'a BuiltTree<P>,
    count: Vec<u32>,
    start: Vec<u32>,
    /// The cheapest cuts ([`Collapser::cheapest_cuts`]).
    cuts: Vec<[u8; W]>,
}

impl<'a, P: WidePrimitive, const W: usize, const B: usize> Collapser<'a, P, W, B> {
    /// The collapser of `built`: every binary subtree's sphere count and first position in the primitive order
    /// (children follow parents), and the cheapest cuts.
    fn new(built: &'a BuiltTree<P>) -> Self {
        let n = built.nodes.len();
        let (mut count, mut start) = (vec![0u32; n], vec![0u32; n]);
        for i in (0..n).rev() {
            let node = &built.nodes[i];
            if node.is_leaf() {
                (count[i], start[i]) = (node.prim_count, node.first);
            } else {
                let f = node.first as usize;
                (count[i], start[i]) = (count[f] + count[f + 1], start[f]);
            }
        }
        let mut c = Collapser { built, count, start, cuts: Vec::new() };
        c.cuts = c.cheapest_cuts();
        c
    }

    /// The cheapest cuts: for binary node `b` and `k` children, `cuts[b][k - 1]` is how many of them its left child's
    /// subtree gets (the rest go to the right), or 0 when the cheapest is `b` itself as one child.
    ///
    /// Computed children first (they follow their parents); the cost of covering `b` with at most `k` children is
    /// 0 for a node that cannot be opened (it is a leaf), else the least of `b` itself (its area plus its own cut's
    /// cost) and every split of `k` between its children. Ties open the node.
    fn cheapest_cuts(&self) -> Vec<[u8; W]> {
        let n = self.built.nodes.len();
        let (mut cost, mut cuts) = (vec![[0f32; W]; n], vec![[0u8; W]; n]);
        for b in (0..n).rev() {
            if !self.openable(b) {
                continue;
            }
            let node = &self.built.nodes[b];
            let (l, r) = (node.first as usize, node.first as usize + 1);
            let split = |k: usize| {
                (1..k)
                    .map(|j| (cost[l][j - 1] + cost[r][k - j - 1], j as u8))
                    .fold((f32::INFINITY, 0), |a, c| if c.0 < a.0 { c } else { a })
            };
            let (own_cost, own_cut) = split(W);
            let own = node.bounds.surface_area() + own_cost;
            let (mut costs, mut cut) = ([own; W], [0u8; W]);
            for k in 2..=W {
                let (c, j) = if k == W { (own_cost, own_cut) } else { split(k) };
                if c <= own {
                    (costs[k - 1], cut[k - 1]) = (c, j);
                }
            }
            (cost[b], cuts[b]) = (costs, cut);
        }
        cuts
    }

    /// True when binary node `b` is interior with more than one block's spheres.
    fn openable(&self, b: usize) -> bool {
        !self.built.nodes[b].is_leaf() && self.count[b] as usize > B
    }

    /// The binary nodes the wide node of binary node `b` gathers, `kids[..len]`, in left-to-right order: its
    /// cheapest cut into `W` (itself alone when it cannot be opened).
    #[inline(always)]
    fn gather(&self, b: usize) -> ([usize; W], usize) {
        let (mut kids, mut len) = ([0usize; W], 0);
        if self.count[b] == 0 {
            return (kids, 0);
        }
        if !self.openable(b) {
            kids[0] = b;
            return (kids, 1);
        }
        let first = self.built.nodes[b].first as usize;
        let j = self.cuts[b][W - 1] as usize;
        self.cut(first, j, &mut kids, &mut len);
        self.cut(first + 1, W - j, &mut kids, &mut len);
        (kids, len)
    }

    /// Appends to `kids` the cheapest cut of binary node `b` into at most `k` children.
    fn cut(&self, b: usize, k: usize, kids: &mut [usize; W], len: &mut usize) {
        let j = self.cuts[b][k - 1] as usize;
        if j == 0 {
            kids[*len] = b;
            *len += 1;
        } else {
            let first = self.built.nodes[b].first as usize;
            self.cut(first, j, kids, len);
            self.cut(first + 1, k - j, kids, len);
        }
    }

    /// Appends the wide node gathered from binary node `b` to `nodes` (then its descendants); returns its index.
    fn node(&self, nodes: &mut Vec<WideNode<W>>, blocks: &mut impl Blocks<P, B>, b: usize) -> u32 {
        let index = nodes.len();
        nodes.push(WideNode::EMPTY);
        let (kids, len) = self.gather(b);
        let mut children = [(ChildRef::EMPTY, Aabb::EMPTY); W];
        for (slot, &k) in children.iter_mut().zip(&kids[..len]) {
            let child =
                if self.openable(k) { ChildRef::node(self.node(nodes, blocks, k)) } else { self.leaf(blocks, k) };
            *slot = (child, self.built.nodes[k].bounds);
        }
        nodes[index] = WideNode::new(&children[..len]);
        index as u32
    }

    /// Puts the blocks of binary subtree `b`'s spheres; returns the leaf.
    fn leaf(&self, blocks: &mut impl Blocks<P, B>, b: usize) -> ChildRef {
        let (start, count) = (self.start[b] as usize, self.count[b] as usize);
        let first = blocks.len() as u32;
        let range = start..start + count;
        let n = blocks.append(&self.built.ordered[range.clone()], &self.built.prim_order[range]);
        ChildRef::leaf(first, n as u32)
    }

    /// True for the binary nodes whose wide nodes are the parallel collapse's serial top.
    fn on_top(&self, b: usize) -> bool {
        self.count[b] as usize >= PARALLEL_COLLAPSE_MIN_PRIMS
    }

    /// Blocks of the leaves of binary subtree `b` (its maximal subtrees that cannot be opened).
    fn block_count(&self, b: usize) -> usize {
        if !self.openable(b) {
            return (self.count[b] as usize).div_ceil(B);
        }
        let f = self.built.nodes[b].first as usize;
        self.block_count(f) + self.block_count(f + 1)
    }

    /// The whole tree, the wide subtrees below the top collapsed in parallel, each into its run of the blocks.
    fn parallel(&self) -> Tree<W, B, P> {
        // The tasks in serial order, each with the blocks of the top's leaves just before it; then the last leaves'.
        let (mut tasks, mut leaf_blocks) = (Vec::new(), 0);
        self.tasks(0, &mut tasks, &mut leaf_blocks);
        let counts: Vec<usize> = parallel::map(tasks.clone(), |(k, _)| self.block_count(k));
        let total = leaf_blocks + tasks.iter().zip(&counts).map(|(&(_, before), &n)| before + n).sum::<usize>();
        let mut blocks = parallel::filled(&P::Block::<B>::PADDING, total, PADDING_CHUNK);
        let (mut runs, mut rest) = (Vec::with_capacity(tasks.len()), &mut blocks[..]);
        for (&(k, before), &n) in tasks.iter().zip(&counts) {
            let (run, after) = rest[before..].split_at_mut(n);
            runs.push((k, run));
            rest = after;
        }
        let pieces: Vec<Vec<WideNode<W>>> = parallel::map(runs, |(k, run)| {
            let (mut nodes, mut run) = (Vec::new(), Run { blocks: run, len: 0 });
            self.node(&mut nodes, &mut run, k);
            debug_assert_eq!(run.len, run.blocks.len());
            nodes
        });
        let mut nodes = Vec::with_capacity(1 + pieces.iter().map(Vec::len).sum::<usize>());
        let mut pieces = pieces.into_iter().zip(counts);
        self.top(&mut nodes, &mut Run { blocks: &mut blocks, len: 0 }, 0, &mut pieces);
        Tree { nodes, blocks }
    }

    /// Appends to `tasks`, in serial order, the wide subtrees below binary node `b`'s top node, each with the blocks
    /// of the top's leaves since the last one (counted in `leaf_blocks`).
    fn tasks(&self, b: usize, tasks: &mut Vec<(usize, usize)>, leaf_blocks: &mut usize) {
        let (kids, len) = self.gather(b);
        for &k in &kids[..len] {
            match (self.openable(k), self.on_top(k)) {
                (true, true) => self.tasks(k, tasks, leaf_blocks),
                (true, false) => tasks.push((k, std::mem::take(leaf_blocks))),
                (false, _) => *leaf_blocks += (self.count[k] as usize).div_ceil(B),
            }
        }
    }

    /// [`Collapser::node`] for a top node: its leaves fill `blocks`, and its wide subtrees below the top are the
    /// next `pieces` (nodes, and blocks already in place), spliced in with their references shifted.
    fn top(
        &self,
        nodes: &mut Vec<WideNode<W>>,
        blocks: &mut Run<'_, P, B>,
        b: usize,
        pieces: &mut impl Iterator<Item = (Vec<WideNode<W>>, usize)>,
    ) -> u32 {
        let index = nodes.len();
        nodes.push(WideNode::EMPTY);
        let (kids, len) = self.gather(b);
        let mut children = [(ChildRef::EMPTY, Aabb::EMPTY); W];
        for (slot, &k) in children.iter_mut().zip(&kids[..len]) {
            let child = match (self.openable(k), self.on_top(k)) {
                (true, true) => ChildRef::node(self.top(nodes, blocks, k, pieces)),
                (true, false) => {
                    let (piece, n) = pieces.next().expect("a piece per task");
                    let shift = (nodes.len() as u32, blocks.len as u32);
                    nodes.extend(
                        piece
                            .iter()
                            .map(|w| WideNode { children: w.children.map(|c| c.shifted(shift.0, shift.1)), ..*w }),
                    );
                    blocks.len += n;
                    ChildRef::node(shift.0)
                }
                (false, _) => self.leaf(blocks, k),
            };
            *slot = (child, self.built.nodes[k].bounds);
        }
        nodes[index] = WideNode::new(&children[..len]);
        index as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::{BvhParams, Split, builder};
    use crate::geometry::Sphere;
    use crate::scene::SceneKind;

    fn check<const W: usize, const B: usize>(spheres: &[Sphere], params: &BvhParams) {
        let built = builder::build(spheres, params);
        let tree = collapse::<_, W, B>(&built);
        let spatial = params.split == Split::SpatialSah;
        let mut seen = vec![0u32; spheres.len()];
        let mut leaves = 0;
        for (i, node) in tree.nodes.iter().enumerate() {
            let len = node.len();
            assert!(node.children[len..].iter().all(|c| *c == ChildRef::EMPTY), "children come first");
            for lane in 0..len {
                let (child, bounds) = (node.children[lane], node.child_bounds(lane));
                if child.is_node() {
                    assert!(child.index() > i, "depth-first: children after parents");
                } else {
                    leaves += 1;
                    let blocks = &tree.blocks[child.blocks()];
                    let real: usize = blocks.iter().map(LeafBlock::len).sum();
                    assert!(
                        real <= (params.leaf_size as usize).max(B) && blocks.len() == real.div_ceil(B),
                        "blocks filled"
                    );
                    for block in blocks {
                        for l in 0..block.len() {
                            let id = block.ids[l];
                            seen[id as usize] += 1;
                            let s = spheres[id as usize].bounds();
                            if spatial {
                                // Spatial splits clip a sphere's box: the leaf holds a part of it.
                                let meet = Aabb { min: bounds.min.max(s.min), max: bounds.max.min(s.max) };
                                assert!(!meet.is_empty(), "leaf box meets its spheres");
                            } else {
                                assert!(bounds.union(&s) == bounds, "leaf box holds its spheres");
                            }
                        }
                    }
                }
            }
            if i > 0 {
                assert!(len >= 2 || W < 2, "inner wide nodes have at least two children");
            }
        }
        if spatial {
            let total: usize = seen.iter().map(|&n| n as usize).sum();
            assert!(seen.iter().all(|&n| n >= 1) && total == built.prim_order.len(), "every reference in one leaf");
        } else {
            assert!(seen.iter().all(|&n| n == 1), "every sphere in exactly one leaf");
        }
        assert!(leaves > 0 || spheres.is_empty());
    }

    #[test]
    fn every_sphere_lands_in_one_filled_leaf() {
        for n in [0, 1, 3, 9, 200, 1500] {
            let spheres = SceneKind::ClusteredSpheres.generate(n, 4).spheres;
            for split in Split::ALL {
                for leaf_size in [1, 4, 16] {
                    let p = BvhParams { split, leaf_size, ..BvhParams::default() };
                    check::<4, 4>(&spheres, &p);
                    check::<8, 8>(&spheres, &p);
                    check::<8, 16>(&spheres, &p);
                    check::<4, 16>(&spheres, &p);
                }
            }
        }
    }

    /// A collapse's cost (the wide nodes' areas; the leaves are the same whatever the cut), each wide node's
    /// children chosen by `gather`.
    fn cost<const W: usize, const B: usize>(
        c: &Collapser<'_, Sphere, W, B>,
        gather: &dyn Fn(usize) -> Vec<usize>,
        b: usize,
    ) -> f64 {
        let kids = gather(b);
        let below: f64 = kids.iter().filter(|&&k| c.openable(k)).map(|&k| cost(c, gather, k)).sum();
        c.built.nodes[b].bounds.surface_area() as f64 + below
    }

    /// The binary nodes `c` gathers for binary node `b`'s wide node.
    fn gathered<const W: usize, const B: usize>(c: &Collapser<'_, Sphere, W, B>, b: usize) -> Vec<usize> {
        let (kids, len) = c.gather(b);
        kids[..len].to_vec()
    }

    /// Every way to cover binary node `b`'s subtree with at most `k` nodes, in left-to-right order.
    fn all_cuts<const W: usize, const B: usize>(
        c: &Collapser<'_, Sphere, W, B>,
        b: usize,
        k: usize,
    ) -> Vec<Vec<usize>> {
        let mut out = vec![vec![b]];
        if c.openable(b) {
            let f = c.built.nodes[b].first as usize;
            for j in 1..k {
                for left in all_cuts(c, f, j) {
                    for right in all_cuts(c, f + 1, k - j) {
                        out.push([left.clone(), right].concat());
                    }
                }
            }
        }
        out
    }

    /// The least cost of any collapse below binary node `b`, by trying every cut of every wide node (`memo`: the
    /// nodes' least costs found so far).
    fn least_cost<const W: usize, const B: usize>(
        c: &Collapser<'_, Sphere, W, B>,
        b: usize,
        memo: &mut Vec<Option<f64>>,
    ) -> f64 {
        if let Some(cost) = memo[b] {
            return cost;
        }
        let f = c.built.nodes[b].first as usize;
        let mut best = f64::INFINITY;
        for j in 1..W {
            for left in all_cuts(c, f, j) {
                for right in all_cuts(c, f + 1, W - j) {
                    let kids = [left.clone(), right].concat();
                    let below = kids.iter().filter(|&&k| c.openable(k)).map(|&k| least_cost(c, k, memo)).sum();
                    best = best.min(below);
                }
            }
        }
        let cost = c.built.nodes[b].bounds.surface_area() as f64 + best;
        memo[b] = Some(cost);
        cost
    }

    /// The greedy collapse: the gathered child of largest area opened until there are `W` (tinybvh's way).
    fn greedy<const W: usize, const B: usize>(c: &Collapser<'_, Sphere, W, B>, b: usize) -> Vec<usize> {
        let mut kids = vec![b];
        while kids.len() < W {
            let area = |k: usize| c.built.nodes[k].bounds.surface_area();
            let open = kids.iter().enumerate().filter(|(_, k)| c.openable(**k));
            let Some((i, _)) = open.max_by(|a, b| area(*a.1).total_cmp(&area(*b.1))) else { break };
            let f = c.built.nodes[kids[i]].first as usize;
            kids.splice(i..=i, [f, f + 1]);
        }
        kids
    }

    #[test]
    fn cuts_cost_the_least_of_every_collapse() {
        for (n, seed) in [(40, 1), (90, 2), (150, 3)] {
            let spheres = SceneKind::ClusteredSpheres.generate(n, seed).spheres;
            let built = builder::build(&spheres, &BvhParams { leaf_size: 1, ..BvhParams::default() });
            let c = Collapser::<Sphere, 4, 2>::new(&built);
            let ours = cost(&c, &|b| gathered(&c, b), 0);
            let least = least_cost(&c, 0, &mut vec![None; built.nodes.len()]);
            assert!((ours - least).abs() <= 1e-5 * least, "{n} spheres: cuts cost {ours}, the least is {least}");
        }
    }

    #[test]
    fn cuts_cost_no_more_than_the_greedy_collapse() {
        for scene in [SceneKind::RandomSpheres, SceneKind::ClusteredSpheres] {
            let spheres = scene.generate(5000, 1).spheres;
            for split in Split::ALL {
                let built = builder::build(&spheres, &BvhParams { split, leaf_size: 1, ..BvhParams::default() });
                let c = Collapser::<Sphere, 8, 4>::new(&built);
                let ours = cost(&c, &|b| gathered(&c, b), 0);
                let greedy = cost(&c, &|b| greedy(&c, b), 0);
                assert!(ours <= greedy * (1.0 + 1e-6), "{scene:?} {split:?}: cuts {ours}, greedy {greedy}");
            }
        }
    }
}
