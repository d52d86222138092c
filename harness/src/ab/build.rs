//! Building another git revision's harness, as `harness ab` (and `history backfill`, `reproduce`) take it: the base
//! revision is built in a fresh git worktree under `target/ab/`, by cargo, into the target folder of
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

use tracer::fingerprint::Fnv64;

use crate::error::Error;

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
pub(super) struct Temporary(pub(super) PathBuf);

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

/// The cached base binary's file name: the revision, the profile and the compiler (a toolchain update builds
/// the base again instead of comparing two compilers).
fn cache_name(rev: &str, profile: &str, rustc_version: &str) -> String {
    let compiler = Fnv64::default().bytes(rustc_version.as_bytes()).finish() as u32;
    format!("harness-{}-{profile}-{compiler:08x}{}", &rev[..12], std::env::consts::EXE_SUFFIX)
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
pub(super) fn copy_running(build: &Build) -> Result<Temporary, Error> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_compiler_hash_is_fnv1a_64_as_before() {
        // The value the former private FNV-1a gave: cached base binaries keep their names.
        assert_eq!(Fnv64::default().bytes(b"rustc 1.95.0").finish(), 0xed19_8b28_56cd_21a7);
        let name = cache_name("0123456789abcdef0123456789abcdef01234567", "release", "rustc 1.95.0");
        assert_eq!(name, format!("harness-0123456789ab-release-56cd21a7{}", std::env::consts::EXE_SUFFIX));
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
