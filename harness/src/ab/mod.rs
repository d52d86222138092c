//! `harness ab`: the trustworthy comparison on a noisy machine. Builds another git revision, then times every
//! configuration with both builds in one job, interleaved (A B, then B A, round after round), each run in a
//! fresh `harness worker` process, and reports each configuration's time ratio old/new (above 1: the new build is
//! faster): the median of the per-round ratios with its 95% interval, by the statistic the reports and the CI gate
//! use for rounds ([`report::RoundRatios::estimate`]: every round is a pair of processes of its own, so it resamples rounds as the
//! processes they are). Both builds must give the same answers, run after run. A configuration the base revision
//! cannot run (a setting newer than it, or a request its worker refuses) is skipped and listed.
//!
//! The stages, in order:
//! 1. [`build`]: the new side is a copy of the running binary; the base revision's is built in a git worktree
//!    into the running binary's target folder and profile, or taken from its cache.
//! 2. [`compare`]: the configurations the base can run are timed with both builds, interleaved; a single-thread
//!    configuration flagged as slower is measured again; the table of ratios and verdicts is reported, and the
//!    comparison fails on answers that differ or change, or on a confirmed regression.

pub(crate) mod build;
mod compare;

use std::path::{Path, PathBuf};

use crate::config::Experiment;
use crate::error::Error;
use crate::plan::Plan;
use build::{Build, base_binary, copy_running, git};

/// What `harness ab` was asked.
pub struct AbRequest<'a> {
    pub base: &'a str,
    pub config: &'a Path,
    pub quick: bool,
    pub min_effect: f64,
    /// Report timings even where the two builds' answers differ (the table still says so).
    pub allow_different_answers: bool,
    /// Fail on a flagged configuration without measuring it again.
    pub no_confirm: bool,
}

/// Runs `harness ab`: builds the base revision, then compares it with the running binary (see
/// [`compare::run`]).
pub fn run(request: &AbRequest<'_>) -> Result<(), Error> {
    let exp = Experiment::load(request.config)?;
    let exp = if request.quick { exp.quick() } else { exp };
    let mut plan = Plan::new(&exp, crate::plan::available_threads())?;
    plan.skip_unavailable(&exp.path.display().to_string(), false)?;
    let root = PathBuf::from(git(Path::new("."), &["rev-parse", "--show-toplevel"])?);
    let rev = git(&root, &["rev-parse", "--verify", &format!("{}^{{commit}}", request.base)])?;
    let build = Build::running()?;
    let new_copy = copy_running(&build)?;
    let old_bin = base_binary(&root, &build, &rev)?;
    compare::run(request, &exp, &plan, &root, &rev, (&old_bin, &new_copy.0))
}
