//! Child orders: which of a node's hit children is visited first (the others wait on the stack).

use super::node::{ChildRef, WideNode};
use super::params::ChildOrdering;
use super::traverse::Stack;

impl ChildOrdering {
    /// Pushes the children in `hits` (a lane mask, two or more bits) with their entry distances `dist`, so that the
    /// one to visit first is on top (and the last one deepest).
    ///
    /// The ordering is a value, not a type: a branch per node of two or more hit children, always taken the same
    /// way in a traversal, instead of every traversal compiled once per ordering.
    #[inline(always)]
    pub fn push<const W: usize>(
        self,
        node: &WideNode<W>,
        hits: u32,
        dist: &[f32; W],
        octant: usize,
        stack: &mut Stack,
    ) {
        match self {
            ChildOrdering::None => stored(node, hits, dist, stack),
            ChildOrdering::Distance => nearest(node, hits, dist, stack),
            ChildOrdering::Octant => by_octant(node, hits, dist, octant, stack),
        }
    }
}

/// Stored order: lane 0 first.
#[inline(always)]
fn stored<const W: usize>(node: &WideNode<W>, mut hits: u32, dist: &[f32; W], stack: &mut Stack) {
    while hits != 0 {
        let lane = 31 - hits.leading_zeros() as usize;
        hits &= !(1 << lane);
        stack.push(node.children[lane], dist[lane]);
    }
}

/// Nearest entry distance first (ties in stored order).
#[inline(always)]
fn nearest<const W: usize>(node: &WideNode<W>, mut hits: u32, dist: &[f32; W], stack: &mut Stack) {
    // Insertion into the top of the stack, farthest deepest; at most W - 1 moves per child.
    let base = stack.len();
    while hits != 0 {
        let lane = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        stack.insert_sorted(base, node.children[lane], dist[lane]);
    }
}

/// The node's precomputed order for the ray's direction octant.
#[inline(always)]
fn by_octant<const W: usize>(node: &WideNode<W>, hits: u32, dist: &[f32; W], octant: usize, stack: &mut Stack) {
    let order = node.octant_order(octant);
    for i in (0..W).rev() {
        let lane = (order >> (4 * i) & 0xf) as usize;
        if hits >> lane & 1 != 0 {
            stack.push(node.children[lane], dist[lane]);
        }
    }
}

/// `ChildRef` is what the stack holds with each distance.
pub type Entry = (ChildRef, f32);
