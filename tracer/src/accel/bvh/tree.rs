//! The binary tree every builder produces: the array layout's node ([`FlatNode`]), the built tree ([`BuiltTree`])
//! and the depth bound ([`MAX_DEPTH`]) the builders keep and the traversal stacks are sized by.

use crate::geometry::{Aabb, Sphere};

/// Deepest level any builder produces; traversal stacks hold this many entries.
pub const MAX_DEPTH: usize = 64;

/// A node of the array layout: bounds, then either two children or a run of primitives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct FlatNode {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// Interior: index of the left child (the right child follows it). Leaf: first index into the primitive order.
    pub first: u32,
    /// Leaf: number of primitives. Interior: [`FlatNode::INTERIOR`].
    pub prim_count: u32,
}

const _: () = assert!(std::mem::size_of::<FlatNode>() == 32);

impl FlatNode {
    /// `prim_count` of interior nodes.
    pub const INTERIOR: u32 = u32::MAX;

    /// True for leaves.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.prim_count != Self::INTERIOR
    }
}

/// The builder's result: nodes in the array layout and the order of primitives their leaves refer to.
#[derive(Clone, Debug)]
pub struct BuiltTree<P = Sphere> {
    /// Nodes; the root is `nodes[0]`.
    pub nodes: Vec<FlatNode>,
    /// Primitive ids in leaf order: a permutation, but for spatial splits, which may repeat an id (in other leaves).
    pub prim_order: Vec<u32>,
    /// The primitives of `prim_order`, in the same order (the builder's own copy, read in sequence).
    pub ordered: Vec<P>,
}

impl<P: Copy> BuiltTree<P> {
    /// A binary tree another builder made (e.g. a peer library's), in this layout: `nodes[0]` the root, an interior
    /// node's children at `first` and `first + 1` in any order of the array, a leaf naming `prim_count` entries of
    /// `prim_order` from `first` (ids into `prims`, repeated in other leaves after spatial splits). Checked — every
    /// index in range, every node reached once, at most [`MAX_DEPTH`] levels — and laid out as this crate's builders
    /// lay out theirs (sibling pairs depth-first, each subtree's primitives contiguous), so the collapse and every
    /// traversal take it as their own.
    pub fn from_external(nodes: &[FlatNode], prim_order: &[u32], prims: &[P]) -> Result<Self, String> {
        let mut out = BuiltTree { nodes: Vec::with_capacity(nodes.len()), prim_order: Vec::new(), ordered: Vec::new() };
        if nodes.is_empty() {
            return Err("no root node".into());
        }
        let mut reached = vec![false; nodes.len()];
        out.nodes.push(PLACEHOLDER);
        // (node of `nodes`, its slot in `out.nodes`, depth); right children are pushed first so left runs first.
        let mut stack = vec![(0usize, 0usize, 0usize)];
        while let Some((n, slot, depth)) = stack.pop() {
            if std::mem::replace(&mut reached[n], true) {
                return Err(format!("node {n} is reached twice"));
            }
            if depth > MAX_DEPTH {
                return Err(format!("deeper than {MAX_DEPTH} levels"));
            }
            let node = nodes[n];
            if node.is_leaf() {
                let (first, count) = (node.first as usize, node.prim_count as usize);
                let ids = prim_order.get(first..first + count).ok_or_else(|| {
                    format!("leaf {n} names entries {first}..{} of {}", first + count, prim_order.len())
                })?;
                if let Some(&bad) = ids.iter().find(|&&id| id as usize >= prims.len()) {
                    return Err(format!("leaf {n} names primitive {bad} of {}", prims.len()));
                }
                let start = out.prim_order.len() as u32;
                out.prim_order.extend_from_slice(ids);
                out.ordered.extend(ids.iter().map(|&id| prims[id as usize]));
                out.nodes[slot] = FlatNode { bounds: node.bounds, first: start, prim_count: count as u32 };
            } else {
                let left = node.first as usize;
                if left + 1 >= nodes.len() {
                    return Err(format!("node {n} has children {left} and {} of {} nodes", left + 1, nodes.len()));
                }
                let pair = out.nodes.len();
                out.nodes.extend([PLACEHOLDER, PLACEHOLDER]);
                out.nodes[slot] = FlatNode { bounds: node.bounds, first: pair as u32, prim_count: FlatNode::INTERIOR };
                stack.push((left + 1, pair + 1, depth + 1));
                stack.push((left, pair, depth + 1));
            }
        }
        Ok(out)
    }
}

/// `ceil(log2(n))` (0 for n ≤ 1): the least depth of a binary tree with `n` leaves.
pub(super) fn ceil_log2(n: usize) -> usize {
    (usize::BITS - n.saturating_sub(1).leading_zeros()) as usize
}

/// A node slot reserved before its subtree is built.
pub(super) const PLACEHOLDER: FlatNode = FlatNode { bounds: Aabb::EMPTY, first: 0, prim_count: 0 };

#[cfg(test)]
mod tests {
    use super::*;

    use crate::accel::bvh::{BvhParams, builder};
    use crate::rng::SplitMix64;
    use glam::Vec3;

    fn spheres(n: usize) -> Vec<Sphere> {
        let mut rng = SplitMix64::new(5);
        let mut at = || rng.range(-10.0, 10.0) as f32;
        (0..n).map(|_| Sphere::new(Vec3::new(at(), at(), at()), 0.3)).collect()
    }

    /// `tree`'s nodes in reverse array order (children pairs kept adjacent) and its leaves' ranges reversed: the
    /// same tree as another builder might store it.
    fn scrambled(tree: &BuiltTree<Sphere>) -> (Vec<FlatNode>, Vec<u32>) {
        let n = tree.nodes.len();
        // Sibling pair k of ours becomes pair `pairs - 1 - k`: the root stays at 0, siblings stay side by side.
        let pairs = (n - 1) / 2;
        let to = |i: usize| if i == 0 { 0 } else { 2 * (pairs - 1 - (i - 1) / 2) + 1 + (i - 1) % 2 };
        let m = tree.prim_order.len();
        let mut nodes = vec![PLACEHOLDER; n];
        for (i, node) in tree.nodes.iter().enumerate() {
            let moved = if node.is_leaf() {
                let end = (node.first + node.prim_count) as usize;
                FlatNode { first: (m - end) as u32, ..*node }
            } else {
                FlatNode { first: to(node.first as usize) as u32, ..*node }
            };
            nodes[to(i)] = moved;
        }
        let order: Vec<u32> = tree.prim_order.iter().rev().copied().collect();
        (nodes, order)
    }

    #[test]
    fn a_tree_stored_another_way_is_laid_out_as_ours() {
        let prims = spheres(300);
        let ours = builder::build(&prims, &BvhParams::default());
        let (nodes, order) = scrambled(&ours);
        assert_ne!(nodes, ours.nodes, "the scrambled copy is stored differently");
        let back = BuiltTree::from_external(&nodes, &order, &prims).unwrap();
        assert_eq!(back.nodes.len(), ours.nodes.len());
        // Same shape in the same depth-first layout; a leaf's primitives may come in the reverse order.
        for (a, b) in back.nodes.iter().zip(&ours.nodes) {
            assert_eq!((a.bounds, a.first, a.prim_count), (b.bounds, b.first, b.prim_count));
        }
        for leaf in ours.nodes.iter().filter(|n| n.is_leaf()) {
            let range = leaf.first as usize..(leaf.first + leaf.prim_count) as usize;
            let mut a = back.prim_order[range.clone()].to_vec();
            let mut b = ours.prim_order[range].to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
        }
        assert!(back.prim_order.iter().zip(&back.ordered).all(|(&id, p)| prims[id as usize] == *p));
    }

    #[test]
    fn a_broken_tree_is_refused_with_the_reason() {
        let prims = spheres(40);
        let ours = builder::build(&prims, &BvhParams::default());
        let err = |nodes: &[FlatNode], order: &[u32]| BuiltTree::from_external(nodes, order, &prims).unwrap_err();
        assert!(err(&[], &[]).contains("no root"));
        let mut bad = ours.nodes.clone();
        bad[0].first = bad.len() as u32 - 1;
        assert!(err(&bad, &ours.prim_order).contains("children"), "{}", err(&bad, &ours.prim_order));
        let mut cycle = ours.nodes.clone();
        let child = cycle[0].first as usize;
        cycle[child] = FlatNode { first: 0, ..cycle[0] };
        assert!(err(&cycle, &ours.prim_order).contains("twice") || err(&cycle, &ours.prim_order).contains("deeper"));
        let leaf = ours.nodes.iter().position(FlatNode::is_leaf).unwrap();
        let mut long = ours.nodes.clone();
        long[leaf].prim_count = ours.prim_order.len() as u32 + 1;
        assert!(err(&long, &ours.prim_order).contains("names entries"));
        let mut order = ours.prim_order.clone();
        order[0] = prims.len() as u32;
        assert!(err(&ours.nodes, &order).contains("names primitive"));
    }

    #[test]
    fn ceil_log2_matches_definition() {
        assert_eq!([1, 2, 3, 4, 5, 8, 9].map(ceil_log2), [0, 1, 2, 2, 3, 3, 4]);
    }
}
