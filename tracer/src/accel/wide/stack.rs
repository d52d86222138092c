//! The single-ray traversal stack: children waiting with their entry distances, pushed by the child orders
//! ([`super::order`]) and popped by the traversal ([`super::traverse`]), which both import it from here.

use std::mem::MaybeUninit;

use super::node::ChildRef;
use crate::accel::bvh::tree::MAX_DEPTH;

/// `ChildRef` is what the stack holds with each distance.
pub type Entry = (ChildRef, f32);

/// Stack entries: a tree is at most [`MAX_DEPTH`] wide levels deep (it has no more levels than the binary tree),
/// each level leaves at most 7 entries, and a node pushes at most 8 before one is popped.
const STACK: usize = MAX_DEPTH * 8;

/// The traversal stack: children waiting with their entry distances.
pub struct Stack {
    entries: [MaybeUninit<Entry>; STACK],
    len: usize,
}

impl Stack {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self { entries: [const { MaybeUninit::uninit() }; STACK], len: 0 }
    }

    /// Entries held.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no entry is held.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Pushes an entry on top.
    #[inline(always)]
    pub fn push(&mut self, child: ChildRef, t: f32) {
        debug_assert!(self.len < STACK);
        // SAFETY: see `STACK`: a traversal never holds more entries.
        unsafe { self.entries.get_unchecked_mut(self.len) }.write((child, t));
        self.len += 1;
    }

    /// Inserts an entry among those from `base` up, kept with the largest distance lowest (equal ones above it).
    #[inline(always)]
    pub fn insert_sorted(&mut self, base: usize, child: ChildRef, t: f32) {
        debug_assert!(self.len < STACK && base <= self.len);
        let mut i = self.len;
        // SAFETY: entries below `len` are written; `i < STACK` as in `push`.
        unsafe {
            while i > base && self.entries.get_unchecked(i - 1).assume_init_ref().1 <= t {
                let below = self.entries.get_unchecked(i - 1).assume_init_read();
                self.entries.get_unchecked_mut(i).write(below);
                i -= 1;
            }
            self.entries.get_unchecked_mut(i).write((child, t));
        }
        self.len += 1;
    }

    /// Pops the top entry.
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
