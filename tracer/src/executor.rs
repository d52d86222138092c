//! Parallel strategies for filling an image row by row; the only place that knows about threads.
//!
//! - `serial`: rows in order on the calling thread.
//! - `rayon-bands` (the paper's main method): the image cut into [`RAYON_BANDS_PER_THREAD`] × threads
//!   horizontal bands of equal height to within one row ([`band_rows`]), work-stolen by the rayon pool the call runs in when that pool has exactly `threads`
//!   threads (a caller that times runs starts it once, outside its timers), else by a pool built for this
//!   call (never the global pool).
//! - `mpsc-threads` (the paper's second method): one scoped std thread per band, one band per thread
//!   (a static split); each renders into its own buffer and sends it through an mpsc channel to the
//!   calling thread, which copies it into place.
//!
//! With two threads or more, each worker is pinned to a CPU of its own ([`crate::pinning`]): the band threads and
//! the pool built for a call alike (a caller's own pool pins its threads itself).
//!
//! Every strategy computes each row with the same function, so images are bit-identical across them.

use std::fmt;
use std::sync::mpsc;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::counters::Counters;
use crate::pinning;

/// Bands per thread for `rayon-bands`: more bands than threads lets stealing even out uneven rows.
pub const RAYON_BANDS_PER_THREAD: usize = 4;

/// The rows `[start, end)` of band `band` when `height` rows are cut into `bands` bands: the same share of the image
/// for every height, each band's height within one row of the others (`bands` at least 1).
///
/// So an image sampled a few percent more densely adds its rows to every band alike, and the threads' loads keep
/// their balance. Cutting into bands of `height.div_ceil(bands)` rows instead left the shortfall in the last band and
/// moved every boundary: 388 rows in 8 bands gave 49-row bands and a 45-row last one.
pub fn band_rows(band: usize, bands: usize, height: usize) -> std::ops::Range<usize> {
    let bands = bands.max(1);
    band * height / bands..(band + 1) * height / bands
}

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
                let mut bands = || {
                    // One entry per band, each a disjoint run of rows (allocated once per call, not per row).
                    let mut rest = &mut out[..];
                    let mut slices = Vec::with_capacity(bands);
                    for b in 0..bands {
                        let rows = band_rows(b, bands, height);
                        let (these, after) = std::mem::take(&mut rest).split_at_mut(rows.len() * width);
                        slices.push((rows.start, these));
                        rest = after;
                    }
                    slices.into_par_iter().map(|(first_row, rows)| band(first_row, rows)).reduce(
                        C::default,
                        |mut a, b| {
                            a.merge(b);
                            a
                        },
                    )
                };
                if rayon::current_thread_index().is_some() && rayon::current_num_threads() == threads {
                    bands()
                } else {
                    let cpus = pinning::cpus_for(threads);
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .start_handler(move |i| pinning::pin_worker(&cpus, i))
                        .build()
                        .expect("building a rayon thread pool");
                    pool.install(bands)
                }
            }
            StrategyKind::MpscThreads => {
                let bands = threads.clamp(1, height.max(1));
                let (sender, receiver) = mpsc::channel::<(usize, Vec<T>, C)>();
                let band = &band;
                let cpus = &pinning::cpus_for(bands);
                std::thread::scope(|scope| {
                    for b in 0..bands {
                        let sender = sender.clone();
                        let rows = band_rows(b, bands, height);
                        let (first_row, rows) = (rows.start, rows.len());
                        scope.spawn(move || {
                            // Its own CPU, not the spawning thread's mask (which may be one pinned CPU).
                            pinning::pin_worker(cpus, b);
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

    #[test]
    fn bands_cover_every_row_once_and_differ_by_at_most_one_row() {
        for height in 0..200 {
            for bands in 1..=70 {
                let all: Vec<_> = (0..bands).map(|b| band_rows(b, bands, height)).collect();
                assert_eq!(all[0].start, 0);
                assert_eq!(all[bands - 1].end, height);
                assert!(all.windows(2).all(|w| w[0].end == w[1].start), "{height} rows, {bands} bands: {all:?}");
                let (low, high) = (height / bands, height.div_ceil(bands));
                assert!(all.iter().all(|r| (low..=high).contains(&r.len())), "{height} rows, {bands} bands: {all:?}");
            }
        }
        // 2% more rows add a row to some bands and move no boundary by more than one row.
        for b in 0..8 {
            assert!(band_rows(b, 8, 388).start.abs_diff(band_rows(b, 8, 384).start * 388 / 384) <= 1);
        }
    }

    #[test]
    fn every_strategy_fills_every_row_once_at_any_height() {
        for kind in StrategyKind::ALL {
            for threads in [1, 2, 3, 7] {
                for height in [0, 1, 5, 13, 64] {
                    let mut out = vec![0; 3 * height];
                    let calls: Vec<_> = (0..height).map(|_| std::sync::atomic::AtomicUsize::new(0)).collect();
                    let _: NoCounters = Strategy::new(kind, threads).run_rows(3, &mut out, |y, items, _| {
                        calls[y].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        items.fill(y + 1);
                    });
                    assert!(calls.iter().all(|c| c.load(std::sync::atomic::Ordering::Relaxed) == 1));
                    let want: Vec<_> = (0..height).flat_map(|y| [y + 1; 3]).collect();
                    assert_eq!(out, want, "{kind:?}×{threads}, {height} rows");
                }
            }
        }
    }
}
