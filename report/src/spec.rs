//! What a report shows, as the experiment config says: series, reference, plots and claims.

use schema::column;
use std::collections::BTreeMap;

/// Everything `report::write` needs besides the rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReportSpec {
    /// Experiment name.
    pub name: String,
    /// One-paragraph description.
    pub description: String,
    /// Label of the series speedups are measured against (`None`: no speedups).
    pub reference: Option<String>,
    /// The metric speedups are ratios of (`None`: `trace_s` for ray-set workloads, `total_s` for `render`).
    pub speedup_metric: Option<String>,
    /// Series labels in config order (legend order).
    pub series: Vec<String>,
    /// For each series label, the setting columns (see ROWS.md) its `[[series]]` table fixes.
    pub series_fixed: BTreeMap<String, Vec<String>>,
    /// Figures to draw.
    pub plots: Vec<PlotSpec>,
    /// Claims to check.
    pub claims: Vec<ClaimSpec>,
    /// The config file's text as run, quoted in REPORT.md.
    pub config_text: String,
    /// Notes the harness wants in the report (skipped series, thread counts above the core count, …).
    pub notes: Vec<String>,
    /// Warnings for the top of the report (e.g. a merge of several machines' rows).
    pub warnings: Vec<String>,
    /// The comparison the experiment leads with (`[headline]`; `None`: taken from its claims, see
    /// [`ReportSpec::headline`]).
    pub headline: Option<HeadlineSpec>,
}

/// The comparison an experiment leads with: one series against a bar, the faster of `against` at each point; read
/// as "how much faster is `series`": the bar's time over the series' (above 1: `series` is faster).
#[derive(Clone, Debug, PartialEq)]
pub struct HeadlineSpec {
    /// The series the experiment is about (ours).
    pub series: String,
    /// The bar: one series, or several of which the faster at each point counts (e.g. Embree's two fast builds).
    /// The first is what the page's ratio matrix and summary compare with.
    pub against: Vec<String>,
    /// The metric compared (a time; `None`: the experiment's speedup metric).
    pub metric: Option<String>,
}

impl ReportSpec {
    /// The comparison the experiment leads with: `[headline]`, else the first claim of the kind `faster` (its
    /// series against its `than`, and every other `than` of that series' claims with the same factor), else the
    /// first series against the reference; `None` without any of them.
    pub fn headline(&self) -> Option<HeadlineSpec> {
        if let Some(h) = &self.headline {
            return Some(h.clone());
        }
        let faster = |c: &ClaimSpec| match &c.kind {
            ClaimKind::Faster { series, than, factor, .. } => {
                Some((series.clone(), than.clone(), *factor, c.metric.clone()))
            }
            ClaimKind::Within { .. } => None,
        };
        if let Some((series, than, factor, metric)) = self.claims.iter().find_map(faster) {
            let mut against = vec![than];
            for (s, t, f, m) in self.claims.iter().filter_map(faster) {
                if s == series && f == factor && m == metric && !against.contains(&t) {
                    against.push(t);
                }
            }
            return Some(HeadlineSpec { series, against, metric: Some(metric) });
        }
        let reference = self.reference.clone()?;
        let series = self.series.iter().find(|s| **s != reference)?.clone();
        Some(HeadlineSpec { series, against: vec![reference], metric: None })
    }

    /// The series the page's ratio matrix and summary compare every series with: the headline's first bar, else
    /// the reference.
    pub fn bar(&self) -> Option<String> {
        self.headline().map(|h| h.against[0].clone()).or_else(|| self.reference.clone())
    }

    /// The metric the speedup of a run's configuration is a ratio of (see [`ReportSpec::speedup_metric`]).
    pub fn speedup_metric_of(&self, workload: &str) -> &str {
        speedup_metric(self.speedup_metric.as_deref(), workload)
    }
}

/// The metric speedups are ratios of: the configured one, else `total_s` for renders and `trace_s` for ray sets.
pub fn speedup_metric<'a>(configured: Option<&'a str>, workload: &str) -> &'a str {
    match configured {
        Some(metric) => metric,
        None if workload == schema::Named::name(schema::Workload::Render) => column::total_s,
        None => column::trace_s,
    }
}

/// What a figure's y axis shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotKind {
    /// The metric itself (median over repetitions and seeds, 95% interval as error bars).
    Metric,
    /// Reference series' metric divided by each series' metric (a speedup when the metric is a time).
    Speedup,
    /// Speedup against the reference divided by thread count (parallel efficiency), x = threads.
    Efficiency,
    /// One point per series and setting combination: metric `x` (e.g. `build_s`) against metric `y` (e.g.
    /// `trace_s`), medians, with `y`'s 95% interval: what a faster build costs in trace time.
    TradeOff,
}

/// One `[[plot]]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSpec {
    /// File stem under `figures/` (`<file>.svg`, `<file>.png`).
    pub file: String,
    /// Figure title.
    pub title: String,
    /// What the y axis shows.
    pub kind: PlotKind,
    /// Setting column on the x axis (e.g. `objects`, `threads`); a metric column for [`PlotKind::TradeOff`].
    pub x: String,
    /// Metric column (e.g. `total_s`, `mrays_per_s`).
    pub y: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Series to draw (empty: all).
    pub series: Vec<String>,
    /// Only runs whose setting column takes one of the listed values (e.g. `workload = primary`).
    pub filter: Vec<(String, Vec<String>)>,
    /// The series a speedup or efficiency plot compares with, when not the experiment's `reference`.
    pub reference: Option<String>,
}

/// One `[[claim]]` table.
#[derive(Clone, Debug, PartialEq)]
pub struct ClaimSpec {
    /// The claim in words, as the report prints it.
    pub text: String,
    /// What the seed paper said on this point, when the claim reproduces one of its statements.
    pub paper: Option<String>,
    /// Why the claim fails where it does, as measured apart (a profile, counted work): printed only where it fails.
    pub if_fails: Option<String>,
    /// What is compared.
    pub kind: ClaimKind,
    /// Metric column compared (a time: smaller is better).
    pub metric: String,
    /// Only points with at least this many objects.
    pub min_objects: Option<u64>,
    /// Only points with at most this many objects.
    pub max_objects: Option<u64>,
    /// Only runs whose setting column takes one of the listed values.
    pub filter: Vec<(String, Vec<String>)>,
}

/// The comparison a claim makes; ratios are `metric(than) / metric(series)`.
#[derive(Clone, Debug, PartialEq)]
pub enum ClaimKind {
    /// `series` is at least `factor` times faster than `than` (times `threads` of `series` when `per_thread`).
    Faster { series: String, than: String, factor: f64, per_thread: bool },
    /// `series` and `than` are within `tolerance` (e.g. 0.10) of each other.
    Within { series: String, than: String, tolerance: f64 },
}

/// A claim's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The 95% interval lies entirely on the claimed side at every point.
    Holds,
    /// At some point the interval lies entirely on the wrong side.
    Fails,
    /// Neither: the intervals straddle the threshold, or no point matched.
    Inconclusive,
}
