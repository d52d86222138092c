//! The figures of a report: one chart per `[[plot]]`, written as `figures/<file>.svg` and `.png`.

pub(crate) mod chart;
pub(crate) mod layout;

use schema::column;
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::pool::{self, Curve, Point, Provenance};
use crate::rows::Rows;
use crate::spec::{PlotKind, PlotSpec, ReportSpec};

use chart::{Chart, ChartPoint, Line};

/// Draws every plot of `spec` into `dir/figures/`; returns the files written.
pub fn draw_all(dir: &Path, rows: &Rows, spec: &ReportSpec) -> Result<Vec<PathBuf>, Error> {
    let figures = dir.join("figures");
    std::fs::create_dir_all(&figures).map_err(|e| Error::write(&figures, e))?;
    let mut files = Vec::new();
    for plot in &spec.plots {
        let svg = figures.join(format!("{}.svg", plot.file));
        let png = figures.join(format!("{}.png", plot.file));
        chart::render(&chart_of(rows, spec, plot), &svg, &png).map_err(|(path, e)| Error::write(path, e))?;
        files.extend([svg, png]);
    }
    Ok(files)
}

/// The series a plot draws, in legend order.
fn plotted_series<'a>(spec: &'a ReportSpec, plot: &'a PlotSpec) -> Vec<&'a str> {
    let wanted = |s: &str| plot.series.is_empty() || plot.series.iter().any(|w| w == s);
    let mut series: Vec<&str> = spec.series.iter().map(String::as_str).filter(|s| wanted(s)).collect();
    // Series named by the plot but missing from the legend order still get drawn.
    series.extend(plot.series.iter().map(String::as_str).filter(|s| !spec.series.iter().any(|k| k == s)));
    series
}

/// A plot's chart and, per line and point, the runs behind the point (the site's tooltips).
pub(crate) struct Figure {
    pub chart: Chart,
    /// Parallel to `chart.lines[i].points`.
    pub provenance: Vec<Vec<Provenance>>,
}

/// What a plot shows, as chart data.
fn chart_of(rows: &Rows, spec: &ReportSpec, plot: &PlotSpec) -> Chart {
    figure_of(rows, spec, plot).chart
}

/// What a plot shows, as chart data with each point's provenance.
pub(crate) fn figure_of(rows: &Rows, spec: &ReportSpec, plot: &PlotSpec) -> Figure {
    let reference = spec.reference.as_deref();
    let metric_ok = rows.is_numeric(&plot.y);
    let runs: Vec<crate::rows::Run> = rows.runs.iter().filter(|r| r.passes(&plot.filter)).cloned().collect();
    let mut lines = Vec::new();
    let mut provenance = Vec::new();
    for series in plotted_series(spec, plot) {
        let curves: Vec<Curve> = match (plot.kind, reference) {
            _ if !metric_ok => Vec::new(),
            (PlotKind::Metric, _) => pool::metric_curves(&runs, series, &plot.x, &plot.y),
            (PlotKind::TradeOff, _) if rows.is_numeric(&plot.x) => {
                pool::trade_off_curves(&runs, series, &plot.x, &plot.y)
            }
            (PlotKind::TradeOff, _) => Vec::new(),
            (_, Some(reference)) if reference == series => Vec::new(),
            (PlotKind::Speedup | PlotKind::Efficiency, Some(reference)) => {
                pool::ratio_curves(spec, &runs, reference, series, &plot.x, &plot.y)
            }
            (_, None) => Vec::new(),
        };
        let per = |p: &Point| if plot.kind == PlotKind::Efficiency { p.threads } else { 1.0 };
        let single = curves.len() == 1;
        for curve in curves.into_iter().filter(|c| !c.points.is_empty()) {
            let points: Vec<ChartPoint> = curve
                .points
                .iter()
                .map(|p| ChartPoint {
                    x: p.x,
                    y: p.estimate.value / per(p),
                    lo: p.estimate.lo / per(p),
                    hi: p.estimate.hi / per(p),
                })
                .collect();
            // A series drawn as one line keeps its config position: the same look in every figure.
            let position = spec.series.iter().position(|s| s == series).filter(|_| single);
            let style = position.unwrap_or(spec.series.len() + lines.len());
            let label = if curve.fixed.is_empty() { series.to_string() } else { format!("{series} ({})", curve.fixed) };
            provenance.push(curve.points.iter().map(|p| p.provenance.clone()).collect());
            lines.push(Line { label, style, points });
        }
    }
    let reference = reference.unwrap_or("reference");
    let (y_label, guide) = match plot.kind {
        PlotKind::Metric | PlotKind::TradeOff => (metric_label(&plot.y), None),
        PlotKind::Speedup if is_time(&plot.y) => {
            (format!("speedup in {} vs {reference} (×)", plot.y), Some((1.0, format!("same as {reference}"))))
        }
        PlotKind::Speedup => {
            (format!("{} ratio, {reference} / series (×)", plot.y), Some((1.0, format!("same as {reference}"))))
        }
        PlotKind::Efficiency => {
            (format!("efficiency: speedup in {} vs {reference} / threads", plot.y), Some((1.0, "ideal".to_string())))
        }
    };
    let title = if lines.is_empty() { format!("{} (no data)", plot.title) } else { plot.title.clone() };
    let x_label = if plot.kind == PlotKind::TradeOff { metric_label(&plot.x) } else { axis_label(&plot.x) };
    Figure { chart: Chart { title, x_label, y_label, log_x: plot.log_x, log_y: plot.log_y, lines, guide }, provenance }
}

fn is_time(name: &str) -> bool {
    name.ends_with("_s") && name != column::mrays_per_s
}

/// A y axis label with units.
fn metric_label(name: &str) -> String {
    match name {
        column::total_s => "total time (s)".into(),
        column::trace_s => "trace time (s)".into(),
        column::build_s => "build time (s)".into(),
        column::scene_s => "scene time (s)".into(),
        column::encode_s => "encode time (s)".into(),
        column::mrays_per_s => "throughput (Mrays/s)".into(),
        column::nodes_per_ray => "nodes visited per ray".into(),
        column::box_tests_per_ray => "box tests per ray".into(),
        column::prim_tests_per_ray => "primitive tests per ray".into(),
        column::sah_cost => "SAH cost".into(),
        column::tree_bytes => "tree size (bytes)".into(),
        other => other.replace('_', " "),
    }
}

/// An x axis label.
fn axis_label(name: &str) -> String {
    match name {
        column::objects => "objects (spheres)".into(),
        column::threads => "worker threads".into(),
        column::leaf_size => "max leaf size".into(),
        column::sah_bins => "SAH bins".into(),
        other => other.replace('_', " "),
    }
}
