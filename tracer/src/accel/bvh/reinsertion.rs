//! Reinsertion: a post-build pass that moves whole subtrees of a built tree to where they cost least.
//!
//! After Bittner, Hapala and Havran, "Fast insertion-based optimization of bounding volume hierarchies" (2013), and
//! Meister and Bittner, "Parallel reinsertion for bounding volume hierarchy optimization" (2018), run serially. A
//! round visits every node but the root in order of decreasing surface area (as Meister and Bittner prioritize),
//! taken when the round starts. Each node is removed (its sibling takes its parent's place, the ancestors' boxes are
//! refitted) and reinserted as the sibling of the node where its SAH cost increase is least, found by a
//! branch-and-bound search from the root: a node's induced cost (what its ancestors' boxes grow by) plus the
//! node's own growth plus the moved node's area bounds every position below it. The move is kept only if it lowers
//! the cost, else the node goes back where it was. Rounds stop at the round limit or when a round lowers the cost
//! by less than [`MIN_ROUND_GAIN`] of it.
//!
//! Leaves stay leaves with the same primitives, so the leaves' SAH terms and the root's box never change: the cost
//! the pass lowers is the sum of the interior nodes' areas, whatever the cost constants or leaf blocks. Moves that
//! would put a leaf deeper than [`MAX_DEPTH`]` - 1` (the builders' bound) are not taken. Costs are summed in
//! `f64` from the same `f32` areas [`super::TreeStats`] reads, so the reported SAH cost never increases.
//!
//! The result is laid out again exactly like the builder's (sibling pairs, depth first, root 0, leaves' primitive
//! runs in depth-first order), so every consumer reads it unchanged. The pass is serial and reads nothing but the
//! tree: the same tree in gives the same tree out, whatever the thread count.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use super::tree::{BuiltTree, FlatNode, MAX_DEPTH};
use crate::geometry::Aabb;

/// A round lowering the cost by less than this fraction of it ends the pass.
pub const MIN_ROUND_GAIN: f64 = 1e-3;

/// A move is kept only if it lowers the sum of interior areas by more than this fraction of the root's area
/// (far above the rounding of the `f64` sums, so kept moves lower the reported cost too).
const MIN_MOVE_GAIN: f64 = 1e-9;

/// No node: the root's parent.
const NONE: u32 = u32::MAX;

/// Optimizes `tree` by at most `rounds` rounds of reinsertion (0: returns it unchanged) and lays it out again.
pub fn optimize<P: Copy>(tree: BuiltTree<P>, rounds: u32) -> BuiltTree<P> {
    if rounds == 0 || tree.nodes.len() < 5 {
        return tree;
    }
    let mut linked = Linked::of(&tree.nodes);
    let mut cost = linked.cost();
    for _ in 0..rounds {
        let gain = linked.round();
        debug_assert!(gain >= 0.0);
        let before = cost;
        cost -= gain;
        if gain < MIN_ROUND_GAIN * before {
            break;
        }
    }
    linked.layout(&tree)
}

/// The tree as linked nodes that subtrees can move between; node ids are stable (a removed node's parent slot is
/// reused for the node inserted next).
struct Linked {
    bounds: Vec<Aabb>,
    parent: Vec<u32>,
    /// Interior nodes' children (leaves: unused).
    children: Vec<[u32; 2]>,
    /// Leaves: their run of the original primitive order (`first`, `count`); interior nodes: `None`.
    leaf: Vec<Option<(u32, u32)>>,
    /// Levels from the node down to its deepest leaf (0 for a leaf).
    height: Vec<u32>,
    root: u32,
    /// Branch-and-bound queue, kept between searches for its memory.
    queue: BinaryHeap<Reverse<Candidate>>,
}

/// A position of the search: ordered by lower bound, then node id (so the search is deterministic).
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Candidate {
    /// Bits of the (non-negative) lower bound on the cost of inserting at or below the node; ordered like the value.
    bound: u64,
    node: u32,
    depth: u32,
    /// Bits of the induced cost: what the node's ancestors' areas grow by.
    induced: u64,
}

fn area(b: &Aabb) -> f64 {
    b.surface_area() as f64
}

impl Linked {
    /// Links the nodes of the builder's layout.
    fn of(nodes: &[FlatNode]) -> Self {
        let n = nodes.len();
        let mut t = Linked {
            bounds: nodes.iter().map(|n| n.bounds).collect(),
            parent: vec![NONE; n],
            children: vec![[NONE; 2]; n],
            leaf: nodes.iter().map(|n| n.is_leaf().then_some((n.first, n.prim_count))).collect(),
            height: vec![0; n],
            root: 0,
            queue: BinaryHeap::new(),
        };
        // Children follow their parents in the layout, so a backward pass meets children before parents.
        for i in (0..n).rev() {
            if !nodes[i].is_leaf() {
                let first = nodes[i].first;
                t.children[i] = [first, first + 1];
                t.parent[first as usize] = i as u32;
                t.parent[first as usize + 1] = i as u32;
                t.height[i] = 1 + t.height[first as usize].max(t.height[first as usize + 1]);
            }
        }
        t
    }

    /// The SAH cost with unit constants, unnormalized: interior areas plus leaves' areas times their counts.
    fn cost(&self) -> f64 {
        (0..self.bounds.len())
            .map(|i| match self.leaf[i] {
                Some((_, count)) => count as f64 * area(&self.bounds[i]),
                None => area(&self.bounds[i]),
            })
            .sum()
    }

    /// One round: every node but the root, by decreasing area, removed and reinserted. Returns the cost it saved.
    fn round(&mut self) -> f64 {
        let mut order: Vec<(Reverse<u32>, u32)> = (0..self.bounds.len() as u32)
            .filter(|&i| i != self.root)
            .map(|i| (Reverse(self.bounds[i as usize].surface_area().to_bits()), i))
            .collect();
        order.sort_unstable();
        order.into_iter().map(|(_, node)| self.reinsert(node)).sum()
    }

    /// Moves `node` to its cheapest position if that lowers the cost; returns the cost saved (0 if not moved).
    fn reinsert(&mut self, node: u32) -> f64 {
        if node == self.root {
            return 0.0;
        }
        let parent = self.parent[node as usize];
        let side = (self.children[parent as usize][1] == node) as usize;
        let sibling = self.children[parent as usize][1 - side];
        let removed = self.remove(node);
        let Some((target, added)) = self.cheapest_position(node) else {
            self.insert(node, parent, sibling, side);
            return 0.0;
        };
        let min_gain = MIN_MOVE_GAIN * area(&self.bounds[self.root as usize]);
        if removed - added > min_gain {
            self.insert(node, parent, target, 0);
            removed - added
        } else {
            self.insert(node, parent, sibling, side);
            0.0
        }
    }

    /// Unlinks `node` and its parent (the sibling takes the parent's place) and refits the ancestors; returns what
    /// the interior areas shrank by.
    fn remove(&mut self, node: u32) -> f64 {
        let parent = self.parent[node as usize];
        let side = (self.children[parent as usize][1] == node) as usize;
        let sibling = self.children[parent as usize][1 - side];
        let grand = self.parent[parent as usize];
        let mut saved = area(&self.bounds[parent as usize]);
        self.parent[sibling as usize] = grand;
        if grand == NONE {
            self.root = sibling;
        } else {
            let slot = (self.children[grand as usize][1] == parent) as usize;
            self.children[grand as usize][slot] = sibling;
            saved += self.refit(grand);
        }
        self.parent[parent as usize] = NONE;
        saved
    }

    /// Inserts `node` as the sibling of `at` (on side `side` of the pair), with `free` as their new parent, and
    /// refits the ancestors.
    fn insert(&mut self, node: u32, free: u32, at: u32, side: usize) {
        let up = self.parent[at as usize];
        if up == NONE {
            self.root = free;
        } else {
            let slot = (self.children[up as usize][1] == at) as usize;
            self.children[up as usize][slot] = free;
        }
        self.parent[free as usize] = up;
        let mut pair = [at, at];
        pair[side] = node;
        pair[1 - side] = at;
        self.children[free as usize] = pair;
        self.parent[node as usize] = free;
        self.parent[at as usize] = free;
        self.refit(free);
    }

    /// Recomputes the boxes and heights of `from` and its ancestors; returns what their areas shrank by.
    fn refit(&mut self, from: u32) -> f64 {
        let mut saved = 0.0;
        let mut at = from;
        while at != NONE {
            let [l, r] = self.children[at as usize];
            let (l, r) = (l as usize, r as usize);
            let bounds = self.bounds[l].union(&self.bounds[r]);
            saved += area(&self.bounds[at as usize]) - area(&bounds);
            self.bounds[at as usize] = bounds;
            self.height[at as usize] = 1 + self.height[l].max(self.height[r]);
            at = self.parent[at as usize];
        }
        saved
    }

    /// Branch and bound from the root: the node to insert the (removed) `node` beside at the least increase of the
    /// interior areas, with that increase; `None` if no position keeps the depth bound.
    fn cheapest_position(&mut self, node: u32) -> Option<(u32, f64)> {
        let moved = self.bounds[node as usize];
        let moved_area = area(&moved);
        let moved_height = self.height[node as usize];
        let mut best: Option<(u32, f64)> = None;
        let mut queue = std::mem::take(&mut self.queue);
        queue.clear();
        let start = Candidate { bound: moved_area.to_bits(), node: self.root, depth: 0, induced: 0f64.to_bits() };
        queue.push(Reverse(start));
        while let Some(Reverse(c)) = queue.pop() {
            let best_cost = best.map_or(f64::INFINITY, |b| b.1);
            if f64::from_bits(c.bound) >= best_cost {
                break;
            }
            let at = c.node as usize;
            let induced = f64::from_bits(c.induced);
            let merged = area(&self.bounds[at].union(&moved));
            let cost = induced + merged;
            let deepest = c.depth + 1 + self.height[at].max(moved_height);
            if cost < best_cost && (deepest as usize) < MAX_DEPTH {
                best = Some((c.node, cost));
            }
            if self.leaf[at].is_none() {
                let induced = induced + merged - area(&self.bounds[at]);
                let bound = induced + moved_area;
                if bound < best.map_or(f64::INFINITY, |b| b.1) {
                    for child in self.children[at] {
                        let induced = induced.to_bits();
                        queue.push(Reverse(Candidate {
                            bound: bound.to_bits(),
                            node: child,
                            depth: c.depth + 1,
                            induced,
                        }));
                    }
                }
            }
        }
        self.queue = queue;
        best
    }

    /// The tree in the builder's layout, with `tree`'s primitives reordered to the new leaf order.
    fn layout<P: Copy>(&self, tree: &BuiltTree<P>) -> BuiltTree<P> {
        let mut out = BuiltTree {
            nodes: Vec::with_capacity(self.bounds.len()),
            prim_order: Vec::with_capacity(tree.prim_order.len()),
            ordered: Vec::with_capacity(tree.ordered.len()),
        };
        out.nodes.push(FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 });
        self.lay_out(self.root, 0, tree, &mut out);
        debug_assert_eq!(out.nodes.len(), self.bounds.len());
        out
    }

    /// Writes linked node `node` at `index` of `out`, then its subtree in the builder's order.
    fn lay_out<P: Copy>(&self, node: u32, index: usize, tree: &BuiltTree<P>, out: &mut BuiltTree<P>) {
        let bounds = self.bounds[node as usize];
        match self.leaf[node as usize] {
            Some((first, count)) => {
                let run = first as usize..(first + count) as usize;
                let offset = out.prim_order.len() as u32;
                out.prim_order.extend_from_slice(&tree.prim_order[run.clone()]);
                out.ordered.extend_from_slice(&tree.ordered[run]);
                out.nodes[index] = FlatNode { bounds, first: offset, prim_count: count };
            }
            None => {
                let first = out.nodes.len();
                let placeholder = FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 };
                out.nodes.extend([placeholder, placeholder]);
                out.nodes[index] = FlatNode { bounds, first: first as u32, prim_count: FlatNode::INTERIOR };
                let [l, r] = self.children[node as usize];
                self.lay_out(l, first, tree, out);
                self.lay_out(r, first + 1, tree, out);
            }
        }
    }
}
