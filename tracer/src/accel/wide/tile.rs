//! Frustum-culled tile packets: the 64 rays of an 8×8 tile of camera rays (the order of
//! [`crate::rays::RaySet::primary`]) go down the tree together, culled by the packet's frustum and carried as a
//! range of rays.
//!
//! At a node the packet's frustum ([`FrustumLanes`]: interval bounds on every ray's origin and reciprocal
//! direction) is tested against all children at once; it bounds every ray's entry distance from below and its exit
//! from above with the rays' own f32 operations, so a child it misses is missed by every ray. The children it keeps
//! get the ranged test of Overbeck et al. 2008: the packet's active rays are box-tested in order until each kept
//! child has a first ray that enters it, and in reverse order until each has a last. A child no ray enters is
//! dropped; the others are pushed with the active rays from their first to their last, nearest frustum entry on
//! top. A coherent packet thus tests a node with the frustum and a few rays instead of every ray. Rays inside a
//! range that miss the child are carried on and tested against its children and spheres anyway; the answers stay
//! exact, as a sphere test is exact whatever box let a ray reach it.
//!
//! Only packets whose directions share an octant go this way. In others (diffuse bounces, the tiles on the image's
//! center lines) the frustum bounds nothing on a mixed axis, and ranges of incoherent rays carry nearly every ray
//! into every node and leaf (diffuse rays over 1e5 spheres took 3.2× as long as single rays); they are traced as
//! one masked packet of 64 ([`super::packet`]), whose rays are each box-tested at every node.
//!
//! The stack, skip-on-pop and leaves are those of [`super::packet`]: a popped entry is taken by the rays of its
//! range whose closest hit lies beyond the entry's distance (here the frustum's bound), and at a leaf each of them
//! tests the blocks. Any-hit packets drop rays at their first hit.
//!
//! Counters count the work done: a `node_visit` and `box_tests(W)` for the frustum test at every node the packet
//! enters (once per packet, not per ray), `box_tests(W)` for every ray box-tested there, and a `prim_test` per real
//! sphere of a block for every ray at a leaf. Per ray, nodes visited are therefore the packet's shared walk.

use super::collapse::Tree;
use super::kernel::{Ops, Query};
use super::leaf::WidePrimitive;
use super::order::Order;
use super::packet::{Answer, CULL_SLACK, Enter, Entry, Masked, Packet, Visit, bits};
use super::ray::FrustumLanes;
use crate::counters::Counters;
use crate::geometry::Ray;

/// Rays of a tile packet: an 8×8 tile.
pub const TILE_RAYS: usize = 64;

/// The rays from the lowest to the highest set bit of `first` and `last` (`first`'s lowest bit at or below
/// `last`'s highest).
#[inline(always)]
fn range(first: u64, last: u64) -> u64 {
    let (lo, hi) = (first.trailing_zeros(), 63 - last.leading_zeros());
    (u64::MAX >> (63 - hi)) & (u64::MAX << lo)
}

/// The largest `t_max` of the packet's rays, widened as the per-ray tests widen theirs.
#[inline(always)]
fn farthest(t_max: &[f32; TILE_RAYS]) -> f32 {
    t_max.iter().fold(f32::NEG_INFINITY, |m, &t| if t > m { t } else { m }) * CULL_SLACK
}

/// Enters a node with the frustum, then ranges the active rays over the children it keeps (see the module docs).
struct Ranged<'a> {
    frustum: &'a FrustumLanes,
    /// [`farthest`] of the packet's rays.
    t_far: f32,
}

impl<'a> Ranged<'a> {
    #[inline(always)]
    fn new(frustum: &'a FrustumLanes, t_max: &[f32; TILE_RAYS]) -> Self {
        Self { frustum, t_far: farthest(t_max) }
    }
}

impl Enter<TILE_RAYS> for Ranged<'_> {
    /// Tests the node's children with the frustum, then ranges the `active` rays over the children it keeps, and
    /// pushes every child some ray enters, nearest on top.
    #[inline(always)]
    unsafe fn enter<K: Ops, C: Counters, const W: usize>(&self, at: Visit<'_, W, TILE_RAYS>, counters: &mut C) {
        let Visit { node, active, packet, stack } = at;
        counters.node_visit();
        counters.box_tests(W as u32);
        let mut entry = [0.0f32; W];
        // SAFETY: forwarded from the caller.
        let kept = unsafe { K::frustum_boxes(node, self.frustum, self.t_far, &mut entry) };
        if kept == 0 {
            return;
        }
        let mut dist = [0.0f32; W];
        // Not a closure: closures do not inherit the kernel's target features, and the tests would not inline.
        macro_rules! test {
            ($i:expr) => {{
                counters.box_tests(W as u32);
                // SAFETY: forwarded from the caller.
                unsafe { K::boxes(node, &packet.lanes[$i], packet.t_max[$i] * CULL_SLACK, &mut dist) }
            }};
        }
        // First rays, in order: `first[lane]` gets the ray's bit.
        let (mut first, mut last) = ([0u64; W], [0u64; W]);
        let mut unfound = kept;
        for i in bits(active) {
            let hits = test!(i) & unfound;
            for lane in bits(hits as u64) {
                first[lane] = 1 << i;
            }
            unfound &= !hits;
            if unfound == 0 {
                break;
            }
        }
        let entered = kept & !unfound;
        // Last rays, in reverse order.
        let mut unfound = entered;
        let mut rest = active;
        while unfound != 0 && rest != 0 {
            let i = 63 - rest.leading_zeros() as usize;
            rest &= !(1 << i);
            let hits = test!(i) & unfound;
            for lane in bits(hits as u64) {
                last[lane] = 1 << i;
            }
            unfound &= !hits;
        }
        let base = stack.len;
        for lane in bits(entered as u64) {
            let rays = active & range(first[lane], last[lane]);
            stack.insert_sorted(base, Entry { child: node.children[lane], rays, t: entry[lane] });
        }
    }

    #[inline(always)]
    fn nearer(&mut self, t_max: &[f32; TILE_RAYS]) {
        self.t_far = farthest(t_max);
    }
}

/// A batch in tile packets of [`TILE_RAYS`] consecutive rays, one `ray` count per ray: nearest hits into
/// `out: &mut [Hit]` or occlusion into `out: &mut [bool]`.
pub struct Tiles<'a, C, A> {
    /// The rays.
    pub rays: &'a [Ray],
    /// One answer per ray.
    pub out: &'a mut [A],
    /// Where their work is counted.
    pub counters: &'a mut C,
}

/// One packet's traversal: frustum-culled and ranged (`RANGED`), or masked ([`super::packet`]).
///
/// Each is run through [`Ops::run_apart`], in a function of its own: compiled into one function, the two
/// traversals made the ranged one 1.4–1.7× slower on primary rays (1e5 and 1e3 spheres), though it is the one
/// that runs for nearly every tile.
struct OnePacket<'a, C, A, const RANGED: bool> {
    packet: &'a mut Packet<TILE_RAYS>,
    frustum: &'a FrustumLanes,
    out: &'a mut [A],
    counters: &'a mut C,
}

impl<C: Counters, A: Answer, const RANGED: bool> Query for OnePacket<'_, C, A, RANGED> {
    type Out = ();
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) {
        let (packet, out, counters) = (self.packet, self.out, self.counters);
        // SAFETY (both): forwarded from the caller.
        if RANGED {
            let ranged = Ranged::new(self.frustum, &packet.t_max);
            unsafe { A::traverse::<K, C, _, Prim, W, B, TILE_RAYS>(tree, packet, ranged, out, counters) }
        } else {
            unsafe { A::traverse::<K, C, _, Prim, W, B, TILE_RAYS>(tree, packet, Masked, out, counters) }
        }
    }
}

impl<C: Counters, A: Answer> Query for Tiles<'_, C, A> {
    type Out = ();
    #[inline(always)]
    unsafe fn run<K: Ops, O: Order, Prim: WidePrimitive, const W: usize, const B: usize>(
        self,
        tree: &Tree<W, B, Prim>,
    ) {
        let packet = &mut Packet::empty();
        for (rays, out) in self.rays.chunks(TILE_RAYS).zip(self.out.chunks_mut(TILE_RAYS)) {
            (0..rays.len()).for_each(|_| self.counters.ray());
            packet.load::<Prim>(rays);
            let frustum = &FrustumLanes::new(&packet.lanes[..rays.len()]);
            let counters = &mut *self.counters;
            // SAFETY (both): forwarded from the caller.
            if frustum.is_one_octant() {
                unsafe {
                    K::run_apart::<_, O, Prim, W, B>(OnePacket::<C, A, true> { packet, frustum, out, counters }, tree)
                }
            } else {
                unsafe {
                    K::run_apart::<_, O, Prim, W, B>(OnePacket::<C, A, false> { packet, frustum, out, counters }, tree)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::wide::kernel::scalar::Scalar;
    use crate::accel::wide::node::{ChildRef, WideNode};
    use crate::accel::wide::ray::RayLanes;
    use crate::geometry::Aabb;
    use crate::rng::SplitMix64;
    use glam::Vec3;

    /// Random packets (a shared origin and a cone of directions, or scattered origins and directions) against random
    /// nodes: a child some ray enters is kept by the frustum, with a bound at or below that ray's entry; every kernel
    /// this CPU has gives the scalar kernel's bits and bounds.
    #[test]
    fn the_frustum_keeps_every_child_a_ray_enters_and_bounds_its_entry() {
        let mut rng = SplitMix64::new(11);
        let mut u = |lo: f32, hi: f32| rng.range(lo as f64, hi as f64) as f32;
        let (mut kept, mut culled) = (0, 0);
        for case in 0..3000 {
            let spread = [0.0, 0.05, 1.0][case % 3];
            let origin = Vec3::new(u(-2.0, 2.0), u(-2.0, 2.0), u(-2.0, 2.0));
            let axis = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)).normalize_or(Vec3::Z);
            let n = 1 + case % TILE_RAYS;
            let rays: Vec<RayLanes> = (0..n)
                .map(|_| {
                    let o = origin + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)) * spread * 4.0;
                    let d = (axis + Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)) * spread).normalize_or(axis);
                    RayLanes::new(&Ray::new(o, d))
                })
                .collect();
            let children: Vec<(ChildRef, Aabb)> = (0..1 + case % 8)
                .map(|i| {
                    let c = Vec3::new(u(-10.0, 10.0), u(-10.0, 10.0), u(-10.0, 10.0));
                    let h = Vec3::new(u(0.0, 2.0), u(0.0, 2.0), u(0.0, 2.0));
                    (ChildRef::node(i as u32), Aabb { min: c - h, max: c + h })
                })
                .collect();
            let node = WideNode::<8>::new(&children);
            let t_max = [f32::INFINITY, 8.0][case % 2];
            let frustum = FrustumLanes::new(&rays);
            let mut bound = [0.0f32; 8];
            // SAFETY: the scalar kernel needs no optional instructions.
            let mask = unsafe { Scalar::frustum_boxes(&node, &frustum, t_max, &mut bound) };
            assert_eq!(mask >> children.len(), 0, "empty lanes are never kept");
            let mut entered = 0;
            for r in &rays {
                let mut dist = [0.0f32; 8];
                // SAFETY: as above.
                let hits = unsafe { Scalar::boxes(&node, r, t_max, &mut dist) };
                for lane in bits(hits as u64) {
                    assert!(mask >> lane & 1 == 1, "case {case}: lane {lane} entered by a ray but culled");
                    assert!(bound[lane] <= dist[lane], "case {case}: bound {} above entry {}", bound[lane], dist[lane]);
                }
                entered |= hits;
            }
            kept += (mask & entered).count_ones();
            culled += (!mask & ((1 << children.len()) - 1)).count_ones();
            #[cfg(target_arch = "x86_64")]
            if crate::accel::wide::Kernel::Avx2.is_available() {
                let mut simd = [0.0f32; 8];
                // SAFETY: AVX2 and FMA are available.
                let simd_mask = unsafe { avx2_frustum(&node, &frustum, t_max, &mut simd) };
                assert_eq!(simd_mask, mask, "case {case}");
                for lane in bits(mask as u64) {
                    assert_eq!(simd[lane].to_bits(), bound[lane].to_bits(), "case {case} lane {lane}");
                }
            }
        }
        assert!(kept > 500 && culled > 1000, "the cases exercise both outcomes: {kept} kept, {culled} culled");
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn avx2_frustum(node: &WideNode<8>, f: &FrustumLanes, t_max: f32, dist: &mut [f32; 8]) -> u32 {
        // SAFETY: forwarded from the caller.
        unsafe { crate::accel::wide::kernel::avx2::Avx2::frustum_boxes(node, f, t_max, dist) }
    }

    #[test]
    fn range_spans_first_to_last() {
        assert_eq!(range(1 << 3, 1 << 3), 1 << 3);
        assert_eq!(range(1 << 2, 1 << 5), 0b111100);
        assert_eq!(range(1, 1 << 63), u64::MAX);
    }
}
