//! Where a row came from: commit, compiler, machine, load and time.

use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

/// Facts fixed for a whole sweep.
#[derive(Clone, Debug)]
pub struct Provenance {
    pub git_commit: String,
    pub git_dirty: bool,
    pub rustc: String,
    pub cpu_model: String,
    pub logical_cores: usize,
    pub harness_version: String,
    pub machine: Machine,
    /// FNV-1a hash of the `Cargo.lock` the harness was built with.
    pub cargo_lock: String,
    /// The Slurm job (`SLURM_ARRAY_JOB_ID`, else `SLURM_JOB_ID`; empty outside Slurm).
    pub slurm_job_id: String,
    /// `SLURMD_NODENAME` (empty outside Slurm; a sharded run fills in the host name).
    pub node: String,
    /// Where this process's large blocks lie (`huge_pages`).
    pub huge_pages: String,
}

/// The instruction-set extensions rows report, as `/proc/cpuinfo` flags and as Rust target features.
const ISA: [(&str, &str); 8] = [
    ("sse4_2", "sse4.2"),
    ("avx", "avx"),
    ("avx2", "avx2"),
    ("fma", "fma"),
    ("avx512f", "avx512f"),
    ("avx512bw", "avx512bw"),
    ("avx512dq", "avx512dq"),
    ("avx512vl", "avx512vl"),
];

/// What tells two machines of one kind apart (see the `cpu_vendor` … `machine_id` columns).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Machine {
    pub cpu_vendor: String,
    /// `family/model/stepping`.
    pub cpu_signature: String,
    pub cpu_isa: String,
    pub cpu_caches: String,
    pub hypervisor: bool,
    pub kernel: String,
    pub target_features: String,
    pub machine_id: String,
    /// This boot's random id (not part of `machine_id`).
    pub boot_id: String,
}

impl Machine {
    /// Reads this machine (Linux: `/proc/cpuinfo`, the cpu0 cache folders, the kernel release).
    pub fn collect(cpu_model: &str, logical_cores: usize, rustc: &str) -> Machine {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let mut caches = Vec::new();
        for index in 0..8 {
            let dir = format!("/sys/devices/system/cpu/cpu0/cache/index{index}");
            let read = |f: &str| std::fs::read_to_string(format!("{dir}/{f}")).map(|s| s.trim().to_string());
            let (Ok(level), Ok(kind), Ok(size)) = (read("level"), read("type"), read("size")) else { break };
            let suffix = match kind.as_str() {
                "Data" => "d",
                "Instruction" => "i",
                _ => "",
            };
            caches.push(format!("L{level}{suffix} {size}"));
        }
        let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default().trim().to_string();
        let compiled: Vec<&str> = ISA.iter().filter(|(_, feature)| compiled_with(feature)).map(|(_, f)| *f).collect();
        let mut m = Machine::from_facts(
            &cpuinfo,
            &caches.join(" "),
            &kernel,
            &compiled.join(" "),
            cpu_model,
            logical_cores,
            rustc,
        );
        m.boot_id = std::fs::read_to_string("/proc/sys/kernel/random/boot_id").unwrap_or_default().trim().to_string();
        m
    }

    /// The machine of these facts (`cpuinfo`: the text of `/proc/cpuinfo`); `machine_id` hashes them all.
    pub fn from_facts(
        cpuinfo: &str,
        caches: &str,
        kernel: &str,
        target_features: &str,
        cpu_model: &str,
        logical_cores: usize,
        rustc: &str,
    ) -> Machine {
        let field = |name: &str| {
            cpuinfo
                .lines()
                .take_while(|l| !l.trim().is_empty())
                .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
                .and_then(|l| l.split_once(':'))
                .map_or(String::new(), |(_, v)| v.trim().to_string())
        };
        let flags = field("flags");
        let flags: Vec<&str> = flags.split_whitespace().collect();
        let isa: Vec<&str> = ISA.iter().filter(|(flag, _)| flags.contains(flag)).map(|(_, name)| *name).collect();
        let mut m = Machine {
            cpu_vendor: field("vendor_id"),
            cpu_signature: format!("{}/{}/{}", field("cpu family"), field("model"), field("stepping")),
            cpu_isa: isa.join(" "),
            cpu_caches: caches.to_string(),
            hypervisor: flags.contains(&"hypervisor"),
            kernel: kernel.to_string(),
            target_features: target_features.to_string(),
            machine_id: String::new(),
            boot_id: String::new(),
        };
        let mut h = tracer::fingerprint::Fnv64::default();
        for part in [
            cpu_model,
            &m.cpu_vendor,
            &m.cpu_signature,
            &m.cpu_isa,
            &m.cpu_caches,
            &m.kernel,
            &m.target_features,
            rustc,
        ] {
            h.bytes(part.as_bytes()).bytes(b"\x1f");
        }
        h.bytes(&[m.hypervisor as u8]).bytes(&(logical_cores as u64).to_le_bytes());
        m.machine_id = format!("{:012x}", h.finish() >> 16);
        m
    }
}

/// Whether this binary was compiled with the target feature `feature` (of [`ISA`]).
fn compiled_with(feature: &str) -> bool {
    match feature {
        "sse4.2" => cfg!(target_feature = "sse4.2"),
        "avx" => cfg!(target_feature = "avx"),
        "avx2" => cfg!(target_feature = "avx2"),
        "fma" => cfg!(target_feature = "fma"),
        "avx512f" => cfg!(target_feature = "avx512f"),
        "avx512bw" => cfg!(target_feature = "avx512bw"),
        "avx512dq" => cfg!(target_feature = "avx512dq"),
        "avx512vl" => cfg!(target_feature = "avx512vl"),
        _ => false,
    }
}

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

impl Provenance {
    /// Reads the facts of this process and machine (the git state of the current directory).
    pub fn collect() -> Self {
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split(':').nth(1))
                    .map(|m| m.trim().to_string())
            })
            .unwrap_or_else(|| std::env::consts::ARCH.to_string());
        let git_commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
        // Dirty means the code differs from the commit: recorded results (rewritten by every run) do not count.
        let git_dirty = git(&["status", "--porcelain", "--untracked-files=no", "--", ".", ":(exclude)results"])
            .is_some_and(|s| !s.is_empty());
        let (rustc, logical_cores) =
            (env!("BVHLAB_RUSTC_VERSION").to_string(), std::thread::available_parallelism().map_or(1, |n| n.get()));
        Provenance {
            git_commit,
            git_dirty,
            machine: Machine::collect(&cpu_model, logical_cores, &rustc),
            rustc,
            cpu_model,
            logical_cores,
            harness_version: env!("CARGO_PKG_VERSION").to_string(),
            cargo_lock: env!("BVHLAB_CARGO_LOCK_HASH").to_string(),
            slurm_job_id: ["SLURM_ARRAY_JOB_ID", "SLURM_JOB_ID"].iter().find_map(|v| env_var(v)).unwrap_or_default(),
            node: env_var("SLURMD_NODENAME").unwrap_or_default(),
            huge_pages: crate::pages::current().name().to_string(),
        }
    }
}

/// A non-empty environment variable.
fn env_var(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.is_empty())
}

/// This machine's host name (`/proc/sys/kernel/hostname`, else `$HOSTNAME`, else `unknown`).
pub fn hostname() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .or_else(|| env_var("HOSTNAME"))
        .unwrap_or_else(|| "unknown".into())
}

/// The 1-minute load average (NaN where `/proc/loadavg` does not exist).
pub fn load_average_1m() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(f64::NAN)
}

/// The current UTC time as RFC 3339 (`2026-11-22T03:04:05Z`).
pub fn timestamp_now() -> String {
    let secs = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z", rem / 3600, rem % 3600 / 60, rem % 60)
}

#[cfg(test)]
mod tests {
    use super::Machine;

    const AVX2: &str = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 25\nmodel\t\t: 1\nmodel name\t: AMD EPYC\n\
                        stepping\t: 1\nflags\t\t: fpu sse4_1 sse4_2 avx fma avx2 hypervisor\n\nprocessor\t: 1\n";

    #[test]
    fn machines_are_told_apart_by_isa_caches_and_kernel() {
        let m = Machine::from_facts(AVX2, "L1d 32K L2 512K", "6.1.0", "", "AMD EPYC", 2, "rustc 1.95.0");
        assert_eq!((m.cpu_vendor.as_str(), m.cpu_signature.as_str()), ("AuthenticAMD", "25/1/1"));
        assert_eq!(m.cpu_isa, "sse4.2 avx avx2 fma");
        assert!(m.hypervisor);
        assert_eq!(m.machine_id.len(), 12);
        let avx512 = AVX2.replace("avx2 hypervisor", "avx2 avx512f avx512bw avx512dq avx512vl hypervisor");
        let other = Machine::from_facts(&avx512, "L1d 32K L2 512K", "6.1.0", "", "AMD EPYC", 2, "rustc 1.95.0");
        assert_eq!(other.cpu_isa, "sse4.2 avx avx2 fma avx512f avx512bw avx512dq avx512vl");
        assert_ne!(other.machine_id, m.machine_id, "same model name, another ISA");
        assert_ne!(
            Machine::from_facts(AVX2, "L1d 32K L2 1024K", "6.1.0", "", "AMD EPYC", 2, "rustc 1.95.0").machine_id,
            m.machine_id
        );
        assert_ne!(
            Machine::from_facts(AVX2, "L1d 32K L2 512K", "6.1.0", "", "AMD EPYC", 4, "rustc 1.95.0").machine_id,
            m.machine_id
        );
        assert_eq!(
            Machine::from_facts(AVX2, "L1d 32K L2 512K", "6.1.0", "", "AMD EPYC", 2, "rustc 1.95.0"),
            m,
            "deterministic"
        );
    }

    #[test]
    fn timestamp_has_rfc3339_shape() {
        let t = super::timestamp_now();
        assert_eq!(t.len(), 20, "{t}");
        assert!(t.starts_with("20") && t.ends_with('Z') && &t[10..11] == "T", "{t}");
    }
}
