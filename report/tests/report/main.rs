//! The report's integration tests, one module a file, in one test binary (one link of polars instead of three;
//! docs/build.md).

mod check;
mod common;
mod golden;
mod history;
