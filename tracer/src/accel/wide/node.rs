//! A wide node: the boxes of up to `W` children stored per axis (SoA), their references and octant orders.

use glam::Vec3;

use crate::geometry::Aabb;

/// A reference to a wide node's child: an interior node, a leaf (a run of leaf blocks) or nothing.
///
/// Bit 31 clear: index of an interior node. Bit 31 set: a leaf, first block in bits 5..31, block count in
/// bits 0..5. All ones: no child.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(transparent)]
pub struct ChildRef(pub u32);

impl ChildRef {
    /// The root node (index 0).
    pub const ROOT: ChildRef = ChildRef(0);
    /// No child (padding lanes of a node with fewer than `W` children).
    pub const EMPTY: ChildRef = ChildRef(u32::MAX);
    const LEAF: u32 = 1 << 31;
    const COUNT_BITS: u32 = 5;
    /// Most blocks one leaf may hold.
    pub const MAX_BLOCKS: u32 = (1 << Self::COUNT_BITS) - 1;
    /// Most blocks a tree may hold (first-block indices stop below it).
    pub const MAX_FIRST_BLOCK: u32 = (1 << (31 - Self::COUNT_BITS)) - 1;

    /// The interior node at `index`.
    pub fn node(index: u32) -> Self {
        assert!(index < Self::LEAF, "too many wide nodes");
        ChildRef(index)
    }

    /// The leaf of blocks `first..first + count`.
    pub fn leaf(first: u32, count: u32) -> Self {
        assert!(first < Self::MAX_FIRST_BLOCK && (1..=Self::MAX_BLOCKS).contains(&count), "leaf out of range");
        ChildRef(Self::LEAF | first << Self::COUNT_BITS | count)
    }

    /// True for leaves (not for [`ChildRef::EMPTY`]).
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.0 & Self::LEAF != 0 && self != Self::EMPTY
    }

    /// True for interior nodes.
    #[inline(always)]
    pub fn is_node(self) -> bool {
        self.0 & Self::LEAF == 0
    }

    /// Index of an interior node.
    #[inline(always)]
    pub fn index(self) -> usize {
        self.0 as usize
    }

    /// Blocks `first..end` of a leaf.
    #[inline(always)]
    pub fn blocks(self) -> std::ops::Range<usize> {
        let first = ((self.0 & !Self::LEAF) >> Self::COUNT_BITS) as usize;
        first..first + (self.0 & Self::MAX_BLOCKS) as usize
    }

    /// The same child in a tree whose nodes start `nodes` and blocks `blocks` further on (empty stays empty).
    #[inline(always)]
    pub fn shifted(self, nodes: u32, blocks: u32) -> Self {
        if self.is_node() {
            Self::node(self.0 + nodes)
        } else if self.is_leaf() {
            let range = self.blocks();
            Self::leaf(range.start as u32 + blocks, range.len() as u32)
        } else {
            self
        }
    }
}

/// Rows of [`WideNode::bounds`]: `2 * axis` holds the children's minima on `axis`, `2 * axis + 1` their maxima.
pub const ROWS: usize = 6;

/// A node of `W` children: their boxes as six rows of `W` lanes, their references, and per ray-direction octant
/// the order to visit them in. 128 bytes for `W = 4`, 256 for `W = 8`: whole cache lines.
///
/// Children fill lanes from 0 in the binary tree's left-to-right order; unused lanes hold [`ChildRef::EMPTY`] and
/// the inverted empty box (`min = +inf`, `max = -inf`), which no slab test enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct WideNode<const W: usize> {
    /// Child boxes per axis: min x, max x, min y, max y, min z, max z.
    pub bounds: [[f32; W]; ROWS],
    /// Child references, lane by lane.
    pub children: [ChildRef; W],
    /// Visiting order per octant: `4 * W` bits per octant (octant `o` at bit `o * 4 * W`), lane `i`-th in that
    /// order in nibble `i`. The octant's bit `a` is set when the ray's direction is negative on axis `a`.
    pub octant_orders: [u32; W],
}

const _: () = assert!(std::mem::size_of::<WideNode<4>>() == 128 && std::mem::size_of::<WideNode<8>>() == 256);

impl<const W: usize> WideNode<W> {
    /// A node without children.
    pub const EMPTY: Self = Self {
        bounds: [
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
        ],
        children: [ChildRef::EMPTY; W],
        octant_orders: [0; W],
    };

    /// A node of `children` (at most `W`) with their boxes, octant orders precomputed.
    pub fn new(children: &[(ChildRef, Aabb)]) -> Self {
        assert!(children.len() <= W && W <= 8, "a wide node holds at most W <= 8 children");
        let mut node = Self::EMPTY;
        for (lane, (child, b)) in children.iter().enumerate() {
            node.children[lane] = *child;
            for axis in 0..3 {
                node.bounds[2 * axis][lane] = b.min[axis];
                node.bounds[2 * axis + 1][lane] = b.max[axis];
            }
        }
        let centers: [Vec3; W] = std::array::from_fn(|lane| children.get(lane).map_or(Vec3::ZERO, |(_, b)| b.center()));
        for octant in 0..8 {
            // Sort lanes by box center along the octant's diagonal; empty lanes last; ties in stored order.
            let sign = |axis: usize| if octant >> axis & 1 == 1 { -1.0 } else { 1.0 };
            let keys: [(u8, f32); W] = std::array::from_fn(|lane| match lane < children.len() {
                true => (0, (0..3).map(|a| centers[lane][a] * sign(a)).sum::<f32>()),
                false => (1, 0.0),
            });
            let mut lanes: [usize; W] = std::array::from_fn(|lane| lane);
            lanes.sort_unstable_by(|&x, &y| {
                let (kx, ky) = (keys[x], keys[y]);
                kx.0.cmp(&ky.0).then(kx.1.total_cmp(&ky.1)).then(x.cmp(&y))
            });
            for (i, lane) in lanes.into_iter().enumerate() {
                let bit = octant * 4 * W + 4 * i;
                node.octant_orders[bit / 32] |= (lane as u32) << (bit % 32);
            }
        }
        node
    }

    /// Lanes in the order rays of `octant` visit them, one per nibble from the lowest.
    #[inline(always)]
    pub fn octant_order(&self, octant: usize) -> u32 {
        let bit = octant * 4 * W;
        let word = self.octant_orders[bit / 32] >> (bit % 32);
        if W >= 8 { word } else { word & ((1 << (4 * W)) - 1) }
    }

    /// Number of children (lanes in use; they come first).
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.children.iter().take_while(|c| **c != ChildRef::EMPTY).count()
    }

    /// True for a node without children (only the root of an empty tree).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The box of the child in `lane`.
    pub fn child_bounds(&self, lane: usize) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: glam::Vec3::new(b[0][lane], b[2][lane], b[4][lane]),
            max: glam::Vec3::new(b[1][lane], b[3][lane], b[5][lane]),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn references_round_trip() {
        let leaf = ChildRef::leaf(1234, 3);
        assert!(leaf.is_leaf() && !leaf.is_node());
        assert_eq!(leaf.blocks(), 1234..1237);
        let node = ChildRef::node(77);
        assert!(node.is_node() && !node.is_leaf());
        assert_eq!(node.index(), 77);
        assert!(!ChildRef::EMPTY.is_leaf() && !ChildRef::EMPTY.is_node());
        assert_eq!((leaf.shifted(5, 100), node.shifted(5, 100)), (ChildRef::leaf(1334, 3), ChildRef::node(82)));
        assert_eq!(ChildRef::EMPTY.shifted(5, 100), ChildRef::EMPTY);
    }

    #[test]
    fn octant_orders_sort_children_along_the_diagonal() {
        let unit = |x: f32| Aabb { min: Vec3::new(x, 0.0, 0.0), max: Vec3::new(x + 1.0, 1.0, 1.0) };
        let children =
            [(ChildRef::node(1), unit(5.0)), (ChildRef::node(2), unit(-5.0)), (ChildRef::node(3), unit(0.0))];
        let node = WideNode::<4>::new(&children);
        assert_eq!(node.len(), 3);
        assert_eq!(node.child_bounds(1), unit(-5.0));
        let lanes = |o| (0..4).map(|i| node.octant_order(o) >> (4 * i) & 0xf).collect::<Vec<_>>();
        assert_eq!(lanes(0), [1, 2, 0, 3], "+x rays meet the -5 box first; the empty lane last");
        assert_eq!(lanes(1), [0, 2, 1, 3], "-x rays meet the +5 box first");
        let wide = WideNode::<8>::new(&children);
        assert_eq!(wide.octant_order(7) & 0xfff, 0x120);
    }
}
