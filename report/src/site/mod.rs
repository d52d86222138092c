//! A self-contained static site of `results/` (no network; opens from `file://`): an index of experiments, a page
//! per experiment with interactive charts and a sortable summary, and the history pages. Every number comes from
//! the functions REPORT.md is written with (rows, summary, pool, claims, figures).

mod chart;
mod experiment;
mod history;
mod html;
mod index;

use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::spec::ReportSpec;

pub use experiment::Experiment;

/// The script every page runs (charts, tooltips, sortable tables).
const SCRIPT: &str = include_str!("assets/site.js");
/// The style sheet every page uses.
const STYLE: &str = include_str!("assets/site.css");

/// The experiment folders of `results_dir` (holding runs.csv and experiment.toml), by name; `baselines/`,
/// `history/` and local quick runs (`*-quick/`) are left out.
pub fn experiment_dirs(results_dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let entries = std::fs::read_dir(results_dir).map_err(|e| Error::read(results_dir, e))?;
    let mut dirs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("runs.csv").is_file() && p.join("experiment.toml").is_file())
        .filter(|p| {
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            name != "baselines" && name != "history" && !name.ends_with("-quick")
        })
        .collect();
    dirs.sort();
    Ok(dirs)
}

/// Writes the site into `out_dir`: `index.html`, a page per experiment folder of `experiments` (each with the spec
/// of its `experiment.toml`), the history pages of `history_dir` (missing files: pages that say so), `site.js` and
/// `site.css`. Returns every file written, `index.html` first.
pub fn write(experiments: &[(PathBuf, ReportSpec)], history_dir: &Path, out_dir: &Path) -> Result<Vec<PathBuf>, Error> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::write(out_dir, e))?;
    // Each experiment's rows, summary, claims and figures are read on a thread of its own (they are independent).
    let experiments: Vec<Experiment> = std::thread::scope(|scope| {
        let reading: Vec<_> =
            experiments.iter().map(|(dir, spec)| scope.spawn(move || Experiment::read(dir, spec))).collect();
        reading.into_iter().map(|r| r.join().expect("reading an experiment does not panic")).collect::<Result<_, _>>()
    })?;
    let mut files = Vec::new();
    let mut put = |name: &str, text: &str| -> Result<(), Error> {
        let path = out_dir.join(name);
        std::fs::write(&path, text).map_err(|e| Error::write(&path, e))?;
        files.push(path);
        Ok(())
    };
    put("index.html", &index::page_of(&experiments))?;
    let mut copied = Vec::new();
    for exp in &experiments {
        let (body, figures) = experiment::body(exp, out_dir)?;
        put(&exp.page(), &html::page(&exp.name, &body))?;
        copied.extend(figures);
    }
    for (name, text) in history::pages(history_dir)? {
        put(&name, &text)?;
    }
    put("site.js", SCRIPT)?;
    put("site.css", STYLE)?;
    files.extend(copied);
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{PlotKind, PlotSpec};
    use schema::column;

    /// A results folder in a temp dir: `one` and `two` (the golden rows, first seed only, so that a chart point
    /// is one configuration's median), a `baselines/` and a `*-quick/` folder that the site leaves out.
    fn results(tag: &str) -> PathBuf {
        let root = std::env::temp_dir().join(format!("bvhlab-site-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let golden =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/runs.csv")).unwrap();
        let mut lines = golden.lines();
        let header = lines.next().unwrap();
        let seed = header.split(',').position(|c| c == column::seed).unwrap();
        let first_seed = golden.lines().nth(1).unwrap().split(',').nth(seed).unwrap().to_string();
        let kept: Vec<&str> = lines.filter(|l| l.split(',').nth(seed) == Some(first_seed.as_str())).collect();
        let runs = format!("{header}\n{}\n", kept.join("\n"));
        for name in ["one", "two", "baselines", "one-quick"] {
            let dir = root.join(name);
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join("runs.csv"), &runs).unwrap();
            std::fs::write(dir.join("experiment.toml"), "").unwrap();
        }
        root
    }

    fn spec(rows_dir: &Path) -> ReportSpec {
        let rows = crate::rows::read(&rows_dir.join("runs.csv")).unwrap();
        let mut series: Vec<String> = rows.runs.iter().map(|r| r.series().to_string()).collect();
        series.dedup();
        ReportSpec {
            name: "golden".into(),
            description: "Golden rows <with> \"markup\" & more".into(),
            series,
            plots: vec![PlotSpec {
                file: "total".into(),
                title: "Total time".into(),
                kind: PlotKind::Metric,
                x: column::objects.into(),
                y: column::total_s.into(),
                log_x: true,
                log_y: true,
                series: vec![],
                filter: vec![],
                reference: None,
            }],
            ..ReportSpec::default()
        }
    }

    /// The JSON embedded under `id` in `page`.
    fn embedded(page: &str, id: &str) -> serde_json::Value {
        let start = page.find(&format!("id=\"{id}\">")).unwrap() + id.len() + 6;
        let end = start + page[start..].find("</script>").unwrap();
        serde_json::from_str(&page[start..end].replace("<\\/", "</")).unwrap()
    }

    #[test]
    fn the_site_has_a_page_per_experiment_linked_from_the_index() {
        let root = results("pages");
        let dirs = experiment_dirs(&root).unwrap();
        assert_eq!(dirs, [root.join("one"), root.join("two")], "baselines and quick runs left out");
        let experiments: Vec<(PathBuf, ReportSpec)> = dirs.iter().map(|d| (d.clone(), spec(d))).collect();
        let out = root.join("site");
        let files = write(&experiments, &root.join("history"), &out).unwrap();
        assert_eq!(files[0], out.join("index.html"));
        for name in ["one.html", "two.html", "history.html", "site.js", "site.css"] {
            assert!(out.join(name).is_file(), "{name}");
        }
        let index = std::fs::read_to_string(out.join("index.html")).unwrap();
        assert!(index.contains("href=\"one.html\"") && index.contains("href=\"two.html\""));
        assert!(!index.contains("one-quick"));
        assert!(index.contains("Golden rows &lt;with&gt; &quot;markup&quot; &amp; more"), "escaped");
        let history = std::fs::read_to_string(out.join("history.html")).unwrap();
        assert!(history.contains("No per-commit history recorded yet"), "missing history files say so");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn a_chart_point_shows_the_summary_median_of_its_configuration() {
        let root = results("median");
        let dir = root.join("one");
        let exp = Experiment::read(&dir, &spec(&dir)).unwrap();
        let summary = experiment::summary_json(&exp.summary);
        let names: Vec<&str> =
            summary["columns"].as_array().unwrap().iter().map(|c| c["name"].as_str().unwrap()).collect();
        let at = |name: &str| names.iter().position(|n| *n == name).unwrap();
        let row = &summary["rows"][0];
        let (series, objects, median) = (
            row[at("series")].as_str().unwrap(),
            row[at("objects")].as_f64().unwrap(),
            row[at("total_s_median")].as_f64().unwrap(),
        );

        let (page, _) = experiment::body(&exp, &root.join("site")).unwrap();
        let chart = embedded(&page, "chart-0");
        let line = chart["lines"].as_array().unwrap().iter().find(|l| l["label"] == series).unwrap();
        let point = line["points"].as_array().unwrap().iter().find(|p| p["x"].as_f64() == Some(objects)).unwrap();
        let y = point["y"].as_f64().unwrap();
        assert!((y - median).abs() <= 1e-12 * median.abs(), "chart {y} vs summary {median}");
        let tip: Vec<&str> = point["tip"].as_array().unwrap().iter().map(|t| t.as_str().unwrap()).collect();
        assert_eq!(tip[0], series);
        assert!(tip.contains(&format!("median {}", html::num(median)).as_str()), "{tip:?}");
        assert!(tip.iter().any(|t| t.starts_with("n ")) && tip.iter().any(|t| t.starts_with("commit ")));
        assert_eq!(names[0], "series", "readable columns first");
        assert!(!page.contains("class=\"matrix\""), "no reference, no ratio matrix");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn an_experiment_page_shows_each_reproduction_with_its_verdict() {
        let root = results("reproduction");
        let dir = root.join("one");
        let mut spec = spec(&dir);
        spec.reference = Some(spec.series[0].clone());
        // The rows against themselves: every deterministic column identical, every ratio where it was.
        let found = crate::reproduction::compare(&dir, &dir, &spec).unwrap();
        assert!(found.differences.is_empty() && found.configurations_compared > 0, "{found:?}");
        assert_eq!(found.outcome(), crate::reproduction::Outcome::Reproduced);
        let at = dir.join("reproductions").join("2026-12-04-abc");
        std::fs::create_dir_all(&at).unwrap();
        crate::reproduction::write(&at, &found, "results/one", &["a test".into()]).unwrap();
        let md = std::fs::read_to_string(at.join(crate::reproduction::MARKDOWN)).unwrap();
        assert!(md.contains("**reproduced**") && md.contains("every compared column identical"), "{md}");

        let exp = Experiment::read(&dir, &spec).unwrap();
        let (page, _) = experiment::body(&exp, &root.join("site")).unwrap();
        let section = page.find("id=\"reproductions\"").expect("a reproductions section");
        assert!(section > page.find("id=\"claims\"").unwrap() && section < page.find("id=\"summary\"").unwrap());
        assert!(page[section..].contains("2026-12-04-abc <span class=\"verdict holds\">reproduced</span>"), "{page}");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn an_experiment_page_leads_with_its_headline_then_the_ratio_matrix_against_its_bar() {
        let root = results("matrix");
        let dir = root.join("one");
        let mut spec = spec(&dir);
        spec.reference = Some(spec.series[0].clone());
        let fixed: Vec<String> =
            ["accel", "split", "leaf_size", "sah_bins", "traversal", "sah_traversal_cost", "sah_intersection_cost"]
                .map(String::from)
                .into();
        spec.series_fixed = spec.series.iter().map(|s| (s.clone(), fixed.clone())).collect();
        let exp = Experiment::read(&dir, &spec).unwrap();
        let (page, _) = experiment::body(&exp, &root.join("site")).unwrap();
        let matrix = page.find("class=\"matrix\"").expect("a ratio matrix");
        let headline = page.find("class=\"headline\"").expect("a headline");
        assert!(headline < page.find("id=\"claims\"").unwrap() && headline < matrix);
        assert!(page[headline..].contains(&format!("How much faster {} is than {}", spec.series[1], spec.series[0])));
        assert!(
            matrix < page.find("id=\"summary\"").unwrap() && matrix < page.find("id=\"figures\"").unwrap_or(usize::MAX)
        );
        // One row per object count, one column per other series, each cell the paired ratio of the summary.
        let table = &page[matrix..matrix + page[matrix..].find("</table>").unwrap()];
        let rows = table.matches("<tr><th>").count() - 1; // the header's row
        assert_eq!(rows, 2, "10 and 100 objects");
        for series in &spec.series[1..] {
            assert!(table.contains(&format!("<th>{}</th>", html::escape(series))), "{series}");
        }
        assert_eq!(table.matches("<td class=\"").count(), 2, "a cell per object count");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn instruction_history_pages_mark_regressions_and_link_commits() {
        use crate::history::commits::{COMMITS_CSV, INSTRUCTIONS_CSV};
        let root = std::env::temp_dir().join(format!("bvhlab-site-history-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).unwrap();
        let mut commits = String::from("commit,position,date,subject,status,compiler,counted,skipped\n");
        let mut counted = String::from(
            "commit,experiment,series,point,config_id,build_instructions,trace_instructions,output_hash,nodes,leaves,\
             depth,tree_bytes,sah_cost,trace_s,build_s,machine_id\n",
        );
        for (i, trace) in [100, 100, 100, 100, 150, 150, 150, 150].iter().enumerate() {
            commits.push_str(&format!(
                "{i:040x},{i},2026-11-{:02}T00:00:00Z,commit <{i}>,recorded,rustc 1.95.0,1,\n",
                i + 1
            ));
            counted.push_str(&format!(
                "{i:040x},ci,flat-bvh,objects 1000 (threads 1),0123456789abcdef,1000,{trace},aa,7,4,2,512,3.5,,,\n"
            ));
        }
        std::fs::write(root.join(COMMITS_CSV), commits).unwrap();
        std::fs::write(root.join(INSTRUCTIONS_CSV), counted).unwrap();
        let pages = history::pages(&root).unwrap();
        let names: Vec<&str> = pages.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["history.html", "history-ci-flat-bvh-objects-1000-threads-1.html", "commits.html"]);
        let track = &pages[1].1;
        let trace = embedded(track, "chart-1");
        assert_eq!(trace["marks"][0]["points"], serde_json::json!([[4.0, 150.0]]), "the regression");
        assert_eq!(trace["marks"][1]["points"], serde_json::json!([[4.0, 150.0]]), "the change point");
        assert_eq!(trace["lines"][0]["points"][4]["href"], format!("commits.html#{:040x}", 4));
        assert!(pages[2].1.contains(&format!("id=\"{:040x}\"", 4)) && pages[2].1.contains("commit &lt;4&gt;"));
        assert!(pages[0].1.contains("<td>1</td><td>1</td></tr>"), "one trace regression, one change point");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
