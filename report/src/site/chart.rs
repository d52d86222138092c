//! An interactive chart's data, as the page embeds it and `site.js` draws it.

use serde::Serialize;

use crate::figures::chart::{Chart, marker_name};

/// One point: x, y with its interval, the tooltip's lines and an optional link.
#[derive(Clone, Debug, Serialize)]
pub struct SitePoint {
    pub x: f64,
    pub y: f64,
    pub lo: f64,
    pub hi: f64,
    /// Tooltip lines, first the series.
    pub tip: Vec<String>,
    /// Where a click on the point goes (history points: their commit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub href: Option<String>,
}

/// One series.
#[derive(Clone, Debug, Serialize)]
pub struct SiteLine {
    pub label: String,
    /// Colour index, as in the PNG figures.
    pub style: usize,
    /// A colour of its own (`#rrggbb`, e.g. its backend family's) instead of the style's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub colour: Option<String>,
    /// Its marker, as in the PNG figures (`circle`, `triangle`, `square`, `diamond`, `triangle-down`, `cross`,
    /// `plus`).
    pub marker: &'static str,
    /// Drawn over the others (a peer's series over ours).
    pub front: bool,
    pub points: Vec<SitePoint>,
}

/// Points drawn as marks only: `cross` (regression) or `ring` (change point).
#[derive(Clone, Debug, Serialize)]
pub struct SiteMarks {
    pub label: String,
    pub mark: &'static str,
    pub points: Vec<(f64, f64)>,
}

/// Everything one interactive chart shows.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SiteChart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub lines: Vec<SiteLine>,
    /// A dashed horizontal line: (y, legend label).
    pub guide: Option<(f64, String)>,
    /// Labels of whole-number x values (commits); empty: numeric ticks.
    pub x_ticks: Vec<(f64, String)>,
    pub marks: Vec<SiteMarks>,
    /// Dashed vertical lines (change points).
    pub rules: Vec<f64>,
    /// The least relative span of the y axis (0: fit the data): a history axis shows at least its gate's width, so
    /// a change far below it is not drawn at full height.
    pub min_span: f64,
    /// The x axis is a category (a word column): points with intervals, side by side, not joined by lines.
    pub categorical: bool,
}

impl SiteChart {
    /// A series' line: its marker from its style, as the PNG figures draw it.
    pub fn line(label: String, style: usize, points: Vec<SitePoint>) -> SiteLine {
        SiteLine { label, style, colour: None, marker: marker_name(style), front: false, points }
    }

    /// The chart of a report figure, each point's tooltip from `tip(line, point)`.
    pub fn of(chart: &Chart, tip: impl Fn(usize, usize) -> Vec<String>) -> SiteChart {
        let lines = chart
            .lines
            .iter()
            .enumerate()
            .map(|(i, line)| SiteLine {
                label: line.label.clone(),
                style: line.style,
                colour: line.colour.map(|(r, g, b)| format!("#{r:02x}{g:02x}{b:02x}")),
                marker: marker_name(line.style),
                front: line.front,
                points: line
                    .points
                    .iter()
                    .enumerate()
                    .map(|(j, p)| SitePoint { x: p.x, y: p.y, lo: p.lo, hi: p.hi, tip: tip(i, j), href: None })
                    .collect(),
            })
            .collect();
        SiteChart {
            title: chart.title.clone(),
            x_label: chart.x_label.clone(),
            y_label: chart.y_label.clone(),
            log_x: chart.log_x,
            log_y: chart.log_y,
            lines,
            guide: chart.guide.clone(),
            ..SiteChart::default()
        }
    }

    /// The chart as JSON (NaN and infinities as null).
    pub fn json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }

    /// The chart's element: a container `site.js` draws into, and its data.
    pub fn element(&self, id: &str) -> String {
        format!(
            "<figure class=\"chart\" data-source=\"{id}\"></figure>\n{}",
            super::html::json_script(id, &self.json())
        )
    }
}
