//! Where every part of a chart goes, computed before anything is drawn: the title (shrunk, then wrapped to
//! the canvas width), the plotting area, the tick label areas beside it, the axis descriptions and the legend,
//! which sits outside the plotting area (right of it when one short column fits there, else below the axis
//! in as many columns as fit the width). The canvas grows when the legend or a label needs more room than
//! [`BASE`] leaves. Text is measured with the bundled font through plotters' text size estimation.

use std::sync::Once;

use plotters::style::{FontDesc, FontFamily, FontStyle};

/// The font every text is set in, bundled so that no system font is needed.
pub const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The canvas size in pixels when everything fits on it.
pub const BASE: (u32, u32) = (1200, 750);
/// Space kept free along every edge of the canvas.
pub const MARGIN: i32 = 24;
/// Space between the blocks (title, plot, legend).
const GAP: i32 = 14;
/// Title font size and the smallest size it shrinks to before it wraps.
pub const TITLE_SIZE: f64 = 32.0;
pub const TITLE_MIN: f64 = 24.0;
/// Axis description font size and the smallest size it shrinks to (then the x one wraps, the y one gets a
/// taller canvas).
pub const DESC_SIZE: f64 = 24.0;
pub const DESC_MIN: f64 = 16.0;
/// Tick label and legend font sizes.
pub const TICK_SIZE: f64 = 20.0;
pub const LEGEND_SIZE: f64 = 20.0;
/// A tick label's distance from its axis (plotters: twice the 5-pixel tick mark).
pub const TICK_DIST: i32 = 10;
/// Width of a legend entry's sample (line and marker), the space after it, the legend's inner padding and the
/// space between its columns.
pub const LEGEND_KEY: i32 = 30;
const LEGEND_KEY_GAP: i32 = 8;
const LEGEND_PAD: i32 = 10;
const LEGEND_COLUMN_GAP: i32 = 24;
/// The smallest plotting area; the canvas grows to keep it.
pub const MIN_PLOT: (i32, i32) = (480, 400);
/// A legend goes right of the plot only when it is at most this fraction of the canvas width.
const RIGHT_LEGEND_MAX: f64 = 0.28;
/// Where a line of text is drawn in its box: the text's top is anchored this many font sizes below the box
/// top. The bundled font's glyphs reach 0.16 sizes above the anchor and 0.72 below it (plotters' ab_glyph
/// backend puts the baseline half a size below the anchor), so this centres them in a [`line_height`] box.
pub const TEXT_OFFSET: f64 = 0.35;

/// Registers the bundled font under [`FONT`] once.
pub fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file is a valid font; if it were not, text would be missing, not the chart.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES);
    });
}

/// The width in pixels of `text` set in the bundled font at `size`.
pub fn text_width(text: &str, size: f64) -> i32 {
    register_font();
    let font = FontDesc::new(FontFamily::Name(FONT), size, FontStyle::Normal);
    match font.box_size(text) {
        Ok((w, _)) => w as i32 + 1,
        // Without the font (never expected): a generous estimate.
        Err(_) => (text.chars().count() as f64 * size * 0.7).ceil() as i32,
    }
}

/// The height of a line of text at `size`: room for the font's ascenders and descenders.
pub fn line_height(size: f64) -> i32 {
    (size * 1.25).ceil() as i32
}

/// A pixel rectangle: `left..right` × `top..bottom`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rect {
    pub left: i32,
    pub top: i32,
    pub right: i32,
    pub bottom: i32,
}

impl Rect {
    pub fn new(left: i32, top: i32, width: i32, height: i32) -> Rect {
        Rect { left, top, right: left + width, bottom: top + height }
    }
    pub fn width(&self) -> i32 {
        self.right - self.left
    }
    pub fn height(&self) -> i32 {
        self.bottom - self.top
    }
    /// Whether the two share any pixel.
    pub fn intersects(&self, other: &Rect) -> bool {
        self.left < other.right && other.left < self.right && self.top < other.bottom && other.top < self.bottom
    }
    /// Whether `other` lies wholly inside.
    pub fn contains(&self, other: &Rect) -> bool {
        other.left >= self.left && other.right <= self.right && other.top >= self.top && other.bottom <= self.bottom
    }
    /// Whether the pixel (x, y) is inside.
    #[cfg(test)]
    pub fn has(&self, x: i32, y: i32) -> bool {
        x >= self.left && x < self.right && y >= self.top && y < self.bottom
    }
    /// Grown by `by` pixels on every side.
    #[cfg(test)]
    pub fn grown(&self, by: i32) -> Rect {
        Rect { left: self.left - by, top: self.top - by, right: self.right + by, bottom: self.bottom + by }
    }
}

/// One line of text and the box its glyphs stay in; `vertical`: read bottom to top (the y description).
#[derive(Clone, Debug, PartialEq)]
pub struct Text {
    pub text: String,
    pub size: f64,
    pub rect: Rect,
    pub vertical: bool,
}

/// One legend entry: its whole box, the sample at its left and its label.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendEntry {
    pub rect: Rect,
    pub key: Rect,
    pub label: Text,
}

/// The legend's box, outside the plotting area, and its entries in the given order (row by row).
#[derive(Clone, Debug, PartialEq)]
pub struct Legend {
    pub rect: Rect,
    pub columns: usize,
    pub right_of_plot: bool,
    pub entries: Vec<LegendEntry>,
}

/// The texts a chart shows, which its layout is made for.
#[derive(Clone, Copy, Debug, Default)]
pub struct Labels<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
    /// Legend entries, in order.
    pub legend: &'a [String],
    /// The labelled ticks of each axis, in axis order.
    pub x_ticks: &'a [String],
    pub y_ticks: &'a [String],
}

/// Where everything of a chart goes.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The canvas size: [`BASE`] or larger.
    pub size: (u32, u32),
    /// The title's lines, top to bottom.
    pub title: Vec<Text>,
    /// The plotting area (the axes run along its left and bottom edges).
    pub plot: Rect,
    /// The y tick labels' area, left of the plot (reaching half a label above and below it).
    pub y_ticks: Rect,
    /// The x tick labels' area, below the plot (reaching half a label beyond both ends).
    pub x_ticks: Rect,
    /// The x axis description's lines, below the x tick labels.
    pub x_desc: Vec<Text>,
    /// The y axis description, left of the y tick labels, centred on the plot.
    pub y_desc: Option<Text>,
    pub legend: Option<Legend>,
}

impl Layout {
    /// Every text box: title lines, axis descriptions and legend labels (tick labels are in their areas).
    pub fn texts(&self) -> impl Iterator<Item = &Text> {
        let legend = self.legend.iter().flat_map(|l| l.entries.iter().map(|e| &e.label));
        self.title.iter().chain(&self.x_desc).chain(&self.y_desc).chain(legend)
    }

    /// The canvas as a rectangle.
    pub fn canvas(&self) -> Rect {
        Rect::new(0, 0, self.size.0 as i32, self.size.1 as i32)
    }
}

/// `text` split into lines no wider than `width` at `size`: at spaces, and inside a word only where the word
/// alone is too wide.
pub fn wrap(text: &str, size: f64, width: i32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let joined = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if text_width(&joined, size) <= width {
            line = joined;
            continue;
        }
        if !line.is_empty() {
            lines.push(std::mem::take(&mut line));
        }
        // A word wider than the line on its own: break it between characters.
        for c in word.chars() {
            let longer = format!("{line}{c}");
            if !line.is_empty() && text_width(&longer, size) > width {
                lines.push(std::mem::replace(&mut line, c.to_string()));
            } else {
                line = longer;
            }
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// The largest size from `max` down to `min` (steps of 1) at which `text` fits `width` on one line, with that
/// line; else `text` wrapped at `min`.
fn fit(text: &str, max: f64, min: f64, width: i32) -> (f64, Vec<String>) {
    let mut size = max;
    while size >= min {
        if text_width(text, size) <= width {
            return (size, if text.trim().is_empty() { vec![] } else { vec![text.to_string()] });
        }
        size -= 1.0;
    }
    (min, wrap(text, min, width))
}

/// Horizontal lines of text at `size`, each centred on `centre`, stacked down from `top`.
fn stacked(lines: Vec<String>, size: f64, centre: i32, top: i32) -> Vec<Text> {
    let h = line_height(size);
    lines
        .into_iter()
        .enumerate()
        .map(|(i, text)| {
            let w = text_width(&text, size);
            let rect = Rect::new(centre - w / 2, top + i as i32 * h, w, h);
            Text { text, size, rect, vertical: false }
        })
        .collect()
}

/// The layout of a chart with `labels`: see the module documentation.
pub fn layout(labels: &Labels) -> Layout {
    let (mut width, mut height) = (BASE.0 as i32, BASE.1 as i32);

    // Legend entries: the widest decides the column width; the canvas widens for one that is wider still.
    let entry_widths: Vec<i32> =
        labels.legend.iter().map(|l| LEGEND_KEY + LEGEND_KEY_GAP + text_width(l, LEGEND_SIZE)).collect();
    let column = entry_widths.iter().copied().max().unwrap_or(0);
    let row = line_height(LEGEND_SIZE) + 2;
    width = width.max(column + 2 * LEGEND_PAD + 2 * MARGIN);

    // Title: one line if it fits at TITLE_MIN or larger, else wrapped.
    let (title_size, title_lines) = fit(labels.title, TITLE_SIZE, TITLE_MIN, width - 2 * MARGIN);
    let title_height = title_lines.len() as i32 * line_height(title_size);

    // Tick labels: the y ones right-aligned left of the axis, the x ones centred under their ticks.
    let tick_line = line_height(TICK_SIZE);
    let y_tick_width = labels.y_ticks.iter().map(|t| text_width(t, TICK_SIZE)).max().unwrap_or(0) + TICK_DIST + 6;
    let x_tick_widths: Vec<i32> = labels.x_ticks.iter().map(|t| text_width(t, TICK_SIZE)).collect();
    let x_overhang = x_tick_widths.iter().copied().max().unwrap_or(0) / 2 + 4;
    let x_tick_height = TICK_DIST + tick_line + 4;
    let y_desc_column = line_height(DESC_SIZE);

    let left = (MARGIN + y_desc_column + 6 + y_tick_width).max(MARGIN + x_overhang);
    let top = MARGIN + title_height + if title_height > 0 { GAP } else { 0 } + tick_line / 2;

    // The legend right of the plot when one column of it is narrow and short enough, else below.
    let n = labels.legend.len() as i32;
    let right_legend_width = column + 2 * LEGEND_PAD;
    let base_plot_height = height - top - x_tick_height - line_height(DESC_SIZE) - MARGIN;
    let right_of_plot = n > 0
        && f64::from(right_legend_width) <= RIGHT_LEGEND_MAX * f64::from(width)
        && n * row + 2 * LEGEND_PAD <= base_plot_height;
    let right = if right_of_plot {
        width - MARGIN - right_legend_width - GAP.max(x_overhang - right_legend_width)
    } else {
        width - MARGIN - x_overhang
    };
    // Too narrow a plot (only for very wide tick labels): widen the canvas.
    let right = if right - left < MIN_PLOT.0 {
        width += MIN_PLOT.0 - (right - left);
        left + MIN_PLOT.0
    } else {
        right
    };
    let plot_width = right - left;

    // Below the plot: x tick labels, the x description (shrunk, then wrapped, to the plot's width), the legend.
    let (x_desc_size, x_desc_lines) = fit(labels.x, DESC_SIZE, DESC_MIN, plot_width);
    let x_desc_height = x_desc_lines.len() as i32 * line_height(x_desc_size);
    let (columns, rows) = if n == 0 || right_of_plot {
        (1, n)
    } else {
        let fit_columns = (width - 2 * MARGIN - 2 * LEGEND_PAD + LEGEND_COLUMN_GAP) / (column + LEGEND_COLUMN_GAP);
        let columns = fit_columns.clamp(1, n);
        let rows = (n + columns - 1) / columns;
        // As few columns as give that many rows: no empty column at the end.
        ((n + rows - 1) / rows, rows)
    };
    let legend_height = if n == 0 { 0 } else { rows * row + 2 * LEGEND_PAD };
    let legend_width = columns * column + (columns - 1) * LEGEND_COLUMN_GAP + 2 * LEGEND_PAD;
    let below = x_tick_height + x_desc_height + if n > 0 && !right_of_plot { GAP + legend_height } else { 0 };

    // The plot's height: what is left, at least MIN_PLOT, the right legend's height and the y description's
    // length at its smallest size; the canvas grows for more.
    let y_desc_min = text_width(labels.y, DESC_MIN) + 8;
    let right_legend_height = if right_of_plot { legend_height } else { 0 };
    let plot_height = (height - top - below - MARGIN).max(MIN_PLOT.1).max(right_legend_height).max(y_desc_min);
    height = height.max(top + plot_height + below + MARGIN);
    let bottom = top + plot_height;
    let plot = Rect { left, top, right, bottom };

    let y_ticks =
        Rect { left: left - y_tick_width, top: top - tick_line / 2, right: left, bottom: bottom + tick_line / 2 };
    let x_ticks =
        Rect { left: left - x_overhang, top: bottom, right: right + x_overhang, bottom: bottom + x_tick_height };
    let centre = (left + right) / 2;
    let x_desc = stacked(x_desc_lines, x_desc_size, centre, x_ticks.bottom);

    let y_desc = (!labels.y.trim().is_empty()).then(|| {
        let mut size = DESC_SIZE;
        while size > DESC_MIN && text_width(labels.y, size) + 8 > plot_height {
            size -= 1.0;
        }
        let length = text_width(labels.y, size);
        let thickness = line_height(size);
        let rect = Rect::new(MARGIN + (y_desc_column - thickness), (top + bottom) / 2 - length / 2, thickness, length);
        Text { text: labels.y.to_string(), size, rect, vertical: true }
    });

    let legend = (n > 0).then(|| {
        let rect = if right_of_plot {
            Rect::new(width - MARGIN - right_legend_width, top, right_legend_width, legend_height)
        } else {
            let legend_top = x_ticks.bottom + x_desc_height + GAP;
            let legend_left = (centre - legend_width / 2).clamp(MARGIN, width - MARGIN - legend_width);
            Rect::new(legend_left, legend_top, legend_width, legend_height)
        };
        let entries = labels
            .legend
            .iter()
            .enumerate()
            .map(|(i, text)| {
                let (r, c) = (i as i32 / columns, i as i32 % columns);
                let entry = Rect::new(
                    rect.left + LEGEND_PAD + c * (column + LEGEND_COLUMN_GAP),
                    rect.top + LEGEND_PAD + r * row,
                    column,
                    row,
                );
                let key = Rect::new(entry.left, entry.top, LEGEND_KEY, row);
                let h = line_height(LEGEND_SIZE);
                let label_rect = Rect::new(
                    entry.left + LEGEND_KEY + LEGEND_KEY_GAP,
                    entry.top + (row - h) / 2,
                    text_width(text, LEGEND_SIZE),
                    h,
                );
                let label = Text { text: text.clone(), size: LEGEND_SIZE, rect: label_rect, vertical: false };
                LegendEntry { rect: entry, key, label }
            })
            .collect();
        Legend { rect, columns: columns as usize, right_of_plot, entries }
    });

    let title = stacked(title_lines, title_size, width / 2, MARGIN);
    let l = Layout { size: (width as u32, height as u32), title, plot, y_ticks, x_ticks, x_desc, y_desc, legend };
    debug_assert!(l.texts().all(|t| l.canvas().contains(&t.rect) && !t.rect.intersects(&l.plot)), "{l:?}");
    debug_assert!(l.legend.as_ref().is_none_or(|g| l.canvas().contains(&g.rect) && !g.rect.intersects(&l.plot)));
    l
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    /// The ratio-to-Embree title that the old layout clipped at both ends.
    const LONG_TITLE: &str =
        "Trace time ratio to Embree (rtcIntersect1), primary rays, one thread (>1: faster than Embree)";

    /// The history chart's legend: 26 entries of ~45 characters, plus its two mark entries.
    fn history_legend() -> Vec<String> {
        let series = ["paper-bvh", "flat-bvh", "flat-front-to-back", "flat-sah-front-to-back", "obvhs-bvh2"];
        let mut v: Vec<String> = series
            .iter()
            .flat_map(|s| [1000, 10000, 100000, 1000000, 5000].map(|o| format!("{s} objects {o} (threads 1)")))
            .collect();
        v.push("flat-front-to-back-rayon objects 10000 (threads 2)".into());
        v.push("regression (drop > 10%)".into());
        v.push("change point (new level from here)".into());
        v
    }

    /// Every geometric promise of a layout.
    fn check(l: &Layout, labels: &Labels) {
        let canvas = l.canvas().grown(-MARGIN / 2);
        assert!(l.size.0 >= BASE.0 && l.size.1 >= BASE.1, "{:?}", l.size);
        for t in l.texts() {
            assert!(canvas.contains(&t.rect), "{:?} outside the canvas {:?}", t, l.size);
            let extent = if t.vertical { t.rect.height() } else { t.rect.width() };
            assert!(extent >= text_width(&t.text, t.size), "{t:?} is narrower than its text");
            assert!(!t.rect.intersects(&l.plot), "{t:?} overlaps the plot {:?}", l.plot);
        }
        for area in [l.plot, l.y_ticks, l.x_ticks] {
            assert!(canvas.contains(&area), "{area:?} outside the canvas {:?}", l.size);
        }
        assert!(l.plot.width() >= MIN_PLOT.0 && l.plot.height() >= MIN_PLOT.1, "{:?}", l.plot);
        // The title above everything else, its lines apart, and within the canvas width at TITLE_MIN or more.
        for pair in l.title.windows(2) {
            assert!(!pair[0].rect.intersects(&pair[1].rect) && pair[0].rect.bottom <= pair[1].rect.top);
        }
        for t in &l.title {
            assert!(t.size >= TITLE_MIN);
            for other in [l.plot, l.y_ticks, l.x_ticks] {
                assert!(!t.rect.intersects(&other), "title {t:?} overlaps {other:?}");
            }
        }
        let title_text: Vec<&str> = l.title.iter().map(|t| t.text.as_str()).collect();
        assert_eq!(
            title_text.join(" ").split_whitespace().collect::<String>(),
            labels.title.split_whitespace().collect::<String>()
        );
        // Tick label areas beside the plot, not in it.
        assert!(l.y_ticks.right <= l.plot.left && l.x_ticks.top >= l.plot.bottom);
        let widest_y = labels.y_ticks.iter().map(|t| text_width(t, TICK_SIZE)).max().unwrap_or(0);
        assert!(l.y_ticks.width() >= widest_y + TICK_DIST);
        // The axis descriptions: outside the tick label areas, and wholly shown.
        for t in l.x_desc.iter().chain(&l.y_desc) {
            assert!(!t.rect.intersects(&l.y_ticks) && !t.rect.intersects(&l.x_ticks), "{t:?}");
        }
        if let Some(y) = &l.y_desc {
            assert!(y.rect.height() <= l.plot.height() && y.size >= DESC_MIN);
        }
        let x_text: Vec<&str> = l.x_desc.iter().map(|t| t.text.as_str()).collect();
        assert_eq!(
            x_text.join(" ").split_whitespace().collect::<String>(),
            labels.x.split_whitespace().collect::<String>()
        );
        // The legend: every entry, inside its box, which stays off the plot and its tick labels.
        match &l.legend {
            None => assert!(labels.legend.is_empty()),
            Some(legend) => {
                assert_eq!(legend.entries.len(), labels.legend.len());
                assert!(canvas.contains(&legend.rect), "{:?} outside {:?}", legend.rect, l.size);
                for area in [l.plot, l.y_ticks, l.x_ticks] {
                    assert!(!legend.rect.intersects(&area), "legend {:?} overlaps {area:?}", legend.rect);
                }
                for t in l.title.iter().chain(&l.x_desc).chain(&l.y_desc) {
                    assert!(!legend.rect.intersects(&t.rect), "legend {:?} overlaps {t:?}", legend.rect);
                }
                for (i, e) in legend.entries.iter().enumerate() {
                    assert!(legend.rect.contains(&e.rect) && e.rect.contains(&e.key) && e.rect.contains(&e.label.rect));
                    assert!(!e.key.intersects(&e.label.rect));
                    for f in &legend.entries[i + 1..] {
                        assert!(!e.rect.intersects(&f.rect), "{e:?} overlaps {f:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn long_titles_shrink_then_wrap_within_the_canvas() {
        let legend = strings(&["same as embree", "paper-bvh", "ours-best", "wide-best", "embree-packets-8"]);
        let ticks = strings(&["100", "1000", "10000", "100000", "1000000"]);
        let labels = Labels {
            title: LONG_TITLE,
            x: "objects (spheres)",
            y: "speedup in trace_s vs embree (×)",
            legend: &legend,
            x_ticks: &ticks,
            y_ticks: &strings(&["0.05", "0.1", "0.2", "0.5", "1", "2"]),
        };
        // The old layout set it in one line at 32 px, wider than the canvas.
        assert!(text_width(LONG_TITLE, TITLE_SIZE) > BASE.0 as i32);
        let l = layout(&labels);
        check(&l, &labels);
        assert_eq!(l.title.len(), 1, "{:?}", l.title);
        assert!(l.title[0].size < TITLE_SIZE);
        assert_eq!(l.size, BASE);

        let longer = format!("{LONG_TITLE}, measured on the AVX-512 machine with every series at its best settings");
        let labels = Labels { title: &longer, ..labels };
        let l = layout(&labels);
        check(&l, &labels);
        assert!(l.title.len() >= 2, "{:?}", l.title);
        assert!(l.title.iter().all(|t| t.size == TITLE_MIN));

        // One word wider than the canvas breaks between characters.
        let word = "x".repeat(120);
        let labels = Labels { title: &word, ..labels };
        let l = layout(&labels);
        check(&l, &labels);
        assert!(l.title.len() >= 2);
    }

    #[test]
    fn many_legend_entries_go_below_the_plot_in_columns_and_grow_the_canvas() {
        let legend = history_legend();
        let ticks = strings(&["1cd5b81", "2e5022d", "ddb51c5"]);
        let labels = Labels {
            title: "ci: speedups over the appended runs",
            x: "commit of each appended run, in order",
            y: "speedup vs reference (×)",
            legend: &legend,
            x_ticks: &ticks,
            y_ticks: &strings(&["20", "50", "100", "200"]),
        };
        let l = layout(&labels);
        check(&l, &labels);
        let legend = l.legend.as_ref().unwrap();
        assert!(!legend.right_of_plot && legend.columns >= 2, "{legend:?}");
        assert!(legend.rect.top >= l.x_ticks.bottom);
        assert!(l.size.1 > BASE.1, "the canvas grows for a long legend: {:?}", l.size);
        assert!(l.plot.height() >= MIN_PLOT.1);
    }

    #[test]
    fn a_short_legend_goes_right_of_the_plot() {
        let legend = strings(&["ours-fast", "ours-medium", "embree-high", "tinybvh-8-hq", "obvhs-slow"]);
        let labels = Labels {
            title: "Bunny, diffuse rays: build time against trace time (one thread)",
            x: "build time (s)",
            y: "trace time (s)",
            legend: &legend,
            x_ticks: &strings(&["0.02", "0.05", "0.1", "0.2"]),
            y_ticks: &strings(&["0", "0.005", "0.01", "0.015", "0.02"]),
        };
        let l = layout(&labels);
        check(&l, &labels);
        let legend = l.legend.as_ref().unwrap();
        assert!(legend.right_of_plot && legend.columns == 1);
        assert!(legend.rect.left >= l.plot.right && legend.rect.bottom <= l.plot.bottom);
        assert_eq!(l.size, BASE);
    }

    #[test]
    fn long_labels_and_legend_entries_fit() {
        let long = "efficiency: speedup in trace_s vs embree-packets-8 over all the worker threads of the machine";
        let very_long_y = format!("{long}, {long}");
        let legend = vec![format!("{long} {long}"), "short".to_string()];
        let ticks: Vec<String> = (0..8).map(|i| format!("{i}000000000.25")).collect();
        let very_long_x = format!("{very_long_y}, {very_long_y}");
        let labels =
            Labels { title: long, x: &very_long_x, y: &very_long_y, legend: &legend, x_ticks: &ticks, y_ticks: &ticks };
        let l = layout(&labels);
        check(&l, &labels);
        assert!(l.x_desc.len() >= 2, "{:?}", l.x_desc);
        assert!(l.size.0 > BASE.0 && l.size.1 > BASE.1, "{:?}", l.size);
        // No text, no legend: the plot fills the canvas within its margins.
        let empty = Labels::default();
        let l = layout(&empty);
        check(&l, &empty);
        assert!(l.title.is_empty() && l.legend.is_none() && l.y_desc.is_none());
    }

    #[test]
    fn wrapping_keeps_every_word_and_the_width() {
        let lines = wrap(LONG_TITLE, TITLE_MIN, 500);
        assert!(lines.len() >= 3);
        assert!(lines.iter().all(|l| text_width(l, TITLE_MIN) <= 500));
        assert_eq!(lines.join(" "), LONG_TITLE);
        assert_eq!(wrap("", 20.0, 100), Vec::<String>::new());
    }
}
