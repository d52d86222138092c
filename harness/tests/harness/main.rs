//! The harness's integration tests, one module a file, in one test binary (one link instead of four; docs/build.md).

mod ab;
mod baseline;
mod common;
mod count;
mod history;
mod output;
mod render;
mod report;
mod reproduce;
mod run;
mod site_browser;
mod slurm;
mod validate;
