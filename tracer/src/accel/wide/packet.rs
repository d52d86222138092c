//! Packet traversal: `P` rays (8 or 16) go down the tree together, with an active mask.
//!
//! One shared stack holds entries of a child, the mask of the packet's rays that entered it and the nearest of
//! their entry distances. A popped entry is taken by the rays of its mask whose closest hit so far lies beyond that
//! distance (none: it is skipped). At a node each active ray box-tests the node's children with the kernel's
//! node test (SIMD across the children); every child that some ray enters is pushed with the mask of those rays,
//! nearest entry on top. At a leaf each active ray tests the leaf's blocks. Each ray's distances come from the
//! same kernel calls as in single-ray traversal, so its answer is the single-ray answer; what the packet shares is
//! the walk: one stack, one fetch of every node and block for all its rays. Any-hit packets drop a ray from the
//! packet at its first hit and stop when none is left.
//!
//! Children are visited nearest-first by the packet's nearest entry distance, whatever the tree's
//! [`super::ChildOrdering`] (an order for one ray direction does not fit a packet). So a ray may reach a far
//! leaf before a near one, and then box-test the near one against a closest hit found there. A box's entry distance
//! can round a hair above the distance of a sphere inside it (seen at coordinates ~1e13 in the degenerate-scene
//! tests: a hit one ulp farther than the nearest was kept), so packets cull children and skip stack entries
//! against `t_max` widened by [`CULL_SLACK`]; the sphere tests still take only strictly nearer hits.
//!
//! Counters count each ray's work: a `node_visit` and the node's `box_tests` for every active ray at a node, a
//! `prim_test` per real sphere of a block for every active ray at a leaf.

use std::mem::MaybeUninit;

use super::collapse::Tree;
use super::kernel::{Ops, Query};
use super::leaf::{LeafBlock, PAD, WidePrimitive};
use super::node::{ChildRef, WideNode};
use super::order::Order;
use super::ray::RayLanes;
use crate::accel::Hit;
use crate::accel::bvh::tree::MAX_DEPTH;
use crate::counters::Counters;
use crate::geometry::Ray;
use crate::render::PrimaryHits;

/// Relative slack on a ray's closest hit when culling boxes: far above the few ulps a box's entry distance can
/// round past a sphere's hit distance, far below what would make a visit useless.
pub(super) const CULL_SLACK: f32 = 1.0 + 1.0 / 65536.0;

/// Stack entries: as for one ray (see `stack`), every level leaves at most `W - 1` entries.
const STACK: usize = MAX_DEPTH * 8;

/// A child waiting, the rays that entered it, and the nearest of their entry distances.
#[derive(Clone, Copy)]
pub(super) struct Entry {
    pub(super) child: ChildRef,
    pub(super) rays: u64,
    pub(super) t: f32,
}

/// The packet's stack.
pub(super) struct Stack {
    entries: [MaybeUninit<Entry>; STACK],
    pub(super) len: usize,
}

impl Stack {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self { entries: [const { MaybeUninit::uninit() }; STACK], len: 0 }
    }

    /// Inserts among the entries from `base` up, the largest distance lowest (the nearest ends on top).
    #[inline(always)]
    pub(super) fn insert_sorted(&mut self, base: usize, e: Entry) {
        assert!(self.len < STACK, "packet stack overflow");
        let mut i = self.len;
        // SAFETY: entries below `len` are written, and `i <= len < STACK`.
        unsafe {
            while i > base && self.entries.get_unchecked(i - 1).assume_init_ref().t <= e.t {
                let below = self.entries.get_unchecked(i - 1).assume_init_read();
                self.entries.get_unchecked_mut(i).write(below);
                i -= 1;
            }
            self.entries.get_unchecked_mut(i).write(e);
        }
        self.len += 1;
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<Entry> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below the old `len` are written, and each is read once.
        Some(unsafe { self.entries.get_unchecked(self.len).assume_init_read() })
    }
}

/// The rays of a packet, prepared once.
pub(super) struct Packet<const P: usize> {
    pub(super) lanes: [RayLanes; P],
    /// Closest hit so far (closest-hit packets) or the ray's own `t_max`.
    pub(super) t_max: [f32; P],
    /// Hit sphere so far ([`PAD`]: none).
    pub(super) best: [u32; P],
}

impl<const P: usize> Packet<P> {
    /// A packet to [`Packet::load`] rays into: made once per batch, as a packet is too large to move cheaply (64
    /// rays take 5 KB, and a packet made per 64 rays was copied each time: a tenth of the tile packets' time).
    #[inline(always)]
    pub(super) fn empty() -> Self {
        Self { lanes: [RayLanes::default(); P], t_max: [0.0; P], best: [PAD; P] }
    }

    /// Loads `rays` (1..=P) in place; lanes past them repeat the last ray and are never active.
    #[inline(always)]
    pub(super) fn load<Prim: WidePrimitive>(&mut self, rays: &[Ray]) {
        let last = rays.len() - 1;
        for i in 0..P {
            let ray = &rays[i.min(last)];
            self.lanes[i] = RayLanes::for_leaves::<Prim>(ray);
            self.t_max[i] = ray.t_max;
        }
        self.best = [PAD; P];
    }

    /// Writes the closest hits of the first `out.len()` rays ([`PrimaryHits::MISS`] where none).
    #[inline(always)]
    pub(super) fn write_closest(&self, out: &mut [Hit]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = match self.best[i] {
                PAD => PrimaryHits::MISS,
                prim => Hit { t: self.t_max[i], prim },
            };
        }
    }
}

/// Iterates the set bits of a mask.
#[inline(always)]
pub(super) fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// The mask of the first `n` rays (`n` in 1..=64).
#[inline(always)]
pub(super) fn all(n: usize) -> u64 {
    u64::MAX >> (64 - n)
}

/// The rays of `mask` whose current `t_max` (with [`CULL_SLACK`]) lies beyond `t`.
#[inline(always)]
pub(super) fn still_wanted<const P: usize>(mask: u64, t: f32, t_max: &[f32; P]) -> u64 {
    bits(mask).filter(|&i| t < t_max[i] * CULL_SLACK).fold(0, |m, i| m | 1 << i)
}

/// How a packet enters a node: every active ray box-tests the children ([`Masked`]), or the tile packets' frustum
/// and ranges ([`super::tile`]).
pub(super) trait Enter<const P: usize> {
    /// Tests the children of the node of `at` for its `active` rays and pushes every child some ray enters, nearest
    /// on top.
    ///
    /// # Safety
    /// The CPU supports `K`'s instructions.
    unsafe fn enter<K: Ops, C: Counters, const W: usize>(&self, at: Visit<'_, W, P>, counters: &mut C);

    /// Some ray's closest hit got nearer: `t_max` holds the rays' new bounds.
    #[inline(always)]
    fn nearer(&mut self, _t_max: &[f32; P]) {}
}

/// A node the packet enters: the node, the rays that reached it, the packet, and the stack its children go on.
pub(super) struct Visit<'a, const W: usize, const P: usize> {
    pub(super) node: &'a WideNode<W>,
    pub(super) active: u64,
    pub(super) packet: &'a Packet<P>,
    pub(super) stack: &'a mut Stack,
}

impl<'a, const W: usize, const P: usize> Visit<'a, W, P> {
    /// Visits node `node` of `tree`.
    ///
    /// # Safety
    /// `node` is a node of `tree`.
    #[inline(always)]
    unsafe fn new<Prim: WidePrimitive, const B: usize>(
        tree: &'a Tree<W, B, Prim>,
        node: ChildRef,
        active: u64,
        packet: &'a Packet<P>,
        stack: &'a mut Stack,
    ) -> Self {
        debug_assert!(node.index() < tree.nodes.len());
        // SAFETY: node references come from the collapse, which emits every node it refers to.
        let node = unsafe { tree.nodes.get_unchecked(node.index()) };
        Self { node, active, packet, stack }
    }
}

/// Every active ray box-tests the node's children; each child is pushed with the rays that entered it.
pub(super) struct Masked;

impl<const P: usize> Enter<P> for Masked {
    #[inline(always)]
    unsafe fn enter<K: Ops, C: Counters, const W: usize>(&self, at: Visit<'_, W, P>, counters: &mut C) {
        let Visit { node, active, packet, stack } = at;
        let mut entered = [0u64; W];
        let mut nearest = [f32::INFINITY; W];
        let mut dist = [0.0f32; W];
        for i in bits(active) {
            counters.node_visit();
            if C::ENABLED {
                counters.box_tests(node.len() as u32);
            }
            // SAFETY: forwarded from the caller.
            let hits = unsafe { K::boxes(node, &packet.lanes[i], packet.t_max[i] * CULL_SLACK, &mut dist) };
            for lane in bits(hits as u64) {
                entered[lane] |= 1 << i;
                nearest[lane] = nearest[lane].min(dist[lane]);
            }
        }
        let base = stack.len;
        for lane in 0..W {
            if entered[lane] != 0 {
                stack.insert_sorted(base, Entry { child: node.children[lane], rays: entered[lane], t: nearest[lane] });
            }
        }
    }
}

/// What a packet traversal answers for each ray: its nearest hit ([`Hit`]) or whether it is occluded (`bool`).
pub(super) trait Answer: Sized {
    /// Traverses `tree` with the packet's first `out.len()` rays (1..=P), entering nodes by `enter`, and writes
    /// their answers into `out`.
    ///
    /// # Safety
    /// The CPU supports `K`'s instructions.
    unsafe fn traverse<
        K: Ops,
        C: Counters,
        E: Enter<P>,
        Prim: WidePrimitive,
        const W: usize,
        const B: usize,
        const P: usize,
    >(
        tree: &Tree<W, B, Prim>,
        packet: &mut Packet<P>,
        enter: E,
        out: &mut [Self],
        counters: &mut C,
    );
}

/// Nearest hits ([`PrimaryHits::MISS`] for misses).
impl Answer for Hit {
    #[inline(always)]
    unsafe fn traverse<
        K: Ops,
        C: Counters,
        E: Enter<P>,
        Prim: WidePrimitive,
        const W: usize,
        const B: usize,
        const P: usize,
    >(
        tree: &Tree<W, B, Prim>,
        packet: &mut Packet<P>,
        mut enter: E,
        out: &mut [Hit],
        counters: &mut C,
    ) {
        let mut stack = Stack::new();
        stack.insert_sorted(0, Entry { child: ChildRef::ROOT, rays: all(out.len()), t: f32::NEG_INFINITY });
        while let Some(e) = stack.pop() {
            let active = still_wanted(e.rays, e.t, &packet.t_max);
            if active == 0 {
                continue;
            }
            if e.child.is_node() {
                // SAFETY: forwarded from the caller.
                unsafe { enter.enter::<K, C, W>(Visit::new(tree, e.child, active, packet, &mut stack), counters) };
                continue;
            }
            // SAFETY: forwarded from the caller.
            if unsafe { leaf_closest::<K, C, Prim, W, B, P>(tree, e.child, active, packet, counters) } {
                enter.nearer(&packet.t_max);
            }
        }
        packet.write_closest(out);
    }
}

/// The `active` rays test the blocks of `leaf`, each keeping a nearer hit; true when some ray's hit got nearer.
///
/// # Safety
/// The CPU supports `K`'s instructions; `leaf` is a leaf of `tree`.
#[inline(always)]
unsafe fn leaf_closest<K: Ops, C: Counters, Prim: WidePrimitive, const W: usize, const B: usize, const P: usize>(
    tree: &Tree<W, B, Prim>,
    leaf: ChildRef,
    active: u64,
    packet: &mut Packet<P>,
    counters: &mut C,
) -> bool {
    debug_assert!(leaf.blocks().end <= tree.blocks.len());
    let mut nearer = false;
    // SAFETY: leaf references name blocks the collapse emitted.
    for block in unsafe { tree.blocks.get_unchecked(leaf.blocks()) } {
        for i in bits(active) {
            if C::ENABLED {
                (0..block.len()).for_each(|_| counters.prim_test());
            }
            // SAFETY: forwarded from the caller.
            if let Some((t, lane)) = unsafe { K::closest(block, &packet.lanes[i], packet.t_max[i]) } {
                packet.t_max[i] = t;
                packet.best[i] = block.ids()[lane];
                nearer = true;
            }
        }
    }
    nearer
}

/// The `active` rays of `unoccluded` test the blocks of `leaf`; returns `unoccluded` without the rays that hit.
///
/// # Safety
/// The CPU supports `K`'s instructions; `leaf` is a leaf of `tree`.
#[inline(always)]
unsafe fn leaf_any<K: Ops, C: Counters, Prim: WidePrimitive, const W: usize, const B: usize, const P: usize>(
    tree: &Tree<W, B, Prim>,
    leaf: ChildRef,
    active: u64,
    mut unoccluded: u64,
    packet: &Packet<P>,
    counters: &mut C,
) -> u64 {
    // SAFETY: as in `leaf_closest`.
    for block in unsafe { tree.blocks.get_unchecked(leaf.blocks()) } {
        for i in bits(active & unoccluded) {
            if C::ENABLED {
                (0..block.len()).for_each(|_| counters.prim_test());
            }
            // SAFETY: forwarded from the caller.
            if unsafe { K::any(block, &packet.lanes[i], packet.t_max[i]) } {
                unoccluded &= !(1 << i);
            }
        }
    }
    unoccluded
}

/// Occlusion: a ray is dropped from the packet at its first hit, and the traversal ends when none is left.
impl Answer for bool {
    #[inline(always)]
    unsafe fn traverse<
        K: Ops,
        C: Counters,
        E: Enter<P>,
        Prim: WidePrimitive,
        const W: usize,
        const B: usize,
        const P: usize,
    >(
        tree: &Tree<W, B, Prim>,
        packet: &mut Packet<P>,
        enter: E,
        out: &mut [bool],
        counters: &mut C,
    ) {
        let mut unoccluded = all(out.len());
        let mut stack = Stack::new();
        stack.insert_sorted(0, Entry { child: ChildRef::ROOT, rays: unoccluded, t: f32::NEG_INFINITY });
        while let Some(e) = stack.pop() {
            let active = e.rays & unoccluded;
            if active == 0 {
                continue;
            }
            if e.child.is_node() {
                // SAFETY: forwarded from the caller.
                unsafe { enter.enter::<K, C, W>(Visit::new(tree, e.child, active, packet, &mut stack), counters) };
                continue;
            }
            // SAFETY: forwarded from the caller.
            unoccluded =
                unsafe { leaf_any::<K, C, Prim, W, B, P>(tree, e.child, active, unoccluded, packet, counters) };
            if unoccluded == 0 {
                break;
            }
        }
        for (i, o) in out.iter_mut().enumerate() {
            *o = unoccluded >> i & 1 == 0;
        }
    }
}

/// A batch in packets of `P`, one `ray` count per ray: nearest hits into `out: &mut [Hit]`
/// ([`PrimaryHits::MISS`] for misses) or occlusion into `out: &mut [bool]`.
pub struct Packets<'a, C, A, const P: usize> {
    /// The rays.
    pub rays: &'a [Ray],
    /// One answer per ray.
    pub out: &'a mut [A],
    /// Where their work is counted.
    pub counters: &'a mut C,
}

impl<C: Counters, A: Answer, const P: usize> Query for Packets<'_, C, A, P> {
    type Out = ();
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) {
        const { assert!(P <= 64, "the active mask is a u64") };
        let mut packet = Packet::empty();
        for (rays, out) in self.rays.chunks(P).zip(self.out.chunks_mut(P)) {
            (0..rays.len()).for_each(|_| self.counters.ray());
            packet.load::<Prim>(rays);
            // SAFETY: forwarded from the caller.
            unsafe { A::traverse::<K, C, _, Prim, W, B, P>(tree, &mut packet, Masked, out, self.counters) };
        }
    }
}
