//! Experiment configs: TOML files naming sweep axes, series, exclusions, quick overrides, plots and claims.
//!
//! Every key is checked; a wrong key, type or value is one line naming the file, the key path and what is
//! allowed (see [`table::Section`]). Axes parse straight into typed values ([`schema::AxisValue`]); nothing
//! here touches the results folder.

mod table;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use report::spec::{ClaimKind, ClaimSpec, HeadlineSpec, PlotKind, PlotSpec, ReportSpec};
use schema::columns::Replaced;
use schema::{Axis, AxisValue, MeshSource, Raw};

use crate::error::Error;
use table::Section;

/// Values per axis.
pub type AxisValues = BTreeMap<Axis, Vec<AxisValue>>;

/// The order in which runs are executed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RunOrder {
    /// Repetition rounds over all configurations (machine drift hits all alike).
    #[default]
    Interleaved,
    /// All repetitions of one configuration, then the next.
    Sequential,
    /// Every (configuration, repetition) in a seeded random order.
    Shuffled,
}

/// A `[[series]]` table: a label and the axes it fixes.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub fixed: AxisValues,
}

/// An `[[exclude]]` table: runs matching every given key are skipped.
#[derive(Clone, Debug, PartialEq)]
pub struct Exclude {
    pub series: Option<Vec<String>>,
    pub axes: AxisValues,
}

/// How many timed repetitions each configuration gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Repetitions {
    /// Exactly this many (`repetitions = N`).
    Fixed(u32),
    /// `repetitions = "auto"`: at least `min` and at most `max`; a configuration stops as soon as the 95% interval
    /// of its median (of the speedup metric) is at most `target_width` of the median wide.
    Auto { min: u32, max: u32, target_width: f64 },
}

impl Repetitions {
    /// Default `min_repetitions` of `"auto"`: ten processes' rounds, whose 95% interval drops the most extreme on
    /// each side (a process-bootstrap interval needs six; docs/statistics.md, "The defaults").
    pub const AUTO_MIN: u32 = 10;
    /// Default `max_repetitions` of `"auto"`: the rounds (one per process) `experiments/resolution.toml` validated.
    pub const AUTO_MAX: u32 = 24;
    /// Default `target_ci_width` of `"auto"`: ±1%, so that an A/A ratio settles within ±2% with room to spare.
    pub const AUTO_TARGET_WIDTH: f64 = 0.02;
    /// `repetitions` of a config that does not set it: `"auto"` with the defaults above.
    pub const DEFAULT: Repetitions =
        Repetitions::Auto { min: Self::AUTO_MIN, max: Self::AUTO_MAX, target_width: Self::AUTO_TARGET_WIDTH };

    /// The most repetitions a configuration can get (what the plan lays out).
    pub fn max(self) -> u32 {
        match self {
            Repetitions::Fixed(n) => n,
            Repetitions::Auto { max, .. } => max,
        }
    }

    /// The fewest repetitions a configuration gets.
    pub fn min(self) -> u32 {
        match self {
            Repetitions::Fixed(n) => n,
            Repetitions::Auto { min, .. } => min,
        }
    }

    /// The rule as rows record it (`repetition_rule`): `fixed 5`, or `auto 3..10 ±3% total_s` with the metric
    /// whose median's interval decides.
    pub fn rule(self, metric: &str) -> String {
        match self {
            Repetitions::Fixed(n) => format!("fixed {n}"),
            Repetitions::Auto { min, max, target_width } => {
                format!("auto {min}..{max} width {} {metric}", target_width)
            }
        }
    }
}

/// `warmups` of a config that does not set it: one untimed round, as `experiments/resolution.toml`.
pub const DEFAULT_WARMUPS: u32 = 1;
/// `sample_ms` of a config that does not set it: 50-ms samples whose passes take turns, as
/// `experiments/resolution.toml` (docs/statistics.md, "Passes in turn").
pub const DEFAULT_SAMPLE_MS: u32 = 50;
/// The most `processes` a config may give, and the most the default takes.
pub const MAX_PROCESSES: u32 = 64;

/// `processes` of a config that does not set it: one per repetition (its maximum, for `"auto"`), at most
/// [`MAX_PROCESSES`] — one round per process, as `experiments/resolution.toml` validated.
pub fn default_processes(repetitions: Repetitions) -> u32 {
    repetitions.max().clamp(1, MAX_PROCESSES)
}

/// The `[quick]` overrides: repetitions, warm-ups and sweep axes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Quick {
    pub repetitions: Option<Repetitions>,
    pub warmups: Option<u32>,
    pub sample_s: Option<f64>,
    pub sweep: AxisValues,
}

/// A parsed, checked experiment.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// The config file (for messages).
    pub path: PathBuf,
    /// The file's text as read.
    pub text: String,
    pub name: String,
    pub description: String,
    pub reference: Option<String>,
    /// The metric speedups are ratios of (`None`: `trace_s` for ray sets, `total_s` for renders).
    pub speedup_metric: Option<String>,
    pub repetitions: Repetitions,
    pub warmups: u32,
    pub order: RunOrder,
    pub order_seed: u64,
    /// The shortest timed sample, in seconds (`sample_ms`): each timed run traces its job again until this much
    /// time has passed and records the mean per pass (0: one pass).
    pub sample_s: f64,
    /// Processes each configuration is timed in (`processes`): its timed runs fall into that many blocks, each timed
    /// in a worker process of its own, so that what lasts a process's life varies between its runs (1: one process).
    pub processes: u32,
    /// Whether the config sets `processes` (else it is [`default_processes`] of the repetitions, `[quick]`'s
    /// included).
    pub processes_given: bool,
    pub sweep: AxisValues,
    /// `sweep.sphere_file`, resolved against the config's folder.
    pub sphere_file: Option<PathBuf>,
    pub series: Vec<Series>,
    pub exclude: Vec<Exclude>,
    pub quick: Option<Quick>,
    pub plots: Vec<PlotSpec>,
    pub claims: Vec<ClaimSpec>,
    /// `[headline]`: the comparison the report leads with (`None`: taken from the claims).
    pub headline: Option<HeadlineSpec>,
}

const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "reference",
    "speedup_metric",
    "repetitions",
    "min_repetitions",
    "max_repetitions",
    "target_ci_width",
    "warmups",
    "order",
    "order_seed",
    "sample_ms",
    "processes",
    "sweep",
    "series",
    "exclude",
    "quick",
    "plot",
    "claim",
    "headline",
];

/// Keys of all axes, for "allowed keys" messages.
fn axis_keys() -> String {
    Axis::ALL.iter().map(|a| a.key()).collect::<Vec<_>>().join(", ")
}

/// The metrics a plot or claim may name.
fn metrics() -> Vec<&'static str> {
    schema::row::plottable_names()
}

/// Checks that `name` is a file-safe identifier.
fn identifier(s: &Section<'_>, key: &str, name: &str, what: &str) -> Result<(), Error> {
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
        return Err(s.error(key, format!("{name:?} is not a valid {what} (allowed: letters, digits, '-', '_')")));
    }
    Ok(())
}

/// Reads axis lists (`key = [values]` or `key = value`) from `s`, skipping `skip` keys.
fn axis_values(s: &Section<'_>, skip: &[&str]) -> Result<AxisValues, Error> {
    let mut out = AxisValues::new();
    for key in s.keys().filter(|k| !skip.contains(&k.as_str())) {
        if let Some(replaced) = Replaced::of(key) {
            return Err(s.error(key, replaced.instead()));
        }
        let axis = Axis::from_key(key).ok_or_else(|| {
            let mut allowed = axis_keys();
            skip.iter().for_each(|k| allowed.push_str(&format!(", {k}")));
            s.error(key, format!("unknown key (allowed: {allowed})"))
        })?;
        let items: Vec<&toml::Value> = match s.get(key).expect("key listed") {
            toml::Value::Array(a) => a.iter().collect(),
            one => vec![one],
        };
        if items.is_empty() {
            return Err(s.error(key, format!("empty list (give at least one value; allowed: {})", axis.allowed())));
        }
        let values = items
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                let raw = match v {
                    toml::Value::Integer(i) => Raw::Int(*i),
                    toml::Value::Float(x) => Raw::Float(*x),
                    toml::Value::String(s) => Raw::Str(s),
                    other => {
                        let found = format!("expected a string or number, found a {}", other.type_str());
                        return Err(s.error(&format!("{key}[{i}]"), format!("{found} (allowed: {})", axis.allowed())));
                    }
                };
                axis.parse(raw).map_err(|m| s.error(&format!("{key}[{i}]"), m))
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.insert(axis, values);
    }
    Ok(out)
}

/// A `where = { axis = value or [values] }` table: the runs a plot or claim looks at, as row text.
fn filter(s: &Section<'_>) -> Result<Vec<(String, Vec<String>)>, Error> {
    let Some(w) = s.section("where")? else { return Ok(vec![]) };
    let axes = axis_values(&w, &[])?;
    Ok(axes
        .into_iter()
        .map(|(axis, values)| (axis.key().to_string(), values.iter().map(|v| v.to_string()).collect()))
        .collect())
}

/// The series labels of a config, for checking the keys that name one.
struct Labels(Vec<String>);

impl Labels {
    fn check(&self, s: &Section<'_>, key: &str, label: &str) -> Result<(), Error> {
        if self.0.iter().any(|l| l == label) {
            Ok(())
        } else {
            Err(s.error(key, format!("unknown series {label:?} (allowed: {})", self.0.join(", "))))
        }
    }
}

impl Experiment {
    /// Reads and checks the config at `path`.
    pub fn load(path: &Path) -> Result<Self, Error> {
        let text =
            std::fs::read_to_string(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
        Self::parse(path, &text)
    }

    /// Checks config `text`, reporting errors against `path`.
    pub fn parse(path: &Path, text: &str) -> Result<Self, Error> {
        let file = path.display().to_string();
        let root: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let line = e.span().map_or(0, |s| text[..s.start.min(text.len())].lines().count().max(1));
            Error::Input(format!("{file}: line {line}: invalid TOML: {}", e.message().trim()))
        })?;
        let top = Section::root(&file, &root);
        top.only(TOP_KEYS)?;
        let name = top.required_string("name")?.to_string();
        identifier(&top, "name", &name, "name")?;
        let sweep_section = top.section("sweep")?.ok_or_else(|| top.error_here("missing [sweep] table"))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut series = parse_series(&top)?;
        series.iter_mut().for_each(|s| meshes_relative_to(dir, &mut s.fixed));
        let mut sweep = axis_values(&sweep_section, &["sphere_file"])?;
        meshes_relative_to(dir, &mut sweep);
        let labels = Labels(series.iter().map(|s| s.label.clone()).collect());
        let reference = top.string("reference")?.map(str::to_string);
        if let Some(r) = &reference {
            labels.check(&top, "reference", r)?;
        }
        let repetitions = parse_repetitions(&top)?.unwrap_or(Repetitions::DEFAULT);
        let processes = top.integer("processes", 1, MAX_PROCESSES as i64)?;
        Ok(Experiment {
            path: path.to_path_buf(),
            text: text.to_string(),
            description: top.string("description")?.unwrap_or("").to_string(),
            speedup_metric: top.string("speedup_metric")?.map(|_| metric(&top, "speedup_metric")).transpose()?,
            repetitions,
            warmups: top.integer("warmups", 0, 100)?.map_or(DEFAULT_WARMUPS, |w| w as u32),
            order: parse_order(&top)?,
            order_seed: top.integer("order_seed", 0, i64::MAX)?.unwrap_or(0) as u64,
            sample_s: sample_seconds(&top)?.unwrap_or(DEFAULT_SAMPLE_MS as f64 / 1e3),
            processes: processes.map_or(default_processes(repetitions), |p| p as u32),
            processes_given: processes.is_some(),
            sweep,
            sphere_file: sweep_section.string("sphere_file")?.map(|f| dir.join(f)),
            exclude: parse_excludes(&top, &labels)?,
            quick: parse_quick(&top)?,
            plots: top
                .sections("plot")?
                .iter()
                .map(|p| parse_plot(p, &labels, reference.is_some()))
                .collect::<Result<_, _>>()?,
            claims: top.sections("claim")?.iter().map(|c| parse_claim(c, &labels)).collect::<Result<_, _>>()?,
            headline: top.section("headline")?.map(|h| parse_headline(&h, &labels)).transpose()?,
            name,
            reference,
            series,
        })
    }

    /// The same experiment with its `[quick]` overrides applied (unchanged when it has none).
    pub fn quick(mut self) -> Self {
        if let Some(q) = self.quick.take() {
            self.repetitions = q.repetitions.unwrap_or(self.repetitions);
            self.warmups = q.warmups.unwrap_or(self.warmups);
            self.sample_s = q.sample_s.unwrap_or(self.sample_s);
            if !self.processes_given {
                self.processes = default_processes(self.repetitions);
            }
            self.sweep.extend(q.sweep);
        }
        self
    }

    /// What the report needs from this experiment.
    pub fn report_spec(&self, notes: Vec<String>) -> ReportSpec {
        let fixed =
            |s: &Series| schema::applicability::fixed_axes(&s.fixed).into_iter().map(|a| a.key().to_string()).collect();
        ReportSpec {
            name: self.name.clone(),
            description: self.description.clone(),
            reference: self.reference.clone(),
            speedup_metric: self.speedup_metric.clone(),
            series: self.series.iter().map(|s| s.label.clone()).collect(),
            series_fixed: self.series.iter().map(|s| (s.label.clone(), fixed(s))).collect(),
            plots: self.plots.clone(),
            claims: self.claims.clone(),
            config_text: self.text.clone(),
            notes,
            warnings: vec![],
            headline: self.headline.clone(),
        }
    }
}

/// `order`.
fn parse_order(top: &Section<'_>) -> Result<RunOrder, Error> {
    Ok(match top.string("order")? {
        None | Some("interleaved") => RunOrder::Interleaved,
        Some("sequential") => RunOrder::Sequential,
        Some("shuffled") => RunOrder::Shuffled,
        Some(o) => {
            return Err(top.error("order", format!("unknown value {o:?} (allowed: interleaved, sequential, shuffled)")));
        }
    })
}

/// `[[series]]` tables.
fn parse_series(top: &Section<'_>) -> Result<Vec<Series>, Error> {
    let mut series: Vec<Series> = Vec::new();
    for s in top.sections("series")? {
        let label = s.required_string("label")?.to_string();
        if series.iter().any(|x| x.label == label) {
            return Err(s.error("label", format!("duplicate series label {label:?}")));
        }
        series.push(Series { label, fixed: axis_values(&s, &["label"])? });
    }
    Ok(series)
}

/// `mesh` paths (not data set names) taken relative to the config's folder, as `sphere_file` is.
fn meshes_relative_to(dir: &Path, values: &mut AxisValues) {
    for value in values.get_mut(&Axis::mesh).into_iter().flatten() {
        if let AxisValue::mesh(Some(MeshSource(source))) = value
            && crate::meshes::is_path(source)
            && Path::new(source.as_str()).is_relative()
        {
            *source = dir.join(source.as_str()).display().to_string();
        }
    }
}

/// `[[exclude]]` tables.
fn parse_excludes(top: &Section<'_>, labels: &Labels) -> Result<Vec<Exclude>, Error> {
    let mut exclude = Vec::new();
    for s in top.sections("exclude")? {
        let only_series = s.strings("series")?;
        for l in only_series.iter().flatten() {
            labels.check(&s, "series", l)?;
        }
        let axes = axis_values(&s, &["series"])?;
        if axes.is_empty() && only_series.is_none() {
            return Err(
                s.error_here(format!("empty [[exclude]] would skip every run (give keys: series, {})", axis_keys()))
            );
        }
        exclude.push(Exclude { series: only_series, axes });
    }
    Ok(exclude)
}

/// `[quick]`.
fn parse_quick(top: &Section<'_>) -> Result<Option<Quick>, Error> {
    let Some(q) = top.section("quick")? else { return Ok(None) };
    Ok(Some(Quick {
        repetitions: parse_repetitions(&q)?,
        warmups: q.integer("warmups", 0, 100)?.map(|v| v as u32),
        sample_s: sample_seconds(&q)?,
        sweep: axis_values(&q, &REPETITION_KEYS)?,
    }))
}

/// `sample_ms` in seconds.
fn sample_seconds(s: &Section<'_>) -> Result<Option<f64>, Error> {
    Ok(s.integer("sample_ms", 0, 10_000)?.map(|ms| ms as f64 / 1e3))
}

/// The keys that say how many repetitions run and how long a sample is (top level and `[quick]`), and `warmups`.
const REPETITION_KEYS: [&str; 6] =
    ["repetitions", "min_repetitions", "max_repetitions", "target_ci_width", "warmups", "sample_ms"];

/// `repetitions` (an integer, or `"auto"` with `min_repetitions`, `max_repetitions` and `target_ci_width`);
/// `None` when the section does not set it.
fn parse_repetitions(s: &Section<'_>) -> Result<Option<Repetitions>, Error> {
    let auto_keys = ["min_repetitions", "max_repetitions", "target_ci_width"];
    let auto = match s.get("repetitions") {
        None | Some(toml::Value::Integer(_)) => false,
        Some(toml::Value::String(v)) if v == "auto" => true,
        Some(v) => {
            let found = match v.as_str() {
                Some(text) => format!("{text:?}"),
                None => format!("a {}", v.type_str()),
            };
            return Err(s.error("repetitions", format!("expected an integer in 1..=1000 or \"auto\", found {found}")));
        }
    };
    if !auto {
        if let Some(key) = auto_keys.iter().find(|k| s.get(k).is_some()) {
            return Err(s.error(key, "applies only with repetitions = \"auto\" (allowed there: min_repetitions, max_repetitions, target_ci_width)"));
        }
        return Ok(s.integer("repetitions", 1, 1000)?.map(|n| Repetitions::Fixed(n as u32)));
    }
    let min = s.integer("min_repetitions", 2, 1000)?.map_or(Repetitions::AUTO_MIN, |v| v as u32);
    let max = s.integer("max_repetitions", 2, 1000)?.map_or(Repetitions::AUTO_MAX.max(min), |v| v as u32);
    if max < min {
        return Err(s.error("max_repetitions", format!("{max} is below min_repetitions {min} (allowed: {min}..=1000)")));
    }
    let target_width = s.number("target_ci_width", 0.0001, 1.0)?.unwrap_or(Repetitions::AUTO_TARGET_WIDTH);
    Ok(Some(Repetitions::Auto { min, max, target_width }))
}

/// A metric key (`y` of a plot, `metric` of a claim), `total_s` when absent.
fn metric(s: &Section<'_>, key: &str) -> Result<String, Error> {
    metric_or(s, key, schema::column::total_s)
}

/// A metric key, `default` when absent.
fn metric_or(s: &Section<'_>, key: &str, default: &str) -> Result<String, Error> {
    let m = s.string(key)?.unwrap_or(default).to_string();
    if !metrics().contains(&m.as_str()) {
        return Err(s.error(key, format!("unknown metric {m:?} (allowed: {})", metrics().join(", "))));
    }
    Ok(m)
}

/// One `[[plot]]` table.
fn parse_plot(p: &Section<'_>, labels: &Labels, has_reference: bool) -> Result<PlotSpec, Error> {
    p.only(&["file", "title", "kind", "x", "y", "log_x", "log_y", "series", "where", "reference"])?;
    let file = p.required_string("file")?.to_string();
    identifier(p, "file", &file, "file stem")?;
    let kind = match p.string("kind")? {
        None | Some("metric") => PlotKind::Metric,
        Some("speedup") => PlotKind::Speedup,
        Some("efficiency") => PlotKind::Efficiency,
        Some("trade-off") => PlotKind::TradeOff,
        Some(k) => {
            return Err(
                p.error("kind", format!("unknown value {k:?} (allowed: metric, speedup, efficiency, trade-off)"))
            );
        }
    };
    let reference = p.string("reference")?.map(str::to_string);
    if let Some(r) = &reference {
        labels.check(p, "reference", r)?;
    }
    if matches!(kind, PlotKind::Speedup | PlotKind::Efficiency) && !has_reference && reference.is_none() {
        return Err(p.error("kind", "speedup and efficiency plots need a `reference` series (top level or the plot's)"));
    }
    let x = if kind == PlotKind::TradeOff {
        metric_or(p, "x", schema::column::build_s)?
    } else {
        let default_x = if kind == PlotKind::Efficiency { Axis::threads } else { Axis::objects };
        let x = p.string("x")?.unwrap_or(default_x.key()).to_string();
        // A setting, or the scene's size as traced (a mesh's triangles: the axis of a sweep over data sets).
        if Axis::from_key(&x).is_none() && x != schema::column::primitives {
            return Err(p.error(
                "x",
                format!("unknown column {x:?} (allowed: {}, {})", axis_keys(), schema::column::primitives),
            ));
        }
        x
    };
    let series = p.strings("series")?.unwrap_or_default();
    for l in &series {
        labels.check(p, "series", l)?;
    }
    Ok(PlotSpec {
        title: p.string("title")?.unwrap_or(&file).to_string(),
        file,
        kind,
        x,
        y: if kind == PlotKind::TradeOff { metric_or(p, "y", schema::column::trace_s)? } else { metric(p, "y")? },
        log_x: p.boolean("log_x")?.unwrap_or(false),
        log_y: p.boolean("log_y")?.unwrap_or(false),
        series,
        filter: filter(p)?,
        reference,
    })
}

/// One `[[claim]]` table.
/// `[headline]`: `series` against `against` (one label or several, the faster at each point counting), optional
/// `metric`.
fn parse_headline(h: &Section<'_>, labels: &Labels) -> Result<HeadlineSpec, Error> {
    h.only(&["series", "against", "metric"])?;
    let series = h.required_string("series")?.to_string();
    labels.check(h, "series", &series)?;
    let against = h.strings("against")?.ok_or_else(|| h.error_here("missing key \"against\" (series labels)"))?;
    if against.is_empty() {
        return Err(h.error("against", "empty list (allowed: one or more series labels)"));
    }
    for a in &against {
        labels.check(h, "against", a)?;
    }
    let metric = h.string("metric")?.map(|_| metric(h, "metric")).transpose()?;
    Ok(HeadlineSpec { series, against, metric })
}

fn parse_claim(c: &Section<'_>, labels: &Labels) -> Result<ClaimSpec, Error> {
    c.only(&[
        "text",
        "paper",
        "if_fails",
        "kind",
        "series",
        "than",
        "factor",
        "per_thread",
        "tolerance",
        "metric",
        "min_objects",
        "max_objects",
        "where",
    ])?;
    let text = c.required_string("text")?.to_string();
    let series = c.required_string("series")?.to_string();
    let than = c.required_string("than")?.to_string();
    labels.check(c, "series", &series)?;
    labels.check(c, "than", &than)?;
    let missing = |key: &str, kind: &str| c.error_here(format!("missing key {key:?} (a number) for kind = {kind:?}"));
    let kind = match c.string("kind")? {
        Some("faster") => ClaimKind::Faster {
            series,
            than,
            factor: c.number("factor", 0.0, 1e9)?.ok_or_else(|| missing("factor", "faster"))?,
            per_thread: c.boolean("per_thread")?.unwrap_or(false),
        },
        Some("within") => ClaimKind::Within {
            series,
            than,
            tolerance: c.number("tolerance", 0.0, 10.0)?.ok_or_else(|| missing("tolerance", "within"))?,
        },
        Some(k) => return Err(c.error("kind", format!("unknown value {k:?} (allowed: faster, within)"))),
        None => return Err(c.error_here("missing key \"kind\" (allowed: faster, within)")),
    };
    let objects = |k| c.integer(k, 0, i64::MAX).map(|v| v.map(|v| v as u64));
    Ok(ClaimSpec {
        text,
        paper: c.string("paper")?.map(str::to_string),
        if_fails: c.string("if_fails")?.map(str::to_string),
        kind,
        metric: metric(c, "metric")?,
        min_objects: objects("min_objects")?,
        max_objects: objects("max_objects")?,
        filter: filter(c)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::{Accel, Named};
    use tracer::accel::{AccelKind, Traversal};
    use tracer::executor::StrategyKind;

    #[test]
    fn series_fix_the_columns_their_accelerator_makes_irrelevant() {
        let (flat, obvhs, list) = (
            AccelKind::FlatBvh.name(),
            Accel::ALL.iter().find(|a| a.peer().is_some_and(|p| p.is_obvhs())).unwrap().name(),
            AccelKind::List.name(),
        );
        let (f2b, serial) = (Traversal::FrontToBack.name(), StrategyKind::Serial.name());
        let text = format!(
            "name = \"t\"\n[sweep]\n[[series]]\nlabel = \"ours\"\naccel = \"{flat}\"\ntraversal = \"{f2b}\"\n\
             [[series]]\nlabel = \"o\"\naccel = \"{obvhs}\"\n[[series]]\nlabel = \"s\"\nstrategy = \"{serial}\"\naccel = \"{list}\"\n"
        );
        let spec = Experiment::parse(Path::new("t.toml"), &text).unwrap().report_spec(vec![]);
        let fixes = |label: &str, yes: &str, no: &str| {
            let fixed = &spec.series_fixed[label];
            for column in yes.split(',') {
                assert!(fixed.iter().any(|c| c == column), "{label} fixes {column}: {fixed:?}");
            }
            for column in no.split(',') {
                assert!(!fixed.iter().any(|c| c == column), "{label} does not fix {column}: {fixed:?}");
            }
        };
        fixes(
            "ours",
            "accel,traversal,obvhs_build,embree_build,embree_isa",
            "split,leaf_size,sah_bins,reinsertion,strategy,threads,objects",
        );
        fixes(
            "o",
            "accel,split,leaf_size,sah_bins,reinsertion,traversal,embree_build,embree_isa",
            "obvhs_build,strategy,threads",
        );
        let serial_list =
            "accel,split,leaf_size,sah_bins,reinsertion,traversal,strategy,threads,obvhs_build,embree_build,embree_isa";
        fixes("s", serial_list, "objects,seed");
    }

    #[test]
    fn a_config_that_sets_no_sampling_key_gets_the_validated_method_and_every_key_it_sets_wins() {
        let parse = |extra: &str| Experiment::parse(Path::new("t.toml"), &format!("name = \"t\"\n{extra}[sweep]\n"));
        let none = parse("").unwrap();
        assert_eq!(none.repetitions, Repetitions::Auto { min: 10, max: 24, target_width: 0.02 });
        assert_eq!((none.warmups, none.sample_s, none.processes, none.order), (1, 0.05, 24, RunOrder::Interleaved));
        // The old method, spelled out, is what a config that relied on the old defaults says now.
        let old = parse("repetitions = 9\nwarmups = 0\nsample_ms = 0\nprocesses = 1\n").unwrap();
        assert_eq!((old.repetitions, old.warmups, old.sample_s, old.processes), (Repetitions::Fixed(9), 0, 0.0, 1));
        // `processes` follows the repetitions it is not given: one per repetition, at most 64, `[quick]`'s too.
        assert_eq!(parse("repetitions = 6\n").unwrap().processes, 6);
        assert_eq!(parse("repetitions = 100\n").unwrap().processes, 64);
        let auto = parse("repetitions = \"auto\"\nmax_repetitions = 12\n").unwrap();
        assert_eq!((auto.repetitions.min(), auto.processes), (10, 12));
        let quick = |extra: &str| {
            Experiment::parse(Path::new("t.toml"), &format!("name = \"t\"\n{extra}[sweep]\n[quick]\nrepetitions = 4\n"))
                .unwrap()
                .quick()
        };
        assert_eq!(quick("").processes, 4);
        assert_eq!(quick("processes = 2\n").processes, 2, "a given value stays");
        assert_eq!(parse("processes = 4\n").unwrap().processes, 4);
        let e = parse("processes = 0\n").unwrap_err().to_string();
        assert!(e.starts_with("t.toml: processes:") && e.contains("1..=64"), "{e}");
    }

    #[test]
    fn float_axes_take_integers_and_floats_and_reject_names() {
        let ok = Experiment::parse(Path::new("t.toml"), "name = \"t\"\n[sweep]\nwidth = 8\n").unwrap();
        assert_eq!(ok.sweep[&Axis::width], vec![AxisValue::width(8)]);
        let e = Experiment::parse(Path::new("t.toml"), "name = \"t\"\n[sweep]\nleaf_size = [4, 17]\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.toml: sweep.leaf_size[1]: 17 is out of range (allowed: integers 1..=16)");
        let e =
            Experiment::parse(Path::new("t.toml"), "name = \"t\"\n[sweep]\nwidth = true\n").unwrap_err().to_string();
        assert!(e.contains("sweep.width[0]: expected a string or number, found a boolean"), "{e}");
    }

    #[test]
    fn mesh_paths_are_relative_to_the_config_and_data_set_names_are_not() {
        let text = "name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = [\"bunny\", \"m.obj\", \"/abs/c.ply\"]\n\
                    [[series]]\nlabel = \"s\"\nmesh = \"../d/city\"\n";
        let e = Experiment::parse(Path::new("exp/t.toml"), text).unwrap();
        let mesh = |v: &AxisValue| match v {
            AxisValue::mesh(Some(m)) => m.0.clone(),
            other => panic!("{other:?}"),
        };
        let sweep: Vec<String> = e.sweep[&Axis::mesh].iter().map(mesh).collect();
        assert_eq!(sweep, ["bunny", "exp/m.obj", "/abs/c.ply"]);
        assert_eq!(mesh(&e.series[0].fixed[&Axis::mesh][0]), "exp/../d/city");
        let here = Experiment::parse(Path::new("t.toml"), text).unwrap();
        assert_eq!(mesh(&here.sweep[&Axis::mesh][1]), "m.obj", "a config in the working folder");
    }
}
