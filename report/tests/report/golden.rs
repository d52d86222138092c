//! Golden test: a small hand-made runs.csv with obvious medians, written into a temp dir.

use crate::common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use report::spec::{ClaimKind, ClaimSpec, PlotKind, PlotSpec, ReportSpec, Verdict};

const LIST: &str = "serial·list";
const BVH: &str = "serial·bvh";

/// A fresh, empty directory under the system temp dir holding a copy of `runs` as runs.csv.
fn run_dir(name: &str, runs: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bvhlab-report-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("runs.csv"), runs).unwrap();
    dir
}

fn golden_rows() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/runs.csv")).unwrap()
}

fn claim(text: &str, kind: ClaimKind, min_objects: Option<u64>) -> ClaimSpec {
    ClaimSpec {
        text: text.into(),
        paper: None,
        if_fails: None,
        kind,
        metric: "total_s".into(),
        min_objects,
        max_objects: None,
        filter: vec![],
    }
}

fn faster(factor: f64, per_thread: bool) -> ClaimKind {
    ClaimKind::Faster { series: BVH.into(), than: LIST.into(), factor, per_thread }
}

fn plot(file: &str, title: &str, kind: PlotKind, x: &str, log: bool) -> PlotSpec {
    PlotSpec {
        file: file.into(),
        title: title.into(),
        kind,
        x: x.into(),
        y: "total_s".into(),
        log_x: log,
        log_y: log,
        series: vec![],
        filter: vec![],
        reference: None,
    }
}

fn spec() -> ReportSpec {
    let mut paper_claim = claim("BVH is at least 2× faster than the list", faster(2.0, true), None);
    paper_claim.paper = Some("the BVH is much faster".into());
    // `if_fails` is printed only for a claim that fails somewhere.
    paper_claim.if_fails = Some("printed although the claim holds".into());
    let mut hundredfold = claim("BVH is 100× faster", faster(100.0, false), None);
    hundredfold.if_fails = Some("a BVH saves at most the list's sphere tests".into());
    ReportSpec {
        description: "Two series, two object counts, two seeds, three repetitions.".into(),
        speedup_metric: Some("total_s".into()),
        plots: vec![
            plot("total_vs_objects", "Total time vs objects", PlotKind::Metric, "objects", true),
            plot("speedup", "Speedup vs objects", PlotKind::Speedup, "objects", false),
            plot("efficiency", "Efficiency vs threads", PlotKind::Efficiency, "threads", false),
        ],
        claims: vec![
            paper_claim,
            hundredfold,
            claim("BVH is 11.5/2.75× faster at 100 objects", faster(11.5 / 2.75, false), Some(100)),
            claim(
                "BVH and list are within 10%",
                ClaimKind::Within { series: BVH.into(), than: LIST.into(), tolerance: 0.1 },
                None,
            ),
            claim("BVH is 2× faster at a million objects", faster(2.0, false), Some(1_000_000)),
        ],
        config_text: "name = \"golden\"\n[[series]]\nlabel = \"serial·list\"\n".into(),
        notes: vec!["a note from the harness".into()],
        warnings: vec![],
        ..common::spec("golden", LIST, &[LIST, BVH])
    }
}

/// summary.csv as config_id → column → text.
fn read_summary(dir: &Path) -> BTreeMap<String, BTreeMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|line| {
            let row: BTreeMap<String, String> =
                header.iter().zip(line.split(',')).map(|(h, v)| (h.to_string(), v.to_string())).collect();
            (row["config_id"].clone(), row)
        })
        .collect()
}

fn value(summary: &BTreeMap<String, BTreeMap<String, String>>, id: &str, column: &str) -> f64 {
    summary[id][column].parse().unwrap_or_else(|_| panic!("{id} {column} = {:?}", summary[id][column]))
}

#[test]
fn golden_report() {
    let dir = run_dir("golden", &golden_rows());
    let spec = spec();
    let outcome = report::write(&dir, &spec).unwrap();

    // Summaries: one row per configuration, ids kept as text (leading zeros, all digits).
    let summary = read_summary(&dir);
    assert_eq!(summary.len(), 8);
    let list10 = "0000000000001000"; // serial·list, 10 objects, seed 1: total 1.0, 1.5, 1.25
    let list100 = "0000000000000042"; // serial·list, 100 objects, seed 1: total 10, 12, 11
    let bvh10 = "0000000000005000"; // serial·bvh, 10 objects, seed 1: total 0.25, 0.375, 0.3125
    let bvh100 = "0000000000007000"; // serial·bvh, 100 objects, seed 1: total 2.0, 3.0, 2.5
    assert_eq!(summary[list10]["series"], LIST);
    assert_eq!(summary[list100]["image_hash"], "0000000000000011");
    for (id, median, min, max, std) in [
        (list10, 1.25, 1.0, 1.5, 0.25),
        (list100, 11.0, 10.0, 12.0, 1.0),
        (bvh10, 0.3125, 0.25, 0.375, 0.0625),
        (bvh100, 2.5, 2.0, 3.0, 0.5),
    ] {
        assert_eq!(value(&summary, id, "n"), 3.0);
        assert_eq!(value(&summary, id, "total_s_median"), median, "{id}");
        assert_eq!(value(&summary, id, "total_s_mean"), median, "{id}");
        assert_eq!(value(&summary, id, "total_s_min"), min, "{id}");
        assert_eq!(value(&summary, id, "total_s_max"), max, "{id}");
        assert!((value(&summary, id, "total_s_std") - std).abs() < 1e-12, "{id}");
        // Three repetitions have no distribution-free 95% interval of their median.
        let (lo, hi) = (value(&summary, id, "total_s_median_lo"), value(&summary, id, "total_s_median_hi"));
        assert!(lo.is_nan() && hi.is_nan(), "{id}: [{lo}, {hi}]");
    }
    // bvh build_s is 0.0625 in every repetition, so trace_s = total_s - 0.0625.
    assert_eq!(value(&summary, bvh10, "trace_s_median"), 0.25);
    assert_eq!(value(&summary, bvh10, "build_s_std"), 0.0);
    assert_eq!(value(&summary, bvh10, "tree_depth"), 3.0);
    // Speedups: median(reference) / median(configuration), same objects and seed.
    assert_eq!(value(&summary, list10, "speedup"), 1.0);
    assert_eq!(value(&summary, bvh10, "speedup"), 1.25 / 0.3125);
    assert_eq!(value(&summary, bvh100, "speedup"), 11.0 / 2.5);
    // One configuration's three repetitions: no interval; the claims below pool two seeds (six rounds) and get one.
    let (lo, hi) = (value(&summary, bvh100, "speedup_lo"), value(&summary, bvh100, "speedup_hi"));
    assert!(lo.is_nan() && hi.is_nan(), "[{lo}, {hi}]");

    // Claims.
    let verdicts: Vec<Verdict> = outcome.claims.iter().map(|c| c.verdict).collect();
    use Verdict::*;
    assert_eq!(verdicts, [Holds, Fails, Inconclusive, Fails, Inconclusive]);
    let holds = &outcome.claims[0];
    assert_eq!(holds.threshold, 2.0, "factor × 1 thread");
    assert!(holds.lo >= 2.0 && holds.detail.starts_with("2 points"), "{holds:?}");
    // Each point on its own: 10 and 100 objects, both holding, the least favourable one the claim's ratio.
    let labels: Vec<&str> = holds.points.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(labels, ["10 objects", "100 objects"], "{holds:?}");
    assert!(holds.points.iter().all(|p| p.verdict == Holds && p.lo >= 2.0 && p.threshold == 2.0));
    assert!(holds.points.iter().any(|p| (p.ratio, p.lo, p.hi) == (holds.ratio, holds.lo, holds.hi)));
    assert!(outcome.claims[1].hi < 100.0);
    let straddles = &outcome.claims[2];
    // Pooled over seeds at 100 objects, paired by round (same seed and repetition): the per-round ratios are
    // 10/2, 12/3, 11/2.5 (seed 1) and 11/2.5, 13/3.5, 12/3 (seed 2), their median (4 + 4.4) / 2; the ratio of the
    // two series' medians would be 11.5/2.75.
    assert!((straddles.ratio - 4.2).abs() < 1e-12, "{straddles:?}");
    assert!(straddles.lo < straddles.ratio && straddles.ratio < straddles.hi, "{straddles:?}");
    assert!(straddles.detail.contains("1 point ") && straddles.detail.contains("100 objects"), "{straddles:?}");
    assert!(outcome.claims[3].lo > 1.1);
    let empty = &outcome.claims[4];
    assert!(empty.ratio.is_nan() && empty.detail.contains("no points"), "{empty:?}");

    // Files.
    for name in ["runs.parquet", "summary.parquet"] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        assert!(bytes.starts_with(b"PAR1") && bytes.ends_with(b"PAR1"), "{name}");
    }
    for file in ["total_vs_objects", "speedup", "efficiency"] {
        let png = std::fs::read(dir.join(format!("figures/{file}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000, "{file}.png: {} bytes", png.len());
        let svg = std::fs::read_to_string(dir.join(format!("figures/{file}.svg"))).unwrap();
        assert!(svg.contains("<svg") && svg.contains(BVH), "{file}.svg");
        assert!(outcome.files.contains(&dir.join(format!("figures/{file}.svg"))));
    }
    let metric_svg = std::fs::read_to_string(dir.join("figures/total_vs_objects.svg")).unwrap();
    assert!(metric_svg.contains(LIST) && metric_svg.contains("total time (s)"));
    assert!(
        std::fs::read_to_string(dir.join("figures/speedup.svg"))
            .unwrap()
            .contains("serial·list&apos;s total time / series&apos; (above 1: faster than serial·list)")
    );

    // REPORT.md.
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    for needle in [
        "# golden",
        "## What ran",
        "24 timed repetitions of 8 configurations (3 repetitions each)",
        "load average min 0.5000 / median 1.000 / max 1.500",
        "a note from the harness",
        "![Total time vs objects](figures/total_vs_objects.svg)",
        "![Speedup vs objects](figures/speedup.svg)",
        "| claim | the paper said | measured ratio [95% CI] | threshold | verdict |",
        "| BVH is at least 2× faster than the list | the BVH is much faster |",
        "| ≥ 2 (2 × 1 threads) | **holds** (2/2 points hold) |",
        "| ≥ 100 | **fails** (0/2 points hold) |",
        "| 1 ± 0.1 | **fails** (0/2 points hold) |",
        "**fails**",
        "| inconclusive |",
        "### Claims point by point\n\n**BVH is at least 2× faster than the list**\n\n| point | ratio [95% CI] | threshold | verdict |",
        "| 100 objects | 4.200 [3.714, 5.000] | ≥ 2 | holds |", // six rounds: the range of their ratios
        "| 10 objects | 4.000 [4.000, 4.000] | 1 ± 0.1 | **fails** |",
        "## Summary",
        "```toml\nname = \"golden\"",
        "harness report <dir>",
    ] {
        assert!(md.contains(needle), "REPORT.md lacks {needle:?}:\n{md}");
    }
    assert!(!md.contains("Warning"), "no row ran more threads than cores");
    let why = "### Why claims fail\n\n- **BVH is 100× faster** (fails at 10 objects; 100 objects): a BVH saves at most \
               the list's sphere tests\n\n";
    assert!(md.contains(why) && !md.contains("printed although"), "{md}");
    // Summary table pooled over seeds: 2 series × 2 object counts, speedup of bvh at 10 objects = 1.375 / 0.34375.
    // The settings each series' table fixes are implied by its label: only the sweep's axes have a column.
    let row = md.lines().find(|l| l.starts_with("| serial·bvh | 10 | "));
    assert!(row.is_some_and(|r| r.starts_with("| serial·bvh | 10 | 2 | 6 | ")), "2 seeds, 6 runs pooled: {md}");
    assert!(md.contains("| 4.000 [4.000, 4.000] |\n"), "how much faster than the list, with its interval: {md}");
    // Answer first: the headline (bvh against the list) before the claims, the claims before the figures.
    let (headline, claims, figures) =
        (md.find("How much faster serial·bvh is than serial·list"), md.find("## Claims"), md.find("## Figures"));
    assert!(headline < claims && claims < figures && headline.is_some(), "{md}");
    // The headline's grid has one column (no ray kind or thread count varies), each point's cell filled in.
    assert!(md.contains("| point | how much faster than serial·list |\n|---|---|\n| 10 objects | **4.000 ["), "{md}");
    // Set REPORT_KEEP_TEST_OUTPUT to look at the report and figures afterwards.
    if std::env::var_os("REPORT_KEEP_TEST_OUTPUT").is_none() {
        let _ = std::fs::remove_dir_all(&dir);
    } else {
        eprintln!("golden report kept in {}", dir.display());
    }
}

#[test]
fn row_order_does_not_change_the_numbers() {
    let rows = golden_rows();
    let mut lines: Vec<&str> = rows.lines().collect();
    let header = lines.remove(0);
    lines.reverse();
    let reversed = format!("{header}\n{}\n", lines.join("\n"));
    let (a, b) = (run_dir("order-a", &rows), run_dir("order-b", &reversed));
    let (oa, ob) = (report::write(&a, &spec()).unwrap(), report::write(&b, &spec()).unwrap());
    assert_eq!(format!("{:?}", oa.claims), format!("{:?}", ob.claims), "NaN-safe comparison");
    // Equal up to float summation order (polars' std may differ in the last bit).
    let (sa, sb) = (read_summary(&a), read_summary(&b));
    assert_eq!(sa.keys().collect::<Vec<_>>(), sb.keys().collect::<Vec<_>>());
    for (id, row) in &sa {
        for (column, text) in row {
            let other = &sb[id][column];
            match (text.parse::<f64>(), other.parse::<f64>()) {
                (Ok(x), Ok(y)) => assert!(
                    (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-12 * x.abs().max(y.abs()),
                    "{id} {column}: {x} vs {y}"
                ),
                _ => assert_eq!(text, other, "{id} {column}"),
            }
        }
    }
    let _ = (std::fs::remove_dir_all(&a), std::fs::remove_dir_all(&b));
}

#[test]
fn errors_name_the_file() {
    let dir = std::env::temp_dir().join(format!("bvhlab-report-{}-missing", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let err = report::write(&dir, &spec()).unwrap_err().to_string();
    assert!(err.contains("runs.csv") && !err.contains('\n'), "{err}");

    let without_seed = golden_rows().replace(",seed,", ",seeds,");
    let dir = run_dir("no-seed", &without_seed);
    let err = report::write(&dir, &spec()).unwrap_err().to_string();
    assert!(err.contains("runs.csv") && err.contains("`seed`"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn failed_validation_is_excluded_and_announced_and_filters_narrow_plots() {
    // Every row exact, plus one extra row of a configuration that failed.
    let golden = golden_rows();
    let first = golden.lines().nth(1).unwrap();
    let failed = first.replacen("0000000000001000", "00000000000bad00", 1).replacen(",10,1,list,", ",10,9,list,", 1);
    let text = format!("{golden}{}\n", failed.replacen(",exact,list,0,", ",FAILED,list,17,", 1));
    let dir = run_dir("failed", &text);
    let mut spec = spec();
    // A metric plot restricted to 100 objects: its curve has one x value only.
    spec.plots[0].filter = vec![("objects".into(), vec!["100".into()])];
    report::write(&dir, &spec).unwrap();
    let summary = read_summary(&dir);
    assert_eq!(summary.len(), 8, "the failed configuration has no summary row");
    assert!(!summary.contains_key("00000000000bad00"));
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.contains("VALIDATION FAILURES"), "announced loudly");
    assert!(md.contains("| serial·list | list | random-spheres | 10 | 9 | primary | 1 | 17 | - | 0 |"), "{md}");
    let svg = std::fs::read_to_string(dir.join("figures/total_vs_objects.svg")).unwrap();
    let unfiltered = run_dir("unfiltered", &golden);
    report::write(&unfiltered, &self::spec()).unwrap();
    let all = std::fs::read_to_string(unfiltered.join("figures/total_vs_objects.svg")).unwrap();
    assert!(
        svg.matches("<polyline").count() < all.matches("<polyline").count(),
        "the filter drops the 10-object points"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&unfiltered).unwrap();
}

#[test]
fn rows_of_two_machines_are_never_pooled() {
    // The golden rows recorded again on a second, 2x slower machine: same configurations, other machine_id.
    let golden = golden_rows();
    let mut lines = golden.lines();
    let mut text = format!("{},machine_id\n", lines.next().unwrap());
    let mut slow = String::new();
    for line in lines {
        text.push_str(&format!("{line},aaaaaaaaaaaa\n"));
        let fields: Vec<String> = line.split(',').map(String::from).collect();
        // Columns 18..=22 are scene_s, build_s, trace_s, encode_s and total_s (see tests/data/runs.csv).
        let doubled: Vec<String> = fields
            .iter()
            .enumerate()
            .map(
                |(i, f)| if (18..=22).contains(&i) { (f.parse::<f64>().unwrap() * 2.0).to_string() } else { f.clone() },
            )
            .collect();
        slow.push_str(&format!("{},bbbbbbbbbbbb\n", doubled.join(",")));
    }
    text.push_str(&slow);
    let dir = run_dir("machines", &text);
    report::write(&dir, &spec()).unwrap();
    let summary = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    assert_eq!(summary.lines().count(), 1 + 2 * 8, "one summary row per configuration and machine");
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.contains("machine `aaaaaaaaaaaa`") && md.contains("machine `bbbbbbbbbbbb`"), "{md}");
    // Speedups are taken within each machine, so both machines give the same speedup at every point.
    let speedups: Vec<&str> =
        md.lines().filter(|l| l.starts_with("| serial·bvh |")).map(|l| l.rsplit(" | ").nth(1).unwrap()).collect();
    assert_eq!(speedups.len(), 4, "2 object counts x 2 machines: {md}");
    assert_eq!(speedups[0].split(' ').next(), speedups[2].split(' ').next(), "{speedups:?}");
    // Combined across machines as a geometric mean of the per-machine speedups (equal here, so the mean is that).
    assert!(md.contains("## Across machines") && md.contains("**geometric mean**"), "{md}");
    let across: Vec<&str> = md.lines().filter(|l| l.starts_with("| `serial·bvh` |")).collect();
    assert_eq!(across.len(), 2, "one line per object count: {md}");
    // Both machines are 2x apart in every time, so each machine's speedup, and their geometric mean, is the list's 4x.
    assert!(across[0].contains("| `aaaaaaaaaaaa` 4.000, `bbbbbbbbbbbb` 4.000 | 2 | 4.000 |"), "{}", across[0]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn speedups_default_to_trace_time_for_ray_sets_and_say_so() {
    let dir = run_dir("speedup-metric", &golden_rows());
    let spec = ReportSpec { speedup_metric: None, ..spec() };
    report::write(&dir, &spec).unwrap();
    let summary = read_summary(&dir);
    let bvh10 = summary.values().find(|r| r["series"] == BVH && r["objects"] == "10").unwrap();
    // The golden rows trace primary rays: list trace_s median 1.25, bvh 0.25 (its total adds a 0.0625 build).
    assert_eq!(bvh10["speedup"].parse::<f64>().unwrap(), 1.25 / 0.25);
    assert_eq!(bvh10["speedup_metric"], "trace_s");
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.contains("how much faster than serial·list |") && md.contains("Time: trace_s."), "{md}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn samples_that_saw_steal_are_counted_in_the_report() {
    let rows = golden_rows();
    let mut lines = rows.lines();
    let mut text = format!("{},steal_s\n", lines.next().unwrap());
    for (i, line) in lines.enumerate() {
        let steal = match i {
            0 => "0.02",
            1 => "0.3",
            2 | 3 => "0.0",
            _ => "",
        };
        text.push_str(&format!("{line},{steal}\n"));
    }
    let dir = run_dir("steal", &text);
    report::write(&dir, &spec()).unwrap();
    let md = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(md.contains("- Hypervisor steal: 2 of 4 timed samples lost CPU time"), "{md}");
    assert!(md.contains("max 0.3000 s"), "{md}");
    let quiet = run_dir("no-steal", &golden_rows());
    report::write(&quiet, &spec()).unwrap();
    assert!(!std::fs::read_to_string(quiet.join("REPORT.md")).unwrap().contains("Hypervisor steal"));
    let _ = (std::fs::remove_dir_all(&dir), std::fs::remove_dir_all(&quiet));
}
