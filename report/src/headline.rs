//! The answer an experiment leads with: its headline comparison ([`HeadlineSpec`]) at every point it was compared
//! at, as one sentence with the numbers and as a grid of points (rows) by ray kind and thread count (columns).
//! One direction everywhere: a cell is the bar's time over the series' time, above 1 = the series is faster.

use schema::column;
use std::fmt::Write as _;

use crate::pool;
use crate::rows::{POINT, Run};
use crate::spec::{HeadlineSpec, ReportSpec};
use crate::stats::Estimate;

/// The settings that make a grid's columns (where they vary); the other varying settings make its rows.
const COLUMN_AXES: [&str; 2] = [column::workload, column::threads];

/// The most columns a grid takes before thread counts move to its rows (one screen's width).
const MAX_COLUMNS: usize = 4;

/// What a cell's 95% interval says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Above 1: the series is faster than the bar.
    Faster,
    /// Below 1: the series is slower.
    Slower,
    /// Contains 1: not told apart.
    Same,
}

impl Side {
    /// The side of 1 that `e`'s interval lies on.
    pub fn of(e: &Estimate) -> Side {
        if e.lo > 1.0 {
            Side::Faster
        } else if e.hi < 1.0 {
            Side::Slower
        } else {
            Side::Same
        }
    }

    /// Its CSS class on the site.
    pub fn class(self) -> &'static str {
        match self {
            Side::Faster => "faster",
            Side::Slower => "slower",
            Side::Same => "same",
        }
    }
}

/// One point of the comparison.
#[derive(Clone, Debug)]
pub struct Cell {
    /// The point's settings (every point column but the seed), as recorded.
    pub settings: Vec<(&'static str, String)>,
    /// The bar at this point (the faster of the headline's `against` here).
    pub bar: String,
    /// The bar's time over the series' time, with its 95% interval.
    pub estimate: Estimate,
}

impl Cell {
    fn get(&self, column: &str) -> &str {
        self.settings.iter().find(|(c, _)| *c == column).map_or("", |(_, v)| v.as_str())
    }

    /// `1.12 [1.08, 1.15]`.
    pub fn text(&self) -> String {
        format!("{} [{}, {}]", ratio(self.estimate.value), ratio(self.estimate.lo), ratio(self.estimate.hi))
    }

    /// What its interval says.
    pub fn side(&self) -> Side {
        Side::of(&self.estimate)
    }
}

/// The headline comparison at every point.
#[derive(Clone, Debug)]
pub struct Headline {
    pub spec: HeadlineSpec,
    /// The metric compared, as the cells were computed (several when workloads differ in it).
    pub metric: String,
    pub cells: Vec<Cell>,
}

/// The grid of a headline: row labels, column labels and, per row, the index of each column's cell.
pub struct Grid {
    pub columns: Vec<String>,
    pub rows: Vec<(String, Vec<Option<usize>>)>,
}

/// The headline comparison of `spec` over `runs`; `None` when the experiment has none or its series never met its
/// bar.
pub fn of(spec: &ReportSpec, runs: &[Run]) -> Option<Headline> {
    let h = spec.headline()?;
    let mut cells: Vec<Cell> = Vec::new();
    let mut metrics: Vec<String> = Vec::new();
    for bar in &h.against {
        for (fixed, groups) in pool::curves_of(runs, &h.series, column::objects) {
            for (x, group) in groups {
                let metric = h
                    .metric
                    .clone()
                    .unwrap_or_else(|| spec.speedup_metric_of(group[0].text(column::workload)).to_string());
                let key = format!("{bar}/{}|{fixed}|{x}|{metric}|headline", h.series);
                let Some(estimate) = pool::ratio_against(spec, runs, bar, &group, &metric, &[column::seed], &key)
                else {
                    continue;
                };
                if !metrics.contains(&metric) {
                    metrics.push(metric);
                }
                let settings: Vec<(&'static str, String)> = POINT
                    .iter()
                    .copied()
                    .filter(|c| *c != column::seed)
                    .map(|c| (c, group[0].text(c).to_string()))
                    .collect();
                match cells.iter_mut().find(|c| c.settings == settings) {
                    Some(cell) if estimate.value < cell.estimate.value => {
                        cell.bar = bar.clone();
                        cell.estimate = estimate;
                    }
                    Some(_) => {}
                    None => cells.push(Cell { settings, bar: bar.clone(), estimate }),
                }
            }
        }
    }
    (!cells.is_empty()).then(|| Headline { spec: h, metric: metrics.join(" or "), cells })
}

/// "1 thread", "2 threads", "all cores".
fn threads_words(threads: &str) -> String {
    match threads {
        "1" => "1 thread".into(),
        "all" => "all cores".into(),
        n => format!("{n} threads"),
    }
}

/// A ratio to three decimals (the harness resolves a fraction of a percent, not less), more where three would
/// round a value other than 1 to 1.000 and hide which side of 1 it lies on.
pub fn ratio(v: f64) -> String {
    (3..=6)
        .map(|d| format!("{v:.d$}"))
        .find(|s| v == 1.0 || s.parse::<f64>() != Ok(1.0))
        .unwrap_or_else(|| format!("{v:.6}"))
}

impl Headline {
    /// The settings that differ between its cells, in row order.
    fn varying(&self) -> Vec<&'static str> {
        let first = &self.cells[0];
        first.settings.iter().map(|(c, _)| *c).filter(|c| self.cells.iter().any(|x| x.get(c) != first.get(c))).collect()
    }

    /// The bar in words: one series, or "the faster of a or b (at each point)".
    pub fn bar_words(&self) -> String {
        match self.spec.against.as_slice() {
            [one] => one.clone(),
            several => format!("the faster of {} at each point", several.join(" and ")),
        }
    }

    /// The answer in one or two sentences: per thread count (where it varies), the range of the ratio and at how
    /// many points the series is faster, slower or not told apart.
    pub fn sentence(&self) -> String {
        let by_threads = self.varying().contains(&column::threads);
        let mut groups: Vec<(String, Vec<&Cell>)> = Vec::new();
        for cell in &self.cells {
            let key = if by_threads { threads_words(cell.get(column::threads)) } else { String::new() };
            match groups.iter_mut().find(|(k, _)| *k == key) {
                Some((_, g)) => g.push(cell),
                None => groups.push((key, vec![cell])),
            }
        }
        let series = &self.spec.series;
        let theirs = match self.spec.against.as_slice() {
            [one] => format!("{one}'s"),
            _ => "the faster one's".to_string(),
        };
        let mut text = format!(
            "How much faster {series} is than {} ({}: {theirs} over {series}'s; above 1 = {series} faster):",
            self.bar_words(),
            self.metric
        );
        for (i, (key, group)) in groups.iter().enumerate() {
            let values: Vec<f64> = group.iter().map(|c| c.estimate.value).collect();
            let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
            let count = |side| group.iter().filter(|c| c.side() == side).count();
            let range =
                if group.len() == 1 { format!("{}×", ratio(lo)) } else { format!("{}–{}×", ratio(lo), ratio(hi)) };
            let _ = write!(
                text,
                "{}{}{range}: faster at {} of {} points, slower at {}, not told apart at {}",
                if i == 0 { " " } else { "; " },
                if key.is_empty() { String::new() } else { format!("{key}, ") },
                count(Side::Faster),
                group.len(),
                count(Side::Slower),
                count(Side::Same),
            );
        }
        text.push_str(" (95% intervals).");
        text
    }

    /// Its cells as a grid: rows the points' other varying settings, columns ray kind × thread count.
    pub fn grid(&self) -> Grid {
        let varying = self.varying();
        let mut col_axes: Vec<&str> = COLUMN_AXES.into_iter().filter(|c| varying.contains(c)).collect();
        let distinct = |c: &str| crate::distinct(self.cells.iter().map(|x| x.get(c).to_string())).len();
        if col_axes.iter().map(|c| distinct(c)).product::<usize>() > MAX_COLUMNS {
            col_axes.retain(|c| *c != column::threads); // too wide: thread counts go to the rows
        }
        let row_axes: Vec<&str> = varying.iter().copied().filter(|c| !col_axes.contains(c)).collect();
        let label = |cell: &Cell, axes: &[&str]| {
            axes.iter()
                .filter(|c| {
                    let value = cell.get(c);
                    let unset = matches!(value, "" | "-") || (**c == column::objects && value == "0");
                    !unset // a mesh's "0 objects", a sphere scene's "-" mesh: nothing to say
                })
                .map(|c| match *c {
                    column::threads => threads_words(cell.get(c)),
                    column::objects => format!("{} objects", cell.get(c)),
                    column::mesh | column::view | column::scene | column::workload => cell.get(c).to_string(),
                    _ => format!("{c} {}", cell.get(c)), // a bare number or word needs its setting's name
                })
                .collect::<Vec<_>>()
                .join(" · ")
        };
        let column_keys = crate::distinct(self.cells.iter().map(|c| label(c, &col_axes)));
        let row_labels = crate::distinct(self.cells.iter().map(|c| label(c, &row_axes)));
        let rows = row_labels
            .into_iter()
            .map(|r| {
                let at = column_keys
                    .iter()
                    .map(|col| self.cells.iter().position(|c| label(c, &row_axes) == r && label(c, &col_axes) == *col))
                    .collect();
                (r, at)
            })
            .collect();
        let columns = if col_axes.is_empty() {
            vec![format!("how much faster than {}", self.bar_words())] // one column: say what it holds
        } else {
            column_keys
        };
        Grid { columns, rows }
    }

    /// The grid as a Markdown table, intervals in the cells, the side of 1 in words where it is not "faster".
    pub fn markdown(&self) -> String {
        let grid = self.grid();
        let mut md = format!("| point | {} |\n|---|{}\n", grid.columns.join(" | "), "---|".repeat(grid.columns.len()));
        for (label, at) in &grid.rows {
            let cells: Vec<String> = at
                .iter()
                .map(|i| match i {
                    Some(i) => {
                        let c = &self.cells[*i];
                        match c.side() {
                            Side::Faster => format!("**{}**", c.text()),
                            Side::Slower => format!("{} slower", c.text()),
                            Side::Same => format!("{} ~", c.text()),
                        }
                    }
                    None => "—".into(),
                })
                .collect();
            let _ = writeln!(md, "| {} | {} |", if label.is_empty() { "all" } else { label }, cells.join(" | "));
        }
        md
    }
}
