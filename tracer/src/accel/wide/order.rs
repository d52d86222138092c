//! Child orders: which of a node's hit children is visited first (the others wait on the stack).

use super::node::WideNode;
use super::stack::Stack;

/// Pushes a node's hit children so that the one to visit first is on top (and the last one deepest).
pub trait Order {
    /// Pushes the children in `hits` (a lane mask, two or more bits) with their entry distances `dist`.
    fn push<const W: usize>(node: &WideNode<W>, hits: u32, dist: &[f32; W], octant: usize, stack: &mut Stack);
}

/// Stored order: lane 0 first.
pub struct Stored;

/// Nearest entry distance first (ties in stored order).
pub struct Nearest;

/// The node's precomputed order for the ray's direction octant.
pub struct ByOctant;

impl Order for Stored {
    #[inline(always)]
    fn push<const W: usize>(node: &WideNode<W>, mut hits: u32, dist: &[f32; W], _: usize, stack: &mut Stack) {
        while hits != 0 {
            let lane = 31 - hits.leading_zeros() as usize;
            hits &= !(1 << lane);
            stack.push(node.children[lane], dist[lane]);
        }
    }
}

impl Order for Nearest {
    #[inline(always)]
    fn push<const W: usize>(node: &WideNode<W>, mut hits: u32, dist: &[f32; W], _: usize, stack: &mut Stack) {
        // Insertion into the top of the stack, farthest deepest; at most W - 1 moves per child.
        let base = stack.len();
        while hits != 0 {
            let lane = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            stack.insert_sorted(base, node.children[lane], dist[lane]);
        }
    }
}

impl Order for ByOctant {
    #[inline(always)]
    fn push<const W: usize>(node: &WideNode<W>, hits: u32, dist: &[f32; W], octant: usize, stack: &mut Stack) {
        let order = node.octant_order(octant);
        for i in (0..W).rev() {
            let lane = (order >> (4 * i) & 0xf) as usize;
            if hits >> lane & 1 != 0 {
                stack.push(node.children[lane], dist[lane]);
            }
        }
    }
}
