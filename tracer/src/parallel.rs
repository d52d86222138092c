//! The builders' data-parallel loops, over one rayon loop compiled once.
//!
//! Every builder is generic over its primitive and every collapse over its tree layout; a rayon iterator chain in
//! each would compile rayon's splitting, joining and collecting machinery again for every instantiation (it was a
//! quarter of the tracer's LLVM IR). Here the only rayon loop is [`for_each_index`], over a `dyn` task; the
//! generic helpers hand each task its own item and slot, so they add no rayon code. A task is a chunk of work (a
//! chunk of primitives, a subtree), so the one indirect call per task costs nothing measurable.

use std::mem::MaybeUninit;
use std::sync::Mutex;

use rayon::prelude::*;

/// Runs `task(i)` for every `i` in `0..n` in the current rayon pool (outside one: rayon's global pool).
pub fn for_each_index(n: usize, task: &(dyn Fn(usize) + Sync)) {
    (0..n).into_par_iter().for_each(task);
}

/// `f` of every item, in the items' order, one task per item.
pub fn map<I: Send, T: Send>(items: Vec<I>, f: impl Fn(I) -> T + Sync) -> Vec<T> {
    // Each slot is locked once, by the one task that owns it: the item goes in, its result comes out.
    let slots: Vec<Mutex<(Option<I>, Option<T>)>> = items.into_iter().map(|i| Mutex::new((Some(i), None))).collect();
    for_each_index(slots.len(), &|i| {
        let mut slot = slots[i].lock().unwrap_or_else(|e| e.into_inner());
        let item = slot.0.take().expect("each slot is taken once");
        slot.1 = Some(f(item));
    });
    slots.into_iter().map(|s| s.into_inner().unwrap_or_else(|e| e.into_inner()).1.expect("every task ran")).collect()
}

/// `f(i)` for every `i` in `0..n`, in order, computed in chunks of `chunk` indices.
pub fn map_indices<T: Send>(n: usize, chunk: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let mut out = Vec::with_capacity(n);
    let tasks: Vec<(usize, &mut [MaybeUninit<T>])> =
        out.spare_capacity_mut()[..n].chunks_mut(chunk).enumerate().map(|(c, o)| (c * chunk, o)).collect();
    map(tasks, |(start, output)| {
        for (i, o) in output.iter_mut().enumerate() {
            o.write(f(start + i));
        }
    });
    // SAFETY: the chunks cover `0..n`, and every task wrote each element of its chunk (a panicking task propagates
    // its panic out of `map` before this line).
    unsafe { out.set_len(n) };
    out
}

/// `n` copies of `value`, written in parallel in chunks of `chunk`.
pub fn filled<T: Clone + Send + Sync>(value: &T, n: usize, chunk: usize) -> Vec<T> {
    let mut out = Vec::with_capacity(n);
    map(out.spare_capacity_mut()[..n].chunks_mut(chunk).collect(), |c: &mut [MaybeUninit<T>]| {
        for o in c {
            o.write(value.clone());
        }
    });
    // SAFETY: as in `map_indices`: the chunks cover `0..n`, each element written.
    unsafe { out.set_len(n) };
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_keeps_order_and_runs_every_item() {
        let out = map((0..1000u64).collect(), |i| i * i);
        assert_eq!(out, (0..1000u64).map(|i| i * i).collect::<Vec<_>>());
    }

    #[test]
    fn map_indices_is_the_serial_map_for_any_chunk() {
        for chunk in [1, 7, 1024, 5000] {
            let out = map_indices(1037, chunk, |i| i as u64 * 3 + 1);
            assert_eq!(out, (0..1037).map(|i| i as u64 * 3 + 1).collect::<Vec<_>>(), "chunk {chunk}");
        }
        assert!(map_indices(0, 4, |i| i).is_empty());
    }

    #[test]
    fn filled_is_vec_from_elem() {
        for (n, chunk) in [(0, 3), (1, 3), (1000, 64), (17, 100)] {
            assert_eq!(filled(&String::from("pad"), n, chunk), vec![String::from("pad"); n]);
        }
    }
}
