//! `harness ab`: the trustworthy comparison on a noisy machine. Builds another git revision, then times every
//! configuration with both builds in one job, interleaved (A B, then B A, round after round), each run in a
//! fresh `harness worker` process, and reports each configuration's time ratio new/old: the median of the per-round
//! ratios with its 95% interval, by the statistic the reports and the CI gate use for rounds ([`RoundRatios::estimate`]:
//! every round is a pair of processes of its own, so it resamples rounds as the processes they are). Both builds must give the same answers, run after run. A configuration the base revision cannot run
//! (a setting newer than it, or a request its worker refuses) is skipped and listed.
//!
//! The base revision is built in a fresh git worktree under `target/ab/`, by cargo, into the target folder of
//! the running binary with the same profile, so that it reuses the dependencies already compiled there and only
//! the workspace crates compile. Cargo hashes a workspace crate's artifacts by its path relative to the
//! workspace root, so the worktree's crates would overwrite (and, by mtime, pass for) the main checkout's:
//! the base is built with `split-debuginfo = "unpacked"` for the workspace crates, which changes their
//! artifact hashes but not their machine code. Cargo links the base's binary to `target/<profile>/harness`;
//! it is put back right after. Base binaries are cached as `target/ab/harness-<rev>-<profile>-<compiler>`.

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use report::RoundRatios;
use report::stats::Estimate;

use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Configuration, Plan};
use crate::revision::Revision;
use crate::run::{self, worker};

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

pub(crate) fn git(root: &Path, args: &[&str]) -> Result<String, Error> {
    let out = Command::new("git").current_dir(root).args(args).output().map_err(|e| Error::Run(format!("git: {e}")))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
    } else {
        Err(Error::Input(format!(
            "git {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim().lines().next().unwrap_or("")
        )))
    }
}

fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// Where cargo put the running harness: `<target>/<profile folder>/harness`.
pub(crate) struct Build {
    pub target: PathBuf,
    /// `release`, `debug`, or a custom profile's name.
    folder: String,
}

impl Build {
    pub fn running() -> Result<Build, Error> {
        let exe =
            std::env::current_exe().map_err(|e| Error::Run(format!("cannot find the harness executable: {e}")))?;
        let exe = exe.canonicalize().unwrap_or(exe);
        let parts = exe.parent().and_then(|p| Some((p.parent()?, p.file_name()?.to_str()?)));
        match parts {
            Some((target, folder))
                if folder != "deps"
                    && (target.join("CACHEDIR.TAG").is_file() || target.join(".rustc_info.json").is_file()) =>
            {
                Ok(Build { target: target.to_path_buf(), folder: folder.to_string() })
            }
            _ => Err(Error::Run(format!(
                "{}: ab builds the base revision next to the running harness, which must be cargo's \
                 target/<profile>/harness (run `cargo run --release -- ab …`)",
                exe.display()
            ))),
        }
    }

    /// Cargo's options that select this build's profile, and the profile's name in `[profile.*]` tables.
    fn profile(&self) -> (Vec<&str>, &str) {
        match self.folder.as_str() {
            "release" => (vec!["--release"], "release"),
            "debug" => (vec![], "dev"),
            custom => (vec!["--profile", custom], custom),
        }
    }

    /// The binary cargo links for this profile (the running one, unless it was rebuilt since).
    fn uplifted(&self) -> PathBuf {
        self.target.join(&self.folder).join(format!("harness{}", std::env::consts::EXE_SUFFIX))
    }
}

/// A file removed when dropped.
struct Temporary(PathBuf);

impl Drop for Temporary {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.0);
    }
}

/// A git worktree removed when dropped.
pub(crate) struct Worktree<'a> {
    root: &'a Path,
    pub path: PathBuf,
}

impl Worktree<'_> {
    pub fn add<'a>(root: &'a Path, path: PathBuf, rev: &str) -> Result<Worktree<'a>, Error> {
        let tree = Worktree { root, path };
        tree.remove();
        git(root, &["worktree", "add", "--detach", "--force", tree.path.to_str().expect("utf-8 path"), rev])?;
        Ok(tree)
    }

    fn remove(&self) {
        if self.path.exists() {
            let _ = git(self.root, &["worktree", "remove", "--force", self.path.to_str().expect("utf-8 path")]);
            let _ = fs::remove_dir_all(&self.path);
        }
    }
}

impl Drop for Worktree<'_> {
    fn drop(&mut self) {
        self.remove();
    }
}

/// Copies `from` to `to` through a temporary name in `to`'s folder, so that `to` is always whole.
fn publish(from: &Path, to: &Path, link: bool) -> std::io::Result<()> {
    let tmp = to.with_file_name(format!(".{}.tmp-{}", to.file_name().unwrap().to_string_lossy(), std::process::id()));
    let _ = fs::remove_file(&tmp);
    if !(link && fs::hard_link(from, &tmp).is_ok()) {
        fs::copy(from, &tmp)?;
    }
    fs::rename(&tmp, to).inspect_err(|_| {
        let _ = fs::remove_file(&tmp);
    })
}

/// Whether `a` and `b` are the same file, or files with the same bytes.
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) else { return false };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if (ma.dev(), ma.ino()) == (mb.dev(), mb.ino()) {
            return true;
        }
    }
    if ma.len() != mb.len() {
        return false;
    }
    let (Ok(mut fa), Ok(mut fb)) = (fs::File::open(a), fs::File::open(b)) else { return false };
    let (mut ba, mut bb) = (vec![0; 1 << 20], vec![0; 1 << 20]);
    loop {
        match (fill(&mut fa, &mut ba), fill(&mut fb, &mut bb)) {
            (Ok(0), Ok(0)) => return true,
            (Ok(n), Ok(m)) if n == m && ba[..n] == bb[..n] => {}
            _ => return false,
        }
    }
}

/// Reads until `buf` is full or the input ends; returns how many bytes it read.
fn fill(input: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match input.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// 64-bit FNV-1a.
fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// The cached base binary's file name: the revision, the profile and the compiler (a toolchain update builds
/// the base again instead of comparing two compilers).
fn cache_name(rev: &str, profile: &str, rustc_version: &str) -> String {
    format!("harness-{}-{profile}-{:08x}{}", &rev[..12], fnv(rustc_version) as u32, std::env::consts::EXE_SUFFIX)
}

pub(crate) fn rustc_version(dir: &Path) -> String {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    Command::new(rustc)
        .current_dir(dir)
        .arg("-vV")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map_or_else(|| "unknown".into(), |o| String::from_utf8_lossy(&o.stdout).into_owned())
}

/// The workspace members of the worktree at `tree`.
fn members(tree: &Path) -> Result<Vec<String>, Error> {
    let out = Command::new(cargo())
        .current_dir(tree)
        .args(["metadata", "--no-deps", "--format-version", "1"])
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| Error::Run(format!("cargo: {e}")))?;
    let failed = |why: String| Error::Run(format!("cargo metadata in {}: {why}", tree.display()));
    if !out.status.success() {
        return Err(failed(String::from_utf8_lossy(&out.stderr).trim().lines().last().unwrap_or("").to_string()));
    }
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| failed(e.to_string()))?;
    let names: Vec<String> = json["packages"]
        .as_array()
        .map(|p| p.iter().filter_map(|p| p["name"].as_str().map(String::from)).collect())
        .unwrap_or_default();
    if names.is_empty() { Err(failed("no packages".into())) } else { Ok(names) }
}

/// What cargo's verbose output says about a base build in the worktree folder named `tree`.
#[derive(Debug, PartialEq)]
enum Built {
    /// The harness binary this build compiled, in cargo's `deps` folder.
    Binary(PathBuf),
    /// A workspace crate was not compiled: its artifacts (shared by every base build) are newer than the
    /// worktree, from another base build that finished meanwhile. Its cargo line.
    Stale(String),
}

fn built(cargo_stderr: &str, tree: &str) -> Result<Built, String> {
    if let Some(fresh) = cargo_stderr.lines().find(|l| l.trim_start().starts_with("Fresh ") && l.contains(tree)) {
        return Ok(Built::Stale(fresh.trim().to_string()));
    }
    let rustc = cargo_stderr
        .lines()
        .find(|l| l.contains(" --crate-name harness ") && l.contains(" --crate-type bin "))
        .ok_or("cargo's output has no rustc command for the harness binary")?;
    let words: Vec<&str> =
        rustc.split_whitespace().map(|w| w.trim_matches(|c| c == '`' || c == '\'' || c == '"')).collect();
    let extra = words.iter().find_map(|w| w.strip_prefix("extra-filename="));
    let out_dir = words.iter().position(|w| *w == "--out-dir").and_then(|i| words.get(i + 1));
    match (extra, out_dir) {
        (Some(extra), Some(dir)) => {
            Ok(Built::Binary(Path::new(dir).join(format!("harness{extra}{}", std::env::consts::EXE_SUFFIX))))
        }
        _ => Err(format!("no --out-dir or extra-filename in `{rustc}`")),
    }
}

/// Builds `rev` in a fresh worktree, with `build`'s target folder and profile; returns its compiled binary, or
/// `None` when another base build's artifacts were taken for this one's (see [`Built::Stale`]).
fn build_once(root: &Path, build: &Build, rev: &str, ab: &Path) -> Result<Option<PathBuf>, Error> {
    let name = format!("tree-{}-{}", &rev[..12], std::process::id());
    // A fresh checkout: its files are newer than the artifacts of any earlier base build, which have the same
    // names (cargo decides freshness by mtime).
    let tree = Worktree::add(root, ab.join(&name), rev)?;
    // Every package of the revision's lock file, for every platform: the harness's build script from 6ca80e1 until
    // it passed `--filter-platform` ran `cargo metadata --offline` over all of them, which fails where cargo has
    // downloaded only the host's. Without a network the build says what is missing.
    let fetched =
        Command::new(cargo()).current_dir(&tree.path).args(["fetch", "--quiet"]).stdin(Stdio::null()).status();
    if !fetched.is_ok_and(|s| s.success()) {
        note!("ab: `cargo fetch` failed in the worktree of {rev}: building with the packages at hand");
    }
    let (options, profile) = build.profile();
    let mut cmd = Command::new(cargo());
    cmd.current_dir(&tree.path)
        .env("CARGO_TARGET_DIR", &build.target)
        .arg("build")
        .args(options)
        .args(["-p", "harness", "--bin", "harness", "-v"]);
    for member in members(&tree.path)? {
        cmd.arg("--config").arg(format!("profile.{profile}.package.{member}.split-debuginfo=\"unpacked\""));
    }
    let out = cmd.stdin(Stdio::null()).output().map_err(|e| Error::Run(format!("cargo: {e}")))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        let progress = ["Running ", "Fresh ", "Dirty ", "Compiling "];
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| l.contains("error") || !progress.iter().any(|p| l.trim_start().starts_with(p)))
            .collect();
        note!("{}", lines[lines.len().saturating_sub(40)..].join("\n"));
        return Err(Error::Run(format!("building {rev} failed (cargo's messages above)")));
    }
    match built(&stderr, &name) {
        Ok(Built::Binary(binary)) => Ok(Some(binary)),
        Ok(Built::Stale(line)) => {
            note!("ab: cargo took another base build's artifacts ({line}): building again");
            Ok(None)
        }
        Err(why) => Err(Error::Run(format!("building {rev}: {why}"))),
    }
}

/// `target/<profile>/harness`, where cargo links the base's binary during its build: put back when dropped.
struct Uplifted {
    path: PathBuf,
    /// A link to (or copy of) the file that was there before, if any.
    saved: Option<Temporary>,
    /// The base binary cargo compiled, once known.
    base: Option<PathBuf>,
}

impl Uplifted {
    fn save(build: &Build, ab: &Path) -> Uplifted {
        let path = build.uplifted();
        let saved = Temporary(ab.join(format!("uplifted-{}", std::process::id())));
        let _ = fs::remove_file(&saved.0);
        let had = fs::hard_link(&path, &saved.0).is_ok() || fs::copy(&path, &saved.0).is_ok();
        Uplifted { path, saved: had.then_some(saved), base: None }
    }
}

impl Drop for Uplifted {
    fn drop(&mut self) {
        // Only the base's binary is replaced: a build of the checkout that finished meanwhile stays.
        let replaced = match (&self.base, &self.saved) {
            (Some(base), _) => same_file(&self.path, base),
            (None, Some(saved)) => !same_file(&self.path, &saved.0),
            (None, None) => false,
        };
        if replaced {
            let _ = match &self.saved {
                Some(saved) => publish(&saved.0, &self.path, true),
                None => fs::remove_file(&self.path),
            };
        }
    }
}

/// The harness binary of `rev`: cached, or built (see the module's documentation).
pub(crate) fn base_binary(root: &Path, build: &Build, rev: &str) -> Result<PathBuf, Error> {
    let ab = build.target.join("ab");
    fs::create_dir_all(&ab).map_err(|e| Error::Run(format!("{}: {e}", ab.display())))?;
    let cache = ab.join(cache_name(rev, &build.folder, &rustc_version(root)));
    if cache.is_file() {
        note!("ab: base {}: {} (built before)", &rev[..12], cache.display());
        return Ok(cache);
    }
    if let Some(why) = running_is_build_of(root, rev) {
        fs::copy("/proc/self/exe", &cache)
            .or_else(|_| fs::copy(build.uplifted(), &cache))
            .map_err(|e| Error::Run(format!("{}: {e}", cache.display())))?;
        note!("ab: base {}: this binary, copied to {} ({why})", &rev[..12], cache.display());
        return Ok(cache);
    }
    note!("ab: building {rev} into {} (its workspace crates only)", build.target.display());
    let mut uplifted = Uplifted::save(build, &ab);
    for _ in 0..3 {
        if let Some(binary) = build_once(root, build, rev, &ab)? {
            uplifted.base = Some(binary.clone());
            drop(uplifted); // put back first: until then `target/<profile>/harness` is the base's
            publish(&binary, &cache, false).map_err(|e| Error::Run(format!("{}: {e}", cache.display())))?;
            return Ok(cache);
        }
        if cache.is_file() {
            return Ok(cache); // built by an `ab` of the same revision meanwhile
        }
    }
    Err(Error::Run(format!("building {rev}: other base builds kept replacing this one's workspace crates; run again")))
}

/// Why the running binary is `rev`'s build, if it is: it was built from the working tree as it is now (the
/// hash its build script took of the sources equals theirs now), and the working tree's sources are `rev`'s (no
/// change, untracked or ignored file among them, and `rev`'s are HEAD's). Building `rev` would compile the same
/// sources with the same compiler and profile again.
fn running_is_build_of(root: &Path, rev: &str) -> Option<String> {
    let built = env!("BVHLAB_SOURCE_HASH");
    let now = format!("{:016x}", crate::source_tree::source_hash(root));
    if now != built {
        return None;
    }
    let sources: Vec<&str> = crate::source_tree::SOURCES.to_vec();
    let status =
        git(root, &[&["status", "--porcelain", "--untracked-files=all", "--ignored", "--"], &sources[..]].concat());
    let same_as_head = status.ok()?.is_empty();
    let diff = Command::new("git")
        .current_dir(root)
        .args([&["diff", "--quiet", "HEAD", rev, "--"], &sources[..]].concat())
        .status()
        .ok()?;
    (same_as_head && diff.success())
        .then(|| format!("built from sources {built}, the working tree's, which are {}'s", &rev[..12]))
}

/// A copy of the running binary, the new side of the comparison: `target/<profile>/harness` may be rebuilt
/// while the comparison runs.
fn copy_running(build: &Build) -> Result<Temporary, Error> {
    let copy = Temporary(build.target.join("ab").join(format!(
        "harness-new-{}{}",
        std::process::id(),
        std::env::consts::EXE_SUFFIX
    )));
    // `/proc/self/exe` is this process's own file even where cargo has linked another in its place.
    let exe = if cfg!(target_os = "linux") { PathBuf::from("/proc/self/exe") } else { build.uplifted() };
    fs::create_dir_all(build.target.join("ab"))
        .and_then(|()| fs::copy(&exe, &copy.0))
        .map_err(|e| Error::Run(format!("copying {} to {}: {e}", exe.display(), copy.0.display())))?;
    Ok(copy)
}

/// The speed verdict of one configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Speed {
    Regressed,
    SlowerNotGating,
    Improved,
    Unchanged,
}

impl Speed {
    /// `e` is new / old; single-thread configurations gate.
    fn of(e: &Estimate, min_effect: f64, gating: bool) -> Speed {
        let slower = e.lo > 1.0 && e.value > 1.0 + min_effect;
        let faster = e.hi < 1.0 && e.value < 1.0 - min_effect;
        match (slower, faster) {
            (true, _) if gating => Speed::Regressed,
            (true, _) => Speed::SlowerNotGating,
            (_, true) => Speed::Improved,
            _ => Speed::Unchanged,
        }
    }

    fn label(self) -> &'static str {
        match self {
            Speed::Regressed => "**regressed**",
            Speed::SlowerNotGating => "slower (not gating: threads > 1)",
            Speed::Improved => "improved",
            Speed::Unchanged => "unchanged",
        }
    }
}

/// How one configuration's answers (output hashes, one per run) compare between the builds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Answers {
    Same,
    Differ,
    /// A build's answers changed from run to run: (old, new).
    Unstable(bool, bool),
}

impl Answers {
    fn of(old: &[u64], new: &[u64]) -> Answers {
        let unstable = |h: &[u64]| h.windows(2).any(|w| w[0] != w[1]);
        match (unstable(old), unstable(new)) {
            (false, false) if old.first() == new.first() => Answers::Same,
            (false, false) => Answers::Differ,
            (o, n) => Answers::Unstable(o, n),
        }
    }

    fn label(self) -> &'static str {
        match self {
            Answers::Same => "same",
            Answers::Differ => "differs",
            Answers::Unstable(true, true) => "unstable (both builds)",
            Answers::Unstable(true, false) => "unstable (old build)",
            Answers::Unstable(..) => "unstable (new build)",
        }
    }
}

/// Why the comparison fails, in one line, or `None`: answers that change between runs of a build always fail,
/// answers that differ between the builds fail unless allowed, and so do significant single-thread slowdowns.
fn failure(results: &[(String, Speed, Answers)], allow_different_answers: bool) -> Option<String> {
    let names = |keep: &dyn Fn(Speed, Answers) -> bool| {
        results.iter().filter(|(_, s, a)| keep(*s, *a)).map(|(n, ..)| n.as_str()).collect::<Vec<_>>().join(", ")
    };
    let reasons: Vec<String> = [
        (names(&|_, a| matches!(a, Answers::Unstable(..))), "answers change from run to run of the same build in", ""),
        (
            names(&|_, a| a == Answers::Differ && !allow_different_answers),
            "the builds' answers differ in",
            " (--allow-different-answers to compare them anyway)",
        ),
        (names(&|s, _| s == Speed::Regressed), "significantly slower than the base revision (single thread):", ""),
    ]
    .into_iter()
    .filter(|(names, ..)| !names.is_empty())
    .map(|(names, what, hint)| format!("{what} {names}{hint}"))
    .collect();
    (!reasons.is_empty()).then(|| reasons.join("; "))
}

/// A configuration as the table and the messages name it.
fn describe(c: &Configuration) -> String {
    let s = &c.settings;
    let scene = match (&s.mesh, s.view) {
        (Some(mesh), Some(view)) => format!("mesh {mesh} {}", schema::Named::name(view)),
        _ => format!("{} objects {}", schema::Named::name(s.scene), s.objects),
    };
    format!("{} | {scene} {} {}", c.series, schema::Named::name(s.workload), s.strategy())
}

/// A configuration's samples and answers from both builds.
#[derive(Default)]
struct Pair {
    old: Vec<f64>,
    new: Vec<f64>,
    old_answers: Vec<u64>,
    new_answers: Vec<u64>,
}

impl Pair {
    /// The per-round ratios new/old, each round a pair of processes of its own.
    fn ratios(&self) -> RoundRatios {
        RoundRatios {
            ratios: self.new.iter().zip(&self.old).map(|(n, o)| n / o).collect(),
            processes: (0..self.new.len() as u64).collect(),
        }
    }
}

/// The verdict that counts: a regression of the first measurement stands only if the second one (when taken)
/// finds it too; otherwise the configuration is unchanged.
fn confirmed(first: Speed, second: Option<Speed>) -> Speed {
    match (first, second) {
        (Speed::Regressed, Some(Speed::Regressed)) | (Speed::Regressed, None) => Speed::Regressed,
        (Speed::Regressed, Some(_)) => Speed::Unchanged,
        (first, _) => first,
    }
}

/// Times `configurations` with both builds, interleaved (old then new, new then old, round after round), each run
/// in a fresh `harness worker` process: one [`Pair`] per configuration.
fn measure(
    plan: &Plan,
    configurations: &[&Configuration],
    rounds: (u32, u32),
    bins: (&Path, &Path),
    root: &Path,
    what: &str,
) -> Result<Vec<Pair>, Error> {
    let (warmups, repetitions) = rounds;
    let (old_bin, new_bin) = bins;
    let mut pairs: Vec<Pair> = configurations.iter().map(|_| Pair::default()).collect();
    for round in 0..warmups + repetitions {
        for (c, pair) in configurations.iter().zip(&mut pairs) {
            let old_first = round % 2 == 0;
            let (first, second) = if old_first { (old_bin, new_bin) } else { (new_bin, old_bin) };
            let job = run::worker_request(plan, c);
            let a = worker::time(first, Some(root), &job)?;
            let b = worker::time(second, Some(root), &job)?;
            let (old, new) = if old_first { (a, b) } else { (b, a) };
            pair.old_answers.push(old.output_hash);
            pair.new_answers.push(new.output_hash);
            if round >= warmups {
                pair.old.push(old.trace_s);
                pair.new.push(new.trace_s);
            }
        }
        note!("ab: {what} round {}/{} done", round + 1, warmups + repetitions);
    }
    Ok(pairs)
}

/// The configurations of `plan` that revision `rev` (built as `base`) can run, and why each other one is skipped:
/// a setting newer than the revision ([`Revision::cannot_run`]), or its worker refusing the request (asked once).
fn runnable_at<'a>(rev: &str, plan: &'a Plan, root: &Path, base: &Path) -> (Vec<&'a Configuration>, Vec<String>) {
    let revision = Revision::read(root, rev);
    let (mut runnable, mut skipped) = (Vec::new(), Vec::new());
    for c in plan.runnable() {
        let why = revision
            .cannot_run(&c.settings)
            .or_else(|| worker::time(base, Some(root), &run::worker_request(plan, c)).err().map(|e| e.to_string()));
        match why {
            Some(why) => skipped.push(format!("{}: {why}", describe(c))),
            None => runnable.push(c),
        }
    }
    (runnable, skipped)
}

/// Runs the comparison; fails (exit 1) on answers that differ or change, or on a significant single-thread
/// regression beyond `min_effect` that a second measurement of the configuration (fresh, interleaved) confirms.
pub fn run(request: &AbRequest<'_>) -> Result<(), Error> {
    let exp = Experiment::load(request.config)?;
    let exp = if request.quick { exp.quick() } else { exp };
    let mut plan = Plan::new(&exp, crate::plan::available_threads())?;
    plan.skip_unavailable(&exp.path.display().to_string(), false)?;
    let root = PathBuf::from(git(Path::new("."), &["rev-parse", "--show-toplevel"])?);
    let rev = git(&root, &["rev-parse", "--verify", &format!("{}^{{commit}}", request.base)])?;
    let build = Build::running()?;
    let new_copy = copy_running(&build)?;
    let (old_bin, new_bin) = (base_binary(&root, &build, &rev)?, new_copy.0.clone());
    let bins = (old_bin.as_path(), new_bin.as_path());
    let rounds = (exp.warmups, exp.repetitions.max());
    let (all, skipped) = runnable_at(&rev, &plan, &root, &old_bin);
    for why in &skipped {
        note!("ab: skipped, {why}");
    }
    if all.is_empty() {
        return Err(Error::Run(format!("{}: no configuration runs at {}", exp.path.display(), &rev[..12])));
    }
    let mut pairs = measure(&plan, &all, rounds, bins, &root, "")?;
    let speed = |c: &Configuration, pair: &Pair| {
        // Old and new ran in the same rounds (one after the other), each round in a pair of processes of its own.
        let e: Estimate = pair.ratios().estimate(&c.id);
        (Speed::of(&e, request.min_effect, c.settings.strategy().threads == 1), e)
    };
    let flagged: Vec<usize> =
        (0..all.len()).filter(|&i| !request.no_confirm && speed(all[i], &pairs[i]).0 == Speed::Regressed).collect();
    let mut again: Vec<Option<Pair>> = all.iter().map(|_| None).collect();
    if !flagged.is_empty() {
        note!("ab: {} configuration(s) flagged as slower: measuring them again", flagged.len());
        let configurations: Vec<&Configuration> = flagged.iter().map(|&i| all[i]).collect();
        let second = measure(&plan, &configurations, rounds, bins, &root, "confirmation")?;
        for (&i, pair) in flagged.iter().zip(second) {
            pairs[i].old_answers.extend(&pair.old_answers);
            pairs[i].new_answers.extend(&pair.new_answers);
            again[i] = Some(pair);
        }
    }
    say!("## A/B: {} (new, this build) against {} (old, {})\n", exp.name, &rev[..12], request.base);
    say!(
        "Trace time per configuration, new / old (below 1: faster), the median of per-round ratios with its 95% interval; {} rounds, interleaved. \
         A single-thread configuration flagged as slower is measured again the same way and fails only if that \
         agrees.\n",
        exp.repetitions.max()
    );
    say!(
        "| series | settings | old median (s) | new median (s) | new / old [95% CI] | verdict | measured again: new / old \
         [95% CI], verdict | output |"
    );
    say!("|---|---|---|---|---|---|---|---|");
    let mut results = vec![];
    for (i, c) in all.iter().enumerate() {
        let (first, e) = speed(c, &pairs[i]);
        let second = again[i].as_ref().map(|pair| speed(c, pair));
        let verdict = confirmed(first, second.as_ref().map(|(s, _)| *s));
        let confirmation = second.map_or("—".to_string(), |(s, e2)| {
            format!("{:.3} [{:.3}, {:.3}], {}", e2.value, e2.lo, e2.hi, s.label())
        });
        let answers = Answers::of(&pairs[i].old_answers, &pairs[i].new_answers);
        say!(
            "| {} | {:.6} | {:.6} | {:.3} [{:.3}, {:.3}] | {} | {} | {} |",
            describe(c),
            report::stats::median(&pairs[i].old),
            report::stats::median(&pairs[i].new),
            e.value,
            e.lo,
            e.hi,
            first.label(),
            confirmation,
            answers.label()
        );
        results.push((describe(c).replace(" | ", ": "), verdict, answers));
    }
    if !skipped.is_empty() {
        say!("\nSkipped: {} configuration(s) the base revision cannot run:\n", skipped.len());
        for why in &skipped {
            say!("- {why}");
        }
    }
    match failure(&results, request.allow_different_answers) {
        Some(why) => Err(Error::Run(why)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(results: &[(Speed, Answers)]) -> Vec<(String, Speed, Answers)> {
        results.iter().enumerate().map(|(i, &(s, a))| (format!("c{i}"), s, a)).collect()
    }

    #[test]
    fn answers_are_the_same_only_when_every_run_of_both_builds_agrees() {
        assert_eq!(Answers::of(&[7, 7, 7], &[7, 7, 7]), Answers::Same);
        assert_eq!(Answers::of(&[7, 7, 7], &[8, 8, 8]), Answers::Differ);
        assert_eq!(Answers::of(&[7, 7, 9], &[7, 7, 7]), Answers::Unstable(true, false));
        assert_eq!(Answers::of(&[7, 7, 7], &[9, 7, 7]), Answers::Unstable(false, true));
        assert_eq!(Answers::of(&[7, 8], &[8, 7]), Answers::Unstable(true, true));
    }

    #[test]
    fn differing_answers_fail_unless_allowed_and_unstable_ones_always_fail() {
        let (same, differ) = ((Speed::Unchanged, Answers::Same), (Speed::Improved, Answers::Differ));
        assert_eq!(failure(&named(&[same, same]), false), None);
        let why = failure(&named(&[same, differ, differ]), false).expect("differing answers fail");
        assert!(why.starts_with("the builds' answers differ in c1, c2 ("), "{why}");
        assert_eq!(failure(&named(&[same, differ]), true), None, "allowed");
        let unstable = (Speed::Unchanged, Answers::Unstable(false, true));
        let why = failure(&named(&[unstable, differ]), true).expect("unstable answers fail even when allowed");
        assert_eq!(why, "answers change from run to run of the same build in c0");
        let why =
            failure(&named(&[(Speed::Regressed, Answers::Differ), (Speed::SlowerNotGating, Answers::Same)]), false)
                .expect("fails");
        assert!(!why.contains('\n') && why.contains("differ in c0 (") && why.ends_with("(single thread): c0"), "{why}");
        assert_eq!(failure(&named(&[(Speed::SlowerNotGating, Answers::Same)]), false), None);
    }

    #[test]
    fn only_a_significant_single_thread_slowdown_beyond_the_minimum_effect_regresses() {
        let e = |value, lo, hi| Estimate { value, lo, hi };
        assert_eq!(Speed::of(&e(1.2, 1.15, 1.25), 0.1, true), Speed::Regressed);
        assert_eq!(Speed::of(&e(1.2, 1.15, 1.25), 0.1, false), Speed::SlowerNotGating);
        assert_eq!(Speed::of(&e(1.05, 1.02, 1.08), 0.1, true), Speed::Unchanged, "within the minimum effect");
        assert_eq!(Speed::of(&e(1.2, 0.95, 1.4), 0.1, true), Speed::Unchanged, "not significant");
        assert_eq!(Speed::of(&e(0.8, 0.75, 0.85), 0.1, true), Speed::Improved);
    }

    #[test]
    fn a_regression_fails_only_when_the_second_measurement_agrees() {
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Regressed)), Speed::Regressed);
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Unchanged)), Speed::Unchanged);
        assert_eq!(confirmed(Speed::Regressed, Some(Speed::Improved)), Speed::Unchanged);
        assert_eq!(confirmed(Speed::Regressed, None), Speed::Regressed, "--no-confirm");
        assert_eq!(confirmed(Speed::Improved, None), Speed::Improved);
        let failing =
            |second| failure(&[("a".into(), confirmed(Speed::Regressed, second), Answers::Same)], false).is_some();
        assert!(failing(Some(Speed::Regressed)) && !failing(Some(Speed::Unchanged)));
    }

    #[test]
    fn the_base_binary_is_the_one_cargo_compiled_from_the_worktree() {
        let tree = "tree-0123456789ab-42";
        let rustc = "     Running `/rustup/bin/rustc --crate-name harness --edition=2024 harness/src/main.rs \
                     --crate-type bin --emit=dep-info,link -C opt-level=3 -C metadata=0f1e -C extra-filename=-8d0e0abad4b6469f \
                     --out-dir /w/target/release/deps -L dependency=/w/target/release/deps`";
        let output = format!(
            "       Fresh serde v1.0.0\n   Compiling tracer v0.1.0 (/w/target/ab/{tree}/tracer)\n     Running `rustc \
             --crate-name build_script_build --crate-type bin -C extra-filename=-11 --out-dir /w/x`\n{rustc}\n"
        );
        let binary = format!("/w/target/release/deps/harness-8d0e0abad4b6469f{}", std::env::consts::EXE_SUFFIX);
        assert_eq!(built(&output, tree), Ok(Built::Binary(binary.into())));
        let stale = format!("       Fresh tracer v0.1.0 (/w/target/ab/{tree}/tracer)\n{rustc}\n");
        assert!(matches!(built(&stale, tree), Ok(Built::Stale(line)) if line.starts_with("Fresh tracer")));
        assert!(built("       Fresh harness v0.1.0 (/w/harness)\n", tree).is_err(), "no binary compiled");
    }

    #[test]
    fn same_file_means_one_file_or_the_same_bytes() {
        let dir = std::env::temp_dir().join(format!("bvhlab-ab-same-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        let big: Vec<u8> = (0..(3 << 20) + 5).map(|i: u32| (i % 251) as u8).collect();
        let mut other = big.clone();
        *other.last_mut().unwrap() ^= 1;
        let file = |name: &str, bytes: &[u8]| {
            let path = dir.join(name);
            fs::write(&path, bytes).unwrap();
            path
        };
        let (a, b, c, d) = (file("a", &big), file("b", &big), file("c", &other), file("d", &big[1..]));
        fs::hard_link(&a, dir.join("link")).unwrap();
        assert!(same_file(&a, &dir.join("link")) && same_file(&a, &b));
        assert!(!same_file(&a, &c), "the last byte differs");
        assert!(!same_file(&a, &d) && !same_file(&a, &dir.join("missing")));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn cached_base_binaries_are_per_revision_profile_and_compiler() {
        let rev = "0123456789abcdef0123456789abcdef01234567";
        let name = cache_name(rev, "release", "rustc 1.95.0");
        assert!(name.starts_with("harness-0123456789ab-release-"), "{name}");
        assert_ne!(name, cache_name(rev, "debug", "rustc 1.95.0"));
        assert_ne!(name, cache_name(rev, "release", "rustc 1.96.0"));
    }
}
