//! Transparent huge pages for every backend's memory, not only Embree's (`--huge-pages`).
//!
//! Embree's allocator asks the kernel for transparent huge pages on its large blocks; our structures, obvhs's and
//! tinybvh's allocate through glibc's malloc, which asks only when its tunables say so (glibc 2.35 and later).
//! Under the kernel's usual `madvise` mode Embree alone gets 2-MiB pages. glibc reads its tunables once, when a
//! process starts, so [`ensure`] starts the harness again with them set (or removed) before it does anything
//! else; the workers it starts inherit them. Every row says which it got (`huge_pages`). Measured on and off
//! (docs/statistics.md): they did not remove the offset between two series of one process, and cost our
//! two-thread builds about 7%, so they are a setting to measure with, not the default.

use std::ffi::OsString;

/// The glibc tunables that put malloc's blocks on transparent huge pages: `hugetlb=1` makes malloc advise the
/// kernel on the heap it grows (and the blocks it maps), and `arena_max=1` keeps every thread on that one heap —
/// the other threads' arenas are heaps malloc does not advise, and builds and traces run on pool threads (measured:
/// with `hugetlb` alone 14–50 MB of a run's 70–140 MB lay on huge pages, with both 110–145 MB of 135–170 MB).
const TUNABLES: [(&str, &str); 2] = [("glibc.malloc.hugetlb", "1"), ("glibc.malloc.arena_max", "1")];

/// Where the timing process's large blocks lie (the `huge_pages` column).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HugePages {
    /// The kernel gives huge pages to every large anonymous mapping (mode `always`).
    Always,
    /// glibc's malloc asks for them (mode `madvise` and the tunable set).
    Malloc,
    /// 4-KiB pages, except where an allocator asks on its own (Embree's).
    No,
}

impl HugePages {
    /// The column's spelling.
    pub fn name(self) -> &'static str {
        match self {
            HugePages::Always => "always",
            HugePages::Malloc => "malloc",
            HugePages::No => "no",
        }
    }
}

/// The kernel's transparent-huge-page mode: the bracketed word of `/sys/kernel/mm/transparent_hugepage/enabled`
/// (`always`, `madvise` or `never`), `never` where the file is missing.
fn kernel_mode() -> String {
    let text = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled").unwrap_or_default();
    mode_of(&text).to_string()
}

/// The bracketed word of a `transparent_hugepage/enabled` text.
fn mode_of(text: &str) -> &str {
    text.split_whitespace().find_map(|w| w.strip_prefix('[')?.strip_suffix(']')).unwrap_or("never")
}

/// Whether this process's C library is glibc 2.35 or later (the first with the tunable).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn glibc_has_tunable() -> bool {
    unsafe extern "C" {
        /// glibc's version string, e.g. `2.36` (static storage).
        fn gnu_get_libc_version() -> *const std::ffi::c_char;
    }
    // SAFETY: glibc returns a pointer to a NUL-terminated string in static storage.
    let version = unsafe { std::ffi::CStr::from_ptr(gnu_get_libc_version()) }.to_string_lossy().into_owned();
    version_has_tunable(&version)
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn glibc_has_tunable() -> bool {
    false
}

/// Whether glibc `version` (`MAJOR.MINOR[...]`) reads the tunable.
fn version_has_tunable(version: &str) -> bool {
    let mut parts = version.split('.').map(|p| p.parse::<u32>().unwrap_or(0));
    let (major, minor) = (parts.next().unwrap_or(0), parts.next().unwrap_or(0));
    (major, minor) >= (2, 35)
}

/// `tunables` (a `GLIBC_TUNABLES` value, `name=value` pairs joined by `:`) with the huge-page tunables set
/// (`huge`) or removed.
fn with_tunable(tunables: &str, huge: bool) -> String {
    let ours = |t: &&str| TUNABLES.iter().any(|(name, _)| t.split('=').next() == Some(name));
    let mut kept: Vec<String> = tunables.split(':').filter(|t| !t.is_empty() && !ours(t)).map(str::to_string).collect();
    if huge {
        kept.extend(TUNABLES.iter().map(|(name, value)| format!("{name}={value}")));
    }
    kept.join(":")
}

/// Whether a `GLIBC_TUNABLES` value sets every huge-page tunable.
fn tunable_set(tunables: &str) -> bool {
    TUNABLES.iter().all(|(name, value)| tunables.split(':').any(|t| t == format!("{name}={value}")))
}

/// What this process got.
pub fn current() -> HugePages {
    match kernel_mode().as_str() {
        "always" => HugePages::Always,
        "madvise" if glibc_has_tunable() && tunable_set(&std::env::var("GLIBC_TUNABLES").unwrap_or_default()) => {
            HugePages::Malloc
        }
        _ => HugePages::No,
    }
}

/// Starts this process again, same arguments, with glibc's malloc asking for huge pages (`huge`) or not, when the
/// kernel's mode is `madvise` and the environment says otherwise; returns only when nothing needs to change or the
/// start failed (then it runs as it is, and its rows say so).
pub fn ensure(huge: bool) {
    if kernel_mode() != "madvise" || !glibc_has_tunable() {
        return;
    }
    let now = std::env::var("GLIBC_TUNABLES").unwrap_or_default();
    if tunable_set(&now) == huge {
        return;
    }
    restart(huge);
}

/// Gives `cmd` this process's `GLIBC_TUNABLES` with the huge-page tunable set (`huge`) or removed.
pub fn set_tunable(cmd: &mut std::process::Command, huge: bool) {
    let tunables = with_tunable(&std::env::var("GLIBC_TUNABLES").unwrap_or_default(), huge);
    if tunables.is_empty() {
        cmd.env_remove("GLIBC_TUNABLES");
    } else {
        cmd.env("GLIBC_TUNABLES", tunables);
    }
}

#[cfg(unix)]
fn restart(huge: bool) {
    use std::os::unix::process::CommandExt;
    let Ok(exe) = std::env::current_exe() else { return };
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    let mut cmd = std::process::Command::new(exe);
    cmd.args(args);
    set_tunable(&mut cmd, huge);
    // `exec` returns only on failure.
    let error = cmd.exec();
    note!("could not start again with glibc's huge-page tunables ({error}); running on the pages as they are");
}

#[cfg(not(unix))]
fn restart(_: bool) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_mode_is_the_bracketed_word() {
        assert_eq!(mode_of("always [madvise] never\n"), "madvise");
        assert_eq!(mode_of("[always] madvise never"), "always");
        assert_eq!(mode_of(""), "never");
    }

    #[test]
    fn the_tunables_are_added_or_removed_beside_others() {
        let both = "glibc.malloc.hugetlb=1:glibc.malloc.arena_max=1";
        assert_eq!(with_tunable("", true), both);
        assert_eq!(with_tunable("glibc.malloc.tcache_count=0", true), format!("glibc.malloc.tcache_count=0:{both}"));
        assert_eq!(with_tunable("glibc.malloc.hugetlb=0:glibc.malloc.arena_max=4", true), both);
        assert_eq!(with_tunable(&format!("{both}:glibc.malloc.tcache_count=0"), false), "glibc.malloc.tcache_count=0");
        assert!(tunable_set(&with_tunable("a=1", true)) && !tunable_set(&with_tunable(both, false)));
        assert!(!tunable_set("glibc.malloc.hugetlb=1"), "arena_max too");
        assert!(!tunable_set("glibc.malloc.hugetlb=2:glibc.malloc.arena_max=1"), "2 asks for reserved pages");
    }

    #[test]
    fn glibc_reads_the_tunable_from_2_35() {
        assert!(version_has_tunable("2.35") && version_has_tunable("2.36") && version_has_tunable("3.0"));
        assert!(!version_has_tunable("2.34") && !version_has_tunable("2.9") && !version_has_tunable("weird"));
    }
}
