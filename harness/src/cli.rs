//! Command-line arguments.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// bvhlab's harness: run BVH experiments from TOML configs, report them, and render single images.
#[derive(Parser, Debug)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Put every backend's large blocks on transparent huge pages (glibc's malloc tunables), as Embree's allocator
    /// puts its own: measured on and off in docs/statistics.md, not the default (the `huge_pages` column).
    #[arg(long, global = true)]
    pub huge_pages: bool,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run an experiment config: plan the sweep, time every run, record rows, write summaries, figures and REPORT.md.
    Run(RunArgs),
    /// Rebuild summaries, figures and REPORT.md of a run folder from its recorded rows alone.
    Report(ReportArgs),
    /// Parse and plan a config without running it; print the number of runs and a time estimate.
    Validate(ValidateArgs),
    /// Render one image of a scene with one accelerator and strategy, and print timings and statistics.
    Render(RenderArgs),
    /// List scenes, accelerators and peer backends (with availability), splits, traversal orders and strategies.
    List,
    /// Compare a run with a stored baseline: exact work counters, instruction counts, and (from the same machine)
    /// every configuration's trace and build times, flagged ones measured again; speedups for information.
    Check(CheckArgs),
    /// Count the instructions of each single-thread configuration's build and trace under callgrind (valgrind),
    /// into instructions.csv of the run folder: the deterministic gate of `harness check`.
    Instructions(InstructionsArgs),
    /// Build another git revision and time both builds on a config, interleaved; report how much faster the new build is (old/new, above 1 = faster), and fail
    /// when the builds' answers differ.
    Ab(AbArgs),
    /// Download a mesh data set once (pinned package, checked SHA-256) into the cache, `$BVHLAB_DATA` or
    /// `~/.cache/bvhlab/meshes`; later runs read it offline.
    Fetch(FetchArgs),
    /// Manage stored baselines.
    #[command(subcommand)]
    Baseline(BaselineCommand),
    /// Run a sweep as a Slurm job array, one shard per task, and merge the shards when it ends.
    #[command(subcommand)]
    Slurm(SlurmCommand),
    /// Merge the shard folders of a run folder into its runs.csv and rebuild summaries, figures and REPORT.md.
    Merge(MergeArgs),
    /// Compare the rows of two runs.csv files (or run folders), in any order; exit 1 when they differ.
    RowsDiff(RowsDiffArgs),
    /// Re-run a committed result set from the commit its rows record (or with today's code), on this machine, into
    /// RESULT_SET/reproductions/, and say whether each claim, time ratio and deterministic column reproduces.
    Reproduce(ReproduceArgs),
    /// Track speedups over commits.
    #[command(subcommand)]
    History(HistoryCommand),
    /// Write a self-contained static site of results/ (index, a page per experiment, history pages) into --out.
    Site(SiteArgs),
    /// Internal: time the configuration of the JSON request on stdin in this fresh process and print its timing
    /// as JSON (used for Embree and `ab`).
    #[command(hide = true)]
    Worker,
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Experiment config (TOML).
    pub config: PathBuf,
    /// Output folder (default: results/<name>/, or results/<name>-quick/ with --quick).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Apply the config's [quick] overrides (a short version of the same experiment).
    #[arg(long)]
    pub quick: bool,
    /// Continue a killed sweep: skip runs already recorded in the output folder.
    #[arg(long)]
    pub resume: bool,
    /// Replace the rows already recorded in the output folder (by default they move aside into previous/).
    #[arg(long)]
    pub force: bool,
    /// Run only shard I of N (1-based), e.g. 2/4, into OUT/shard-I-of-N/, to spread a sweep over machines (whole
    /// scene cells per shard);
    /// `env` reads it from SLURM_ARRAY_TASK_ID/SLURM_ARRAY_TASK_COUNT, `env/N` from SLURM_ARRAY_TASK_ID or
    /// JOB_COMPLETION_INDEX (a Kubernetes indexed Job) with N shards.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<ShardArg>,
    /// Refuse to run unless the config's text has this hash (16 hex digits; job scripts pin the config they were
    /// submitted with).
    #[arg(long)]
    pub config_hash: Option<String>,
    /// Exit with code 1 when a claim of the config fails.
    #[arg(long)]
    pub check_claims: bool,
    /// Exit with code 2 when a backend the config names is unavailable (default: skip it and say so).
    #[arg(long)]
    pub require_all: bool,
}

#[derive(Args, Debug)]
pub struct FetchArgs {
    /// The data set (see `--list`).
    #[arg(required_unless_present = "list", conflicts_with = "list")]
    pub name: Option<String>,
    /// List the data sets: name, triangles, package, license.
    #[arg(long)]
    pub list: bool,
}

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// The run folder to check.
    pub run_dir: PathBuf,
    /// The baseline folder (e.g. results/baselines/ci).
    #[arg(long)]
    pub baseline: PathBuf,
    /// Smallest change of a trace time or speedup that counts as a regression or improvement (0.10 = 10%): a time
    /// regressed when the 95% interval of new/old lies above 1 + this.
    #[arg(long, default_value_t = 0.10)]
    pub min_effect: f64,
    /// The same for build times (builds of a few ms drift by up to 1.5x between runs on a shared machine).
    #[arg(long, default_value_t = 0.30)]
    pub min_effect_build: f64,
    /// Metric the speedups are computed from.
    #[arg(long, default_value = schema::column::trace_s)]
    pub metric: String,
    /// List changed work counters without failing on them.
    #[arg(long)]
    pub accept_counter_changes: bool,
    /// Compare times for information only (never fail on them), even when run and baseline come from the same
    /// machine (another machine's are always for information).
    #[arg(long)]
    pub timings_for_information: bool,
    /// Largest growth of a phase's instruction count that passes (0.02 = 2%).
    #[arg(long, default_value_t = 0.02)]
    pub instruction_threshold: f64,
    /// Phases whose baseline median is shorter than this many seconds are compared for information only.
    #[arg(long, default_value_t = 1e-4)]
    pub min_time: f64,
    /// Compare times for information only where the run's median 1-minute load average exceeds the baseline's by
    /// more than this (more runnable tasks than cores slow every phase, its second measurement too).
    #[arg(long, default_value_t = 1.0)]
    pub max_extra_load: f64,
    /// Fail on a flagged time without measuring its configuration again.
    #[arg(long)]
    pub no_confirm: bool,
    /// Where to write the JSON of every measure (default: RUN_DIR/check.json).
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct InstructionsArgs {
    /// Experiment config (TOML).
    pub config: PathBuf,
    /// Run folder to write instructions.csv to (default: results/<name>/, or results/<name>-quick/ with --quick).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Apply the config's [quick] overrides.
    #[arg(long)]
    pub quick: bool,
    /// Also simulate caches (D1 and last-level misses, recorded for information; 1.3-2.2x slower).
    #[arg(long)]
    pub cache_sim: bool,
    /// Count at this image size instead of each configuration's own, e.g. 64x48.
    #[arg(long, value_parser = parse_image)]
    pub image: Option<(u32, u32)>,
    /// Valgrind processes at once (default: logical cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub jobs: Option<u32>,
}

fn parse_image(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{s:?} is not an image size (allowed: WxH with 1 <= W, H <= 16384, e.g. 64x48)");
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if (1..=16384).contains(&w) && (1..=16384).contains(&h) { Ok((w, h)) } else { Err(bad()) }
}

#[derive(Args, Debug)]
pub struct AbArgs {
    /// The revision to compare against (anything `git rev-parse` takes; it needs `harness worker`).
    #[arg(long)]
    pub base: String,
    /// Experiment config (TOML).
    pub config: PathBuf,
    /// Use the config's [quick] overrides.
    #[arg(long)]
    pub quick: bool,
    /// Smallest slowdown that counts as a regression (0.10 = 10%).
    #[arg(long, default_value_t = 0.10)]
    pub min_effect: f64,
    /// Compare timings even where the two builds' answers differ (exit 0 unless slower; the table says
    /// `differs`). Answers that change between runs of one build always fail.
    #[arg(long)]
    pub allow_different_answers: bool,
    /// Fail on a configuration flagged as slower without measuring it again.
    #[arg(long)]
    pub no_confirm: bool,
}

#[derive(Args, Debug)]
pub struct ReproduceArgs {
    /// The result set: a folder `harness run` wrote (runs.csv and experiment.toml), e.g. results/paper.
    pub dir: PathBuf,
    /// Which code runs it: the commit its rows record (`recorded`, built in a worktree as `ab` builds its base), or
    /// the checkout's (`HEAD`).
    #[arg(long, value_enum, default_value = "recorded")]
    pub at: ReproduceAt,
    /// Run the config's [quick] overrides (the points both ran are compared).
    #[arg(long)]
    pub quick: bool,
    /// Where to write the new rows (default: DIR/reproductions/<date>-<machine_id>[-head][-quick]/, a new folder).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Judge claims and time ratios for information only: exit 1 only on a deterministic difference (CI, where two
    /// runs minutes apart on a shared machine are not a timing experiment).
    #[arg(long)]
    pub timings_for_information: bool,
}

/// `--at`: which code re-runs a result set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReproduceAt {
    /// The commit the rows record.
    #[value(name = "recorded")]
    Recorded,
    /// The checkout's code.
    #[value(name = "HEAD", alias = "head")]
    Head,
}

#[derive(Subcommand, Debug)]
pub enum HistoryCommand {
    /// Append a run's speedups (with intervals), commit, time and counter fingerprint to the history.
    Append {
        /// The run folder.
        run_dir: PathBuf,
        /// The history folder.
        #[arg(long, default_value = "results/history")]
        dir: PathBuf,
    },
    /// Count the CI suite at past commits (each built as `ab` builds its base): build and trace instructions under
    /// callgrind, answer hash and tree shape of every single-thread configuration the revision can run, one entry
    /// per commit in commits.csv and instructions.csv; commits already there are skipped.
    Backfill(BackfillArgs),
    /// Plot every tracked speedup over the appended runs (SVG + PNG per experiment, regressions marked).
    Plot {
        /// The history folder.
        #[arg(long, default_value = "results/history")]
        dir: PathBuf,
    },
}

#[derive(Args, Debug)]
pub struct BackfillArgs {
    /// The commits: a git revision range on the first-parent line, e.g. `d4ea610^..main` (d4ea610 included).
    pub range: String,
    /// Count every K-th commit of the range (and its last commit always).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub every: u32,
    /// The suite (its single-thread configurations are counted).
    #[arg(long, default_value = "experiments/ci.toml")]
    pub config: PathBuf,
    /// Apply the config's [quick] overrides.
    #[arg(long)]
    pub quick: bool,
    /// The history folder.
    #[arg(long, default_value = "results/history")]
    pub dir: PathBuf,
    /// Also time each counted configuration this many times (median build and trace seconds, with the machine).
    #[arg(long, default_value_t = 0)]
    pub timings: u32,
    /// Valgrind processes at once (default: logical cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub jobs: Option<u32>,
}

#[derive(Subcommand, Debug)]
pub enum BaselineCommand {
    /// Store a run folder as results/baselines/NAME/ (refuses to replace one without --force).
    Save {
        /// The run folder.
        run_dir: PathBuf,
        /// The baseline's name.
        name: String,
        /// Replace an existing baseline.
        #[arg(long)]
        force: bool,
    },
}

/// `--shard`: a fixed shard, or one read from the environment of a job array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShardArg {
    /// Shard I of N (1-based).
    Fixed(usize, usize),
    /// From the environment, with the shard count if given (`env/N`).
    Env(Option<usize>),
}

/// Parses `I/N`, `env` or `env/N`.
pub fn parse_shard(s: &str) -> Result<ShardArg, String> {
    let bad = || format!("{s:?} is not a shard (allowed: I/N with 1 <= I <= N, e.g. 2/4; env; env/N with N >= 1)");
    if s == "env" {
        return Ok(ShardArg::Env(None));
    }
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let n: usize = n.parse().map_err(|_| bad())?;
    if i == "env" {
        return if n >= 1 { Ok(ShardArg::Env(Some(n))) } else { Err(bad()) };
    }
    let i: usize = i.parse().map_err(|_| bad())?;
    if i >= 1 && i <= n { Ok(ShardArg::Fixed(i, n)) } else { Err(bad()) }
}

#[derive(Subcommand, Debug)]
pub enum SlurmCommand {
    /// Write and submit a job array (one shard per task) and a merge job that runs when the array ends.
    Submit(SubmitArgs),
    /// Submit again only the shards of a submitted run folder that are missing rows (failed, cancelled, timed out).
    Resubmit {
        /// The run folder (holding slurm/jobs.json).
        run_dir: PathBuf,
        /// Print the job scripts and the shards to run; submit nothing.
        #[arg(long)]
        dry_run: bool,
    },
}

#[derive(Args, Debug)]
pub struct SubmitArgs {
    /// Experiment config (TOML).
    pub config: PathBuf,
    /// Number of shards (array tasks); at most the number of scene cells of the plan.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub shards: u32,
    /// Array tasks running at once (`--array=...%K`; default: all shards).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub max_parallel: Option<u32>,
    /// Slurm partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Slurm node constraint (features), e.g. `avx512` to keep every shard on one kind of machine.
    #[arg(long)]
    pub constraint: Option<String>,
    /// Time limit of each array task, in any format sbatch takes (e.g. 30, 1:00:00).
    #[arg(long)]
    pub time: Option<String>,
    /// Apply the config's [quick] overrides.
    #[arg(long)]
    pub quick: bool,
    /// Share nodes with other jobs (default: each task has its node to itself, `--exclusive`).
    #[arg(long)]
    pub no_exclusive: bool,
    /// Let the merge job pool shards of different machines into one result set (REPORT.md then warns).
    #[arg(long)]
    pub allow_mixed_machines: bool,
    /// The run folder (default: results/<name>/, or results/<name>-quick/ with --quick).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the job scripts; write and submit nothing.
    #[arg(long)]
    pub dry_run: bool,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The run folder holding shard-I-of-N/ folders.
    pub run_dir: PathBuf,
    /// Merge rows recorded on different machines (their times stay apart; REPORT.md carries a warning).
    #[arg(long)]
    pub allow_mixed_machines: bool,
}

#[derive(Args, Debug)]
pub struct RowsDiffArgs {
    /// A runs.csv, or a run folder holding one.
    pub a: PathBuf,
    /// The other runs.csv or run folder.
    pub b: PathBuf,
    /// Compare every column but timings and the per-run provenance (load, time stamp, shard, job, node).
    #[arg(long)]
    pub ignore_timing: bool,
}

#[derive(Args, Debug)]
pub struct SiteArgs {
    /// The results folder (experiment folders, and history/).
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// Where to write the site (its index.html opens from file://).
    #[arg(long, default_value = "target/site")]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// A run folder (holding runs.csv and experiment.toml).
    pub dir: PathBuf,
    /// Another run of the same config (e.g. the committed one, moved into DIR/previous/ by the run): exit 1 when a
    /// claim that held there fails here at every point, naming it.
    #[arg(long, value_name = "RUN_DIR")]
    pub claims_against: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Experiment config (TOML).
    pub config: PathBuf,
    /// Validate the [quick] version.
    #[arg(long)]
    pub quick: bool,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// A setting as in a config's [sweep], `KEY=VALUE` (repeatable), e.g. `--set accel=wide-bvh --set
    /// objects=100000`; every key, default and allowed value is in `harness list` and docs/configuration.md.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Sphere CSV for `--set scene=sphere-file` (format: see the tracer's `scene::sphere_file` docs).
    #[arg(long)]
    pub file: Option<PathBuf>,
    /// Also trace a separate counted pass and print work per ray.
    #[arg(long)]
    pub count: bool,
    /// Where to write the PNG.
    #[arg(long, default_value = "image.png")]
    pub out: PathBuf,
}
