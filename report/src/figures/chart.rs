//! Drawing one line chart with 95% error bars to SVG and PNG with plotters and the bundled font.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::combinators::BindKeyPoints;
use plotters::coord::ranged1d::{AsRangedCoord, DefaultFormatting, KeyPointHint, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::layout::{self, FONT, LEGEND_KEY, Labels, Layout, Rect, TEXT_OFFSET, TICK_SIZE, Text, register_font};

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

/// The palette's colour of style `style`, as RGB.
pub fn palette(style: usize) -> (u8, u8, u8) {
    let RGBColor(r, g, b) = PALETTE[style % PALETTE.len()];
    (r, g, b)
}

/// The markers' names, by style index (`style % MARKERS.len()`), as [`marker`] draws them and `site.js` knows them:
/// seven, so that with the palette's eight colours a style's colour and marker repeat together only after 56.
pub const MARKERS: [&str; 7] = ["circle", "triangle", "square", "diamond", "triangle-down", "cross", "plus"];

/// The name of style `style`'s marker.
pub fn marker_name(style: usize) -> &'static str {
    MARKERS[style % MARKERS.len()]
}

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
    /// A colour of its own instead of the style's (e.g. its backend family's), as RGB.
    pub colour: Option<(u8, u8, u8)>,
    /// Drawn over the others (a peer's series over ours).
    pub front: bool,
    pub points: Vec<ChartPoint>,
}

impl Line {
    /// The colour it is drawn in: its own, else its style's.
    pub fn rgb(&self) -> (u8, u8, u8) {
        self.colour.unwrap_or_else(|| palette(self.style))
    }
}

/// The order lines are drawn in, last on top: the front ones (peers) over the others, and within each group the
/// first in legend order on top (Embree's single rays over its packets), so that a line that overlaps another of its
/// group stays visible.
pub fn drawing_order(front: &[bool]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..front.len()).rev().collect();
    order.sort_by_key(|&i| front[i]); // stable: reversed legend order within each group
    order
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
    /// The x axis is a category (a word column such as `workload`): points with their intervals, not joined by
    /// lines (there is nothing between two categories).
    pub categorical: bool,
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

/// Draws `chart` with `overlay` to `svg` and to `png`; the error is a message.
pub fn render_with(
    chart: &Chart,
    overlay: &Overlay,
    svg: &Path,
    png: &Path,
) -> Result<(), (std::path::PathBuf, String)> {
    register_font();
    let plan = plan(chart, overlay);
    let size = plan.layout.size;
    draw_any(SVGBackend::new(svg, size).into_drawing_area(), chart, overlay, &plan)
        .map_err(|e| (svg.to_path_buf(), e))?;
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    draw_any(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area(), chart, overlay, &plan)
        .map_err(|e| (png.to_path_buf(), e))?;
    write_png(png, size, &rgb).map_err(|e| (png.to_path_buf(), e.to_string()))
}

/// How many labelled ticks plotters' own axes get (its default).
const AXIS_LABELS: usize = 11;

/// What a legend entry's sample shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Key {
    /// The dashed guide line.
    Guide,
    /// A series' line and marker: its style index and colour.
    Series(usize, (u8, u8, u8)),
    Marks(Mark),
}

/// A chart ready to draw: its axis ranges, legend samples (in the layout's legend order) and layout.
struct Plan {
    x: (f64, f64),
    y: (f64, f64),
    /// Whether the x axis is an overlay's labelled whole-number axis.
    labelled: bool,
    keys: Vec<Key>,
    layout: Layout,
}

/// The axis ranges, tick labels and legend of `chart` with `overlay`, and the layout made for them.
fn plan(chart: &Chart, overlay: &Overlay) -> Plan {
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
    // The labels plotters will draw: the same key points and formatters as `draw`.
    let linear = |lo: f64, hi: f64| RangedCoordf64::from(lo..hi).key_points(AXIS_LABELS);
    let x_ticks: Vec<String> = if labelled {
        shown_ticks(&overlay.x_ticks).into_iter().map(|t| t.1).collect()
    } else if chart.log_x {
        log_ticks(x0, x1, false).into_iter().map(tick).collect()
    } else {
        linear(x0, x1).into_iter().map(tick).collect()
    };
    let y_values = if chart.log_y { log_ticks(y0, y1, false) } else { linear(y0, y1) };
    let y_ticks: Vec<String> = y_values.into_iter().map(tick).collect();
    let mut legend: Vec<String> = Vec::new();
    let mut keys: Vec<Key> = Vec::new();
    if let Some((_, label)) = &chart.guide {
        legend.push(label.clone());
        keys.push(Key::Guide);
    }
    for line in &chart.lines {
        legend.push(line.label.clone());
        keys.push(Key::Series(line.style, line.rgb()));
    }
    for marks in overlay.marks.iter().filter(|m| !m.points.is_empty()) {
        legend.push(marks.label.clone());
        keys.push(Key::Marks(marks.mark));
    }
    let labels = Labels {
        title: &chart.title,
        x: &chart.x_label,
        y: &chart.y_label,
        legend: &legend,
        x_ticks: &x_ticks,
        y_ticks: &y_ticks,
    };
    Plan { x: (x0, x1), y: (y0, y1), labelled, keys, layout: layout::layout(&labels) }
}

/// Encodes an RGB buffer with the tracer's PNG encoder (plotters' own encoder would bring in the `image`
/// crate and a second `png` version: 8 s of a clean build's compile time, docs/build.md, "Build time").
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

/// Picks linear or logarithmic axes and draws; returns the plotting area plotters drew in.
fn draw_any<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    chart: &Chart,
    overlay: &Overlay,
    plan: &Plan,
) -> Result<Rect, String>
where
    DB::ErrorType: 'static,
{
    let ((x0, x1), (y0, y1)) = (plan.x, plan.y);
    // Log axes get their own 1-2-5 ticks: plotters' defaults label too few or overlapping values.
    let log = |lo: f64, hi: f64| {
        (lo..hi).log_scale().with_key_points(log_ticks(lo, hi, false)).with_light_points(log_ticks(lo, hi, true))
    };
    // Whole-number x ticks: bold (labelled) at the shown ones, light at every labelled value (up to 100).
    let whole = || WholeTicks {
        inner: (x0..x1).into(),
        bold: shown_ticks(&overlay.x_ticks).into_iter().map(|t| t.0).collect(),
        light: if overlay.x_ticks.len() <= 100 { overlay.x_ticks.iter().map(|t| t.0).collect() } else { vec![] },
    };
    let (o, p) = (overlay, plan);
    match (chart.log_x, chart.log_y) {
        (false, false) if p.labelled => draw(root, chart, o, p, whole(), y0..y1),
        (false, true) if p.labelled => draw(root, chart, o, p, whole(), log(y0, y1)),
        (false, false) => draw(root, chart, o, p, x0..x1, y0..y1),
        (true, false) => draw(root, chart, o, p, log(x0, x1), y0..y1),
        (false, true) => draw(root, chart, o, p, x0..x1, log(y0, y1)),
        (true, true) => draw(root, chart, o, p, log(x0, x1), log(y0, y1)),
    }
}

/// Tick values for a log axis over [lo, hi] (lo > 0): 1-2-5 per decade over few decades, fewer
/// over many, every integer multiple when that leaves fewer than three, and linear steps when even those are
/// fewer than three (a narrow range within one decade); `light`: grid lines (1..9).
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
    if ticks.len() >= 3 {
        return ticks;
    }
    let all = in_range(&all);
    if all.len() >= 3 { all } else { RangedCoordf64::from(lo..hi).key_points(6) }
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

/// A marker outline around (0, 0) in pixels, by [`MARKERS`]: circle-like, triangle, square, diamond, inverted
/// triangle, × and +.
fn marker(kind: usize) -> Vec<(i32, i32)> {
    match kind % MARKERS.len() {
        0 => (0..12)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                ((6.0 * a.cos()).round() as i32, (6.0 * a.sin()).round() as i32)
            })
            .collect(),
        1 => vec![(0, -7), (7, 5), (-7, 5)],
        2 => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
        3 => vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
        4 => vec![(0, 7), (7, -5), (-7, -5)],
        5 => vec![
            (-5, -7),
            (0, -2),
            (5, -7),
            (7, -5),
            (2, 0),
            (7, 5),
            (5, 7),
            (0, 2),
            (-5, 7),
            (-7, 5),
            (-2, 0),
            (-7, -5),
        ],
        _ => vec![
            (-2, -7),
            (2, -7),
            (2, -2),
            (7, -2),
            (7, 2),
            (2, 2),
            (2, 7),
            (-2, 7),
            (-2, 2),
            (-7, 2),
            (-7, -2),
            (-2, -2),
        ],
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

/// Draws one line of laid-out text so that its glyphs stay in its box.
fn text<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, t: &Text) -> Result<(), String> {
    let offset = (t.size * TEXT_OFFSET).round() as i32;
    let font = (FONT, t.size).into_font().color(&BLACK);
    let drawn = if t.vertical {
        // Rotated to read bottom to top: the anchor's "below" points right.
        let style = font.transform(FontTransform::Rotate270).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw_text(&t.text, &style, (t.rect.left + offset, (t.rect.top + t.rect.bottom) / 2))
    } else {
        root.draw_text(&t.text, &font.pos(Pos::new(HPos::Left, VPos::Top)), (t.rect.left, t.rect.top + offset))
    };
    drawn.map_err(|e| e.to_string())
}

/// Draws the legend box of `plan`'s layout with every entry's sample and label.
fn draw_legend<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, plan: &Plan) -> Result<(), String> {
    let Some(legend) = &plan.layout.legend else { return Ok(()) };
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let r = legend.rect;
    let corners = [(r.left, r.top), (r.right - 1, r.bottom - 1)];
    root.draw(&Rectangle::new(corners, WHITE.filled())).map_err(e)?;
    root.draw(&Rectangle::new(corners, RGBColor(160, 160, 160).stroke_width(1))).map_err(e)?;
    for (entry, key) in legend.entries.iter().zip(&plan.keys) {
        let at = (entry.key.left + LEGEND_KEY / 2, (entry.key.top + entry.key.bottom) / 2);
        match *key {
            Key::Guide => {
                let style = BLACK.stroke_width(2);
                let (x, y) = at;
                root.draw(&PathElement::new([(x - 13, y), (x - 3, y)], style)).map_err(e)?;
                root.draw(&PathElement::new([(x + 3, y), (x + 13, y)], style)).map_err(e)?;
            }
            Key::Series(style, (r, g, b)) => {
                let colour = RGBColor(r, g, b);
                let sample = EmptyElement::at(at)
                    + PathElement::new([(-13, 0), (13, 0)], colour.stroke_width(2))
                    + Polygon::new(marker(style), colour.filled());
                root.draw(&sample).map_err(e)?;
            }
            Key::Marks(mark) => {
                let [(a, a_style), (b, b_style)] = mark_shape(mark);
                let sample = EmptyElement::at(at) + PathElement::new(a, a_style) + PathElement::new(b, b_style);
                root.draw(&sample).map_err(e)?;
            }
        }
        text(root, &entry.label)?;
    }
    Ok(())
}

/// Draws the chart where `plan`'s layout puts each part; returns the plotting area plotters drew in.
fn draw<DB, X, Y>(
    root: DrawingArea<DB, Shift>,
    chart: &Chart,
    overlay: &Overlay,
    plan: &Plan,
    x: X,
    y: Y,
) -> Result<Rect, String>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let l = &plan.layout;
    root.fill(&WHITE).map_err(e)?;
    for t in &l.title {
        text(&root, t)?;
    }
    // The plot with its tick label areas left of and below it; the axis descriptions and legend outside.
    let (y_ticks, x_ticks) = (l.plot.left - l.y_ticks.left, l.x_ticks.height());
    let area = root.clone().shrink((l.y_ticks.left, l.plot.top), (l.plot.width() + y_ticks, l.plot.height() + x_ticks));
    let mut cc = ChartBuilder::on(&area)
        .margin(0)
        .x_label_area_size(x_ticks)
        .y_label_area_size(y_ticks)
        .build_cartesian_2d(x, y)
        .map_err(e)?;
    let (px, py) = cc.plotting_area().get_pixel_range();
    let drawn = Rect { left: px.start, top: py.start, right: px.end, bottom: py.end };
    let format = |v: &f64| tick(*v);
    let x_format = |v: &f64| match overlay.x_ticks.iter().find(|t| (t.0 - v).abs() < 1e-6) {
        Some(t) => t.1.clone(),
        None => tick(*v),
    };
    cc.configure_mesh()
        .x_labels(AXIS_LABELS)
        .y_labels(AXIS_LABELS)
        .label_style((FONT, TICK_SIZE))
        .x_label_formatter(&x_format)
        .y_label_formatter(&format)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(200, 200, 200))
        .draw()
        .map_err(e)?;

    if let Some((value, _)) = &chart.guide {
        let (x0, x1) = (cc.x_range().start, cc.x_range().end);
        let style = BLACK.stroke_width(2);
        cc.draw_series(DashedLineSeries::new([(x0, *value), (x1, *value)], 12, 8, style)).map_err(e)?;
    }

    // Rules first, behind the data.
    if !overlay.rules.is_empty() {
        let (y0, y1) = (cc.y_range().start, cc.y_range().end);
        let style = RGBColor(90, 90, 90).stroke_width(2);
        cc.draw_series(overlay.rules.iter().flat_map(|&x| DashedLineSeries::new([(x, y0), (x, y1)], 10, 6, style)))
            .map_err(e)?;
    }

    let front: Vec<bool> = chart.lines.iter().map(|l| l.front).collect();
    for line in drawing_order(&front).into_iter().map(|i| &chart.lines[i]) {
        let (r, g, b) = line.rgb();
        let colour = RGBColor(r, g, b);
        let stroke = colour.stroke_width(2);
        let shape = marker(line.style);
        // 95% intervals: a vertical bar with caps at both ends (none where too few runs give no interval).
        let bounded = || line.points.iter().filter(|p| p.lo.is_finite() && p.hi.is_finite());
        cc.draw_series(bounded().map(|p| PathElement::new([(p.x, p.lo), (p.x, p.hi)], stroke))).map_err(e)?;
        cc.draw_series(
            bounded()
                .flat_map(|p| [(p.x, p.lo), (p.x, p.hi)])
                .map(|at| EmptyElement::at(at) + PathElement::new([(-6, 0), (6, 0)], stroke)),
        )
        .map_err(e)?;
        if !overlay.categorical {
            cc.draw_series(LineSeries::new(line.points.iter().map(|p| (p.x, p.y)), stroke)).map_err(e)?;
        }
        cc.draw_series(
            line.points.iter().map(|p| EmptyElement::at((p.x, p.y)) + Polygon::new(shape.clone(), colour.filled())),
        )
        .map_err(e)?;
    }

    for marks in overlay.marks.iter().filter(|m| !m.points.is_empty()) {
        let [(a, a_style), (b, b_style)] = mark_shape(marks.mark);
        cc.draw_series(marks.points.iter().map(|&at| {
            EmptyElement::at(at) + PathElement::new(a.clone(), a_style) + PathElement::new(b.clone(), b_style)
        }))
        .map_err(e)?;
    }

    for t in l.x_desc.iter().chain(&l.y_desc) {
        text(&root, t)?;
    }
    draw_legend(&root, plan)?;
    root.present().map_err(e)?;
    Ok(drawn)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::figures::layout::{BASE, Layout, MARGIN};

    /// Draws into an RGB buffer: the pixels, the plan and the plotting area plotters drew in.
    fn render_rgb(chart: &Chart, overlay: &Overlay) -> (Vec<u8>, Plan, Rect) {
        register_font();
        let plan = plan(chart, overlay);
        let size = plan.layout.size;
        let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
        let area = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        let drawn = draw_any(area, chart, overlay, &plan).unwrap();
        (rgb, plan, drawn)
    }

    /// The pixels that are not background.
    fn ink(rgb: &[u8], width: u32) -> impl Iterator<Item = (i32, i32)> + '_ {
        rgb.chunks_exact(3)
            .enumerate()
            .filter(|(_, p)| p != &[255, 255, 255])
            .map(move |(i, _)| ((i as u32 % width) as i32, (i as u32 / width) as i32))
    }

    /// A chart with `series` lines of long labels, every point inside a 95% interval, over x 1..=8.
    fn busy_chart(title: &str, series: usize, log_y: bool) -> Chart {
        let lines = (0..series)
            .map(|s| Line {
                label: format!("flat-sah-front-to-back-{s} objects 1000000 (threads 1)"),
                style: s,
                colour: None,
                front: false,
                points: (1..=8)
                    .map(|x| {
                        let y = 1.0 + (s * 7 + x * 3) as f64 % 20.0;
                        ChartPoint { x: x as f64, y, lo: y * 0.9, hi: y * 1.1 }
                    })
                    .collect(),
            })
            .collect();
        Chart {
            title: title.into(),
            x_label: "commit of each appended run, in order".into(),
            y_label: "speedup vs reference (×)".into(),
            log_x: false,
            log_y,
            lines,
            guide: Some((1.0, "same as reference".into())),
        }
    }

    fn history_overlay() -> Overlay {
        Overlay {
            x_ticks: (1..=8).map(|i| (i as f64, format!("{i:07x}"))).collect(),
            marks: vec![
                Marks { label: "regression (drop > 10%)".into(), mark: Mark::Cross, points: vec![(3.0, 5.0)] },
                Marks {
                    label: "change point (new level from here)".into(),
                    mark: Mark::Ring,
                    points: vec![(8.0, 21.0)],
                },
            ],
            rules: vec![2.5],
            categorical: false,
        }
    }

    /// Checks a rendered chart: plotters drew the plot where the layout put it, the legend box is off the
    /// plot (with room for markers at its edge), and every drawn pixel lies in a box the layout gave out.
    fn check_drawn(rgb: &[u8], layout: &Layout, drawn: Rect) {
        assert_eq!(drawn, layout.plot, "plotters' plotting area is not the layout's");
        // Markers and interval caps reach this far beyond the plot around points at its edges.
        let plot = layout.plot.grown(14);
        let legend = layout.legend.as_ref().map(|l| l.rect);
        if let Some(legend) = legend {
            assert!(!legend.intersects(&plot), "legend {legend:?} covers the plot {plot:?}");
        }
        let boxes: Vec<Rect> = [plot, layout.y_ticks, layout.x_ticks]
            .into_iter()
            .chain(layout.texts().map(|t| t.rect))
            .chain(legend)
            .collect();
        let stray: Vec<(i32, i32)> =
            ink(rgb, layout.size.0).filter(|&(x, y)| !boxes.iter().any(|b| b.has(x, y))).collect();
        assert!(
            stray.is_empty(),
            "{} pixels drawn outside the layout's boxes, e.g. {:?}",
            stray.len(),
            &stray[..stray.len().min(5)]
        );
        // Nothing in the margin.
        let inner = layout.canvas().grown(-MARGIN / 2);
        assert!(ink(rgb, layout.size.0).all(|(x, y)| inner.has(x, y)));
    }

    #[test]
    fn drawn_charts_keep_to_their_layout() {
        let long = "Trace time ratio to Embree (rtcIntersect1), primary rays, one thread (>1: faster than Embree)";
        // Many long legend entries below the plot, on a taller canvas; the x axis labelled with commits.
        let chart = busy_chart(long, 26, true);
        let (rgb, plan, drawn) = render_rgb(&chart, &history_overlay());
        check_drawn(&rgb, &plan.layout, drawn);
        assert!(plan.layout.size.1 > BASE.1);
        assert_eq!(plan.keys.len(), 26 + 3);
        // A few short entries right of the plot; linear axes.
        let mut chart = busy_chart("Build time", 4, false);
        chart.lines.iter_mut().for_each(|l| l.label = format!("ours-{}", l.style));
        let (rgb, plan, drawn) = render_rgb(&chart, &Overlay::default());
        check_drawn(&rgb, &plan.layout, drawn);
        assert!(plan.layout.legend.as_ref().unwrap().right_of_plot);
        // No data at all.
        let empty = Chart { lines: vec![], guide: None, ..busy_chart("(no data)", 0, true) };
        let (rgb, plan, drawn) = render_rgb(&empty, &Overlay::default());
        check_drawn(&rgb, &plan.layout, drawn);
    }

    #[test]
    fn text_stays_in_its_box() {
        register_font();
        for vertical in [false, true] {
            for size in [16.0, 20.0, 24.0, 32.0] {
                let sample = "Éjgq(|) ÅÇ ×}{";
                let length = layout::text_width(sample, size);
                let thickness = layout::line_height(size);
                let (w, h) = if vertical { (thickness, length) } else { (length, thickness) };
                let rect = Rect::new(20, 30, w, h);
                let size_px = (400, 400);
                let mut rgb = vec![255u8; 400 * 400 * 3];
                let root = BitMapBackend::with_buffer(&mut rgb, size_px).into_drawing_area();
                text(&root, &Text { text: sample.into(), size, rect, vertical }).unwrap();
                root.present().unwrap();
                drop(root);
                let pixels: Vec<(i32, i32)> = ink(&rgb, 400).collect();
                assert!(!pixels.is_empty());
                let outside: Vec<_> = pixels.iter().filter(|&&(x, y)| !rect.has(x, y)).collect();
                assert!(outside.is_empty(), "vertical {vertical}, size {size}: {outside:?} outside {rect:?}");
            }
        }
    }

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
        assert!(log_ticks(1.05, 1.8, false).len() >= 3, "{:?}", log_ticks(1.05, 1.8, false));
    }
}
