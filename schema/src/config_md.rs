//! `docs/configuration.md`, the configuration reference, generated from the declaration (a test keeps the file in
//! step, as for `report/ROWS.md`).

use crate::columns::{Axis, REPLACED};

/// The keys of a config around the sweep's settings, with what they take (the harness parses them).
const TABLES: &str = "\
| key | what it takes |
|---|---|
| `name` | the experiment's name; results go to `results/<name>/` |
| `description` | free text for the report |
| `reference` | the series label speedups are measured against |
| `speedup_metric` | the metric speedups are ratios of (default `total_s` for renders, `trace_s` for ray sets) |
| `repetitions` | 1..=1000, or `\"auto\"` with `min_repetitions` (default 10), `max_repetitions` (default 24), `target_ci_width` (default 0.02: ±1%); default `\"auto\"` with those: a configuration stops after 10 to 24 rounds, once the 95% interval of its ratio to the `reference` (of its own median without one) is within ±1% (docs/statistics.md, \"The defaults\"). Cost: every round is a sample (and, by default, a process) per configuration |
| `warmups` | unrecorded runs of each configuration before its first repetition, 0..=100 (default 1: one sample per configuration) |
| `order` | `interleaved` (default), `sequential` or `shuffled` (with `order_seed`) |
| `sample_ms` | the shortest timed sample in ms, 0..=10000 (default 50; 0: one pass, as every row before #60): each timed run traces its job again until this long has passed and records the median pass (`trace_passes`); with `order = \"interleaved\"` the series of one point are built together and traced a pass of each in turn (`sample_configs`); a long sample that saw hypervisor steal time is taken again (`steal_s`). Cost: at least this long per run, where one pass of a small scene takes a few ms |
| `processes` | processes each configuration is timed in, 1..=64 (default: one per repetition — `repetitions`, or `max_repetitions` with `\"auto\"` — at most 64; 1: this one, or one worker for backends with threads of their own): its timed runs fall into that many blocks of consecutive runs, each timed in a worker process of its own started for it (and warmed by one untimed pass) and ended before the next, so that what lasts a process's life (docs/statistics.md: an offset of up to ±4.5% between two series of one process) varies between its runs and the interval, which resamples processes, sees it. Cost: a worker's start and warm-up (its scene, an untimed build and an untimed pass) per process, about one more run of one pass |
| `[sweep]` | any setting below, a value or a list; the runs are the cartesian product |
| `[[series]]` | `label` and the settings it fixes; each series runs the sweep's product |
| `[[exclude]]` | settings (and/or `series`) whose every match is skipped |
| `[quick]` | overrides for `--quick`: repetitions (and the auto keys), warmups, settings |
| `[[plot]]` | `file`, `title`, `kind` (`metric`, `speedup`, `efficiency`, `trade-off`: metric `x` against metric `y`, one point per series), `x` (a setting: numbers on a numeric axis, words such as `workload` as categories; or `primitives`, the scene's size as traced), `y` (a metric or numeric counter; log-log metric plots give each line's fitted growth), `log_x`, `log_y`, `series`, `where`, `reference` (the series a speedup plot compares with, instead of the experiment's) |
| `[[claim]]` | `text`, `paper`, `if_fails` (why it fails where it does, printed only then), `kind` (`faster` with `factor` and `per_thread`, or `within` with `tolerance`), `series`, `than`, `metric`, `min_objects`, `max_objects`, `where` |
| `[headline]` | `series`, `against` (a label or a list: the faster at each point is the bar), `metric`: the comparison the report, the site and the index lead with, read as the bar's time over the series' (above 1: the series is faster); the page's ratio matrix, summary speedups and speedup figures without a `reference` compare with the first of `against`. Absent: the first `faster` claim's series against its `than` (with every other `than` of that series' claims of the same factor), else the first series against `reference` |
";

/// The whole text of configuration.md.
pub fn text() -> String {
    let mut md = String::from(
        "# Configuration reference\n\n\
         Generated from `schema/src/columns.rs` (the one declaration of every setting); `cargo test -p schema` fails \
         when this file is out of step, and `BVHLAB_WRITE_DOCS=1 cargo test -p schema` rewrites it. \
         [experiments.md](experiments.md) shows a whole config and how a run uses it; `report/ROWS.md` lists the \
         columns a run records.\n\n\
         ## The tables of a config\n\n",
    );
    md.push_str(TABLES);
    md.push_str(
        "\n## Settings\n\n\
         Every setting may be given in `[sweep]`, a `[[series]]`, an `[[exclude]]` or `[quick]`. A setting that \
         does not apply to a configuration (a list has no split, serial has one thread, only `wide-bvh` has \
         `node_width`) is normalized to the value in the last column, so it never multiplies runs.\n\n\
         | key | default | allowed | unit | where it does not apply | meaning |\n|---|---|---|---|---|---|\n",
    );
    for &axis in Axis::ALL {
        let na = axis.not_applicable().map_or_else(|| "applies always".to_string(), |v| format!("`{v}`"));
        md.push_str(&format!(
            "| `{}` | `{}` | {} | {} | {na} | {} |\n",
            axis.key(),
            axis.default_value(),
            axis.allowed().replace('|', "\\|"),
            axis.unit(),
            axis.doc().trim().replace('|', "\\|"),
        ));
    }
    md.push_str("\nKeys of earlier versions, refused with what to write instead:\n\n");
    for r in REPLACED {
        md.push_str(&format!("- `{}`: {}.\n", r.key, r.instead()));
    }
    md
}

#[cfg(test)]
mod tests {
    #[test]
    fn docs_configuration_md_is_the_generated_reference() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/configuration.md");
        let want = super::text();
        if std::env::var_os("BVHLAB_WRITE_DOCS").is_some() {
            std::fs::write(&path, &want).unwrap();
        }
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            have == want,
            "{} is out of step with schema/src/columns.rs: run `BVHLAB_WRITE_DOCS=1 cargo test -p schema`",
            path.display()
        );
    }
}
