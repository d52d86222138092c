//! Collapsing the binary tree into `W`-wide nodes (tinybvh's `BVH8_CPU::ConvertFrom`, Embree's wide builders).
//!
//! Starting from a binary node, its children are gathered and the gathered child with the largest surface area
//! is repeatedly replaced by its own two children, until there are `W` of them or none can be opened. A binary
//! node can be opened when it is interior and holds more than `B` spheres: a subtree of at most `B` spheres
//! becomes one leaf of one block (Embree makes subtrees of at most 8 spheres one leaf), and a binary leaf of more
//! than `B` spheres (`leaf_size > B`) becomes one leaf of several blocks. So whatever the binary `leaf_size`,
//! leaves fill their blocks: a leaf holds at most `max(leaf_size, B)` spheres, and only its last block is padded.
//! Children keep the binary tree's left-to-right order; wide nodes and leaf blocks come out in depth-first order.

use super::leaf::Block;
use super::node::{ChildRef, WideNode};
use crate::accel::bvh::builder::BuiltTree;
use crate::geometry::Aabb;

/// A wide tree: nodes (the root first, depth-first) and the blocks their leaves refer to.
#[derive(Clone, Debug)]
pub struct Tree<const W: usize, const B: usize> {
    /// Wide nodes; the root is `nodes[0]`, and a tree always has one (without children when empty).
    pub nodes: Vec<WideNode<W>>,
    /// Leaf blocks, each leaf's blocks contiguous.
    pub blocks: Vec<Block<B>>,
}

/// Collapses `built` into a `W`-wide tree with leaves in blocks of `B`.
pub fn collapse<const W: usize, const B: usize>(built: &BuiltTree) -> Tree<W, B> {
    // Sphere count and first position in the primitive order of every binary subtree (children follow parents).
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
    let spheres = built.prim_order.len();
    let blocks = Vec::with_capacity(spheres.div_ceil(B) + spheres / 2);
    let mut c = Collapser::<W, B> { built, count, start, tree: Tree { nodes: Vec::new(), blocks } };
    c.node(0);
    c.tree
}

struct Collapser<'a, const W: usize, const B: usize> {
    built: &'a BuiltTree,
    count: Vec<u32>,
    start: Vec<u32>,
    tree: Tree<W, B>,
}

impl<const W: usize, const B: usize> Collapser<'_, W, B> {
    /// True when binary node `b` is interior with more than one block's spheres.
    fn openable(&self, b: usize) -> bool {
        !self.built.nodes[b].is_leaf() && self.count[b] as usize > B
    }

    /// Emits the wide node gathered from binary node `b` (and, first, its descendants); returns its index.
    fn node(&mut self, b: usize) -> u32 {
        let index = self.tree.nodes.len();
        self.tree.nodes.push(WideNode::EMPTY);
        // The gathered binary nodes, `kids[..len]`, in left-to-right order.
        let (mut kids, mut len) = ([0usize; W], 0);
        if self.count[b] > 0 {
            (kids[0], len) = (b, 1);
        }
        while len < W {
            let mut best: Option<(usize, f32)> = None;
            for (i, &k) in kids[..len].iter().enumerate() {
                if self.openable(k) {
                    let area = self.built.nodes[k].bounds.surface_area();
                    if best.is_none_or(|(_, a)| area > a) {
                        best = Some((i, area));
                    }
                }
            }
            let Some((i, _)) = best else { break };
            let first = self.built.nodes[kids[i]].first as usize;
            kids.copy_within(i + 1..len, i + 2);
            (kids[i], kids[i + 1], len) = (first, first + 1, len + 1);
        }
        let mut children = [(ChildRef::EMPTY, Aabb::EMPTY); W];
        for (slot, &k) in children.iter_mut().zip(&kids[..len]) {
            let child = if self.openable(k) { ChildRef::node(self.node(k)) } else { self.leaf(k) };
            *slot = (child, self.built.nodes[k].bounds);
        }
        self.tree.nodes[index] = WideNode::new(&children[..len]);
        index as u32
    }

    /// Emits the blocks of binary subtree `b`'s spheres; returns the leaf.
    fn leaf(&mut self, b: usize) -> ChildRef {
        let (start, count) = (self.start[b] as usize, self.count[b] as usize);
        let first = self.tree.blocks.len() as u32;
        let range = start..start + count;
        let blocks = Block::append(
            &mut self.tree.blocks,
            &self.built.ordered_spheres[range.clone()],
            &self.built.prim_order[range],
        );
        ChildRef::leaf(first, blocks as u32)
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
        let tree = collapse::<W, B>(&built);
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
                    let real: usize = blocks.iter().map(Block::len).sum();
                    assert!(
                        real <= (params.leaf_size as usize).max(B) && blocks.len() == real.div_ceil(B),
                        "blocks filled"
                    );
                    for block in blocks {
                        for l in 0..block.len() {
                            let id = block.ids[l];
                            seen[id as usize] += 1;
                            let s = spheres[id as usize].bounds();
                            assert!(bounds.union(&s) == bounds, "leaf box holds its spheres");
                        }
                    }
                }
            }
            if i > 0 {
                assert!(len >= 2 || W < 2, "inner wide nodes have at least two children");
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "every sphere in exactly one leaf");
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

    #[test]
    fn nodes_fill_up_until_only_leaves_are_left() {
        let spheres = SceneKind::RandomSpheres.generate(5000, 1).spheres;
        let built = builder::build(&spheres, &BvhParams { leaf_size: 1, ..BvhParams::default() });
        let tree = collapse::<8, 4>(&built);
        for node in &tree.nodes {
            assert!(node.len() == 8 || node.children[..node.len()].iter().all(|c| c.is_leaf()), "{node:?}");
        }
        assert!(tree.nodes.iter().any(|n| n.len() == 8));
    }
}
