//! Recording: the row of each timed repetition, and the one row of a rejected configuration, with what every row
//! shares (the experiment, provenance, shard).

use schema::Row;

use super::provenance::{self, Provenance, load_average_1m, timestamp_now};
use super::schedule::ConfigurationState;
use super::trial::Timing;
use super::validate::{Findings, Validation};
use crate::config::Experiment;
use crate::error::Error;
use crate::plan::{Configuration, PlannedRun};

/// What every row of one sweep shares: the experiment, where and how it was recorded, and its shard.
pub struct Recording<'a> {
    pub exp: &'a Experiment,
    pub provenance: &'a Provenance,
    pub shard: Option<(usize, usize)>,
}

/// When a run started: the 1-minute load average just before it and its RFC 3339 time.
#[derive(Clone)]
pub struct Started {
    load: f64,
    timestamp: String,
}

impl Started {
    pub fn now() -> Self {
        Started { load: load_average_1m(), timestamp: timestamp_now() }
    }
}

/// What a run left: its row (a timed repetition's, or a rejected configuration's one row; none for a warm-up), and
/// what it was, for the progress line.
pub struct Recorded {
    pub row: Option<Row>,
    pub what: String,
}

/// Configuration `c` in a few words: series, workload, objects, seed and strategy.
fn describe(c: &Configuration) -> String {
    let s = &c.settings;
    format!("{} {} objects={} seed={} {}", c.series, schema::Named::name(s.workload), s.objects, s.seed, s.strategy())
}

/// What timed run `run` of a validated configuration (`state`) records: for a repetition its row, `width` the
/// interval its configuration reached; nothing for a warm-up. A timed pass whose output differs from the counted
/// pass's is an error (the tracer is not deterministic).
pub fn timed(
    r: &Recording,
    state: &ConfigurationState,
    run: &PlannedRun,
    t: &Timing,
    width: Option<f64>,
    started: Started,
) -> Result<Recorded, Error> {
    let (c, validation) = (state.configuration, &state.validation);
    let Some(Validation::Validated { findings: v, .. }) = validation else {
        unreachable!("only a validated configuration is timed")
    };
    let Some(rep) = run.repetition else {
        return Ok(Recorded { row: None, what: format!("{} warm-up", describe(c)) });
    };
    if v.output_hash != t.output_hash {
        return Err(Error::Run(format!(
            "{}: the counted pass produced output {:016x} but the timed pass {:016x}: the tracer is not deterministic",
            describe(c),
            v.output_hash,
            t.output_hash
        )));
    }
    let mut row = validated(r, state, v, started);
    row.repetition = rep;
    let metric = |x: f64| x.is_finite().then_some(x);
    row.setup_s = metric(t.setup_s);
    row.scene_s = metric(t.scene_s);
    row.build_s = metric(t.build_s);
    row.trace_s = metric(t.trace_s);
    row.overhead_s = t.overhead_s.and_then(metric);
    row.trace_passes = t.trace_passes;
    row.sample_configs = t.sample_configs;
    row.steal_s = t.steal_s;
    row.process_id = t.process_id;
    row.peak_rss_bytes = t.peak_rss_bytes;
    row.encode_s = metric(t.encode_s);
    row.total_s = metric(t.total_s());
    row.mrays_per_s = metric(t.trace_s).map(|trace_s| v.counters.rays as f64 / trace_s.max(1e-12) / 1e6);
    row.tree_nodes = t.stats.nodes as u64;
    row.tree_leaves = t.stats.leaves as u64;
    row.tree_depth = t.stats.depth as u64;
    row.tree_bytes = t.stats.bytes as u64;
    row.sah_cost = t.stats.sah_cost;
    row.image_hash = format!("{:016x}", t.output_hash);
    row.scene_fingerprint = format!("{:016x}", t.scene_fingerprint);
    row.peer_info = t.peer_info.clone();
    row.simd_kernel_used = t.simd_kernel.clone();
    row.interval_width = width;
    let shown = width.map_or(String::new(), |w| format!(" (interval ±{:.1}%)", w * 50.0));
    let what = format!("{} rep {rep}: {:.3} s{shown}", describe(c), t.total_s());
    Ok(Recorded { row: Some(row.rounded()), what })
}

/// The one row of a configuration that validation rejected (`state`): what it found, no timing (it is never timed),
/// the kernel it was validated with; says why on stderr.
pub fn rejected(r: &Recording, state: &ConfigurationState, started: Started) -> Recorded {
    let (c, validation) = (state.configuration, &state.validation);
    let Some(Validation::Rejected(v)) = validation else { unreachable!("recorded as rejected once rejected") };
    note!("{}", v.failure(&describe(c)));
    let mut row = validated(r, state, v, started);
    row.image_hash = format!("{:016x}", v.output_hash);
    row.peer_info = "-".into();
    row.simd_kernel_used = match c.settings.simd_kernel {
        Some(k) => k.resolve_for(c.settings.accel_params().wide.leaf_block).name().to_string(),
        None => "-".into(),
    };
    Recorded { row: Some(row.rounded()), what: format!("{} FAILED validation", describe(c)) }
}

/// What every row of a configuration (`state`) records but its timing: settings, repetition rule, provenance,
/// counters and validation (`v`).
fn validated(r: &Recording, state: &ConfigurationState, v: &Findings, started: Started) -> Row {
    let (exp, p, shard, c) = (r.exp, r.provenance, r.shard, state.configuration);
    let Started { load, timestamp } = started;
    let w = &v.counters;
    let (nodes, boxes, prims) = w.per_ray();
    let mut row = Row::of(&c.settings);
    row.experiment = exp.name.clone();
    row.config_id = c.id.clone();
    row.series = c.series.clone();
    row.repetition_rule = state.repetition_rule.clone();
    row.rays = w.rays;
    row.primitives = v.primitives;
    row.nodes_per_ray = nodes;
    row.box_tests_per_ray = boxes;
    row.prim_tests_per_ray = prims;
    row.git_commit = p.git_commit.clone();
    row.git_dirty = p.git_dirty;
    row.rustc = p.rustc.clone();
    row.cpu_model = p.cpu_model.clone();
    row.logical_cores = p.logical_cores as u32;
    row.threads = c.threads;
    row.threads_used = c.settings.strategy().threads as u32;
    row.load_avg_1m = load;
    row.timestamp = timestamp;
    row.harness_version = p.harness_version.clone();
    row.validation = v.status;
    row.validated_against = v.reference.to_string();
    row.mismatches = v.judged.mismatches as u64;
    row.grazing = v.judged.grazing as u64;
    row.ties = v.judged.ties as u64;
    row.leaks = v.judged.leaks as u64;
    row.reference_checked = v.judged.reference_checked as u64;
    row.wrong_side = v.judged.wrong_side;
    let m = &p.machine;
    row.cpu_vendor = m.cpu_vendor.clone();
    row.cpu_signature = m.cpu_signature.clone();
    row.cpu_isa = m.cpu_isa.clone();
    row.cpu_caches = m.cpu_caches.clone();
    row.hypervisor = m.hypervisor;
    row.kernel = m.kernel.clone();
    row.target_features = m.target_features.clone();
    row.machine_id = m.machine_id.clone();
    row.boot_id = m.boot_id.clone();
    row.cargo_lock = p.cargo_lock.clone();
    row.slurm_job_id = p.slurm_job_id.clone();
    row.huge_pages = p.huge_pages.clone();
    if let Some((i, n)) = shard {
        row.shard = format!("{i}/{n}");
        row.node = if p.node.is_empty() { provenance::hostname() } else { p.node.clone() };
    } else {
        row.node = p.node.clone();
    }
    row
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use schema::{ValidationStatus, WrongSide};
    use tracer::counters::WorkCounters;

    use super::*;
    use crate::plan::Plan;
    use crate::run::reference::Judgement;
    use crate::run::schedule::Schedule;

    #[test]
    fn rejected_rows_leave_every_metric_empty() {
        let exp = Experiment::parse(Path::new("t.toml"), "name = \"t\"\n[sweep]\nworkload = \"primary\"\n").unwrap();
        let plan = Plan::new(&exp, 2).unwrap();
        let counters = WorkCounters { rays: 786_432, ..Default::default() };
        let v = Findings {
            status: ValidationStatus::Failed,
            counters,
            output_hash: 1,
            reference: "reference",
            judged: Judgement {
                mismatches: 3,
                grazing: 2,
                ties: 4,
                leaks: 5,
                reference_checked: 16_384,
                wrong_side: WrongSide::Backend,
            },
            rays: 786_432,
            primitives: 1000,
        };
        let provenance = Provenance::collect();
        let recording = Recording { exp: &exp, provenance: &provenance, shard: None };
        let started = Started { load: 0.5, timestamp: "t".into() };
        let mut schedule = Schedule::new(&exp, &plan);
        schedule.states[0].validation = Some(Validation::Rejected(v));
        let row = rejected(&recording, &schedule.states[0], started).row.unwrap();
        assert_eq!((row.validation, row.mismatches), (ValidationStatus::Failed, 3));
        assert_eq!((row.grazing, row.reference_checked, row.wrong_side), (2, 16_384, WrongSide::Backend));
        assert_eq!((row.ties, row.leaks), (4, 5));
        assert_eq!(row.primitives, 1000, "a rejected row records its scene's size too");
        let text = format!("{}\n{}", schema::row::header(), schema::row::csv_line(&row).unwrap());
        let back = &schema::row::read_rows(&text).unwrap()[0];
        let metrics =
            [back.setup_s, back.scene_s, back.build_s, back.trace_s, back.encode_s, back.total_s, back.mrays_per_s];
        assert!(metrics.iter().all(Option::is_none), "{metrics:?} in {text}");
    }
}
