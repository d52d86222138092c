//! The paper's tree: boxed nodes linked by pointers, leaves holding lists of primitive indices.

use super::builder;
use super::params::{BvhParams, Traversal};
use super::split::Referenced;
use super::stats::TreeStats;
use super::traverse::{self, ChildOrder, OrderedQueries, TreeView, traverse};
use super::tree::BuiltTree;
use crate::accel::{Accelerator, Hit};
use crate::counters::Counters;
use crate::geometry::{Aabb, Ray, Sphere};

/// A node of the pointer tree.
#[derive(Clone, Debug)]
pub struct BvhNode {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// Children or primitives.
    pub kind: BvhNodeKind,
}

/// What a pointer-tree node holds.
#[derive(Clone, Debug)]
pub enum BvhNodeKind {
    /// Two boxed children.
    Interior {
        /// First child.
        left: Box<BvhNode>,
        /// Second child.
        right: Box<BvhNode>,
    },
    /// Indices of the primitives in the leaf.
    Leaf {
        /// Indices into the scene's primitive list.
        prims: Vec<u32>,
    },
}

/// A BVH of boxed nodes over the primitives in scene order (the paper's layout).
#[derive(Clone, Debug)]
pub struct Bvh<P = Sphere> {
    root: BvhNode,
    prims: Vec<P>,
    params: BvhParams,
}

fn boxed<P>(tree: &BuiltTree<P>, index: usize) -> BvhNode {
    let n = &tree.nodes[index];
    let kind = if n.is_leaf() {
        let range = n.first as usize..(n.first + n.prim_count) as usize;
        BvhNodeKind::Leaf { prims: tree.prim_order[range].to_vec() }
    } else {
        BvhNodeKind::Interior {
            left: Box::new(boxed(tree, n.first as usize)),
            right: Box::new(boxed(tree, n.first as usize + 1)),
        }
    };
    BvhNode { bounds: n.bounds, kind }
}

impl<P: Referenced> Bvh<P> {
    /// Builds the tree and boxes its nodes.
    ///
    /// Builds with the threads of the current rayon pool (outside any pool: rayon's global pool); the tree is
    /// identical whatever the thread count (see [`builder`]).
    pub fn build(prims: &[P], params: &BvhParams) -> Self {
        let built = builder::build(prims, params);
        Self { root: boxed(&built, 0), prims: prims.to_vec(), params: *params }
    }

    /// The same tree traversed in `traversal` order (the order does not change the tree: nothing is rebuilt).
    pub fn with_traversal(mut self, traversal: Traversal) -> Self {
        self.params.traversal = traversal;
        self
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &BvhParams {
        &self.params
    }

    /// The root node.
    pub fn root(&self) -> &BvhNode {
        &self.root
    }

    fn heap_bytes(node: &BvhNode) -> usize {
        match &node.kind {
            BvhNodeKind::Interior { left, right } => {
                2 * std::mem::size_of::<BvhNode>() + Self::heap_bytes(left) + Self::heap_bytes(right)
            }
            BvhNodeKind::Leaf { prims } => prims.capacity() * std::mem::size_of::<u32>(),
        }
    }
}

impl<P: Referenced> OrderedQueries for Bvh<P> {
    #[inline(always)]
    fn traversal(&self) -> Traversal {
        self.params.traversal
    }

    #[inline(always)]
    fn closest<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        traverse::<_, O, C, _>(self, ray, counters, |node: &BvhNode, t_max, counters| {
            if let BvhNodeKind::Leaf { prims } = &node.kind {
                for &p in prims {
                    counters.prim_test();
                    if let Some(t) = self.prims[p as usize].intersect(ray, *t_max) {
                        *t_max = t;
                        best = Some(Hit { t, prim: p });
                    }
                }
            }
            false
        });
        best
    }

    #[inline(always)]
    fn any<O: ChildOrder, C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let mut found = false;
        traverse::<_, O, C, _>(self, ray, counters, |node: &BvhNode, t_max, counters| {
            if let BvhNodeKind::Leaf { prims } = &node.kind {
                found = prims.iter().any(|&p| {
                    counters.prim_test();
                    self.prims[p as usize].intersect(ray, *t_max).is_some()
                });
            }
            found
        });
        found
    }
}

impl<P: Referenced> TreeView for Bvh<P> {
    type Node<'a> = &'a BvhNode;

    #[inline(always)]
    fn root(&self) -> &BvhNode {
        &self.root
    }

    #[inline(always)]
    fn bounds<'a>(&'a self, node: &'a BvhNode) -> &'a Aabb {
        &node.bounds
    }

    #[inline(always)]
    fn children<'a>(&'a self, node: &'a BvhNode) -> Option<[&'a BvhNode; 2]> {
        match &node.kind {
            BvhNodeKind::Interior { left, right } => Some([left, right]),
            BvhNodeKind::Leaf { .. } => None,
        }
    }

    fn leaf_len(&self, node: &BvhNode) -> usize {
        match &node.kind {
            BvhNodeKind::Leaf { prims } => prims.len(),
            BvhNodeKind::Interior { .. } => 0,
        }
    }
}

impl<P: Referenced> Accelerator for Bvh<P> {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        traverse::intersect(self, ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        traverse::occluded(self, ray, counters)
    }

    fn stats(&self) -> TreeStats {
        let bytes =
            std::mem::size_of::<Self>() + Self::heap_bytes(&self.root) + std::mem::size_of_val(self.prims.as_slice());
        TreeStats::of_tree(self, bytes)
    }
}
