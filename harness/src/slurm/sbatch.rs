//! The job scripts: a job array with one shard per task, and a merge job that waits for it.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// Everything the scripts say, kept in `slurm/jobs.json` so that a resubmission writes the same jobs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JobOptions {
    /// Experiment name (job names).
    pub experiment: String,
    /// The config, absolute.
    pub config: PathBuf,
    /// 16 hex digits: FNV-1a of the config's text; the tasks refuse a config that changed since.
    pub config_hash: String,
    /// Whether the config's [quick] overrides apply.
    pub quick: bool,
    /// Number of shards.
    pub shards: usize,
    /// Array tasks running at once.
    pub max_parallel: usize,
    /// Each task has its node to itself.
    pub exclusive: bool,
    /// CPUs per task: the plan's largest thread count (`all` left to the node; see docs/clusters.md).
    pub cpus_per_task: usize,
    pub partition: Option<String>,
    pub constraint: Option<String>,
    /// Time limit of each task.
    pub time: Option<String>,
    /// Merge rows of different machines.
    pub allow_mixed_machines: bool,
    /// The harness binary, absolute.
    pub harness: PathBuf,
    /// The run folder, absolute.
    pub run_dir: PathBuf,
    /// The working folder of the jobs (where `submit` ran: the git checkout whose commit rows record).
    pub workdir: PathBuf,
}

/// `text` quoted for bash (single quotes unless it is plainly safe).
pub fn quote(text: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || "/._-+=:,@%".contains(c);
    if !text.is_empty() && text.chars().all(safe) {
        text.to_string()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

fn path(p: &Path) -> String {
    quote(&p.display().to_string())
}

/// The `--array` value of 0-based `tasks`, at most `max_parallel` at once: `0-7%4` or `1,5%4`.
pub fn array_spec(tasks: &[usize], max_parallel: usize) -> String {
    let contiguous = tasks.windows(2).all(|w| w[1] == w[0] + 1);
    let list = match (tasks.first(), tasks.last()) {
        (Some(first), Some(last)) if contiguous && first != last => format!("{first}-{last}"),
        _ => tasks.iter().map(usize::to_string).collect::<Vec<_>>().join(","),
    };
    format!("{list}%{max_parallel}")
}

/// The folder of the job logs.
pub fn log_dir(o: &JobOptions) -> PathBuf {
    o.run_dir.join("slurm").join("logs")
}

/// `#SBATCH` lines both jobs share.
fn common(s: &mut String, o: &JobOptions) {
    for (key, value) in [("partition", &o.partition), ("constraint", &o.constraint)] {
        if let Some(v) = value {
            let _ = writeln!(s, "#SBATCH --{key}={}", quote(v));
        }
    }
    let _ = writeln!(s, "#SBATCH --chdir={}", path(&o.workdir));
}

/// The array job running 0-based `tasks` (task a runs shard a+1 of N).
pub fn array_script(o: &JobOptions, tasks: &[usize]) -> String {
    let n = o.shards;
    let mut s = String::from("#!/bin/bash\n");
    let quick = if o.quick { " (quick)" } else { "" };
    let _ =
        writeln!(s, "# bvhlab: experiment {}{quick} in {n} shards, written by `harness slurm submit`.", o.experiment);
    let _ = writeln!(
        s,
        "# Array task a runs shard a+1 of {n} into RUN_DIR/shard-<a+1>-of-{n}/; config hash {}.",
        o.config_hash
    );
    let _ = writeln!(s, "#SBATCH --job-name={}", quote(&format!("bvhlab-{}", o.experiment)));
    let _ = writeln!(s, "#SBATCH --array={}", array_spec(tasks, o.max_parallel));
    s.push_str("#SBATCH --ntasks=1\n");
    let _ = writeln!(s, "#SBATCH --cpus-per-task={}", o.cpus_per_task);
    if o.exclusive {
        s.push_str("#SBATCH --exclusive\n");
    }
    if let Some(t) = &o.time {
        let _ = writeln!(s, "#SBATCH --time={}", quote(t));
    }
    common(&mut s, o);
    let _ = writeln!(s, "#SBATCH --output={}", path(&log_dir(o).join("shard-task-%a-job-%A.log")));
    s.push_str("set -euo pipefail\n");
    let _ = writeln!(
        s,
        "exec {} run {}{} --shard env/{n} --config-hash {} --resume --out {}",
        path(&o.harness),
        path(&o.config),
        if o.quick { " --quick" } else { "" },
        o.config_hash,
        path(&o.run_dir),
    );
    s
}

/// The merge job, run once the array job `array_id` has ended in any state.
pub fn merge_script(o: &JobOptions, array_id: &str) -> String {
    let mut s = String::from("#!/bin/bash\n");
    let _ = writeln!(
        s,
        "# bvhlab: merge the {} shards of experiment {} once array job {array_id} has ended.",
        o.shards, o.experiment
    );
    let _ = writeln!(s, "#SBATCH --job-name={}", quote(&format!("bvhlab-{}-merge", o.experiment)));
    let _ = writeln!(s, "#SBATCH --dependency=afterany:{array_id}");
    s.push_str("#SBATCH --ntasks=1\n#SBATCH --cpus-per-task=1\n");
    common(&mut s, o);
    let _ = writeln!(s, "#SBATCH --output={}", path(&log_dir(o).join("merge-job-%j.log")));
    s.push_str("set -euo pipefail\n");
    let mixed = if o.allow_mixed_machines { " --allow-mixed-machines" } else { "" };
    let _ = writeln!(s, "exec {} merge {}{mixed}", path(&o.harness), path(&o.run_dir));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> JobOptions {
        JobOptions {
            experiment: "ci".into(),
            config: "/repo/experiments/ci.toml".into(),
            config_hash: "0123456789abcdef".into(),
            quick: true,
            shards: 4,
            max_parallel: 2,
            exclusive: true,
            cpus_per_task: 8,
            partition: Some("bench".into()),
            constraint: Some("avx2&zen3".into()),
            time: Some("1:00:00".into()),
            allow_mixed_machines: false,
            harness: "/repo/target/release/harness".into(),
            run_dir: "/repo/results/my run".into(),
            workdir: "/repo".into(),
        }
    }

    #[test]
    fn the_array_script_pins_binary_config_and_shards() {
        let text = array_script(&options(), &[0, 1, 2, 3]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "#!/bin/bash");
        for want in [
            "#SBATCH --job-name=bvhlab-ci",
            "#SBATCH --array=0-3%2",
            "#SBATCH --ntasks=1",
            "#SBATCH --cpus-per-task=8",
            "#SBATCH --exclusive",
            "#SBATCH --time=1:00:00",
            "#SBATCH --partition=bench",
            "#SBATCH --constraint='avx2&zen3'",
            "#SBATCH --chdir=/repo",
            "#SBATCH --output='/repo/results/my run/slurm/logs/shard-task-%a-job-%A.log'",
            "exec /repo/target/release/harness run /repo/experiments/ci.toml --quick --shard env/4 --config-hash \
             0123456789abcdef --resume --out '/repo/results/my run'",
        ] {
            assert!(lines.contains(&want), "missing {want:?} in\n{text}");
        }
        assert!(lines.iter().position(|l| l.starts_with("#SBATCH")) < lines.iter().position(|l| l.starts_with("set ")));
        let shared = array_script(&JobOptions { exclusive: false, partition: None, ..options() }, &[1, 3]);
        assert!(!shared.contains("--exclusive") && !shared.contains("--partition"), "{shared}");
        assert!(shared.contains("#SBATCH --array=1,3%2\n"), "{shared}");
    }

    #[test]
    fn the_merge_script_waits_for_the_array() {
        let text = merge_script(&JobOptions { allow_mixed_machines: true, ..options() }, "4242");
        for want in [
            "#SBATCH --dependency=afterany:4242",
            "#SBATCH --job-name=bvhlab-ci-merge",
            "#SBATCH --output='/repo/results/my run/slurm/logs/merge-job-%j.log'",
            "exec /repo/target/release/harness merge '/repo/results/my run' --allow-mixed-machines",
        ] {
            assert!(text.lines().any(|l| l == want), "missing {want:?} in\n{text}");
        }
        assert!(!text.contains("--exclusive") && !text.contains("--array"), "{text}");
    }

    #[test]
    fn array_specs_and_quoting() {
        assert_eq!(array_spec(&[0, 1, 2], 3), "0-2%3");
        assert_eq!(array_spec(&[0], 1), "0%1");
        assert_eq!(array_spec(&[0, 2, 5], 2), "0,2,5%2");
        assert_eq!(quote("/a/b-c_d.toml"), "/a/b-c_d.toml");
        assert_eq!(quote("it's"), "'it'\\''s'");
        assert_eq!(quote(""), "''");
    }
}
