//! The figures of a report: one chart per `[[plot]]`, written as `figures/<file>.svg` and `.png`.

pub(crate) mod chart;
pub(crate) mod layout;

use schema::column;
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::pool::{self, Curve, Point, Provenance};
use crate::rows::Rows;
use crate::spec::{PlotKind, PlotSpec, ReportSpec};

use chart::{Chart, ChartPoint, Line, Overlay};

/// Draws every plot of `spec` into `dir/figures/`; returns the files written.
pub fn draw_all(dir: &Path, rows: &Rows, spec: &ReportSpec) -> Result<Vec<PathBuf>, Error> {
    let figures = dir.join("figures");
    std::fs::create_dir_all(&figures).map_err(|e| Error::write(&figures, e))?;
    let mut files = Vec::new();
    for plot in &spec.plots {
        let svg = figures.join(format!("{}.svg", plot.file));
        let png = figures.join(format!("{}.png", plot.file));
        let figure = figure_of(rows, spec, plot);
        chart::render_with(&figure.chart, &figure.overlay, &svg, &png).map_err(|(path, e)| Error::write(path, e))?;
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
    /// A category axis's labels (x ticks at 1, 2, …), else nothing.
    pub overlay: Overlay,
    /// Parallel to `chart.lines[i].points`.
    pub provenance: Vec<Vec<Provenance>>,
}

/// A backend family's colours (ours, Embree, tinybvh, obvhs): a hue each, a shade of it per variant.
const FAMILY_SHADES: [&[(u8, u8, u8)]; 4] = [
    &[(31, 119, 180), (94, 165, 220), (16, 72, 120), (130, 190, 235), (45, 100, 160), (10, 150, 200)],
    &[(214, 39, 40), (255, 127, 14), (150, 20, 25), (250, 160, 110)],
    &[(44, 160, 44), (120, 200, 100), (20, 100, 20)],
    &[(148, 103, 189), (190, 160, 220), (100, 60, 140)],
];

/// The family of a backend by its `accel` value: 0 ours, 1 Embree, 2 tinybvh, 3 obvhs.
fn family(accel: &str) -> usize {
    if accel.starts_with("embree") {
        1
    } else if accel.starts_with("tinybvh") {
        2
    } else if accel.starts_with("obvhs") {
        3
    } else {
        0
    }
}

/// How a series looks in every figure of an experiment (and on its site page): its colour, marker (style index) and
/// whether it is drawn over the others.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Look {
    pub colour: (u8, u8, u8),
    pub style: usize,
    /// A peer's series (Embree, tinybvh, obvhs): drawn on top of ours.
    pub front: bool,
}

/// The look of `series`, by its label alone, so that it is the same in every chart of the experiment: its position in
/// the experiment's legend order gives its marker; its colour is its backend family's (a hue per family, a shade per
/// variant in legend order) when the experiment's series span more than one family, else the palette's by position.
pub(crate) fn look(rows: &Rows, spec: &ReportSpec, series: &str) -> Look {
    let family_of = |s: &str| rows.runs.iter().find(|r| r.series() == s).map_or(0, |r| family(r.text(column::accel)));
    let position = spec.series.iter().position(|s| s == series).unwrap_or(spec.series.len());
    let families: Vec<usize> = spec.series.iter().map(|s| family_of(s)).collect();
    let f = family_of(series);
    let mixed = families.iter().chain([&f]).any(|g| *g != f);
    let colour = if mixed {
        let shades = FAMILY_SHADES[f];
        let variant = families[..position.min(families.len())].iter().filter(|g| **g == f).count();
        shades[variant % shades.len()]
    } else {
        chart::palette(position)
    };
    Look { colour, style: position, front: f != 0 }
}

/// The exponent `k` of the least-squares fit `y ∝ x^k` through a curve's medians on log-log axes (the growth
/// a log-log figure shows); `None` with fewer than three positive points.
pub fn growth_exponent(points: &[ChartPoint]) -> Option<f64> {
    let logs: Vec<(f64, f64)> =
        points.iter().filter(|p| p.x > 0.0 && p.y > 0.0).map(|p| (p.x.ln(), p.y.ln())).collect();
    if logs.len() < 3 {
        return None;
    }
    let n = logs.len() as f64;
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// True for an x axis that is the scene's size (`primitives`, `objects`): a log-log figure over it gets each
/// line's fitted growth.
pub fn grows_with_size(x: &str) -> bool {
    x == column::primitives || x == column::objects
}

/// What a plot shows, as chart data with each point's provenance.
pub(crate) fn figure_of(rows: &Rows, spec: &ReportSpec, plot: &PlotSpec) -> Figure {
    let bar = spec.bar();
    let reference = plot.reference.as_deref().or(bar.as_deref());
    let metric_ok = rows.is_numeric(&plot.y);
    let runs: Vec<crate::rows::Run> = rows.runs.iter().filter(|r| r.passes(&plot.filter)).cloned().collect();
    let categories = if plot.kind == PlotKind::TradeOff { None } else { pool::categories(&runs, &plot.x) };
    let series = plotted_series(spec, plot);
    let mut lines = Vec::new();
    let mut provenance = Vec::new();
    for series in series {
        let look = look(rows, spec, series);
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
        // The curves of one series (e.g. at 1 and at all threads) share its colour and differ in marker.
        for (k, curve) in curves.into_iter().filter(|c| !c.points.is_empty()).enumerate() {
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
            let mut label =
                if curve.fixed.is_empty() { series.to_string() } else { format!("{series} ({})", curve.fixed) };
            if plot.kind == PlotKind::Metric
                && grows_with_size(&plot.x)
                && plot.log_x
                && plot.log_y
                && categories.is_none()
                && let Some(k) = growth_exponent(&points)
            {
                label = format!("{label} ∝ x^{k:.2}");
            }
            provenance.push(curve.points.iter().map(|p| p.provenance.clone()).collect());
            let (colour, style, front) = (Some(look.colour), look.style + k, look.front);
            lines.push(Line { label, style, colour, front, points });
        }
    }
    // On a category axis the lines sit side by side within each category, so that their intervals do not hide
    // each other.
    let mut overlay = Overlay::default();
    if let Some(values) = &categories {
        let n = lines.len().max(1) as f64;
        for (i, line) in lines.iter_mut().enumerate() {
            let offset = (i as f64 - (n - 1.0) / 2.0) * (0.6 / n);
            line.points.iter_mut().for_each(|p| p.x += offset);
        }
        overlay.x_ticks = values.iter().enumerate().map(|(i, v)| ((i + 1) as f64, v.clone())).collect();
        overlay.categorical = true;
    }
    let reference = reference.unwrap_or("reference");
    // Axis titles in words: "embree-high's trace time / series' (above 1: faster than embree-high)".
    let quantity = quantity(&plot.y);
    let (y_label, guide) = match plot.kind {
        PlotKind::Metric | PlotKind::TradeOff => (metric_label(&plot.y), None),
        PlotKind::Speedup if is_time(&plot.y) => (
            format!("{reference}'s {quantity} / series' (above 1: faster than {reference})"),
            Some((1.0, format!("same as {reference}"))),
        ),
        PlotKind::Speedup => {
            (format!("{reference}'s {quantity} / series'"), Some((1.0, format!("same as {reference}"))))
        }
        PlotKind::Efficiency => (
            format!("{reference}'s {quantity} / series' / threads (1: ideal scaling)"),
            Some((1.0, "ideal".to_string())),
        ),
    };
    let title = if lines.is_empty() { format!("{} (no data)", plot.title) } else { plot.title.clone() };
    let x_label = if plot.kind == PlotKind::TradeOff { metric_label(&plot.x) } else { axis_label(&plot.x) };
    let chart = Chart { title, x_label, y_label, log_x: plot.log_x, log_y: plot.log_y, lines, guide };
    Figure { chart, overlay, provenance }
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

/// What a metric measures, in words and without its unit: "trace time".
fn quantity(name: &str) -> String {
    let label = metric_label(name);
    match label.find(" (") {
        Some(at) if label.ends_with(')') => label[..at].to_string(),
        _ => label,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The golden rows with the 100-object runs tracing shadow rays and the `bvh` series run by Embree.
    fn rows() -> Rows {
        let golden = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/runs.csv");
        let text = std::fs::read_to_string(golden).unwrap();
        let changed: String = text
            .lines()
            .map(|l| {
                let l = if l.contains(",random-spheres,100,") { l.replace(",primary,", ",shadow,") } else { l.into() };
                l.replace(",1,bvh,", ",1,embree,") + "\n"
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("bvhlab-figures-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("runs.csv"), changed).unwrap();
        let rows = crate::rows::read(&dir.join("runs.csv")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        rows
    }

    #[test]
    fn growth_exponent_is_the_log_log_slope() {
        let at = |x: f64, y: f64| ChartPoint { x, y, lo: y, hi: y };
        let cubic: Vec<ChartPoint> = [1e4, 1e5, 1e6, 5e6].iter().map(|&x| at(x, 2e-9 * x.powf(1.5))).collect();
        assert!((growth_exponent(&cubic).unwrap() - 1.5).abs() < 1e-9);
        assert_eq!(growth_exponent(&cubic[..2]), None, "two points make no fit");
        let flat: Vec<ChartPoint> = [1e4, 1e5, 1e6].iter().map(|&x| at(x, 3.0)).collect();
        assert!(growth_exponent(&flat).unwrap().abs() < 1e-12);
    }

    #[test]
    fn a_word_valued_x_is_a_category_axis_with_families_coloured() {
        let rows = rows();
        let series: Vec<String> = crate::distinct(rows.runs.iter().map(|r| r.series().to_string()));
        assert_eq!(series.len(), 2, "{series:?}");
        let spec = ReportSpec { series: series.clone(), ..ReportSpec::default() };
        let plot = PlotSpec {
            file: "by-workload".into(),
            title: "by workload".into(),
            kind: PlotKind::Metric,
            x: column::workload.into(),
            y: column::trace_s.into(),
            log_x: false,
            log_y: false,
            series: vec![],
            filter: vec![],
            reference: None,
        };
        let figure = figure_of(&rows, &spec, &plot);
        assert_eq!(figure.overlay.x_ticks, vec![(1.0, "primary".to_string()), (2.0, "shadow".to_string())]);
        assert!(!figure.chart.lines.is_empty());
        for line in &figure.chart.lines {
            for p in &line.points {
                assert!((p.x - p.x.round()).abs() < 0.5 && p.x != p.x.round(), "beside its category: {}", p.x);
            }
        }
        let colour = |s: &str| figure.chart.lines.iter().find(|l| l.label.starts_with(s)).unwrap().colour;
        assert_eq!(colour(&series[0]), Some(FAMILY_SHADES[family("list")][0]), "ours: blue");
        assert_eq!(colour(&series[1]), Some(FAMILY_SHADES[family("embree")][0]), "Embree: red");
        // A ratio plot against the plot's own reference.
        let plot = PlotSpec { kind: PlotKind::Speedup, reference: Some(series[1].clone()), ..plot };
        let figure = figure_of(&rows, &spec, &plot);
        assert!(figure.chart.y_label.contains(&series[1]), "{}", figure.chart.y_label);
        assert!(figure.chart.lines.iter().all(|l| l.label.starts_with(&series[0])), "the reference is not drawn");
    }
}
