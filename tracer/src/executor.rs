//! Parallel strategies for filling an image row by row; the only place that knows about threads.
//!
//! - `serial`: rows in order on the calling thread.
//! - `rayon-bands` (the paper's main method): the image cut into [`RAYON_BANDS_PER_THREAD`] × threads
//!   horizontal bands, work-stolen by the rayon pool the call runs in when that pool has exactly `threads`
//!   threads (a caller that times runs starts it once, outside its timers), else by a pool built for this
//!   call (never the global pool).
//! - `mpsc-threads` (the paper's second method): one scoped std thread per band, one band per thread
//!   (a static split); each renders into its own buffer and sends it through an mpsc channel to the
//!   calling thread, which copies it into place.
//!
//! Every strategy computes each row with the same function, so images are bit-identical across them.

use std::fmt;
use std::sync::mpsc;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::counters::Counters;

/// Bands per thread for `rayon-bands`: more bands than threads lets stealing even out uneven rows.
pub const RAYON_BANDS_PER_THREAD: usize = 4;

/// How rows are spread over threads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StrategyKind {
    /// One thread, rows in order.
    Serial,
    /// Rayon work stealing over horizontal bands.
    RayonBands,
    /// One std thread per band, results through an mpsc channel.
    MpscThreads,
}

impl StrategyKind {
    /// Every strategy, in the order tools list them.
    pub const ALL: [StrategyKind; 3] = [StrategyKind::Serial, StrategyKind::RayonBands, StrategyKind::MpscThreads];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Serial => "serial",
            StrategyKind::RayonBands => "rayon-bands",
            StrategyKind::MpscThreads => "mpsc-threads",
        }
    }
}

/// A strategy and its thread count (ignored by `serial`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Strategy {
    /// The strategy.
    pub kind: StrategyKind,
    /// Worker threads, at least 1.
    pub threads: usize,
}

impl fmt::Display for Strategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            StrategyKind::Serial => write!(f, "serial"),
            k => write!(f, "{}×{}", k.name(), self.threads),
        }
    }
}

impl Strategy {
    /// Rows in order on the calling thread.
    pub const SERIAL: Strategy = Strategy { kind: StrategyKind::Serial, threads: 1 };

    /// `kind` with `threads` workers.
    pub fn new(kind: StrategyKind, threads: usize) -> Self {
        Self { kind, threads }
    }

    /// Fills `out` (rows of `width` items) by calling `row(y, row_items, counters)` for every row, and
    /// returns the counters of all rows merged.
    ///
    /// `row` is monomorphized for its accelerator and counters (its loop over the row's rays has no dynamic
    /// dispatch); the threading around it is compiled once per item and counter type and calls `row` once per row
    /// through a reference to it (one indirect call per row of rays). Compiled once per closure instead, the
    /// thread pools, scopes and channels were a third of the harness's compile.
    #[inline]
    pub fn run_rows<T, C, F>(&self, width: usize, out: &mut [T], row: F) -> C
    where
        T: Copy + Default + Send,
        C: Counters,
        F: Fn(usize, &mut [T], &mut C) + Sync,
    {
        self.run_rows_with(width, out, &row)
    }

    /// [`Strategy::run_rows`] with the row function behind a reference.
    #[inline(never)]
    fn run_rows_with<T, C>(&self, width: usize, out: &mut [T], row: &(dyn Fn(usize, &mut [T], &mut C) + Sync)) -> C
    where
        T: Copy + Default + Send,
        C: Counters,
    {
        let width = width.max(1);
        let height = out.len() / width;
        let threads = self.threads.max(1);
        let band = |first_row: usize, rows: &mut [T]| {
            let mut counters = C::default();
            for (i, items) in rows.chunks_mut(width).enumerate() {
                row(first_row + i, items, &mut counters);
            }
            counters
        };
        match self.kind {
            StrategyKind::Serial => band(0, out),
            StrategyKind::RayonBands => {
                let bands = (threads * RAYON_BANDS_PER_THREAD).clamp(1, height.max(1));
                let rows_per_band = height.div_ceil(bands).max(1);
                let mut bands = || {
                    out.par_chunks_mut(rows_per_band * width)
                        .enumerate()
                        .map(|(b, rows)| band(b * rows_per_band, rows))
                        .reduce(C::default, |mut a, b| {
                            a.merge(b);
                            a
                        })
                };
                if rayon::current_thread_index().is_some() && rayon::current_num_threads() == threads {
                    bands()
                } else {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .expect("building a rayon thread pool");
                    pool.install(bands)
                }
            }
            StrategyKind::MpscThreads => {
                let rows_per_band = height.div_ceil(threads).max(1);
                let (sender, receiver) = mpsc::channel::<(usize, Vec<T>, C)>();
                let band = &band;
                std::thread::scope(|scope| {
                    for first_row in (0..height).step_by(rows_per_band) {
                        let sender = sender.clone();
                        let rows = rows_per_band.min(height - first_row);
                        scope.spawn(move || {
                            let mut buffer = vec![T::default(); rows * width];
                            let counters = band(first_row, &mut buffer);
                            sender.send((first_row, buffer, counters)).expect("the receiver outlives the band threads");
                        });
                    }
                    drop(sender);
                    let mut total = C::default();
                    for (first_row, buffer, counters) in receiver {
                        out[first_row * width..first_row * width + buffer.len()].copy_from_slice(&buffer);
                        total.merge(counters);
                    }
                    total
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::counters::NoCounters;

    /// The names of the threads that ran each row of a 16-row image under `strategy`.
    fn row_threads(strategy: Strategy) -> Vec<String> {
        let mut out = vec![0u8; 16];
        let names = std::sync::Mutex::new(Vec::new());
        let _: NoCounters = strategy.run_rows(1, &mut out, |_, _, _| {
            names.lock().unwrap().push(std::thread::current().name().unwrap_or("").to_string());
        });
        names.into_inner().unwrap()
    }

    #[test]
    fn rayon_bands_run_in_the_callers_pool_when_it_has_the_threads() {
        let pool =
            |n| rayon::ThreadPoolBuilder::new().num_threads(n).thread_name(|i| format!("setup-{i}")).build().unwrap();
        let strategy = Strategy::new(StrategyKind::RayonBands, 2);
        let inside = pool(2).install(|| row_threads(strategy));
        assert!(inside.iter().all(|n| n.starts_with("setup-")), "{inside:?}");
        let other_size = pool(3).install(|| row_threads(strategy));
        assert!(other_size.iter().all(|n| !n.starts_with("setup-")), "{other_size:?}");
        assert!(row_threads(strategy).iter().all(|n| !n.starts_with("setup-")));
    }
}
