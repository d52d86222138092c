//! Drawing one line chart with 95% error bars to SVG and PNG with plotters and the bundled font.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::coord::combinators::BindKeyPoints;
use plotters::coord::ranged1d::{AsRangedCoord, DefaultFormatting, KeyPointHint, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// Image size in pixels.
const SIZE: (u32, u32) = (1200, 750);
/// The font every text is set in, bundled so that no system font is needed.
const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// Series colours (Tableau 10), distinct in colour and in lightness.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// A point: x, y and y's 95% interval.
#[derive(Clone, Copy, Debug)]
pub struct ChartPoint {
    pub x: f64,
    pub y: f64,
    pub lo: f64,
    pub hi: f64,
}

/// One series of a chart.
#[derive(Clone, Debug)]
pub struct Line {
    pub label: String,
    /// Colour and marker index, so a series looks the same in every figure.
    pub style: usize,
    pub points: Vec<ChartPoint>,
}

/// Everything one figure shows.
#[derive(Clone, Debug)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub lines: Vec<Line>,
    /// A dashed horizontal line (y value, legend label), e.g. at 1 for speedups.
    pub guide: Option<(f64, String)>,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file is a valid font; if it were not, text would be missing, not the chart.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES);
    });
}

/// What a figure over commits adds to a chart: whole-number x ticks with labels, unjoined marks and
/// vertical rules.
#[derive(Clone, Debug, Default)]
pub struct Overlay {
    /// Labels of whole-number x values (e.g. short commit hashes by run index). When given on a linear x
    /// axis, the axis spans the first − 0.5 to the last + 0.5 and ticks sit only at these values (every
    /// k-th of them when there are more than [`MAX_X_LABELS`]), labelled with their text.
    pub x_ticks: Vec<(f64, String)>,
    /// Sets of points drawn as marks only, never joined by a line.
    pub marks: Vec<Marks>,
    /// Dashed vertical lines at these x values, across the whole plot.
    pub rules: Vec<f64>,
}

/// Points drawn with one mark and one legend entry.
#[derive(Clone, Debug)]
pub struct Marks {
    pub label: String,
    pub mark: Mark,
    pub points: Vec<(f64, f64)>,
}

/// How [`Marks`] look.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A thick red ×.
    Cross,
    /// A black ring around the point.
    Ring,
}

/// The most x tick labels an [`Overlay`] axis gets.
pub const MAX_X_LABELS: usize = 12;

/// Draws `chart` to `svg` and to `png`; the error is a message.
pub fn render(chart: &Chart, svg: &Path, png: &Path) -> Result<(), (std::path::PathBuf, String)> {
    render_with(chart, &Overlay::default(), svg, png)
}

/// Draws `chart` with `overlay` to `svg` and to `png`; the error is a message.
pub fn render_with(
    chart: &Chart,
    overlay: &Overlay,
    svg: &Path,
    png: &Path,
) -> Result<(), (std::path::PathBuf, String)> {
    register_font();
    draw_any(SVGBackend::new(svg, SIZE).into_drawing_area(), chart, overlay).map_err(|e| (svg.to_path_buf(), e))?;
    let mut rgb = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    draw_any(BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area(), chart, overlay)
        .map_err(|e| (png.to_path_buf(), e))?;
    write_png(png, SIZE, &rgb).map_err(|e| (png.to_path_buf(), e.to_string()))
}

/// Encodes an RGB buffer with the tracer's PNG encoder (plotters' own encoder would bring in the `image`
/// crate and a second `png` version: 8 s of a clean build's compile time, README "Build time").
fn write_png(path: &Path, (width, height): (u32, u32), rgb: &[u8]) -> Result<(), Box<dyn std::error::Error>> {
    let pixels = rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    tracer::render::Image { width, height, pixels }.write_png(file)?;
    Ok(())
}

/// The labelled ticks of an overlay's x axis: every k-th, k the smallest step that keeps them to
/// [`MAX_X_LABELS`], counted from the first.
fn shown_ticks(ticks: &[(f64, String)]) -> Vec<(f64, String)> {
    let step = ticks.len().div_ceil(MAX_X_LABELS).max(1);
    ticks.iter().step_by(step).cloned().collect()
}

/// A linear axis with given bold (labelled) and light tick values: plotters' `WithKeyPoints` over a linear
/// range has no default formatter, which the chart's generic drawing asks for.
struct WholeTicks {
    inner: RangedCoordf64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ranged for WholeTicks {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() { self.light.clone() } else { self.bold.clone() }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }
}

/// Picks linear or logarithmic axes and draws.
fn draw_any<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart, overlay: &Overlay) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let xs = chart.lines.iter().flat_map(|l| l.points.iter().map(|p| p.x));
    let labelled = !chart.log_x && !overlay.x_ticks.is_empty();
    let (x0, x1) = if labelled {
        let ticks = overlay.x_ticks.iter().map(|t| t.0);
        let (lo, hi) = ticks.chain(xs).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        (lo - 0.5, hi + 0.5)
    } else {
        range(xs, chart.log_x, false)
    };
    let ys = chart.lines.iter().flat_map(|l| l.points.iter().flat_map(|p| [p.y, p.lo, p.hi]));
    let (y0, y1) = range(ys.chain(chart.guide.as_ref().map(|g| g.0)), chart.log_y, true);
    // Log axes get their own 1-2-5 ticks: plotters' defaults label too few or overlapping values.
    let log = |lo: f64, hi: f64| {
        (lo..hi).log_scale().with_key_points(log_ticks(lo, hi, false)).with_light_points(log_ticks(lo, hi, true))
    };
    let corner = legend_corner(chart, (x0, x1), (y0, y1));
    // Whole-number x ticks: bold (labelled) at the shown ones, light at every labelled value (up to 100).
    let whole = || WholeTicks {
        inner: (x0..x1).into(),
        bold: shown_ticks(&overlay.x_ticks).into_iter().map(|t| t.0).collect(),
        light: if overlay.x_ticks.len() <= 100 { overlay.x_ticks.iter().map(|t| t.0).collect() } else { vec![] },
    };
    let o = overlay;
    match (chart.log_x, chart.log_y) {
        (false, false) if labelled => draw(root, chart, o, corner, whole(), y0..y1),
        (false, true) if labelled => draw(root, chart, o, corner, whole(), log(y0, y1)),
        (false, false) => draw(root, chart, o, corner, x0..x1, y0..y1),
        (true, false) => draw(root, chart, o, corner, log(x0, x1), y0..y1),
        (false, true) => draw(root, chart, o, corner, x0..x1, log(y0, y1)),
        (true, true) => draw(root, chart, o, corner, log(x0, x1), log(y0, y1)),
    }
}

/// The plot corner with the fewest data marks (points and interval ends), for the legend.
fn legend_corner(chart: &Chart, x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let unit = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log { (v.ln() - lo.ln()) / (hi.ln() - lo.ln()) } else { (v - lo) / (hi - lo) }
    };
    let marks: Vec<(f64, f64)> = chart
        .lines
        .iter()
        .flat_map(|l| l.points.iter())
        .flat_map(|p| [(p.x, p.y), (p.x, p.lo), (p.x, p.hi)])
        .map(|(px, py)| (unit(px, x, chart.log_x), unit(py, y, chart.log_y)))
        .collect();
    let busy = |left: bool, upper: bool| {
        marks
            .iter()
            .filter(|(u, _)| if left { *u < 0.4 } else { *u > 0.6 })
            .filter(|(_, v)| if upper { *v > 0.65 } else { *v < 0.35 })
            .count()
    };
    let corners = [
        (SeriesLabelPosition::UpperLeft, busy(true, true)),
        (SeriesLabelPosition::UpperRight, busy(false, true)),
        (SeriesLabelPosition::LowerRight, busy(false, false)),
        (SeriesLabelPosition::LowerLeft, busy(true, false)),
    ];
    // The first corner with the fewest marks (min_by_key keeps the first of equals).
    corners.into_iter().min_by_key(|c| c.1).map(|c| c.0).unwrap_or(SeriesLabelPosition::UpperLeft)
}

/// Tick values for a log axis over [lo, hi] (lo > 0): 1-2-5 per decade over few decades, fewer
/// over many, every integer multiple when that leaves fewer than three; `light`: grid lines (1..9).
fn log_ticks(lo: f64, hi: f64, light: bool) -> Vec<f64> {
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let in_range = |multipliers: &[f64]| -> Vec<f64> {
        (first..=last)
            .flat_map(|e| multipliers.iter().map(move |m| if e >= 0 { m * 10f64.powi(e) } else { m / 10f64.powi(-e) }))
            .filter(|v| *v >= lo && *v <= hi)
            .collect()
    };
    let all = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    if light {
        return in_range(&all);
    }
    let decades = last - first;
    let ticks = in_range(match decades {
        0..=3 => &[1.0, 2.0, 5.0],
        4..=5 => &[1.0, 3.0],
        _ => &[1.0],
    });
    if ticks.len() < 3 { in_range(&all) } else { ticks }
}

/// The axis range for `values`, padded; positive only on log axes, from zero on linear y axes.
fn range(values: impl Iterator<Item = f64>, log: bool, is_y: bool) -> (f64, f64) {
    let values: Vec<f64> = values.filter(|v| v.is_finite() && (!log || *v > 0.0)).collect();
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if values.is_empty() {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        let pad = if is_y { 1.25 } else { 1.3 };
        let (min, max) = if min == max { (min / 2.0, max * 2.0) } else { (min, max) };
        return (min / pad, max * pad);
    }
    let span = if max > min { max - min } else { max.abs().max(1.0) };
    let low = if is_y && min >= 0.0 { 0.0 } else { min - 0.05 * span };
    (low, max + if is_y { 0.08 } else { 0.05 } * span)
}

/// A compact tick label: integers as integers, very large or small values in exponent form.
pub fn tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e7).contains(&a) {
        return format!("{v:.1e}").replace(".0e", "e");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_string() } else { text }
}

/// A marker outline around (0, 0) in pixels: circle-like, triangle, square, diamond, inverted triangle.
fn marker(kind: usize) -> Vec<(i32, i32)> {
    match kind % 5 {
        0 => (0..12)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                ((6.0 * a.cos()).round() as i32, (6.0 * a.sin()).round() as i32)
            })
            .collect(),
        1 => vec![(0, -7), (7, 5), (-7, 5)],
        2 => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
        3 => vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
        _ => vec![(0, 7), (7, -5), (-7, -5)],
    }
}

/// The two strokes of a [`Mark`] around (0, 0) in pixels.
fn mark_shape(mark: Mark) -> [(Vec<(i32, i32)>, ShapeStyle); 2] {
    match mark {
        Mark::Cross => {
            let red = RGBColor(200, 0, 0).stroke_width(4);
            [(vec![(-9, -9), (9, 9)], red), (vec![(-9, 9), (9, -9)], red)]
        }
        Mark::Ring => {
            let ring: Vec<(i32, i32)> = (0..=24)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / 24.0;
                    ((11.0 * a.cos()).round() as i32, (11.0 * a.sin()).round() as i32)
                })
                .collect();
            // One closed path, drawn in two halves.
            let (first, second) = (ring[..=12].to_vec(), ring[12..].to_vec());
            [(first, BLACK.stroke_width(3)), (second, BLACK.stroke_width(3))]
        }
    }
}

fn draw<DB, X, Y>(
    root: DrawingArea<DB, Shift>,
    chart: &Chart,
    overlay: &Overlay,
    legend: SeriesLabelPosition,
    x: X,
    y: Y,
) -> Result<(), String>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let mut cc = ChartBuilder::on(&root)
        .caption(&chart.title, (FONT, 32))
        .margin(24)
        .x_label_area_size(70)
        .y_label_area_size(100)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    let format = |v: &f64| tick(*v);
    let x_format = |v: &f64| match overlay.x_ticks.iter().find(|t| (t.0 - v).abs() < 1e-6) {
        Some(t) => t.1.clone(),
        None => tick(*v),
    };
    cc.configure_mesh()
        .x_desc(chart.x_label.as_str())
        .y_desc(chart.y_label.as_str())
        .axis_desc_style((FONT, 24))
        .label_style((FONT, 20))
        .x_label_formatter(&x_format)
        .y_label_formatter(&format)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(e)?;

    if let Some((value, label)) = &chart.guide {
        let (x0, x1) = (cc.x_range().start, cc.x_range().end);
        let style = BLACK.stroke_width(2);
        cc.draw_series(DashedLineSeries::new([(x0, *value), (x1, *value)], 12, 8, style))
            .map_err(e)?
            .label(label.as_str())
            .legend(move |(lx, ly)| PathElement::new([(lx, ly), (lx + 10, ly), (lx + 16, ly), (lx + 26, ly)], style));
    }

    // Rules first, behind the data.
    if !overlay.rules.is_empty() {
        let (y0, y1) = (cc.y_range().start, cc.y_range().end);
        let style = RGBColor(90, 90, 90).stroke_width(2);
        cc.draw_series(overlay.rules.iter().flat_map(|&x| DashedLineSeries::new([(x, y0), (x, y1)], 10, 6, style)))
            .map_err(e)?;
    }

    for line in &chart.lines {
        let colour = PALETTE[line.style % PALETTE.len()];
        let stroke = colour.stroke_width(2);
        let shape = marker(line.style);
        // 95% intervals: a vertical bar with caps at both ends.
        cc.draw_series(line.points.iter().map(|p| PathElement::new([(p.x, p.lo), (p.x, p.hi)], stroke))).map_err(e)?;
        cc.draw_series(
            line.points
                .iter()
                .flat_map(|p| [(p.x, p.lo), (p.x, p.hi)])
                .map(|at| EmptyElement::at(at) + PathElement::new([(-6, 0), (6, 0)], stroke)),
        )
        .map_err(e)?;
        cc.draw_series(LineSeries::new(line.points.iter().map(|p| (p.x, p.y)), stroke)).map_err(e)?;
        let legend_shape = shape.clone();
        cc.draw_series(
            line.points.iter().map(|p| EmptyElement::at((p.x, p.y)) + Polygon::new(shape.clone(), colour.filled())),
        )
        .map_err(e)?
        .label(line.label.as_str())
        .legend(move |(lx, ly)| {
            EmptyElement::at((lx + 13, ly))
                + PathElement::new([(-13, 0), (13, 0)], stroke)
                + Polygon::new(legend_shape.clone(), colour.filled())
        });
    }

    for marks in overlay.marks.iter().filter(|m| !m.points.is_empty()) {
        let [(a, a_style), (b, b_style)] = mark_shape(marks.mark);
        let (la, lb) = (a.clone(), b.clone());
        cc.draw_series(marks.points.iter().map(|&at| {
            EmptyElement::at(at) + PathElement::new(a.clone(), a_style) + PathElement::new(b.clone(), b_style)
        }))
        .map_err(e)?
        .label(marks.label.as_str())
        .legend(move |(lx, ly)| {
            EmptyElement::at((lx + 13, ly))
                + PathElement::new(la.clone(), a_style)
                + PathElement::new(lb.clone(), b_style)
        });
    }

    cc.configure_series_labels()
        .position(legend)
        .label_font((FONT, 20))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_compact() {
        assert_eq!(tick(1000.0), "1000");
        assert_eq!(tick(100000.0), "100000");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(1.5), "1.5");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(1e8), "1e8");
    }

    #[test]
    fn overlay_ticks_are_thinned_to_fit() {
        let ticks = |n: usize| (1..=n).map(|i| (i as f64, format!("c{i}"))).collect::<Vec<_>>();
        let xs = |n: usize| shown_ticks(&ticks(n)).iter().map(|t| t.0).collect::<Vec<_>>();
        assert_eq!(xs(3), [1.0, 2.0, 3.0]);
        assert_eq!(xs(MAX_X_LABELS).len(), MAX_X_LABELS);
        assert_eq!(xs(14), [1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0]);
        assert_eq!(xs(100).len(), 12);
        assert!(xs(1000).len() <= MAX_X_LABELS);
        assert!(shown_ticks(&[]).is_empty());
    }

    #[test]
    fn log_ticks_follow_one_two_five() {
        assert_eq!(log_ticks(8.0, 130.0, false), [10.0, 20.0, 50.0, 100.0]);
        assert_eq!(log_ticks(0.2, 0.45, false), [0.2, 0.3, 0.4]);
        assert_eq!(log_ticks(1.0, 1e7, false), [1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6, 1e7]);
        assert_eq!(log_ticks(8.0, 21.0, true), [8.0, 9.0, 10.0, 20.0]);
    }
}
