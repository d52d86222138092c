//! Plans a sweep: series × cartesian product of the axes, minus exclusions, normalized and deduplicated,
//! then ordered into runs (warm-ups and repetitions).
//!
//! Settings that do not apply are normalized so that they do not multiply runs: a list has no split, leaf
//! size or traversal; only binned SAH has bins; serial runs one thread; a sphere file fixes objects and seed;
//! the primary kernel has no reflection depth.

mod estimate;
mod order;

use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;

use tracer::accel::{AccelKind, AccelParams, BvhParams, Split, Traversal};
use tracer::executor::{Strategy, StrategyKind};
use tracer::fingerprint::Fnv64;
use tracer::scene::{Scene, SceneKind, sphere_file};

use crate::config::axes::{Axis, EMBREE_ISAS, SPHERE_FILE, Value, Workload};
use crate::peers::{EmbreeQuality, ObvhsQuality, PeerKind};
use crate::config::{Experiment, Series};
use crate::error::Error;

pub use estimate::estimate_seconds;

/// Where a configuration's spheres come from.
#[derive(Clone, Debug)]
pub enum SceneSource {
    Generated(SceneKind),
    File(Arc<Scene>),
}

/// A peer backend and its build settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeerSettings {
    pub kind: PeerKind,
    pub obvhs: ObvhsQuality,
    pub embree: EmbreeQuality,
    /// `None`: Embree picks its best instruction set.
    pub isa: Option<&'static str>,
}

/// Every setting of one configuration, typed and normalized.
#[derive(Clone, Debug)]
pub struct Settings {
    pub scene: SceneSource,
    pub objects: usize,
    pub seed: u64,
    /// The tracer's structure (ignored when `peer` is set).
    pub accel: AccelParams,
    /// A peer backend instead of the tracer's structure.
    pub peer: Option<PeerSettings>,
    pub strategy: Strategy,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub workload: Workload,
}

impl Settings {
    /// Scene name as in rows.
    pub fn scene_name(&self) -> &'static str {
        match &self.scene {
            SceneSource::Generated(k) => k.name(),
            SceneSource::File(_) => SPHERE_FILE,
        }
    }

    /// True when the accelerator is one of the tracer's trees (tree settings apply).
    pub fn is_tree(&self) -> bool {
        self.peer.is_none() && self.accel.kind != AccelKind::List
    }

    /// The accelerator's name as in rows.
    pub fn accel_name(&self) -> &'static str {
        self.peer.map_or(self.accel.kind.name(), |p| p.kind.name())
    }

    /// The row values of the axes, in [`Axis::ALL`] order; settings that do not apply are `-` or `0`.
    pub fn columns(&self) -> Vec<String> {
        let tree = self.is_tree();
        let na = |applies: bool, v: String, none: &str| if applies { v } else { none.to_string() };
        vec![
            self.scene_name().to_string(),
            self.objects.to_string(),
            self.seed.to_string(),
            self.accel_name().to_string(),
            na(tree, self.accel.bvh.split.name().into(), "-"),
            na(tree, self.accel.bvh.max_leaf_size.to_string(), "0"),
            na(tree && self.accel.bvh.split == Split::BinnedSah, self.accel.bvh.sah_bins.to_string(), "0"),
            na(tree, self.accel.bvh.traversal.name().into(), "-"),
            self.strategy.kind.name().to_string(),
            self.strategy.threads.to_string(),
            self.width.to_string(),
            self.height.to_string(),
            self.max_depth.to_string(),
            self.workload.name().to_string(),
            self.peer.filter(|p| !p.kind.needs_embree()).map_or("-".into(), |p| p.obvhs.name().to_string()),
            self.peer.filter(|p| p.kind.needs_embree()).map_or("-".into(), |p| p.embree.name().to_string()),
            self.peer.filter(|p| p.kind.needs_embree()).map_or("-".into(), |p| p.isa.unwrap_or(EMBREE_ISAS[0]).to_string()),
        ]
    }
}

/// One configuration: a series label and its settings.
#[derive(Clone, Debug)]
pub struct Configuration {
    /// 16 hex digits: FNV-1a of the series label and every column value.
    pub id: String,
    pub series: String,
    pub settings: Settings,
}

/// One execution: a configuration and its repetition index (`None` for a warm-up, which is not recorded).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlannedRun {
    pub config: usize,
    pub repetition: Option<u32>,
}

/// The whole sweep.
#[derive(Clone, Debug)]
pub struct Plan {
    pub configurations: Vec<Configuration>,
    pub runs: Vec<PlannedRun>,
    /// Things the report should say about the plan (e.g. threads above the core count).
    pub notes: Vec<String>,
}

fn name_of(v: &Value) -> &'static str {
    match v {
        Value::Name(n) => n,
        Value::Int(_) => unreachable!("a named axis holds names"),
    }
}

fn int_of(v: &Value) -> u64 {
    match v {
        Value::Int(i) => *i,
        Value::Name(_) => unreachable!("a numeric axis holds integers (threads \"all\" is resolved before)"),
    }
}

fn find<T: Copy>(all: &[T], name: fn(T) -> &'static str, n: &str) -> T {
    *all.iter().find(|&&t| name(t) == n).expect("names were checked when parsing")
}

/// Builds settings from one value per axis (in [`Axis::ALL`] order).
fn settings(values: &[Value], cores: usize, file_scene: &Option<Arc<Scene>>) -> Settings {
    let get = |a: Axis| &values[Axis::ALL.iter().position(|&x| x == a).expect("axis listed")];
    let accel_name = name_of(get(Axis::Accel));
    let peer = PeerKind::ALL.into_iter().find(|p| p.name() == accel_name).map(|kind| PeerSettings {
        kind,
        obvhs: find(&ObvhsQuality::ALL, ObvhsQuality::name, name_of(get(Axis::ObvhsBuild))),
        embree: find(&EmbreeQuality::ALL, EmbreeQuality::name, name_of(get(Axis::EmbreeBuild))),
        isa: Some(name_of(get(Axis::EmbreeIsa))).filter(|&i| i != EMBREE_ISAS[0]),
    });
    let accel_kind = if peer.is_some() { AccelKind::List } else { find(&AccelKind::ALL, AccelKind::name, accel_name) };
    let split = find(&Split::ALL, Split::name, name_of(get(Axis::Split)));
    let tree = peer.is_none() && accel_kind != AccelKind::List;
    let bvh = if tree {
        BvhParams {
            max_leaf_size: int_of(get(Axis::LeafSize)) as u32,
            split,
            sah_bins: if split == Split::BinnedSah { int_of(get(Axis::SahBins)) as u32 } else { BvhParams::default().sah_bins },
            traversal: find(&Traversal::ALL, Traversal::name, name_of(get(Axis::Traversal))),
        }
    } else {
        BvhParams::default()
    };
    let kind = find(&StrategyKind::ALL, StrategyKind::name, name_of(get(Axis::Strategy)));
    let threads = match (kind, get(Axis::Threads)) {
        (StrategyKind::Serial, _) => 1,
        (_, Value::Name(_)) => cores,
        (_, Value::Int(t)) => *t as usize,
    };
    let workload = find(&Workload::ALL, Workload::name, name_of(get(Axis::Workload)));
    let (scene, objects, seed) = match name_of(get(Axis::Scene)) {
        SPHERE_FILE => {
            let s = file_scene.clone().expect("checked when planning");
            let n = s.spheres.len();
            (SceneSource::File(s), n, 0)
        }
        n => (SceneSource::Generated(find(&SceneKind::ALL, SceneKind::name, n)), int_of(get(Axis::Objects)) as usize, int_of(get(Axis::Seed))),
    };
    Settings {
        scene,
        objects,
        seed,
        accel: AccelParams { kind: accel_kind, bvh },
        peer,
        strategy: Strategy::new(kind, threads),
        width: int_of(get(Axis::Width)) as u32,
        height: int_of(get(Axis::Height)) as u32,
        max_depth: if workload == Workload::Render { int_of(get(Axis::MaxDepth)) as u32 } else { 0 },
        workload,
    }
}

/// The stable id of a configuration.
pub fn config_id(series: &str, columns: &[String]) -> String {
    let mut h = Fnv64::default();
    h.bytes(series.as_bytes()).bytes(b"\x1f");
    for c in columns {
        h.bytes(c.as_bytes()).bytes(b"\x1f");
    }
    format!("{:016x}", h.finish())
}

/// Every combination of the lists, first axis slowest.
fn product(lists: &[Vec<Value>]) -> Vec<Vec<Value>> {
    lists.iter().fold(vec![vec![]], |acc, list| {
        acc.into_iter().flat_map(|prefix| list.iter().map(move |v| [prefix.clone(), vec![v.clone()]].concat())).collect()
    })
}

impl Plan {
    /// Plans `exp` for a machine with `cores` logical cores; reads the sphere file if the sweep names one.
    pub fn new(exp: &Experiment, cores: usize) -> Result<Plan, Error> {
        let file = exp.path.display().to_string();
        let default_series = [Series { label: "default".into(), fixed: Default::default() }];
        let series: &[Series] = if exp.series.is_empty() { &default_series } else { &exp.series };
        let uses_file = series.iter().any(|s| {
            s.fixed.get(&Axis::Scene).or(exp.sweep.get(&Axis::Scene)).is_some_and(|v| v.contains(&Value::Name(SPHERE_FILE)))
        });
        let file_scene = if uses_file {
            let path: &PathBuf = exp.sphere_file.as_ref().ok_or_else(|| {
                Error::Input(format!("{file}: sweep.sphere_file: missing (scene \"sphere-file\" needs a CSV path, relative to the config)"))
            })?;
            let text = std::fs::read_to_string(path)
                .map_err(|e| Error::Input(format!("{file}: sweep.sphere_file: {}: cannot read: {e}", path.display())))?;
            let scene = sphere_file::parse(&text)
                .map_err(|e| Error::Input(format!("{file}: sweep.sphere_file: {}: {e}", path.display())))?;
            Some(Arc::new(scene))
        } else {
            None
        };

        let mut configurations = Vec::new();
        let mut seen = HashSet::new();
        let mut above_cores = Vec::new();
        for s in series {
            let lists: Vec<Vec<Value>> = Axis::ALL
                .iter()
                .map(|a| s.fixed.get(a).or(exp.sweep.get(a)).cloned().unwrap_or_else(|| vec![a.default_value()]))
                .collect();
            for values in product(&lists) {
                let excluded = exp.exclude.iter().any(|x| {
                    x.series.as_ref().is_none_or(|l| l.contains(&s.label))
                        && x.axes.iter().all(|(a, allowed)| allowed.contains(&values[Axis::ALL.iter().position(|b| b == a).unwrap()]))
                });
                if excluded {
                    continue;
                }
                let settings = settings(&values, cores, &file_scene);
                let columns = settings.columns();
                let id = config_id(&s.label, &columns);
                if seen.insert(id.clone()) {
                    if settings.strategy.threads > cores {
                        above_cores.push(settings.strategy.threads);
                    }
                    configurations.push(Configuration { id, series: s.label.clone(), settings });
                }
            }
        }
        if configurations.is_empty() {
            return Err(Error::Input(format!("{file}: exclude: every run is excluded (nothing to run)")));
        }
        let mut notes = Vec::new();
        if !above_cores.is_empty() {
            above_cores.sort_unstable();
            above_cores.dedup();
            notes.push(format!(
                "Thread counts {above_cores:?} exceed the {cores} logical cores of this machine: those runs oversubscribe the CPU."
            ));
        }
        let runs = order::runs(exp, configurations.len());
        Ok(Plan { configurations, runs, notes })
    }

    /// Number of recorded (non-warm-up) runs.
    pub fn recorded_runs(&self) -> usize {
        self.runs.iter().filter(|r| r.repetition.is_some()).count()
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::config::Experiment;

    fn plan(text: &str) -> Plan {
        Plan::new(&Experiment::parse(Path::new("t.toml"), text).unwrap(), 2).unwrap()
    }

    const BASE: &str = "name = \"t\"\nrepetitions = 2\nwarmups = 1\n";

    #[test]
    fn series_times_product_with_normalization_and_exclusions() {
        let p = plan(&format!(
            "{BASE}[sweep]\nobjects = [10, 20]\nseed = [1, 2]\nsplit = [\"centroid-midpoint\", \"binned-sah\"]\nthreads = [1, 2, 4]\n\
             [[series]]\nlabel = \"list\"\naccel = \"list\"\nstrategy = \"serial\"\n\
             [[series]]\nlabel = \"tree\"\naccel = \"flat-bvh\"\nstrategy = \"rayon-bands\"\n\
             [[exclude]]\nseries = \"tree\"\nobjects = 20\nthreads = 4\n"
        ));
        // list: split and threads do not apply -> 2 objects x 2 seeds; tree: 2x2x2 splits x 3 threads minus 2x2 excluded.
        let count = |label: &str| p.configurations.iter().filter(|c| c.series == label).count();
        assert_eq!(count("list"), 4);
        assert_eq!(count("tree"), 24 - 4);
        assert_eq!(p.recorded_runs(), 2 * 24);
        assert_eq!(p.runs.len() - p.recorded_runs(), 24);
        assert_eq!(p.notes.len(), 1, "threads 4 > 2 cores is flagged: {:?}", p.notes);
        let ids: HashSet<_> = p.configurations.iter().map(|c| &c.id).collect();
        assert_eq!(ids.len(), p.configurations.len());
    }

    #[test]
    fn config_ids_are_stable_and_depend_on_every_setting() {
        let a = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\n"));
        let b = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\n"));
        assert_eq!(a.configurations[0].id, b.configurations[0].id);
        assert_ne!(a.configurations[0].id, a.configurations[1].id);
        let c = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\nwidth = 321\n"));
        assert_ne!(a.configurations[0].id, c.configurations[0].id);
        // The id is a pure function of series and columns: pinned so rows stay comparable across versions.
        assert_eq!(config_id("s", &["a".into(), "b".into()]), config_id("s", &["a".into(), "b".into()]));
        assert_ne!(config_id("s", &["ab".into()]), config_id("s", &["a".into(), "b".into()]));
    }

    #[test]
    fn run_orders() {
        let text = |order: &str| format!("{BASE}order = \"{order}\"\n[sweep]\nobjects = [1, 2, 3]\n");
        let reps = |p: &Plan| p.runs.iter().filter_map(|r| r.repetition.map(|x| (r.config, x))).collect::<Vec<_>>();
        let inter = plan(&text("interleaved"));
        assert_eq!(reps(&inter), vec![(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)]);
        assert!(inter.runs[..3].iter().all(|r| r.repetition.is_none()), "warm-ups first");
        let seq = plan(&text("sequential"));
        assert_eq!(seq.runs.iter().map(|r| (r.config, r.repetition)).collect::<Vec<_>>()[..3], [(0, None), (0, Some(0)), (0, Some(1))]);
        let shuf = plan(&text("shuffled"));
        let mut sorted = reps(&shuf);
        assert_ne!(sorted, reps(&inter), "seeded shuffle changes the order");
        sorted.sort();
        let mut want = reps(&inter);
        want.sort();
        assert_eq!(sorted, want, "a shuffle runs every repetition once");
        assert_eq!(reps(&plan(&text("shuffled"))), reps(&shuf), "same seed, same order");
    }

    #[test]
    fn quick_overrides_sweep_and_repetitions() {
        let exp = Experiment::parse(Path::new("t.toml"), &format!("{BASE}[sweep]\nobjects = [1, 2, 3]\n[quick]\nrepetitions = 1\nobjects = 5\n")).unwrap();
        let p = Plan::new(&exp.quick(), 2).unwrap();
        assert_eq!(p.configurations.len(), 1);
        assert_eq!(p.configurations[0].settings.objects, 5);
        assert_eq!(p.recorded_runs(), 1);
    }

    #[test]
    fn sphere_files_fix_objects_and_seed() {
        let dir = std::env::temp_dir().join(format!("bvhlab-plan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("s.csv"), "0,0,0,1\n3,0,0,1\n").unwrap();
        let cfg = dir.join("e.toml");
        let text = "name = \"f\"\n[sweep]\nscene = \"sphere-file\"\nsphere_file = \"s.csv\"\nobjects = [10, 20]\nseed = [1, 2]\n";
        let p = Plan::new(&Experiment::parse(&cfg, text).unwrap(), 2).unwrap();
        assert_eq!(p.configurations.len(), 1);
        assert_eq!((p.configurations[0].settings.objects, p.configurations[0].settings.seed), (2, 0));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
