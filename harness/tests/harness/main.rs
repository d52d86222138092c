//! The harness's integration tests, one module a file, in one test binary (one link instead of four; docs/build.md).

mod cli;
mod common;
mod count;
mod reproduce;
mod site_browser;
mod slurm;
