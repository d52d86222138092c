//! A wide BVH with SIMD leaves (issue #11): the binary tree collapsed into 4- or 8-wide nodes whose child boxes are
//! tested at once, and leaves whose primitives (spheres or triangles) are tested a block at a time.
//!
//! - [`params`]: width, leaf block, kernel, child order and any-hit order ([`WideParams`]);
//! - [`node`]: the wide node (child boxes per axis, 64-byte aligned); [`leaf`]: the primitive blocks;
//!   [`primitives`]: each primitive's block and its leaf tests;
//! - [`collapse`]: from the shared binary builder's tree (built with the SAH counting leaf blocks) to wide nodes;
//! - [`ray`], [`order`], [`stack`], [`traverse`]: the traversal, generic over [`kernel`] (scalar, AVX2, AVX-512),
//!   child order and counters; [`packet`]: packets of 8 or 16 rays with an active mask; [`tile`]: frustum-culled
//!   packets of an 8×8 tile of camera rays.
//!
//! [`WideBvh`] holds one of six layouts (width × leaf block) and the kernel resolved at build time; each query
//! dispatches once (layout, order, kernel) into a traversal compiled for exactly that combination.

pub mod collapse;
pub mod kernel;
pub mod leaf;
pub mod node;
pub mod order;
pub mod packet;
pub mod params;
pub mod primitives;
pub mod ray;
pub mod stack;
pub mod tile;
pub mod traverse;

use collapse::{Tree, collapse};
use kernel::Query;
#[cfg(target_arch = "x86_64")]
use kernel::simd::Simd;
use node::ChildRef;
use order::{ByOctant, Nearest, Order, Stored};
use packet::Packets;
use tile::Tiles;
use traverse::{Any, AnyBatch, Closest, ClosestBatch};

pub use leaf::{LeafBlock, WidePrimitive};
pub use params::{AnyHitOrdering, ChildOrdering, Kernel, WideParams};

use super::bvh::tree::BuiltTree;
use super::bvh::{BvhParams, ParamError, TreeStats, builder, sah};
use super::{Accelerator, Hit};
use crate::counters::Counters;
use crate::fingerprint::Fnv64;
use crate::geometry::{Aabb, Ray, Sphere};

/// The tree in one of its layouts (width × leaf block).
#[derive(Clone, Debug)]
enum Layout<P: WidePrimitive> {
    W4B4(Tree<4, 4, P>),
    W4B8(Tree<4, 8, P>),
    W4B16(Tree<4, 16, P>),
    W8B4(Tree<8, 4, P>),
    W8B8(Tree<8, 8, P>),
    W8B16(Tree<8, 16, P>),
}

/// A wide BVH: `width`-wide nodes over leaves of `leaf_block`-primitive SIMD blocks, traversed with one kernel.
#[derive(Clone, Debug)]
pub struct WideBvh<P: WidePrimitive = Sphere> {
    layout: Layout<P>,
    bvh: BvhParams,
    params: WideParams,
    kernel: Kernel,
    stats: TreeStats,
}

impl<P: WidePrimitive> WideBvh<P> {
    /// Builds the binary tree with `bvh` (its SAH counting leaves in blocks of [`WideParams::build_block`]), collapses it
    /// and lays it out; refuses invalid parameters, and a kernel this CPU lacks, with the reason.
    ///
    /// Builds with the threads of the current rayon pool; the tree is identical whatever the thread count.
    pub fn try_build(prims: &[P], bvh: &BvhParams, wide: &WideParams) -> Result<Self, ParamError> {
        bvh.validate()?;
        wide.validate()?;
        let built = builder::build_for_blocks(prims, bvh, wide.build_block());
        Self::laid_out(&built, bvh, wide)
    }

    /// A binary tree built elsewhere ([`BuiltTree::from_external`]) collapsed and laid out as [`WideBvh::try_build`]
    /// lays out its own; refuses a leaf of more primitives than one wide leaf holds (31 blocks), with the reason.
    pub fn try_from_tree(built: &BuiltTree<P>, bvh: &BvhParams, wide: &WideParams) -> Result<Self, ParamError> {
        bvh.validate()?;
        wide.validate()?;
        let most = ChildRef::MAX_BLOCKS as usize * wide.leaf_block as usize;
        if let Some(leaf) = built.nodes.iter().find(|n| n.is_leaf() && n.prim_count as usize > most) {
            return Err(ParamError {
                key: "leaf",
                allowed: format!("at most {most} primitives a leaf with leaf_block {}", wide.leaf_block),
                found: leaf.prim_count.to_string(),
            });
        }
        Self::laid_out(built, bvh, wide)
    }

    /// Collapses `built` into the layout `wide` names.
    fn laid_out(built: &BuiltTree<P>, bvh: &BvhParams, wide: &WideParams) -> Result<Self, ParamError> {
        let layout = match (wide.width, wide.leaf_block) {
            (4, 4) => Layout::W4B4(collapse(built)),
            (4, 8) => Layout::W4B8(collapse(built)),
            (4, _) => Layout::W4B16(collapse(built)),
            (_, 4) => Layout::W8B4(collapse(built)),
            (_, 8) => Layout::W8B8(collapse(built)),
            _ => Layout::W8B16(collapse(built)),
        };
        let stats = match &layout {
            Layout::W4B4(t) => stats(t),
            Layout::W4B8(t) => stats(t),
            Layout::W4B16(t) => stats(t),
            Layout::W8B4(t) => stats(t),
            Layout::W8B8(t) => stats(t),
            Layout::W8B16(t) => stats(t),
        };
        Ok(Self { layout, bvh: *bvh, params: *wide, kernel: wide.kernel.resolve_for(wide.leaf_block), stats })
    }

    /// [`WideBvh::try_build`] for parameters known to be valid; panics with the reason otherwise.
    pub fn build(prims: &[P], bvh: &BvhParams, wide: &WideParams) -> Self {
        Self::try_build(prims, bvh, wide).unwrap_or_else(|e| panic!("invalid wide BVH parameters: {e}"))
    }

    /// The same tree traversed with `kernel` (refused when this CPU lacks it).
    pub fn with_kernel(mut self, kernel: Kernel) -> Result<Self, ParamError> {
        WideParams { kernel, ..self.params }.validate()?;
        self.params.kernel = kernel;
        self.kernel = kernel.resolve_for(self.params.leaf_block);
        Ok(self)
    }

    /// The kernel that runs (never [`Kernel::Auto`]).
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Name of the kernel that runs: `scalar`, `avx2` or `avx512`.
    pub fn kernel_name(&self) -> &'static str {
        self.kernel.name()
    }

    /// The wide parameters it was built with (the kernel as requested; see [`WideBvh::kernel`]).
    pub fn params(&self) -> &WideParams {
        &self.params
    }

    /// The binary tree's parameters.
    pub fn bvh_params(&self) -> &BvhParams {
        &self.bvh
    }

    /// A fingerprint of the laid-out tree (every node and block, bit by bit).
    pub fn tree_hash(&self) -> u64 {
        fn hash<P: WidePrimitive, const W: usize, const B: usize>(t: &Tree<W, B, P>) -> u64 {
            let mut h = Fnv64::default();
            for n in &t.nodes {
                n.bounds.iter().flatten().for_each(|&v| _ = h.f32(v));
                n.children.iter().for_each(|c| _ = h.u32(c.0));
                n.octant_orders.iter().for_each(|&o| _ = h.u32(o));
            }
            for b in &t.blocks {
                b.floats().for_each(|v| _ = h.f32(v));
                b.ids().iter().for_each(|&id| _ = h.u32(id));
            }
            h.finish()
        }
        match &self.layout {
            Layout::W4B4(t) => hash(t),
            Layout::W4B8(t) => hash(t),
            Layout::W4B16(t) => hash(t),
            Layout::W8B4(t) => hash(t),
            Layout::W8B8(t) => hash(t),
            Layout::W8B16(t) => hash(t),
        }
    }

    /// The child order of any-hit queries.
    fn any_hit_order(&self) -> ChildOrdering {
        match self.params.any_hit_order {
            AnyHitOrdering::ChildOrder => self.params.order,
            AnyHitOrdering::None => ChildOrdering::None,
        }
    }

    /// Runs `query` with this tree's layout, child order `order` and kernel: the one dispatch per query.
    #[inline(always)]
    fn dispatch<Q: Query>(&self, order: ChildOrdering, query: Q) -> Q::Out {
        match &self.layout {
            Layout::W4B4(t) => self.ordered(t, order, query),
            Layout::W4B8(t) => self.ordered(t, order, query),
            Layout::W4B16(t) => self.ordered(t, order, query),
            Layout::W8B4(t) => self.ordered(t, order, query),
            Layout::W8B8(t) => self.ordered(t, order, query),
            Layout::W8B16(t) => self.ordered(t, order, query),
        }
    }

    /// [`WideBvh::dispatch`] for packet queries, which order children by the packet's entry distances whatever
    /// the child order (so they are compiled once, not once per order).
    #[inline(always)]
    fn dispatch_packets<Q: Query>(&self, query: Q) -> Q::Out {
        match &self.layout {
            Layout::W4B4(t) => self.run::<Q, Nearest, 4, 4>(t, query),
            Layout::W4B8(t) => self.run::<Q, Nearest, 4, 8>(t, query),
            Layout::W4B16(t) => self.run::<Q, Nearest, 4, 16>(t, query),
            Layout::W8B4(t) => self.run::<Q, Nearest, 8, 4>(t, query),
            Layout::W8B8(t) => self.run::<Q, Nearest, 8, 8>(t, query),
            Layout::W8B16(t) => self.run::<Q, Nearest, 8, 16>(t, query),
        }
    }

    #[inline(always)]
    fn ordered<Q: Query, const W: usize, const B: usize>(
        &self,
        tree: &Tree<W, B, P>,
        order: ChildOrdering,
        query: Q,
    ) -> Q::Out {
        match order {
            ChildOrdering::None => self.run::<Q, Stored, W, B>(tree, query),
            ChildOrdering::Distance => self.run::<Q, Nearest, W, B>(tree, query),
            ChildOrdering::Octant => self.run::<Q, ByOctant, W, B>(tree, query),
        }
    }

    #[inline(always)]
    fn run<Q: Query, O: Order, const W: usize, const B: usize>(&self, tree: &Tree<W, B, P>, query: Q) -> Q::Out {
        match self.kernel {
            // SAFETY: the kernel was validated as available on this CPU when it was chosen.
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => unsafe { kernel::avx2::Avx2::run::<Q, O, P, W, B>(query, tree) },
            // SAFETY: as above.
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => unsafe { kernel::avx512::Avx512::run::<Q, O, P, W, B>(query, tree) },
            _ => kernel::scalar::run::<Q, O, P, W, B>(query, tree),
        }
    }
}

/// Size and quality of a wide tree.
///
/// `nodes` counts wide nodes and leaves (as the binary trees count their leaves as nodes), `leaves` the leaves,
/// `depth` the levels below the root of the deepest leaf, `bytes` the nodes and blocks (padding included). The SAH
/// cost uses the binary trees' unit costs, so that it compares with theirs: 1 per wide node and 1 per sphere of a
/// leaf, each weighted by its box's area relative to the root's (the union of the root's children).
fn stats<P: WidePrimitive, const W: usize, const B: usize>(tree: &Tree<W, B, P>) -> TreeStats {
    let root = &tree.nodes[0];
    let bounds = |n: &node::WideNode<W>| (0..n.len()).map(|l| n.child_bounds(l)).fold(Aabb::EMPTY, |a, b| a.union(&b));
    let root_area = bounds(root).surface_area() as f64;
    let root_area = if root_area > 0.0 { root_area } else { 1.0 };
    let bytes = std::mem::size_of_val(tree.nodes.as_slice()) + std::mem::size_of_val(tree.blocks.as_slice());
    let mut s = TreeStats { nodes: 0, leaves: 0, depth: 0, bytes, sah_cost: 0.0 };
    let mut stack = vec![(0usize, 0usize)];
    while let Some((index, depth)) = stack.pop() {
        let node = &tree.nodes[index];
        s.nodes += 1;
        s.depth = s.depth.max(depth);
        s.sah_cost += sah::TRAVERSAL_COST as f64 * bounds(node).surface_area() as f64 / root_area;
        for lane in 0..node.len() {
            let child = node.children[lane];
            if child.is_node() {
                stack.push((child.index(), depth + 1));
            } else {
                s.nodes += 1;
                s.leaves += 1;
                s.depth = s.depth.max(depth + 1);
                let spheres: usize = tree.blocks[child.blocks()].iter().map(LeafBlock::len).sum();
                s.sah_cost +=
                    sah::leaf_cost(spheres) as f64 * node.child_bounds(lane).surface_area() as f64 / root_area;
            }
        }
    }
    s
}

impl<P: WidePrimitive> Accelerator for WideBvh<P> {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.dispatch(self.params.order, Closest { ray, counters })
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.dispatch(self.any_hit_order(), Any { ray, counters })
    }

    fn stats(&self) -> TreeStats {
        self.stats
    }

    fn intersect_batch<C: Counters>(&self, rays: &[Ray], out: &mut [Hit], counters: &mut C) {
        match self.params.packet {
            8 => self.dispatch_packets(Packets::<C, _, 8> { rays, out, counters }),
            16 => self.dispatch_packets(Packets::<C, _, 16> { rays, out, counters }),
            64 => self.dispatch_packets(Tiles { rays, out, counters }),
            _ => self.dispatch(self.params.order, ClosestBatch { rays, out, counters }),
        }
    }

    fn occluded_batch<C: Counters>(&self, rays: &[Ray], out: &mut [bool], counters: &mut C) {
        match self.params.packet {
            8 => self.dispatch_packets(Packets::<C, _, 8> { rays, out, counters }),
            16 => self.dispatch_packets(Packets::<C, _, 16> { rays, out, counters }),
            64 => self.dispatch_packets(Tiles { rays, out, counters }),
            _ => self.dispatch(self.any_hit_order(), AnyBatch { rays, out, counters }),
        }
    }
}
