//! The tracer's integration tests, one module a file, in one test binary: the tests instantiate the same generic
//! traversals (every tree, kernel and primitive), which a binary per file compiled and optimized a dozen times
//! over (docs/build.md).

mod affinity;
mod agreement;
mod build_pinned;
mod counters;
mod degenerate;
mod determinism;
mod parallel_build;
mod rays;
mod reinsertion;
mod sah_costs;
mod spatial;
mod triangles;
mod wide;
