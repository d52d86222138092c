//! Plans a sweep: series × cartesian product of the axes, minus exclusions, normalized and deduplicated,
//! then ordered into runs (warm-ups and repetitions).
//!
//! Settings that do not apply are normalized by the declaration (`schema::Settings::normalized`) so that
//! they do not multiply runs; a sphere file fixes objects (its sphere count) and seed.

mod estimate;
mod order;
pub mod shard;

use std::collections::HashSet;
use std::sync::Arc;

use schema::{Axis, AxisValue, Named, SceneName, Settings, Threads};
use tracer::scene::{Scene, sphere_file};

use crate::backend::{self, Unavailable};
use crate::config::{Experiment, Series};
use crate::error::Error;

pub use estimate::{estimate_seconds, plan_seconds, round_seconds};

/// Logical cores available to this process: what `threads = "all"` means here ([`Threads::cores_here`]).
pub fn available_threads() -> usize {
    Threads::cores_here()
}

/// One configuration: a series label and its settings (normalized, `threads` resolved).
#[derive(Clone, Debug)]
pub struct Configuration {
    /// 16 hex digits: see [`schema::row::config_id`].
    pub id: String,
    pub series: String,
    /// The settings it runs with (`threads = "all"` resolved to the planning machine's cores).
    pub settings: Settings,
    /// The threads as configured (`all` stays `all`, as in the id and the row's `threads` column).
    pub threads: Threads,
    /// Its point: its values on the axes no series fixes, numbered in order of first appearance. The series of
    /// one point are compared with each other, so interleaved rounds run them together.
    pub point: usize,
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
    /// The experiment's sphere file, read once (when a configuration uses it).
    pub sphere_file: Option<SphereFile>,
    /// Things the report should say about the plan (e.g. threads above the core count).
    pub notes: Vec<String>,
    /// The shard `(I, N)` this plan was cut to (see [`shard`]), if any.
    pub shard: Option<(usize, usize)>,
    /// The shortest timed sample in seconds (the experiment's `sample_ms`; 0: one pass per timed run).
    pub sample_s: f64,
}

/// A sphere file and its spheres.
#[derive(Clone, Debug)]
pub struct SphereFile {
    pub path: std::path::PathBuf,
    pub scene: Arc<Scene>,
}

impl SphereFile {
    /// Reads and parses `path`; errors name `config` and the key.
    pub fn read(config: &str, path: &std::path::Path) -> Result<SphereFile, Error> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::Input(format!("{config}: sweep.sphere_file: {}: cannot read: {e}", path.display())))?;
        let scene = sphere_file::parse(&text)
            .map_err(|e| Error::Input(format!("{config}: sweep.sphere_file: {}: {e}", path.display())))?;
        Ok(SphereFile { path: path.to_path_buf(), scene: Arc::new(scene) })
    }
}

/// Every combination of the lists, first axis slowest.
fn product(lists: &[Vec<AxisValue>]) -> Vec<Vec<AxisValue>> {
    lists.iter().fold(vec![vec![]], |acc, list| {
        acc.into_iter()
            .flat_map(|prefix| list.iter().map(move |v| [prefix.clone(), vec![v.clone()]].concat()))
            .collect()
    })
}

/// The settings of one combination, normalized, a sphere file's count as objects (`threads` as configured).
fn settings(values: &[AxisValue], file: Option<&SphereFile>) -> Settings {
    let mut s = Settings::default();
    for v in values {
        s.set(v.clone());
    }
    let mut s = s.normalized();
    if let (SceneName::SphereFile, Some(f)) = (s.scene, file) {
        s.objects = f.scene.spheres.len() as u64;
    }
    s
}

impl Plan {
    /// Plans `exp` for a machine with `cores` logical cores; reads the sphere file if the sweep names one.
    pub fn new(exp: &Experiment, cores: usize) -> Result<Plan, Error> {
        let file = exp.path.display().to_string();
        let default_series = [Series { label: "default".into(), fixed: Default::default() }];
        let series: &[Series] = if exp.series.is_empty() { &default_series } else { &exp.series };
        let uses_file = series.iter().any(|s| {
            let scenes = s.fixed.get(&Axis::scene).or(exp.sweep.get(&Axis::scene));
            scenes.is_some_and(|v| v.contains(&AxisValue::scene(SceneName::SphereFile)))
        });
        let sphere_file = match (&exp.sphere_file, uses_file) {
            (_, false) => None,
            (Some(path), true) => Some(SphereFile::read(&file, path)?),
            (None, true) => {
                let scene = SceneName::SphereFile;
                return Err(Error::Input(format!(
                    "{file}: sweep.sphere_file: missing (scene {:?} needs a CSV path, relative to the config)",
                    schema::Named::name(scene)
                )));
            }
        };

        let mut configurations = Vec::new();
        // Each configuration's point: its values on the axes no series fixes, numbered in order of first appearance
        // (the series of one point are compared with each other, so the rounds run them back to back).
        let fixed_somewhere: HashSet<usize> = series
            .iter()
            .flat_map(|s| Axis::ALL.iter().enumerate().filter(|(_, a)| s.fixed.contains_key(a)).map(|(i, _)| i))
            .collect();
        let mut points: Vec<Vec<AxisValue>> = Vec::new();
        let mut seen = HashSet::new();
        let mut above_cores = Vec::new();
        for s in series {
            let lists: Vec<Vec<AxisValue>> = Axis::ALL
                .iter()
                .map(|a| s.fixed.get(a).or(exp.sweep.get(a)).cloned().unwrap_or_else(|| vec![a.default_value()]))
                .collect();
            for values in product(&lists) {
                let excluded = exp.exclude.iter().any(|x| {
                    x.series.as_ref().is_none_or(|l| l.contains(&s.label))
                        && x.axes.iter().all(|(a, allowed)| {
                            allowed.contains(&values[Axis::ALL.iter().position(|b| b == a).unwrap()])
                        })
                });
                if excluded {
                    continue;
                }
                let configured = settings(&values, sphere_file.as_ref());
                // The id is the configured settings' (machine-independent); the run resolves `all` here.
                let id = schema::row::config_id(&s.label, &configured);
                if seen.insert(id.clone()) {
                    let settings =
                        Settings { threads: Threads::Count(configured.threads.resolve(cores)), ..configured.clone() };
                    let threads = settings.strategy().threads;
                    if threads > cores {
                        above_cores.push(threads);
                    }
                    let point: Vec<AxisValue> = values
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| !fixed_somewhere.contains(i))
                        .map(|(_, v)| v.clone())
                        .collect();
                    let point = points.iter().position(|p| *p == point).unwrap_or_else(|| {
                        points.push(point);
                        points.len() - 1
                    });
                    configurations.push(Configuration {
                        id,
                        series: s.label.clone(),
                        settings,
                        threads: configured.threads,
                        point,
                    });
                }
            }
        }
        if configurations.is_empty() {
            return Err(Error::Input(format!("{file}: exclude: every run is excluded (nothing to run)")));
        }
        // Every mesh is loaded now (once per process), so a bad name or a data set not fetched is bad input
        // before anything runs.
        for c in &configurations {
            match (c.settings.scene, &c.settings.mesh) {
                (SceneName::Mesh, None) => {
                    return Err(Error::Input(format!(
                        "{file}: mesh: missing (scene \"mesh\" needs a data set name or an .obj/.ply path)"
                    )));
                }
                (SceneName::Mesh, Some(m)) => {
                    crate::meshes::load_source(&m.0).map_err(|e| Error::Input(format!("{file}: mesh: {e}")))?;
                }
                _ => {}
            }
        }
        let mut notes = Vec::new();
        if !above_cores.is_empty() {
            above_cores.sort_unstable();
            above_cores.dedup();
            notes.push(format!(
                "Thread counts {above_cores:?} exceed the {cores} logical cores of this machine: those runs oversubscribe the CPU."
            ));
        }
        let runs = order::runs(exp, &configurations.iter().map(|c| c.point).collect::<Vec<_>>());
        Ok(Plan { configurations, runs, sphere_file, notes, shard: None, sample_s: exp.sample_s })
    }

    /// The load summary of every mesh the configurations name ([`crate::meshes::summary`]), in first-use order:
    /// its triangles, how many are degenerate, its fingerprint. Planning loaded them, so this reads them again
    /// from memory.
    pub fn mesh_summaries(&self) -> Result<Vec<String>, Error> {
        let mut sources: Vec<&str> = Vec::new();
        for c in &self.configurations {
            if let (SceneName::Mesh, Some(m)) = (c.settings.scene, &c.settings.mesh)
                && !sources.contains(&m.0.as_str())
            {
                sources.push(&m.0);
            }
        }
        sources.into_iter().map(crate::meshes::summary).collect()
    }

    /// Drops the runs of the configurations whose backend cannot run here (Embree absent, a SIMD kernel this CPU
    /// lacks), so one config runs on every machine kind, with a note per reason for the report. With
    /// `require_all`, what could be installed is bad input instead; nothing left to run is bad input too.
    pub fn skip_unavailable(&mut self, file: &str, require_all: bool) -> Result<(), Error> {
        let mut skipped: Vec<(Unavailable, Vec<String>)> = Vec::new();
        let mut unavailable = HashSet::new();
        for (i, c) in self.configurations.iter().enumerate() {
            let available =
                backend::scene_support(&c.settings).and_then(|_| backend::of(c.settings.accel).available(&c.settings));
            let Err(why) = available else { continue };
            if why.installable && require_all {
                return Err(Error::Input(format!("{file}: accel {}: {why}", c.settings.accel.name())));
            }
            unavailable.insert(i);
            match skipped.iter_mut().find(|(w, _)| *w == why) {
                Some((_, series)) if series.contains(&c.series) => {}
                Some((_, series)) => series.push(c.series.clone()),
                None => skipped.push((why, vec![c.series.clone()])),
            }
        }
        if skipped.is_empty() {
            return Ok(());
        }
        let had_runs = !self.runs.is_empty();
        self.runs.retain(|r| !unavailable.contains(&r.config));
        for (why, series) in skipped {
            let note = format!("These series cannot run here, so they were skipped: {}. {why}", series.join(", "));
            note!("note: {note}");
            self.notes.push(note);
        }
        if had_runs && self.runs.is_empty() {
            return Err(Error::Input(format!("{file}: nothing is left to run here (see the notes above)")));
        }
        Ok(())
    }

    /// The configurations that still have runs (after [`Plan::skip_unavailable`]).
    pub fn runnable(&self) -> impl Iterator<Item = &Configuration> {
        let planned: HashSet<usize> = self.runs.iter().map(|r| r.config).collect();
        self.configurations.iter().enumerate().filter(move |(i, _)| planned.contains(i)).map(|(_, c)| c)
    }

    /// The sphere file's scene, if the plan has one.
    pub fn scene_file(&self) -> Option<&Scene> {
        self.sphere_file.as_ref().map(|f| &*f.scene)
    }

    /// Number of recorded (non-warm-up) runs.
    pub fn recorded_runs(&self) -> usize {
        self.runs.iter().filter(|r| r.repetition.is_some()).count()
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use schema::{EmbreePacket, Named, Packet, PeerKind};
    use tracer::accel::{AccelKind, Split};
    use tracer::executor::StrategyKind;

    use super::*;
    use crate::config::Experiment;
    use schema::Workload;

    fn plan(text: &str) -> Plan {
        Plan::new(&Experiment::parse(Path::new("t.toml"), text).unwrap(), 2).unwrap()
    }

    const BASE: &str = "name = \"t\"\nrepetitions = 2\nwarmups = 1\n";

    #[test]
    fn series_times_product_with_normalization_and_exclusions() {
        let (midpoint, sah) = (Split::CentroidMidpoint.name(), Split::BinnedSah.name());
        let (list, flat) = (AccelKind::List.name(), AccelKind::FlatBvh.name());
        let (serial, rayon) = (StrategyKind::Serial.name(), StrategyKind::RayonBands.name());
        let p = plan(&format!(
            "{BASE}[sweep]\nobjects = [10, 20]\nseed = [1, 2]\nsplit = [\"{midpoint}\", \"{sah}\"]\nthreads = [1, 2, 4]\n\
             [[series]]\nlabel = \"brute\"\naccel = \"{list}\"\nstrategy = \"{serial}\"\n\
             [[series]]\nlabel = \"tree\"\naccel = \"{flat}\"\nstrategy = \"{rayon}\"\n\
             [[exclude]]\nseries = \"tree\"\nobjects = 20\nthreads = 4\n"
        ));
        // list: split and threads do not apply -> 2 objects x 2 seeds; tree: 2x2x2 splits x 3 threads minus 2x2 excluded.
        let count = |label: &str| p.configurations.iter().filter(|c| c.series == label).count();
        assert_eq!(count("brute"), 4);
        assert_eq!(count("tree"), 24 - 4);
        assert_eq!(p.recorded_runs(), 2 * 24);
        assert_eq!(p.runs.len() - p.recorded_runs(), 24);
        assert_eq!(p.notes.len(), 1, "threads 4 > 2 cores is flagged: {:?}", p.notes);
        let ids: HashSet<_> = p.configurations.iter().map(|c| &c.id).collect();
        assert_eq!(ids.len(), p.configurations.len());
    }

    #[test]
    fn threads_all_stays_symbolic_in_the_id_and_is_resolved_to_run() {
        let rayon = StrategyKind::RayonBands.name();
        let text = format!("{BASE}[sweep]\nstrategy = \"{rayon}\"\nthreads = [\"all\", 2]\n");
        let exp = Experiment::parse(Path::new("t.toml"), &text).unwrap();
        let (on2, on16) = (Plan::new(&exp, 2).unwrap(), Plan::new(&exp, 16).unwrap());
        let all = |p: &Plan| p.configurations.iter().find(|c| c.threads == Threads::All).unwrap().clone();
        assert_eq!(all(&on2).id, all(&on16).id, "the same id on machines of 2 and 16 cores");
        assert_eq!((all(&on2).settings.strategy().threads, all(&on16).settings.strategy().threads), (2, 16));
        assert_eq!(on2.configurations.len(), 2, "all and 2 stay two configurations on 2 cores");
        assert_ne!(on2.configurations[0].id, on2.configurations[1].id);
    }

    #[test]
    fn threads_all_is_this_machines_cores_for_run_render_and_every_command() {
        let text = format!("{BASE}[sweep]\nstrategy = [\"rayon-bands\", \"mpsc-threads\"]\nthreads = \"all\"\n");
        let planned = Plan::new(&Experiment::parse(Path::new("t.toml"), &text).unwrap(), available_threads()).unwrap();
        let cores = available_threads();
        assert_eq!(cores, std::thread::available_parallelism().unwrap().get());
        for c in &planned.configurations {
            assert_eq!(c.settings.strategy().threads, cores, "run (and ab, reproduce, slurm, which plan): {}", c.id);
        }
        for strategy in ["rayon-bands", "mpsc-threads"] {
            let set = [format!("strategy={strategy}"), "threads=all".to_string()];
            let rendered = crate::render::settings_of(&set).unwrap();
            assert_eq!(rendered.strategy().threads, cores, "render --set threads=all --set strategy={strategy}");
        }
        // Unresolved settings say the same as resolved ones.
        let all = Settings { threads: Threads::All, ..planned.configurations[0].settings.clone() };
        assert_eq!(all.strategy(), planned.configurations[0].settings.strategy());
    }

    #[test]
    fn config_ids_are_stable_and_depend_on_every_setting() {
        let a = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\n"));
        let b = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\n"));
        assert_eq!(a.configurations[0].id, b.configurations[0].id);
        assert_ne!(a.configurations[0].id, a.configurations[1].id);
        let c = plan(&format!("{BASE}[sweep]\nobjects = [10, 20]\nwidth = 321\n"));
        assert_ne!(a.configurations[0].id, c.configurations[0].id);
        // Pinned: the id of the default configuration at 10 spheres, as recorded since the first row format.
        assert_eq!(a.configurations[0].id, schema::row::config_id("default", &a.configurations[0].settings));
    }

    #[test]
    fn embree_packets_trace_16_unless_told_8_and_keep_their_ids() {
        let embree = PeerKind::EmbreePackets.name();
        let p = plan(&format!(
            "{BASE}[sweep]\nworkload = [\"render\", \"primary\"]\n[[series]]\nlabel = \"e\"\naccel = \"{embree}\"\n\
             [[series]]\nlabel = \"e8\"\naccel = \"{embree}\"\nembree_packet = 8\n\
             [[series]]\nlabel = \"e16\"\naccel = \"{embree}\"\nembree_packet = 16\n"
        ));
        let config = |label: &str, render: bool| {
            let c = p
                .configurations
                .iter()
                .find(|c| c.series == label && (c.settings.workload == Workload::Render) == render);
            c.unwrap().clone()
        };
        for label in ["e", "e8", "e16"] {
            assert_eq!(config(label, true).settings.embree_packet, None, "{label}: renders trace one ray at a time");
            assert_eq!(config(label, false).settings.packet, None, "{label}: the wide BVH's grouping does not apply");
        }
        assert_eq!(config("e", false).settings.embree_packet, Some(EmbreePacket(16)));
        assert_eq!(config("e8", false).settings.embree_packet, Some(EmbreePacket(8)));
        // The default 16 stays out of the id, so configurations recorded before embree-packets had a width (as not
        // applicable, `0`) keep their ids; 8 is a configuration of its own.
        let e = config("e", false);
        assert_eq!(e.id, schema::row::config_id("e", &Settings { embree_packet: None, ..e.settings.clone() }));
        let e8 = config("e8", false);
        let as16 = Settings { embree_packet: Some(EmbreePacket(16)), ..e8.settings.clone() };
        assert_ne!(e8.id, schema::row::config_id("e8", &as16));
    }

    #[test]
    fn packets_keep_the_ids_they_had_as_packet_size() {
        // What `packet_size` (1, 8, 16, 64; embree-packets 8, 16) hashed, as its last id cell unless at its default.
        let old_id = |series: &str, s: &Settings, packet_size: Option<i64>| {
            let mut h = tracer::fingerprint::Fnv64::default();
            h.bytes(series.as_bytes()).bytes(b"\x1f");
            let cells = Settings { packet: None, embree_packet: None, ..s.clone() }.id_cells();
            for cell in cells.iter().map(ToString::to_string).chain(packet_size.map(|n| n.to_string())) {
                h.bytes(cell.as_bytes()).bytes(b"\x1f");
            }
            format!("{:016x}", h.finish())
        };
        let wide = Settings {
            accel: schema::Accel::Ours(AccelKind::WideBvh),
            workload: Workload::Rays(tracer::rays::RayKind::Primary),
            ..Settings::default()
        }
        .normalized();
        for &packet in Packet::ALL {
            let s = Settings { packet: Some(packet), ..wide.clone() };
            let old = (packet != Packet::Single).then(|| i64::from(packet.rays()));
            assert_eq!(schema::row::config_id("w", &s), old_id("w", &s, old), "{packet}");
        }
        let embree = Settings { accel: schema::Accel::Peer(PeerKind::EmbreePackets), ..wide }.normalized();
        for (width, old) in [(8, Some(8)), (16, None)] {
            let s = Settings { embree_packet: Some(EmbreePacket(width)), ..embree.clone() };
            assert_eq!(schema::row::config_id("e", &s), old_id("e", &s, old), "embree-packets {width}");
        }
    }

    #[test]
    fn run_orders() {
        let text = |order: &str| format!("{BASE}order = \"{order}\"\n[sweep]\nobjects = [1, 2, 3]\n");
        let reps = |p: &Plan| p.runs.iter().filter_map(|r| r.repetition.map(|x| (r.config, x))).collect::<Vec<_>>();
        let inter = plan(&text("interleaved"));
        // Every other round in reverse.
        assert_eq!(reps(&inter), vec![(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1)]);
        // Two series: a round runs them point by point, back to back, so that their per-round ratios compare
        // neighbours in time (configurations 0..3 are series a, 3..6 series b).
        let two = plan(&format!(
            "{}[[series]]\nlabel = \"a\"\n[[series]]\nlabel = \"b\"\nleaf_size = 2\n",
            text("interleaved")
        ));
        let round: Vec<(usize, u32)> = reps(&two).into_iter().take(12).collect();
        let expected = [(0, 0), (3, 0), (1, 0), (4, 0), (2, 0), (5, 0), (5, 1), (2, 1), (4, 1), (1, 1), (3, 1), (0, 1)];
        assert_eq!(round, expected);
        assert!(inter.runs[..3].iter().all(|r| r.repetition.is_none()), "warm-ups first");
        let seq = plan(&text("sequential"));
        assert_eq!(
            seq.runs.iter().map(|r| (r.config, r.repetition)).collect::<Vec<_>>()[..3],
            [(0, None), (0, Some(0)), (0, Some(1))]
        );
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
        let exp = Experiment::parse(
            Path::new("t.toml"),
            &format!("{BASE}[sweep]\nobjects = [1, 2, 3]\n[quick]\nrepetitions = 1\nobjects = 5\n"),
        )
        .unwrap();
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
        let text = format!(
            "name = \"f\"\n[sweep]\nscene = \"{}\"\nsphere_file = \"s.csv\"\nobjects = [10, 20]\nseed = [1, 2]\n",
            SceneName::SphereFile.name()
        );
        let p = Plan::new(&Experiment::parse(&cfg, &text).unwrap(), 2).unwrap();
        assert_eq!(p.configurations.len(), 1);
        assert_eq!((p.configurations[0].settings.objects, p.configurations[0].settings.seed), (2, 0));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
