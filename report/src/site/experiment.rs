//! One experiment's page: provenance, claims with verdicts, each `[[plot]]` as an interactive chart, and the
//! summary table (the frame of `summary.csv`), sortable.

use std::path::{Path, PathBuf};

use polars_core::prelude::{DataFrame, DataType};
use schema::column;

use super::chart::SiteChart;
use super::html::{escape, json_script, num};
use crate::claims::{self, ClaimResult};
use crate::error::Error;
use crate::figures;
use crate::headline::{self, Headline, Side, ratio};
use crate::reproduction::{self, Outcome, Reproduction};
use crate::rows::{self, Rows, Run};
use crate::spec::{ReportSpec, Verdict};
use crate::summary;

/// An experiment folder read for the site: its spec, rows, claim verdicts and summary.
pub struct Experiment {
    /// The folder under results/.
    pub dir: PathBuf,
    /// The folder's name, which names its page.
    pub name: String,
    pub spec: ReportSpec,
    pub rows: Rows,
    pub claims: Vec<ClaimResult>,
    pub summary: DataFrame,
    /// Its reproductions (`reproductions/<name>/reproduction.json`), by folder name.
    pub reproductions: Vec<(String, Reproduction)>,
    /// The comparison it leads with, at every point.
    pub headline: Option<Headline>,
}

impl Experiment {
    /// Reads `dir/runs.csv` and computes what REPORT.md shows from it.
    pub fn read(dir: &Path, spec: &ReportSpec) -> Result<Experiment, Error> {
        let runs_csv = dir.join("runs.csv");
        let rows = rows::read(&runs_csv)?;
        let summary = summary::summarise(&rows, spec).map_err(|e| Error::read(&runs_csv, e))?;
        let claims = claims::check_all(&rows, spec);
        let name = dir.file_name().map_or_else(|| spec.name.clone(), |n| n.to_string_lossy().into_owned());
        let reproductions = reproduction::read_all(dir)?;
        let headline = headline::of(spec, &rows.runs);
        Ok(Experiment { dir: dir.into(), name, spec: spec.clone(), rows, claims, summary, reproductions, headline })
    }

    /// The page's file name.
    pub fn page(&self) -> String {
        format!("{}.html", self.name)
    }

    /// Distinct values of a text column over the timed rows, in order of appearance.
    pub fn distinct(&self, column: &str) -> Vec<String> {
        crate::distinct(self.rows.runs.iter().map(|r| r.text(column).to_string()))
    }

    /// Distinct machines (see [`Run::machine`]), in order of appearance.
    pub fn machines(&self) -> Vec<String> {
        crate::distinct(self.rows.runs.iter().map(Run::machine))
    }
}

/// A verdict's word and CSS class.
pub fn verdict_word(verdict: Verdict) -> &'static str {
    match verdict {
        Verdict::Holds => "holds",
        Verdict::Fails => "fails",
        Verdict::Inconclusive => "inconclusive",
    }
}

/// A verdict as a coloured badge.
pub fn badge(verdict: Verdict) -> String {
    let word = verdict_word(verdict);
    format!("<span class=\"verdict {word}\">{word}</span>")
}

/// A claim's verdict as a badge with its points counted ("holds 14/16").
pub fn claim_badge(c: &ClaimResult) -> String {
    let word = verdict_word(c.verdict);
    let n = c.points.len();
    let count = if n > 1 {
        format!(" {}/{n}", c.points.iter().filter(|p| p.verdict == Verdict::Holds).count())
    } else {
        String::new()
    };
    format!("<span class=\"verdict {word}\" title=\"points where it holds / points judged\">{word}{count}</span>")
}

/// The headline: its sentence, and (with `grid`) its points as a grid of coloured cells with their intervals.
pub fn headline_html(exp: &Experiment, grid: bool) -> String {
    let Some(h) = &exp.headline else { return String::new() };
    let mut html = format!("<p class=\"headline\">{}</p>\n", escape(&h.sentence()));
    if !grid || h.cells.len() < 2 {
        return html;
    }
    let g = h.grid();
    html.push_str(&format!(
        "<table class=\"matrix answer\" data-series=\"{}\"><thead><tr><th>point</th>{}</tr></thead><tbody>\n",
        escape(&h.spec.series),
        g.columns.iter().map(|c| format!("<th>{}</th>", escape(c))).collect::<String>()
    ));
    for (label, at) in &g.rows {
        html.push_str(&format!("<tr><th>{}</th>", escape(if label.is_empty() { "all" } else { label })));
        for i in at {
            match i {
                Some(i) => {
                    let c = &h.cells[*i];
                    html.push_str(&format!(
                        "<td class=\"{}\" title=\"against {}\">{} <span class=\"ci\">[{}, {}]</span></td>",
                        c.side().class(),
                        escape(&c.bar),
                        ratio(c.estimate.value),
                        ratio(c.estimate.lo),
                        ratio(c.estimate.hi)
                    ));
                }
                None => html.push_str("<td></td>"),
            }
        }
        html.push_str("</tr>\n");
    }
    html.push_str(
        "</tbody></table>\n<p class=\"legend-line\">Green: ours faster (95% interval above 1); red: slower (below \
         1); grey: not told apart.</p>\n",
    );
    html
}

/// The page's body; copies the committed figures next to it (`<name>/figures/`). Returns the body and the files
/// copied.
pub fn body(exp: &Experiment, out_dir: &Path) -> Result<(String, Vec<PathBuf>), Error> {
    let mut html = format!("<h1>{}</h1>\n", escape(&exp.name));
    html.push_str(&headline_html(exp, true));
    html.push_str(&provenance(exp));
    html.push_str(&format!("<p class=\"description\">{}</p>\n", inline_code(&exp.spec.description)));
    html.push_str(&claims_table(&exp.claims));
    html.push_str(&ratio_matrix(exp));
    html.push_str(&reproductions_section(&exp.reproductions));
    let (figures_html, copied) = figures_section(exp, out_dir)?;
    html.push_str(&figures_html);
    html.push_str(
        "<h2 id=\"summary\">Summary</h2>\n<p>One row per configuration and machine, as <code>summary.csv</code> \
                   (medians with their 95% intervals); click a header to sort.</p>\n",
    );
    html.push_str(&summary_table(&exp.summary));
    Ok((html, copied))
}

/// `text` escaped, with Markdown's `code` spans as `<code>`.
pub fn inline_code(text: &str) -> String {
    escape(text)
        .split('`')
        .enumerate()
        .map(|(i, part)| if i % 2 == 1 { format!("<code>{part}</code>") } else { part.to_string() })
        .collect()
}

/// What the numbers were measured under, as recorded: logical cores (what `threads = "all"` is), the kernels and
/// ISA, the machine's load and hypervisor steal.
pub fn context(exp: &Experiment) -> String {
    let runs = &exp.rows.runs;
    let join = |v: Vec<String>| v.into_iter().filter(|s| !s.is_empty() && s != "-").collect::<Vec<_>>().join(", ");
    let loads: Vec<f64> = runs.iter().map(|r| r.num(column::load_avg_1m)).filter(|v| v.is_finite()).collect();
    let steal: f64 = runs.iter().map(|r| r.num(column::steal_s)).filter(|v| v.is_finite()).sum();
    let trace: f64 = runs.iter().map(|r| r.num(column::trace_s)).filter(|v| v.is_finite()).sum();
    let mut parts = vec![format!("{} logical cores (\"all\" threads)", join(exp.distinct(column::logical_cores)))];
    let kernels = join(exp.distinct(column::simd_kernel_used));
    if !kernels.is_empty() {
        parts.push(format!("kernels {kernels}"));
    }
    let isa = join(exp.distinct(column::cpu_isa));
    if !isa.is_empty() {
        parts.push(format!("ISA {isa}"));
    }
    if !loads.is_empty() {
        parts.push(format!("load (1 min) median {}", num(crate::stats::median(&loads))));
    }
    if trace > 0.0 {
        parts.push(format!("hypervisor steal {:.2}% of trace time", 100.0 * steal / trace));
    }
    parts.join("; ")
}

/// Whether today's code still gives the result set's deterministic columns, from its newest reproduction with the
/// code of a later commit (`harness reproduce DIR --at HEAD [--quick]`, folder `*-head*`): `Some(true)` identical,
/// `Some(false)` moved, `None` not told (never reproduced so, or no configuration both ran); with its words.
pub fn still_holds(exp: &Experiment) -> (Option<bool>, String) {
    let newest = exp.reproductions.iter().filter(|(name, _)| name.contains("-head")).max_by(|a, b| a.0.cmp(&b.0));
    let Some((_, r)) = newest else { return (None, "never reproduced with later code".into()) };
    let commit = r.reproduced_origin.commits.first().map_or("?", |c| reproduction::short_commit(c));
    if r.configurations_compared == 0 {
        return (None, format!("not told at {commit}: its quick run shares no configuration with the recorded rows"));
    }
    if r.differences.is_empty() {
        let n = r.configurations_compared;
        (Some(true), format!("HEAD {commit} gives its deterministic columns: identical at {n} configurations"))
    } else {
        let (d, n) = (r.differences.len(), r.configurations_compared);
        (
            Some(false),
            format!("HEAD {commit} no longer gives its deterministic columns: {d} differences in {n} compared"),
        )
    }
}

/// [`still_holds`] as a badge and its words.
pub fn still_holds_html(exp: &Experiment) -> String {
    let (badge, text) = match still_holds(exp) {
        (Some(true), text) => ("<span class=\"verdict holds\">still holds</span>", text),
        (Some(false), text) => ("<span class=\"verdict fails\">moved</span>", text),
        (None, text) => ("<span class=\"verdict inconclusive\">not re-checked</span>", text),
    };
    format!("{badge} {}", escape(&text))
}

fn provenance(exp: &Experiment) -> String {
    let list = |values: Vec<String>| values.iter().map(|v| escape(v)).collect::<Vec<_>>().join("<br>");
    let mut html = String::from("<dl class=\"provenance\">\n");
    html.push_str(&format!("<dt>machine</dt><dd>{}</dd>\n", list(exp.machines())));
    html.push_str(&format!("<dt>commit</dt><dd>{}</dd>\n", list(exp.distinct(column::git_commit))));
    html.push_str(&format!("<dt>rustc</dt><dd>{}</dd>\n", list(exp.distinct(column::rustc))));
    html.push_str(&format!("<dt>context</dt><dd>{}</dd>\n", escape(&context(exp))));
    html.push_str(&format!("<dt>at HEAD</dt><dd>{}</dd>\n", still_holds_html(exp)));
    html.push_str(&format!(
        "<dt>runs</dt><dd>{} timed{}</dd>\n",
        exp.rows.runs.len(),
        if exp.rows.failed.is_empty() {
            String::new()
        } else {
            format!(", {} failed validation", exp.rows.failed.len())
        }
    ));
    html.push_str("</dl>\n");
    html
}

/// Every series against the page's bar ([`ReportSpec::bar`]) at every point it was compared at (rows: the points;
/// columns: the series), the ratio `metric(bar) / metric(series)` (above 1: the series is faster) with its 95%
/// interval, coloured by what the interval says — faster, slower, or not told apart.
fn ratio_matrix(exp: &Experiment) -> String {
    let Some(bar) = exp.spec.bar() else { return String::new() };
    let bar = bar.as_str();
    let runs = &exp.rows.runs;
    let mut points: Vec<String> = Vec::new();
    let mut columns: Vec<(String, Vec<(usize, crate::stats::Estimate)>)> = Vec::new();
    for series in exp.spec.series.iter().filter(|s| *s != bar) {
        let Some(first) = runs.iter().find(|r| r.series() == series) else { continue };
        let metric = exp.spec.speedup_metric_of(first.text(column::workload));
        let mut cells = Vec::new();
        for curve in crate::pool::ratio_curves(&exp.spec, runs, bar, series, column::objects, metric) {
            for p in curve.points {
                let label = crate::pool::point_label(&curve.fixed, p.x);
                let at = points.iter().position(|l| *l == label).unwrap_or_else(|| {
                    points.push(label);
                    points.len() - 1
                });
                cells.push((at, p.estimate));
            }
        }
        if !cells.is_empty() {
            columns.push((series.clone(), cells));
        }
    }
    if columns.is_empty() {
        return String::new();
    }
    let mut html = format!(
        "<h2 id=\"ratios\">Every series against {bar}</h2>\n<p>How much faster each series is than <code>{bar}</code>: \
         its time over the series' time at that point (above 1: the series is faster), the median of the per-round \
         ratios with its 95% interval; green where the interval lies above 1, red where below, grey where it \
         contains 1.</p>\n<table class=\"matrix\"><thead><tr><th>point</th>{}</tr></thead><tbody>\n",
        columns.iter().map(|(s, _)| format!("<th>{}</th>", escape(s))).collect::<String>(),
        bar = escape(bar)
    );
    for (i, point) in points.iter().enumerate() {
        html.push_str(&format!("<tr><th>{}</th>", escape(point)));
        for (_, cells) in &columns {
            match cells.iter().find(|(at, _)| *at == i) {
                Some((_, e)) => html.push_str(&format!(
                    "<td class=\"{}\">{} <span class=\"ci\">[{}, {}]</span></td>",
                    Side::of(e).class(),
                    ratio(e.value),
                    ratio(e.lo),
                    ratio(e.hi)
                )),
                None => html.push_str("<td></td>"),
            }
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</tbody></table>\n");
    html
}

/// Each reproduction's verdict and its claims, recorded against reproduced.
fn reproductions_section(reproductions: &[(String, Reproduction)]) -> String {
    if reproductions.is_empty() {
        return String::new();
    }
    let badge = |o: Outcome| {
        let class = match o {
            Outcome::Reproduced => "holds",
            Outcome::NotReproduced => "fails",
            Outcome::NotComparable => "inconclusive",
        };
        format!("<span class=\"verdict {class}\">{}</span>", o.word())
    };
    let mut html = String::from(
        "<h2 id=\"reproductions\">Reproductions</h2>\n<p>The result set re-run by <code>harness reproduce</code>: \
         deterministic columns must be identical, time ratios within the harness's resolution or their intervals.</p>\n",
    );
    for (name, r) in reproductions {
        let moved = r.points.iter().filter(|p| p.outcome == Outcome::NotReproduced).count();
        html.push_str(&format!(
            "<h3>{} {}</h3>\n<p>Recorded on {}; reproduced on {} ({}). {} configurations' deterministic columns \
             compared, {} differences; {} of {} time ratios reproduced.</p>\n",
            escape(name),
            badge(r.outcome()),
            escape(&r.recorded_origin.machines.join(", ")),
            escape(&r.reproduced_origin.machines.join(", ")),
            escape(
                &r.reproduced_origin
                    .commits
                    .iter()
                    .map(|c| reproduction::short_commit(c))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            r.configurations_compared,
            r.differences.len(),
            r.points.len() - moved,
            r.points.len()
        ));
        if !r.claims.is_empty() {
            html.push_str(
                "<table class=\"claims reproduction\"><thead><tr><th>outcome</th><th>claim</th><th>then</th><th>now</th>\
                 <th>why</th></tr></thead><tbody>\n",
            );
            for c in &r.claims {
                html.push_str(&format!(
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                    badge(c.outcome),
                    escape(&c.text),
                    escape(&c.recorded),
                    escape(&c.reproduced),
                    escape(&c.reason)
                ));
            }
            html.push_str("</tbody></table>\n");
        }
    }
    html
}

fn claims_table(claims: &[ClaimResult]) -> String {
    if claims.is_empty() {
        return "<h2 id=\"claims\">Claims</h2>\n<p>None.</p>\n".into();
    }
    let mut html = String::from(
        "<h2 id=\"claims\">Claims</h2>\n<table class=\"claims\"><thead><tr><th>verdict</th><th>claim</th>\
         <th>ratio at the least favourable point [95% interval]</th><th>threshold</th><th>points</th></tr></thead><tbody>\n",
    );
    for c in claims {
        let points: String = c
            .points
            .iter()
            .map(|p| {
                let settle = match (p.verdict, p.more) {
                    (Verdict::Inconclusive, Some(m)) if m.count() <= claims::SETTLE_LIMIT => format!(" {m}"),
                    (Verdict::Inconclusive, _) => " on the threshold".to_string(),
                    _ => String::new(),
                };
                format!(
                    "<tr><td>{}{settle}</td><td>{}</td><td>{} [{}, {}]</td><td>{}</td></tr>",
                    badge(p.verdict),
                    escape(&p.label),
                    num(p.ratio),
                    num(p.lo),
                    num(p.hi),
                    num(p.threshold)
                )
            })
            .collect();
        html.push_str(&format!(
            "<tr><td>{}</td><td>{}</td><td>{} [{}, {}]</td><td>{}</td><td><details><summary>{}</summary>\
             <table class=\"points\"><tbody>{points}</tbody></table></details></td></tr>\n",
            claim_badge(c),
            escape(&c.text),
            num(c.ratio),
            num(c.lo),
            num(c.hi),
            num(c.threshold),
            escape(&c.detail)
        ));
    }
    html.push_str("</tbody></table>\n");
    html
}

/// The charts of every `[[plot]]`, each point's tooltip naming series, x, median, interval, n, commit and machine.
pub fn charts(exp: &Experiment) -> Vec<SiteChart> {
    exp.spec
        .plots
        .iter()
        .map(|plot| {
            let figure = figures::figure_of(&exp.rows, &exp.spec, plot);
            let (chart, ticks) = (&figure.chart, &figure.overlay.x_ticks);
            let mut site = SiteChart::of(chart, |i, j| {
                let (line, p, prov) = (&chart.lines[i], &chart.lines[i].points[j], &figure.provenance[i][j]);
                // On a category axis a point sits beside its category's whole number: name the category.
                let x = ticks.iter().find(|t| (t.0 - p.x).abs() < 0.5).map_or_else(|| num(p.x), |t| t.1.clone());
                vec![
                    line.label.clone(),
                    format!("{}: {x}", chart.x_label),
                    format!("median {}", num(p.y)),
                    format!("95% interval [{}, {}]", num(p.lo), num(p.hi)),
                    format!("n {}", prov.n),
                    format!("commit {}", prov.commits.join(", ")),
                    format!("machine {}", prov.machines.join(", ")),
                ]
            });
            site.x_ticks = ticks.clone();
            site.categorical = figure.overlay.categorical;
            site
        })
        .collect()
}

fn figures_section(exp: &Experiment, out_dir: &Path) -> Result<(String, Vec<PathBuf>), Error> {
    if exp.spec.plots.is_empty() {
        return Ok((String::new(), vec![]));
    }
    let mut html = String::from(
        "<h2 id=\"figures\">Figures</h2>\n<p>Hover a point for its numbers; click a legend entry \
                                 to hide or show its series.</p>\n",
    );
    let mut copied = Vec::new();
    let figures_out = out_dir.join(&exp.name).join("figures");
    for (k, (plot, chart)) in exp.spec.plots.iter().zip(charts(exp)).enumerate() {
        html.push_str(&chart.element(&format!("chart-{k}")));
        let mut links = Vec::new();
        for ext in ["svg", "png"] {
            let source = exp.dir.join("figures").join(format!("{}.{ext}", plot.file));
            if source.is_file() {
                std::fs::create_dir_all(&figures_out).map_err(|e| Error::write(&figures_out, e))?;
                let target = figures_out.join(format!("{}.{ext}", plot.file));
                std::fs::copy(&source, &target).map_err(|e| Error::write(&target, e))?;
                links.push(format!("<a href=\"{}/figures/{}.{ext}\">{ext}</a>", escape(&exp.name), escape(&plot.file)));
                copied.push(target);
            }
        }
        if !links.is_empty() {
            html.push_str(&format!("<p class=\"figure-links\">Report figure: {}</p>\n", links.join(" · ")));
        }
    }
    Ok((html, copied))
}

/// The summary's columns a reader looks for first, in this order: the series and the point, the answer (speedup
/// with its interval), then the medians with theirs. Every other column follows in the frame's order, and the ids last.
const FIRST_COLUMNS: [&str; 21] = [
    column::series,
    column::scene,
    column::mesh,
    column::view,
    column::workload,
    column::objects,
    column::threads,
    "speedup",
    "speedup_lo",
    "speedup_hi",
    "trace_s_median",
    "trace_s_median_lo",
    "trace_s_median_hi",
    "mrays_per_s_median",
    "mrays_per_s_median_lo",
    "mrays_per_s_median_hi",
    "build_s_median",
    "build_s_median_lo",
    "build_s_median_hi",
    "total_s_median",
    "n",
];

/// Columns that identify rather than describe, shown last.
const LAST_COLUMNS: [&str; 2] = [column::config_id, column::machine_id];

/// The summary frame as a sortable table's data: columns equal in every row are listed once above it; the
/// readable columns come first ([`FIRST_COLUMNS`]), the ids last.
pub fn summary_json(frame: &DataFrame) -> serde_json::Value {
    let mut columns = Vec::new();
    let mut constant = Vec::new();
    let mut values: Vec<Vec<serde_json::Value>> = Vec::new();
    let rank = |name: &str| match FIRST_COLUMNS.iter().position(|c| *c == name) {
        Some(i) => i,
        None if LAST_COLUMNS.contains(&name) => usize::MAX,
        None => FIRST_COLUMNS.len(),
    };
    let mut ordered: Vec<_> = frame.columns().iter().collect();
    ordered.sort_by_key(|c| rank(c.name().as_str())); // stable: the frame's order within a rank
    for c in ordered {
        let numeric = c.dtype().is_primitive_numeric();
        let cells: Vec<serde_json::Value> = if numeric {
            match c.cast(&DataType::Float64).and_then(|c| c.f64().map(|a| a.iter().collect::<Vec<_>>())) {
                Ok(v) => v.into_iter().map(|v| v.map_or(serde_json::Value::Null, serde_json::Value::from)).collect(),
                Err(_) => continue,
            }
        } else {
            match c
                .cast(&DataType::String)
                .and_then(|c| c.str().map(|a| a.iter().map(|v| v.map(String::from)).collect::<Vec<_>>()))
            {
                Ok(v) => v.into_iter().map(|v| serde_json::Value::from(v.unwrap_or_default())).collect(),
                Err(_) => continue,
            }
        };
        let name = c.name().to_string();
        if frame.height() > 1 && cells.iter().all(|v| *v == cells[0]) && name != column::config_id {
            constant.push(serde_json::json!([name, cells[0]]));
            continue;
        }
        columns.push(serde_json::json!({ "name": name, "numeric": numeric }));
        values.push(cells);
    }
    let rows: Vec<Vec<serde_json::Value>> =
        (0..frame.height()).map(|i| values.iter().map(|column| column[i].clone()).collect()).collect();
    serde_json::json!({ "columns": columns, "constant": constant, "rows": rows })
}

fn summary_table(frame: &DataFrame) -> String {
    format!(
        "<div class=\"table\" data-source=\"summary-data\"></div>\n{}",
        json_script("summary-data", &summary_json(frame))
    )
}
