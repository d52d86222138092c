//! Size and quality of a built structure: node count, depth, memory and SAH cost.

use serde::{Deserialize, Serialize};

use super::sah;
use super::traverse::TreeView;

/// Statistics of a built accelerator, recorded with every run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TreeStats {
    /// Tree nodes (0 for a list).
    pub nodes: usize,
    /// Leaves among them.
    pub leaves: usize,
    /// Levels below the root of the deepest leaf (0 for a single leaf or a list).
    pub depth: usize,
    /// Bytes of the structure, primitives included.
    pub bytes: usize,
    /// SAH cost relative to one ray-sphere test (a list of n spheres costs n).
    pub sah_cost: f64,
}

impl TreeStats {
    /// Statistics of brute force over `count` spheres held in `bytes`.
    pub fn list(count: usize, bytes: usize) -> Self {
        Self { nodes: 0, leaves: 0, depth: 0, bytes, sah_cost: sah::leaf_cost(count) as f64 }
    }

    /// Walks a tree and totals its statistics; `bytes` is the layout's own memory count.
    pub fn of_tree<T: TreeView>(tree: &T, bytes: usize) -> Self {
        let root = tree.root();
        let root_area = tree.bounds(root).surface_area() as f64;
        let root_area = if root_area > 0.0 { root_area } else { 1.0 };
        let mut s = Self { nodes: 0, leaves: 0, depth: 0, bytes, sah_cost: 0.0 };
        let mut stack = vec![(root, 0usize)];
        while let Some((node, depth)) = stack.pop() {
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            let area = tree.bounds(node).surface_area() as f64 / root_area;
            match tree.children(node) {
                Some([l, r]) => {
                    s.sah_cost += sah::TRAVERSAL_COST as f64 * area;
                    stack.push((r, depth + 1));
                    stack.push((l, depth + 1));
                }
                None => {
                    s.leaves += 1;
                    s.sah_cost += sah::leaf_cost(tree.leaf_len(node)) as f64 * area;
                }
            }
        }
        s
    }
}
