//! REPORT.md, answer first: the headline, claims, figures with captions, what ran, a summary table pooled over
//! seeds, the config.

use schema::column;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use crate::claims::ClaimResult;
use crate::pool;
use crate::rows::{POINT, Rows, Run};
use crate::spec::{ClaimKind, ReportSpec, Verdict};
use crate::stats;

/// The whole REPORT.md text.
pub fn report(rows: &Rows, spec: &ReportSpec, claims: &[ClaimResult]) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# {}\n", spec.name);
    headline(&mut md, rows, spec, claims);
    if !spec.description.trim().is_empty() {
        let _ = writeln!(md, "{}\n", spec.description.trim());
    }
    for warning in &spec.warnings {
        let _ = writeln!(md, "> **Warning:** {}\n", cell(warning));
    }
    if !rows.failed.is_empty() {
        md.push_str(
            "## ⚠ VALIDATION FAILURES

",
        );
        md.push_str("These configurations disagreed with the reference before timing and were **not timed**; their series lack these points.

");
        md.push_str(
            "Each disagreement was decided by an f64 brute force: `wrong` says whose answer it showed wrong \
(beyond the f32 rounding bound of the primitive test); grazing rays, edge ties and leaks (within it) are tolerated and counted apart.

",
        );
        md.push_str("| series | accel | scene | objects | seed | workload | threads | rays disagreeing | wrong | grazing (tolerated) | reference |
|---|---|---|---|---|---|---|---|---|---|---|
");
        let columns = [
            column::accel,
            column::scene,
            column::objects,
            column::seed,
            column::workload,
            column::threads,
            column::mismatches,
            column::wrong_side,
            column::grazing,
            column::validated_against,
        ];
        for r in &rows.failed {
            let cells: Vec<&str> = columns.iter().map(|&c| r.text(c)).collect();
            let _ = writeln!(md, "| {} | {} |", r.series(), cells.join(" | "));
        }
        md.push('\n');
    }
    claims_table(&mut md, spec, claims);
    figures(&mut md, spec);
    what_ran(&mut md, rows, spec);
    if !spec.notes.is_empty() {
        md.push_str("## Notes\n\n");
        for note in &spec.notes {
            let _ = writeln!(md, "- {note}");
        }
        md.push('\n');
    }
    summary_table(&mut md, rows, spec);
    across_machines(&mut md, rows, spec);
    md.push_str("## Config as run\n\n```toml\n");
    md.push_str(spec.config_text.trim_end());
    md.push_str("\n```\n\n## Regenerate\n\n");
    md.push_str(
        "This file, `summary.csv`, `summary.parquet`, `runs.parquet` and `figures/` are rebuilt from `runs.csv` \
         by `harness report <dir>` (with `<dir>` this directory).\n",
    );
    md
}

/// Distinct values of a text column, in sorted order, joined.
fn distinct(runs: &[Run], column: &str) -> String {
    let values: BTreeSet<&str> = runs.iter().map(|r| r.text(column)).collect();
    values.into_iter().collect::<Vec<_>>().join(", ")
}

/// Whether some configuration's runs took turns between enough processes (`processes`) that its ratios' intervals
/// resample processes ([`crate::pool::RoundRatios::estimate`]).
fn timed_in_several_processes(runs: &[Run]) -> bool {
    let mut by_config: std::collections::HashMap<&str, Vec<&Run>> = Default::default();
    for r in runs {
        by_config.entry(r.row.config_id.as_str()).or_default().push(r);
    }
    by_config.values().any(|group| crate::pool::processes(group.iter().copied()) >= stats::MIN_SAMPLES_FOR_INTERVAL)
}

fn what_ran(md: &mut String, rows: &Rows, spec: &ReportSpec) {
    let runs = &rows.runs;
    let configs: BTreeSet<&str> = runs.iter().map(Run::config_id).collect();
    let reps: Vec<usize> = configs.iter().map(|id| runs.iter().filter(|r| r.config_id() == *id).count()).collect();
    let (rep_min, rep_max) = (reps.iter().min().unwrap_or(&0), reps.iter().max().unwrap_or(&0));
    let reps_text = if rep_min == rep_max { format!("{rep_min}") } else { format!("{rep_min}–{rep_max}") };
    let loads = pool::samples(runs, column::load_avg_1m);
    let load_min = loads.iter().copied().fold(f64::INFINITY, f64::min);
    let load_max = loads.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let dirty = runs.iter().any(|r| r.text(column::git_dirty) == "true");
    let stamps: BTreeSet<&str> = runs.iter().map(|r| r.text(column::timestamp)).collect();

    md.push_str("## What ran\n\n");
    let _ = writeln!(md, "- Experiment: {} (rows say: {})", spec.name, distinct(runs, column::experiment));
    let _ = writeln!(
        md,
        "- Rows: {} timed repetitions of {} configurations ({reps_text} repetitions each)",
        runs.len(),
        configs.len()
    );
    let _ = writeln!(
        md,
        "- Machine: {}, {} logical cores; 1-minute load average min {} / median {} / max {}",
        distinct(runs, column::cpu_model),
        distinct(runs, column::logical_cores),
        num(load_min),
        num(stats::median(&loads)),
        num(load_max)
    );
    machines(md, runs);
    repetitions_line(md, runs);
    let _ = writeln!(
        md,
        "- Code: commit {}{}; {}; harness {}",
        distinct(runs, column::git_commit),
        if dirty { " (dirty: uncommitted changes)" } else { " (clean)" },
        distinct(runs, column::rustc),
        distinct(runs, column::harness_version)
    );
    validation_line(md, runs);
    overhead_line(md, runs);
    steal_line(md, runs);
    let _ =
        writeln!(md, "- Time: {} to {}", stamps.first().copied().unwrap_or("?"), stamps.last().copied().unwrap_or("?"));
    let _ = writeln!(
        md,
        "- Statistics: medians over repetitions (and seeds where pooled); intervals are the median's distribution-free \
         95% interval (order statistics; none below {} values, shown as —), for a ratio of two series that ran in the \
         same rounds that of the median of their per-round ratios, else a 95% percentile bootstrap ({} resamples) \
         of the ratio of medians{}\n",
        stats::MIN_SAMPLES_FOR_INTERVAL,
        stats::RESAMPLES,
        if timed_in_several_processes(runs) {
            format!(
                "; where the rounds ran in {} or more pairs of processes (`processes`, `process_id`), that interval \
                 resamples processes, not rounds (a cluster bootstrap, {} resamples: rounds of one process share its \
                 offset)",
                stats::MIN_SAMPLES_FOR_INTERVAL,
                stats::RESAMPLES
            )
        } else {
            String::new()
        }
    );
    let over = runs.iter().filter(|r| r.num(column::threads) > r.num(column::logical_cores)).count();
    if over > 0 {
        let _ = writeln!(
            md,
            "> **Warning:** {over} rows ran with more threads than the machine's logical cores; \
             their times measure oversubscription.\n"
        );
    }
}

/// Nanoseconds per ray of a run's `metric` (a time in seconds over its rays); NaN without rays.
fn ns_per_ray(run: &Run, metric: &str) -> f64 {
    let rays = run.num(column::rays);
    if rays > 0.0 { run.num(metric) / rays * 1e9 } else { f64::NAN }
}

/// True when the runs recorded the harness's own cost (`overhead_s`: ray sets recorded since it existed).
fn has_overhead(runs: &[Run]) -> bool {
    runs.iter().any(|r| r.num(column::overhead_s).is_finite())
}

/// The harness's own cost per ray, as the `null` backend measured it after every timed ray-set trace.
fn overhead_line(md: &mut String, runs: &[Run]) {
    if !has_overhead(runs) {
        return;
    }
    let per_ray: Vec<f64> = runs.iter().map(|r| ns_per_ray(r, column::overhead_s)).filter(|v| v.is_finite()).collect();
    let (lo, hi) = per_ray.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let _ = writeln!(
        md,
        "- Harness overhead: the `null` backend (every ray misses, nothing read) traced the same rays under the same \
         strategy after every timed trace in {} to {} ns per ray (median {}); every trace time includes it (the \
         summary's `harness ns/ray` beside each `median trace ns/ray`)",
        num(lo),
        num(hi),
        num(stats::median(&per_ray))
    );
}

/// How many timed samples saw the hypervisor take the CPU (`steal_s`), and how much: a recording where many did
/// has wider intervals than the machine's resolution, and is worth recording again (nothing when none did).
fn steal_line(md: &mut String, runs: &[Run]) {
    let measured: Vec<f64> = runs.iter().map(|r| r.num(column::steal_s)).filter(|v| v.is_finite()).collect();
    let stolen: Vec<f64> = measured.iter().copied().filter(|&v| v > 0.0).collect();
    if stolen.is_empty() {
        return;
    }
    let max = stolen.iter().copied().fold(0.0, f64::max);
    let _ = writeln!(
        md,
        "- Hypervisor steal: {} of {} timed samples lost CPU time to other tenants (median {} s, max {} s among them; \
         each was taken again up to 3 times, keeping the least); the rounds they fell in widen their points' intervals",
        stolen.len(),
        measured.len(),
        num(stats::median(&stolen)),
        num(max)
    );
}

/// How many repetitions the configurations got under `repetitions = "auto"`: how many stopped because their
/// interval was narrow enough, and how many at the maximum (nothing for fixed repetitions).
fn repetitions_line(md: &mut String, runs: &[Run]) {
    // Per configuration: its rule, repetitions and the interval width after its last one.
    let mut configs: BTreeMap<&str, (&str, u32, f64)> = BTreeMap::new();
    for r in runs.iter().filter(|r| r.text(column::validation) != schema::Named::name(schema::ValidationStatus::Failed))
    {
        let e = configs.entry(r.config_id()).or_insert((r.text(column::repetition_rule), 0, f64::NAN));
        e.1 += 1;
        e.2 = r.num(column::interval_width);
    }
    let rules: BTreeSet<&str> = configs.values().map(|c| c.0).filter(|rule| rule.starts_with("auto ")).collect();
    for rule in rules {
        // `auto MIN..MAX width W METRIC`
        let words: Vec<&str> = rule.split(' ').collect();
        let (Some(max), Some(target)) = (
            words.get(1).and_then(|r| r.split("..").nth(1)).and_then(|m| m.parse::<u32>().ok()),
            words.get(3).and_then(|w| w.parse::<f64>().ok()),
        ) else {
            continue;
        };
        let metric = words.get(4).copied().unwrap_or("?");
        let of_rule: Vec<&(&str, u32, f64)> = configs.values().filter(|c| c.0 == rule).collect();
        let narrow = of_rule.iter().filter(|c| c.2 <= target).count();
        let at_max = of_rule.iter().filter(|c| c.2 > target && c.1 >= max).count();
        let counts: Vec<f64> = of_rule.iter().map(|c| c.1 as f64).collect();
        let widest = of_rule.iter().map(|c| c.2).filter(|w| w.is_finite()).fold(0.0, f64::max);
        let _ = writeln!(
            md,
            "- Repetitions: `{rule}`: each configuration timed until the 95% interval of its median {metric} was at \
             most {:.1}% of the median wide (at least {} and at most {max} times); {narrow} of {} configurations got \
             there, {at_max} stopped at {max} (widest final interval {:.1}%); repetitions per configuration: median {}, \
             total {}",
            target * 100.0,
            words.get(1).and_then(|r| r.split("..").next()).unwrap_or("?"),
            of_rule.len(),
            widest * 100.0,
            stats::median(&counts),
            counts.iter().sum::<f64>()
        );
    }
}

/// How the timed configurations were validated: references, rays of the references checked against f64 brute
/// force, and grazing rays tolerated.
fn validation_line(md: &mut String, runs: &[Run]) {
    let mut configs: std::collections::BTreeMap<&str, &Run> = Default::default();
    for r in runs {
        configs.entry(r.config_id()).or_insert(r);
    }
    let grazing: Vec<&&Run> = configs.values().filter(|r| r.num(column::grazing) > 0.0).collect();
    let graze_rays: f64 = grazing.iter().map(|r| r.num(column::grazing)).sum();
    let checked = configs.values().map(|r| r.num(column::reference_checked)).fold(0.0, f64::max);
    let _ = write!(
        md,
        "- Validation: {} timed configurations agreed with their reference ({}) before timing",
        configs.len(),
        distinct(runs, column::validated_against)
    );
    if checked > 0.0 {
        let _ = write!(md, "; each reference checked against f64 brute force on up to {checked} rays of its ray set");
    }
    if !grazing.is_empty() {
        let _ = write!(
            md,
            "; {graze_rays} grazing rays tolerated in {} configurations (f64 brute force puts them within the f32 \
             rounding bound of the primitive test)",
            grazing.len()
        );
    }
    for (c, what) in [(column::ties, "edge ties (same distance, another triangle)"), (column::leaks, "leaks")] {
        let mut by_series: std::collections::BTreeMap<&str, f64> = Default::default();
        for r in configs.values().filter(|r| r.num(c) > 0.0) {
            *by_series.entry(r.series()).or_default() += r.num(c);
        }
        if !by_series.is_empty() {
            let each: Vec<String> = by_series.iter().map(|(s, n)| format!("{s} {n}")).collect();
            let _ = write!(md, "; {what}: {}", each.join(", "));
        }
    }
    md.push('\n');
}

/// One line per machine that recorded rows (rows recorded before machine identity existed are left out).
fn machines(md: &mut String, runs: &[Run]) {
    let mut seen = BTreeSet::new();
    for r in runs.iter().filter(|r| !r.text(column::machine_id).is_empty()) {
        if seen.insert(r.text(column::machine_id)) {
            let hypervisor = if r.text(column::hypervisor) == "true" { ", virtual machine" } else { "" };
            let _ = writeln!(
                md,
                "  - machine `{}`: {} ({} {}), ISA {}, caches {}, kernel {}{hypervisor}; compiled for {}",
                r.text(column::machine_id),
                r.text(column::cpu_model),
                r.text(column::cpu_vendor),
                r.text(column::cpu_signature),
                r.text(column::cpu_isa),
                r.text(column::cpu_caches),
                r.text(column::kernel),
                if r.text(column::target_features).is_empty() {
                    "the baseline target"
                } else {
                    r.text(column::target_features)
                }
            );
        }
    }
    if seen.len() > 1 {
        let _ =
            writeln!(md, "  - rows of different machines are never pooled: each machine's runs are their own points");
    }
}

/// The headline comparison in a sentence and a grid, and the claims' verdicts counted.
fn headline(md: &mut String, rows: &Rows, spec: &ReportSpec, claims: &[ClaimResult]) {
    if let Some(h) = crate::headline::of(spec, &rows.runs) {
        let _ = writeln!(md, "**{}**\n", h.sentence());
        if h.cells.len() > 1 {
            md.push_str(&h.markdown());
            md.push_str(
                "\nEach cell: the bar's time over ours, median [95% interval]; **bold**: ours faster, `slower`: \
                 ours slower, `~`: not told apart.\n\n",
            );
        }
    }
    if !claims.is_empty() {
        let count = |v| claims.iter().filter(|c| c.verdict == v).count();
        let _ = writeln!(
            md,
            "Claims: {} of {} hold, {} fail, {} inconclusive ([Claims](#claims)).\n",
            count(Verdict::Holds),
            claims.len(),
            count(Verdict::Fails),
            count(Verdict::Inconclusive)
        );
    }
}

fn figures(md: &mut String, spec: &ReportSpec) {
    if spec.plots.is_empty() {
        return;
    }
    md.push_str("## Figures\n\n");
    for plot in &spec.plots {
        let title = plot.title.replace(['[', ']'], "");
        let _ = writeln!(
            md,
            "![{title}](figures/{}.svg)\n\n*{title}.* {} [PNG](figures/{}.png)\n",
            plot.file,
            caption(spec, plot),
            plot.file
        );
    }
}

/// What a figure's y axis reads, in words and in the one direction.
fn caption(spec: &ReportSpec, plot: &crate::spec::PlotSpec) -> String {
    use crate::spec::PlotKind;
    let reference = plot.reference.clone().or_else(|| spec.reference.clone()).unwrap_or_default();
    match plot.kind {
        PlotKind::Speedup => format!(
            "{reference}'s {} over each series': above 1, the series is faster; bars are 95% intervals.",
            plot.y
        ),
        PlotKind::Efficiency => format!("Speedup over {reference} divided by the thread count: 1 is linear scaling."),
        PlotKind::Metric => {
            let lower = match plot.y.as_str() {
                y if y.ends_with("_per_s") => "higher is faster",
                y if y.ends_with("_s") => "lower is faster",
                _ => "lower is less",
            };
            let mut text = format!("Median {} per series, bars 95% intervals: {lower}.", plot.y);
            if plot.log_x && plot.log_y && crate::figures::grows_with_size(&plot.x) {
                text.push_str(&format!(
                    " Each legend entry ends with its line's growth, {} ∝ {}^k, k fitted by least squares through the \
                     medians on these log-log axes.",
                    plot.y, plot.x
                ));
            }
            text
        }
        PlotKind::TradeOff => format!("Median {} against median {}: lower-left is better for times.", plot.x, plot.y),
    }
}

fn claims_table(md: &mut String, spec: &ReportSpec, claims: &[ClaimResult]) {
    if claims.is_empty() {
        return;
    }
    md.push_str("## Claims\n\n");
    let paper = spec.claims.iter().any(|c| c.paper.is_some());
    md.push_str(if paper {
        "| claim | the paper said | measured ratio [95% CI] | threshold | verdict | detail |\n|---|---|---|---|---|---|\n"
    } else {
        "| claim | measured ratio [95% CI] | threshold | verdict | detail |\n|---|---|---|---|---|\n"
    });
    for (claim, result) in spec.claims.iter().zip(claims) {
        let measured = if result.ratio.is_finite() {
            format!("{} [{}, {}]", num(result.ratio), num(result.lo), num(result.hi))
        } else {
            "—".to_string()
        };
        let threshold = match claim.kind {
            ClaimKind::Faster { factor, per_thread: true, .. } if result.threshold.is_finite() => format!(
                "≥ {} ({} × {} threads)",
                compact(result.threshold),
                compact(factor),
                compact(result.threshold / factor)
            ),
            ClaimKind::Faster { .. } => format!("≥ {}", compact(result.threshold)),
            ClaimKind::Within { tolerance, .. } => format!("1 ± {}", compact(tolerance)),
        };
        let verdict = format!(
            "{}{}",
            match result.verdict {
                Verdict::Holds => "**holds**",
                Verdict::Fails => "**fails**",
                Verdict::Inconclusive => "inconclusive",
            },
            points_held(result)
        );
        let paper = if paper { format!(" {} |", cell(claim.paper.as_deref().unwrap_or("—"))) } else { String::new() };
        let _ = writeln!(
            md,
            "| {} |{paper} {measured} | {threshold} | {verdict} | {} |",
            cell(&result.text),
            cell(&result.detail)
        );
    }
    md.push_str(
        "\nRatios are `metric(than) / metric(series)` at each point, pooled over seeds: above 1, the claim's series \
         is faster.\n\n",
    );
    claim_failures(md, spec, claims);
    claim_points(md, spec, claims);
}

/// " (14/16 points hold)" for a claim judged at several points, else nothing.
pub fn points_held(result: &ClaimResult) -> String {
    let n = result.points.len();
    if n < 2 {
        return String::new();
    }
    let held = result.points.iter().filter(|p| p.verdict == Verdict::Holds).count();
    format!(" ({held}/{n} points hold)")
}

/// The config's `if_fails` of every claim that fails somewhere: why, as measured apart, with the points it fails at.
fn claim_failures(md: &mut String, spec: &ReportSpec, claims: &[ClaimResult]) {
    let failing: Vec<_> = spec
        .claims
        .iter()
        .zip(claims)
        .filter_map(|(s, c)| Some((s.if_fails.as_deref()?, c)))
        .filter(|(_, c)| c.verdict == Verdict::Fails || c.points.iter().any(|p| p.verdict == Verdict::Fails))
        .collect();
    if failing.is_empty() {
        return;
    }
    md.push_str("### Why claims fail\n\n");
    for (why, claim) in failing {
        let at: Vec<&str> =
            claim.points.iter().filter(|p| p.verdict == Verdict::Fails).map(|p| p.label.as_str()).collect();
        let at = match at.len() {
            0 => String::new(),
            1..=4 => format!(" (fails at {})", at.join("; ")),
            n => format!(" (fails at {n} of {} points)", claim.points.len()),
        };
        let _ = writeln!(md, "- **{}**{at}: {}", claim.text.replace('\n', " "), why.replace('\n', " "));
    }
    md.push('\n');
}

/// Every point of each claim compared at more than one point: where it holds and where it does not.
fn claim_points(md: &mut String, spec: &ReportSpec, claims: &[ClaimResult]) {
    let several: Vec<_> = spec.claims.iter().zip(claims).filter(|(_, c)| c.points.len() > 1).collect();
    if several.is_empty() {
        return;
    }
    md.push_str("### Claims point by point\n\n");
    for (spec, claim) in several {
        let _ = writeln!(md, "**{}**\n", claim.text.replace('\n', " "));
        md.push_str("| point | ratio [95% CI] | threshold | verdict |\n|---|---|---|---|\n");
        for p in &claim.points {
            let verdict = match (p.verdict, p.more) {
                (Verdict::Holds, _) => "holds".to_string(),
                (Verdict::Fails, _) => "**fails**".to_string(),
                (Verdict::Inconclusive, Some(m)) if m.count() <= crate::claims::SETTLE_LIMIT => {
                    format!("inconclusive ({m})")
                }
                (Verdict::Inconclusive, _) => "inconclusive (on the threshold)".to_string(),
            };
            let threshold = match spec.kind {
                ClaimKind::Faster { .. } => format!("≥ {}", compact(p.threshold)),
                ClaimKind::Within { .. } => format!("1 ± {}", compact(p.threshold)),
            };
            let _ = writeln!(
                md,
                "| {} | {} [{}, {}] | {threshold} | {verdict} |",
                cell(&p.label),
                num(p.ratio),
                num(p.lo),
                num(p.hi),
            );
        }
        md.push('\n');
    }
}

fn summary_table(md: &mut String, rows: &Rows, spec: &ReportSpec) {
    let runs = &rows.runs;
    // Settings a series' own table fixes are implied by its label: only the sweep's axes get a column.
    let by_series: BTreeSet<&str> = spec.series_fixed.values().flatten().map(String::as_str).collect();
    let varying: Vec<&str> = POINT
        .iter()
        .copied()
        .filter(|c| *c != column::seed && !by_series.contains(c))
        .filter(|c| runs.iter().map(|r| r.text(c)).collect::<BTreeSet<_>>().len() > 1)
        .collect();
    let several_seeds = runs.iter().map(|r| r.text(column::seed)).collect::<BTreeSet<_>>().len() > 1;
    md.push_str("## Summary\n\n");
    md.push_str(
        "One row per configuration with seeds pooled, medians [95% intervals]; every column and statistic is in \
         `summary.csv` and `summary.parquet`.\n\n",
    );
    let mut header = vec![column::series.to_string()];
    header.extend(varying.iter().map(|c| c.to_string()));
    if several_seeds {
        header.push("seeds".into());
    }
    header.extend(["n", "time (s)", "Mrays/s"].map(String::from));
    let overhead = has_overhead(runs);
    if overhead {
        header.extend(["trace ns/ray", "harness ns/ray"].map(String::from));
    }
    let bar = spec.bar();
    if let Some(bar) = &bar {
        header.push(format!("how much faster than {bar}"));
    }
    let _ = writeln!(md, "| {} |", header.iter().map(|h| cell(h)).collect::<Vec<_>>().join(" | "));
    let _ = writeln!(md, "|{}", "---|".repeat(header.len()));
    for group in pool::seed_pools(runs) {
        let first = group[0];
        let metric = spec.speedup_metric_of(first.text(column::workload));
        let mut cells = vec![cell(first.series())];
        cells.extend(varying.iter().map(|c| cell(first.text(c))));
        if several_seeds {
            let seeds: BTreeSet<&str> = group.iter().map(|r| r.text(column::seed)).collect();
            cells.push(seeds.len().to_string());
        }
        cells.push(group.len().to_string());
        let time = stats::median_ci(&pool::samples(group.iter().copied(), metric));
        cells.push(format!("{} [{}, {}]", num(time.value), num(time.lo), num(time.hi)));
        cells.push(num(stats::median(&pool::samples(group.iter().copied(), column::mrays_per_s))));
        if overhead {
            let median_of = |metric: &str| {
                let values: Vec<f64> = group.iter().map(|r| ns_per_ray(r, metric)).filter(|v| v.is_finite()).collect();
                if values.is_empty() { "—".to_string() } else { num(stats::median(&values)) }
            };
            cells.push(median_of(column::trace_s));
            cells.push(median_of(column::overhead_s));
        }
        if let Some(bar) = &bar {
            let key = format!("{}|pooled speedup", first.config_id());
            cells.push(match pool::ratio_against(spec, runs, bar, &group, metric, &[column::seed], &key) {
                Some(e) => format!("{} [{}, {}]", num(e.value), num(e.lo), num(e.hi)),
                None => "—".into(),
            });
        }
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
    let metrics: BTreeSet<&str> = runs.iter().map(|r| spec.speedup_metric_of(r.text(column::workload))).collect();
    let _ = writeln!(
        md,
        "\nTime: {}. {}",
        metrics.into_iter().collect::<Vec<_>>().join(" or "),
        bar.map(|b| format!("How much faster: {b}'s time over the configuration's, above 1 = faster than {b}."))
            .unwrap_or_default()
    );
    md.push('\n');
}

/// Where rows come from several machines: each configuration's speedup on every machine (taken against the
/// reference's runs on that machine) and their geometric mean.
fn across_machines(md: &mut String, rows: &Rows, spec: &ReportSpec) {
    let runs = &rows.runs;
    let machines: BTreeSet<&str> = runs.iter().map(|r| r.text(column::machine_id)).filter(|m| !m.is_empty()).collect();
    let Some(reference) = &spec.reference else { return };
    if machines.len() < 2 {
        return;
    }
    let varying: Vec<&str> = POINT
        .iter()
        .copied()
        .filter(|c| *c != column::seed && *c != column::machine_id)
        .filter(|c| runs.iter().map(|r| r.text(c)).collect::<BTreeSet<_>>().len() > 1)
        .collect();
    md.push_str(
        "## Across machines

",
    );
    let _ = writeln!(
        md,
        "Rows come from {} machines. Speedups over {reference} are taken within each machine (against the reference's \
         runs on that machine), then combined across machines as the **geometric mean** of the per-machine speedups; \
         absolute times of different machines are never pooled.\n",
        machines.len()
    );
    let mut header = vec![column::series.to_string()];
    header.extend(varying.iter().map(|c| c.to_string()));
    header.extend(["speedup per machine", "machines", "geometric mean"].map(String::from));
    let _ = writeln!(md, "| {} |", header.join(" | "));
    let _ = writeln!(md, "|{}", "---|".repeat(header.len()));
    // Seed pools (one machine each) grouped by everything but the machine.
    let mut groups: Vec<(Vec<String>, Vec<Vec<&Run>>)> = Vec::new();
    for pool in pool::seed_pools(runs) {
        let key = schema::row::pool_key(pool[0].series(), |c| {
            if c == column::machine_id { String::new() } else { pool[0].text(c).to_string() }
        });
        match groups.iter_mut().find(|(k, _)| *k == key) {
            Some((_, pools)) => pools.push(pool),
            None => groups.push((key, vec![pool])),
        }
    }
    for (_, pools) in groups {
        let first = pools[0][0];
        let metric = spec.speedup_metric_of(first.text(column::workload));
        let per_machine: Vec<(String, f64)> = pools
            .iter()
            .filter_map(|group| {
                let key = format!("{}|{}|machine speedup", group[0].config_id(), group[0].text(column::machine_id));
                let e = pool::ratio_against(spec, runs, reference, group, metric, &[column::seed], &key)?;
                Some((group[0].text(column::machine_id).to_string(), e.value))
            })
            .filter(|(_, v)| v.is_finite() && *v > 0.0)
            .collect();
        if per_machine.is_empty() {
            continue;
        }
        let geomean = (per_machine.iter().map(|(_, v)| v.ln()).sum::<f64>() / per_machine.len() as f64).exp();
        let mut cells = vec![format!("`{}`", cell(first.series()))];
        cells.extend(varying.iter().map(|c| cell(first.text(c))));
        cells.push(per_machine.iter().map(|(m, v)| format!("`{m}` {}", num(*v))).collect::<Vec<_>>().join(", "));
        cells.push(per_machine.len().to_string());
        cells.push(num(geomean));
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
    md.push('\n');
}

/// A table cell: pipes escaped, line breaks flattened.
pub(crate) fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// A number as short as it can be written exactly to four significant digits (`2`, `0.1`, `4.182`).
fn compact(v: f64) -> String {
    let text = num(v);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// A number with four significant digits (more for large integers), `—` when not finite.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "—".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-4..1e9).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}
