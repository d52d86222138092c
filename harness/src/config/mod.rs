//! Experiment configs: TOML files naming sweep axes, series, exclusions, quick overrides, plots and claims.
//!
//! Every key is checked; a wrong key, type or value is one line naming the file, the key path and what is
//! allowed (see [`table::Section`]). Nothing here touches the results folder.

pub mod axes;
mod table;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use report::spec::{ClaimKind, ClaimSpec, PlotKind, PlotSpec, ReportSpec};

use crate::error::Error;
use axes::{Axis, Value, axis_keys};
use table::Section;

/// Values per axis.
pub type AxisValues = BTreeMap<Axis, Vec<Value>>;

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
    pub repetitions: u32,
    pub warmups: u32,
    pub order: RunOrder,
    pub order_seed: u64,
    pub sweep: AxisValues,
    /// `sweep.sphere_file`, resolved against the config's folder.
    pub sphere_file: Option<PathBuf>,
    pub series: Vec<Series>,
    pub exclude: Vec<Exclude>,
    /// The `[quick]` overrides: repetitions, warm-ups and sweep axes.
    pub quick: Option<(Option<u32>, Option<u32>, AxisValues)>,
    pub plots: Vec<PlotSpec>,
    pub claims: Vec<ClaimSpec>,
}

const TOP_KEYS: &[&str] = &[
    "name", "description", "reference", "repetitions", "warmups", "order", "order_seed", "sweep", "series", "exclude",
    "quick", "plot", "claim",
];
const METRICS: &[&str] = &[
    "total_s", "trace_s", "build_s", "scene_s", "encode_s", "mrays_per_s", "nodes_per_ray", "box_tests_per_ray",
    "prim_tests_per_ray", "sah_cost",
];

/// Reads axis lists (`key = [values]` or `key = value`) from `s`, skipping `skip` keys.
fn axis_values(s: &Section<'_>, skip: &[&str]) -> Result<AxisValues, Error> {
    let mut out = AxisValues::new();
    for key in s.keys().filter(|k| !skip.contains(&k.as_str())) {
        let axis = Axis::from_key(key).ok_or_else(|| {
            let mut allowed = axis_keys();
            skip.iter().for_each(|k| allowed.push_str(&format!(", {k}")));
            s.error(key, format!("unknown key (allowed: {allowed})"))
        })?;
        let raw = s.get(key).expect("key listed");
        let items: Vec<&toml::Value> = match raw {
            toml::Value::Array(a) => a.iter().collect(),
            one => vec![one],
        };
        if items.is_empty() {
            return Err(s.error(key, format!("empty list (give at least one value; allowed: {})", axis.allowed())));
        }
        let values = items
            .into_iter()
            .enumerate()
            .map(|(i, v)| axis.parse(v).map_err(|m| s.error(&format!("{key}[{i}]"), m)))
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

impl Experiment {
    /// Reads and checks the config at `path`.
    pub fn load(path: &Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
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
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
            return Err(top.error("name", format!("{name:?} is not a valid name (allowed: letters, digits, '-', '_')")));
        }
        let order = match top.string("order")? {
            None | Some("interleaved") => RunOrder::Interleaved,
            Some("sequential") => RunOrder::Sequential,
            Some("shuffled") => RunOrder::Shuffled,
            Some(o) => return Err(top.error("order", format!("unknown value {o:?} (allowed: interleaved, sequential, shuffled)"))),
        };
        let sweep_section = top.section("sweep")?.ok_or_else(|| top.error_here("missing [sweep] table"))?;
        let sweep = axis_values(&sweep_section, &["sphere_file"])?;
        let sphere_file = sweep_section.string("sphere_file")?.map(|f| path.parent().unwrap_or(Path::new(".")).join(f));

        let mut series = Vec::new();
        for s in top.sections("series")? {
            let label = s.required_string("label")?.to_string();
            if series.iter().any(|x: &Series| x.label == label) {
                return Err(s.error("label", format!("duplicate series label {label:?}")));
            }
            series.push(Series { label, fixed: axis_values(&s, &["label"])? });
        }
        let labels: Vec<&str> = series.iter().map(|s| s.label.as_str()).collect();
        let known_label = |s: &Section<'_>, key: &str, label: &str| -> Result<(), Error> {
            if labels.contains(&label) {
                Ok(())
            } else {
                Err(s.error(key, format!("unknown series {label:?} (allowed: {})", labels.join(", "))))
            }
        };

        let reference = top.string("reference")?.map(str::to_string);
        if let Some(r) = &reference {
            known_label(&top, "reference", r)?;
        }
        let mut exclude = Vec::new();
        for s in top.sections("exclude")? {
            let only_series = s.strings("series")?;
            for l in only_series.iter().flatten() {
                known_label(&s, "series", l)?;
            }
            let axes = axis_values(&s, &["series"])?;
            if axes.is_empty() && only_series.is_none() {
                return Err(s.error_here(format!("empty [[exclude]] would skip every run (give keys: series, {})", axis_keys())));
            }
            exclude.push(Exclude { series: only_series, axes });
        }
        let quick = match top.section("quick")? {
            None => None,
            Some(q) => {
                let reps = q.integer("repetitions", 1, 1000)?.map(|v| v as u32);
                let warm = q.integer("warmups", 0, 100)?.map(|v| v as u32);
                Some((reps, warm, axis_values(&q, &["repetitions", "warmups"])?))
            }
        };

        let mut plots = Vec::new();
        for p in top.sections("plot")? {
            p.only(&["file", "title", "kind", "x", "y", "log_x", "log_y", "series", "where"])?;
            let file = p.required_string("file")?.to_string();
            if file.is_empty() || !file.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
                return Err(p.error("file", format!("{file:?} is not a valid file stem (allowed: letters, digits, '-', '_')")));
            }
            let kind = match p.string("kind")? {
                None | Some("metric") => PlotKind::Metric,
                Some("speedup") => PlotKind::Speedup,
                Some("efficiency") => PlotKind::Efficiency,
                Some(k) => return Err(p.error("kind", format!("unknown value {k:?} (allowed: metric, speedup, efficiency)"))),
            };
            if kind != PlotKind::Metric && reference.is_none() {
                return Err(p.error("kind", "speedup and efficiency plots need a top-level `reference` series"));
            }
            let x = p.string("x")?.unwrap_or(if kind == PlotKind::Efficiency { "threads" } else { "objects" }).to_string();
            if Axis::from_key(&x).is_none() {
                return Err(p.error("x", format!("unknown column {x:?} (allowed: {})", axis_keys())));
            }
            let y = p.string("y")?.unwrap_or("total_s").to_string();
            if !METRICS.contains(&y.as_str()) {
                return Err(p.error("y", format!("unknown metric {y:?} (allowed: {})", METRICS.join(", "))));
            }
            let series = p.strings("series")?.unwrap_or_default();
            for l in &series {
                known_label(&p, "series", l)?;
            }
            let title = p.string("title")?.unwrap_or(&file).to_string();
            let (log_x, log_y) = (p.boolean("log_x")?.unwrap_or(false), p.boolean("log_y")?.unwrap_or(false));
            let filter = filter(&p)?;
            plots.push(PlotSpec { file, title, kind, x, y, log_x, log_y, series, filter });
        }

        let mut claims = Vec::new();
        for c in top.sections("claim")? {
            c.only(&["text", "paper", "kind", "series", "than", "factor", "per_thread", "tolerance", "metric", "min_objects", "max_objects", "where"])?;
            let text = c.required_string("text")?.to_string();
            let series = c.required_string("series")?.to_string();
            let than = c.required_string("than")?.to_string();
            known_label(&c, "series", &series)?;
            known_label(&c, "than", &than)?;
            let kind = match c.string("kind")? {
                Some("faster") => ClaimKind::Faster {
                    series,
                    than,
                    factor: c.number("factor", 0.0, 1e9)?.ok_or_else(|| c.error_here("missing key \"factor\" (a number) for kind = \"faster\""))?,
                    per_thread: c.boolean("per_thread")?.unwrap_or(false),
                },
                Some("within") => ClaimKind::Within {
                    series,
                    than,
                    tolerance: c.number("tolerance", 0.0, 10.0)?.ok_or_else(|| c.error_here("missing key \"tolerance\" (a number) for kind = \"within\""))?,
                },
                Some(k) => return Err(c.error("kind", format!("unknown value {k:?} (allowed: faster, within)"))),
                None => return Err(c.error_here("missing key \"kind\" (allowed: faster, within)")),
            };
            let metric = c.string("metric")?.unwrap_or("total_s").to_string();
            if !METRICS.contains(&metric.as_str()) {
                return Err(c.error("metric", format!("unknown metric {metric:?} (allowed: {})", METRICS.join(", "))));
            }
            let objects = |k| c.integer(k, 0, i64::MAX).map(|v| v.map(|v| v as u64));
            claims.push(ClaimSpec {
                text,
                paper: c.string("paper")?.map(str::to_string),
                kind,
                metric,
                min_objects: objects("min_objects")?,
                max_objects: objects("max_objects")?,
                filter: filter(&c)?,
            });
        }

        Ok(Experiment {
            path: path.to_path_buf(),
            text: text.to_string(),
            description: top.string("description")?.unwrap_or("").to_string(),
            repetitions: top.integer("repetitions", 1, 1000)?.unwrap_or(1) as u32,
            warmups: top.integer("warmups", 0, 100)?.unwrap_or(0) as u32,
            order_seed: top.integer("order_seed", 0, i64::MAX)?.unwrap_or(0) as u64,
            name,
            reference,
            order,
            sweep,
            sphere_file,
            series,
            exclude,
            quick,
            plots,
            claims,
        })
    }

    /// The same experiment with its `[quick]` overrides applied (unchanged when it has none).
    pub fn quick(mut self) -> Self {
        if let Some((reps, warm, axes)) = self.quick.take() {
            self.repetitions = reps.unwrap_or(self.repetitions);
            self.warmups = warm.unwrap_or(self.warmups);
            self.sweep.extend(axes);
        }
        self
    }

    /// Columns a series fixes, counting those its fixed values make irrelevant (serial fixes threads at 1;
    /// each kind of accelerator leaves the other kinds' settings at `-`), so that speedup matching
    /// ignores them.
    fn fixed_columns(s: &Series) -> Vec<String> {
        let all_in = |a: Axis, names: &[&str]| {
            s.fixed.get(&a).is_some_and(|v| v.iter().all(|x| matches!(x, Value::Name(n) if names.contains(n))))
        };
        let tree = [Axis::Split, Axis::LeafSize, Axis::SahBins, Axis::Traversal];
        let mut axes: Vec<Axis> = s.fixed.keys().copied().collect();
        if all_in(Axis::Strategy, &["serial"]) {
            axes.push(Axis::Threads);
        }
        if all_in(Axis::Split, &["centroid-midpoint", "object-median", "sweep-sah"]) {
            axes.push(Axis::SahBins);
        }
        if all_in(Axis::Accel, &["list"]) {
            axes.extend(tree);
        }
        if all_in(Axis::Accel, &["list", "bvh", "flat-bvh", "embree", "embree-packets"]) {
            axes.push(Axis::ObvhsBuild);
        }
        if all_in(Axis::Accel, &["list", "bvh", "flat-bvh", "obvhs-bvh2", "obvhs-cwbvh"]) {
            axes.extend([Axis::EmbreeBuild, Axis::EmbreeIsa]);
        }
        if all_in(Axis::Accel, &["obvhs-bvh2", "obvhs-cwbvh", "embree", "embree-packets"]) {
            axes.extend(tree);
        }
        axes.sort();
        axes.dedup();
        axes.into_iter().map(|a| a.key().to_string()).collect()
    }

    /// What the report needs from this experiment.
    pub fn report_spec(&self, notes: Vec<String>) -> ReportSpec {
        ReportSpec {
            name: self.name.clone(),
            description: self.description.clone(),
            reference: self.reference.clone(),
            series: self.series.iter().map(|s| s.label.clone()).collect(),
            series_fixed: self.series.iter().map(|s| (s.label.clone(), Self::fixed_columns(s))).collect(),
            plots: self.plots.clone(),
            claims: self.claims.clone(),
            config_text: self.text.clone(),
            notes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_fix_the_columns_their_accelerator_makes_irrelevant() {
        let text = "name = \"t\"\n[sweep]\n[[series]]\nlabel = \"ours\"\naccel = \"flat-bvh\"\ntraversal = \"front-to-back\"\n\
                    [[series]]\nlabel = \"o\"\naccel = \"obvhs-bvh2\"\n[[series]]\nlabel = \"s\"\nstrategy = \"serial\"\naccel = \"list\"\n";
        let spec = Experiment::parse(Path::new("t.toml"), text).unwrap().report_spec(vec![]);
        let fixed = |l: &str| spec.series_fixed[l].join(",");
        assert_eq!(fixed("ours"), "accel,traversal,obvhs_build,embree_build,embree_isa");
        assert_eq!(fixed("o"), "accel,split,leaf_size,sah_bins,traversal,embree_build,embree_isa");
        assert_eq!(fixed("s"), "accel,split,leaf_size,sah_bins,traversal,strategy,threads,obvhs_build,embree_build,embree_isa");
    }
}
