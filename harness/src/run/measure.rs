//! One run: generate the scene, build the backend, trace (and encode), each phase timed; the counted pass
//! that gives the deterministic work counters; and the answers used to validate a backend.

use std::time::Instant;

use schema::SceneName;
use schema::{Settings, Workload};
use serde::{Deserialize, Serialize};
use tracer::accel::{Null, TreeStats};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::geometry::{TrianglePrimitive, WatertightTriangle};
use tracer::job::{Job, Output};
use tracer::rays::{RayAnswers, RaySet, trace};
use tracer::render::RenderSettings;
use tracer::scene::{MeshScene, Scene, SceneKind, random_triangles, tessellate};

use crate::backend::workload::{bvhlab_phase_build, bvhlab_phase_trace};
use crate::backend::{self, Geometry, Setup};
use crate::error::Error;

/// Wall times of one run, and what it produced (a worker process answers with it as JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// The backend's one-time start-up in this process ([`Setup`]), the same for every run of a configuration;
    /// not part of [`Timing::total_s`]. Absent (0) in answers of workers older than the `setup_s` phase.
    #[serde(default)]
    pub setup_s: f64,
    pub scene_s: f64,
    pub build_s: f64,
    pub trace_s: f64,
    /// The `null` backend's trace of the same ray set right after (the harness's own cost); `None` for renders
    /// and in answers of workers older than it.
    #[serde(default)]
    pub overhead_s: Option<f64>,
    pub encode_s: f64,
    /// Passes of the job in the timed trace (`trace_s` is the median pass); 1 in answers of earlier workers.
    #[serde(default = "one")]
    pub trace_passes: u32,
    /// The hypervisor's steal time over all CPUs during the kept trace sample (`/proc/stat`, 10-ms ticks);
    /// `None` where the kernel does not report it and in answers of earlier workers.
    #[serde(default)]
    pub steal_s: Option<f64>,
    /// Image hash (render) or ray-set answer hash.
    pub output_hash: u64,
    pub scene_fingerprint: u64,
    pub stats: TreeStats,
    /// Peer library facts (`-` for the tracer's structures).
    pub peer_info: String,
    /// The SIMD kernel that ran (`-` for structures without SIMD kernels, and in answers of older workers).
    #[serde(default = "dash")]
    pub simd_kernel: String,
}

fn dash() -> String {
    "-".into()
}

fn one() -> u32 {
    1
}

/// Seconds per tick of `/proc/stat` (`USER_HZ`, 100 on Linux).
const STAT_TICK_S: f64 = 0.01;

/// The hypervisor's steal time so far, summed over all CPUs, in ticks (`/proc/stat`'s `cpu` line, 8th value).
fn steal_ticks() -> Option<u64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    stat.lines().next()?.split_whitespace().nth(8)?.parse().ok()
}

/// Attempts of a timed trace when steal time was seen during it (the sample with the least steal is kept).
const STEAL_ATTEMPTS: u32 = 3;

/// Runs `run` until at least `min_s` seconds have passed since `start` (at least once); the passes, the last
/// pass's output, and (when `min_s` is above 0) the median of the passes' own times.
fn repeat<T>(start: Instant, min_s: f64, mut run: impl FnMut() -> T) -> (u32, T, Option<f64>) {
    let mut output = run();
    if min_s <= 0.0 {
        return (1, output, None);
    }
    let mut times = vec![start.elapsed().as_secs_f64()];
    let mut last = start.elapsed().as_secs_f64();
    while last < min_s {
        output = run();
        let now = start.elapsed().as_secs_f64();
        times.push(now - last);
        last = now;
    }
    (times.len() as u32, output, Some(report::stats::median(&times)))
}

impl Timing {
    /// The timing of a configuration that was never timed (it failed validation): every phase NaN.
    pub fn untimed(output_hash: u64) -> Timing {
        let nan = f64::NAN;
        Timing {
            setup_s: nan,
            scene_s: nan,
            build_s: nan,
            trace_s: nan,
            overhead_s: None,
            encode_s: nan,
            trace_passes: 0,
            steal_s: None,
            output_hash,
            scene_fingerprint: 0,
            stats: Default::default(),
            peer_info: "-".into(),
            simd_kernel: "-".into(),
        }
    }

    /// Sum of the phases run for every repetition (not `setup_s`).
    pub fn total_s(&self) -> f64 {
        self.scene_s + self.build_s + self.trace_s + self.encode_s
    }
}

/// A configuration's scene: spheres, or a triangle mesh with its view and light.
#[derive(Clone, Debug)]
pub enum SceneData {
    Spheres(Scene),
    Triangles(MeshScene),
}

impl SceneData {
    /// What the structures are built over.
    pub fn geometry(&self) -> Geometry<'_> {
        match self {
            SceneData::Spheres(s) => Geometry::Spheres(&s.spheres),
            SceneData::Triangles(t) => Geometry::Triangles(&t.mesh),
        }
    }

    /// The sphere scene (the render workload of timed runs needs one).
    pub fn spheres(&self) -> Option<&Scene> {
        match self {
            SceneData::Spheres(s) => Some(s),
            SceneData::Triangles(_) => None,
        }
    }

    /// The render job of this scene: a triangle scene's triangles come from [`SceneData::triangles`].
    pub fn render<'a>(&'a self, settings: &Settings, triangles: &'a [WatertightTriangle]) -> Job<'a> {
        match self {
            SceneData::Spheres(s) => Job::RenderSpheres(s, RenderSettings { max_depth: settings.max_depth }),
            SceneData::Triangles(t) => Job::RenderTriangles(t, triangles),
        }
    }

    /// The job of a timed run: the sphere scene's render (a timed run renders sphere scenes only), or `rays`.
    pub fn job<'a>(&'a self, settings: &Settings, rays: Option<&'a RaySet>) -> Job<'a> {
        match settings.workload {
            Workload::Render => {
                let scene = self.spheres().expect("the render workload of timed runs renders sphere scenes");
                Job::RenderSpheres(scene, RenderSettings { max_depth: settings.max_depth })
            }
            Workload::Rays(_) => Job::Rays(rays.expect("ray-set workloads come with their rays")),
        }
    }

    /// A triangle scene's triangles in mesh order, for their normals (empty for spheres).
    pub fn triangles(&self) -> Vec<WatertightTriangle> {
        match self {
            SceneData::Spheres(_) => Vec::new(),
            SceneData::Triangles(t) => WatertightTriangle::all(t.mesh.triangles()),
        }
    }

    /// The scene's fingerprint (a triangle scene's covers its mesh, camera and light).
    pub fn fingerprint(&self) -> u64 {
        match self {
            SceneData::Spheres(s) => s.fingerprint(),
            SceneData::Triangles(t) => t.fingerprint(),
        }
    }

    /// Number of primitives.
    pub fn primitives(&self) -> usize {
        match self {
            SceneData::Spheres(s) => s.spheres.len(),
            SceneData::Triangles(t) => t.mesh.triangle_count(),
        }
    }
}

/// The scene of `s` at its image size; `file` holds the spheres of a sphere-file scene. A mesh is loaded once per
/// process (planning loads it first, so a missing data set is bad input before anything runs).
pub fn make_scene(s: &Settings, file: Option<&Scene>) -> SceneData {
    let (w, h) = (s.width, s.height);
    let spheres = |scene: Scene| SceneData::Spheres(Scene { camera: scene.camera.with_resolution(w, h), ..scene });
    let view = s.view.unwrap_or(tracer::scene::View::Overview);
    let triangles = |mesh, up| {
        let scene = MeshScene::new(mesh, view, up);
        SceneData::Triangles(MeshScene { camera: scene.camera.with_resolution(w, h), ..scene })
    };
    match (s.scene, file) {
        (SceneName::Generated(kind), _) => spheres(kind.generate(s.objects as usize, s.seed)),
        (SceneName::SphereFile, Some(scene)) => spheres(Scene::clone(scene)),
        (SceneName::SphereFile, None) => panic!("a sphere-file scene needs its file (read when planning)"),
        (SceneName::TessellatedSpheres, _) => {
            let scene = SceneKind::RandomSpheres.generate(s.objects as usize, s.seed);
            triangles(tessellate(&scene.spheres, SceneName::SEGMENTS), tracer::Vec3::Y)
        }
        (SceneName::RandomTriangles, _) => triangles(random_triangles(s.objects as usize, s.seed), tracer::Vec3::Y),
        (SceneName::Mesh, _) => {
            let source = s.mesh.as_ref().expect("a mesh scene names its mesh (checked when planning)");
            let mesh = crate::meshes::load_source(&source.0).unwrap_or_else(|e| panic!("mesh {source}: {e}"));
            triangles(tracer::scene::mesh::Mesh::clone(&mesh), crate::meshes::up_axis(&source.0))
        }
    }
}

/// Seconds to PNG-encode `image` into memory (the render workload's encode phase).
fn encode_seconds(image: &tracer::render::Image) -> f64 {
    let t = Instant::now();
    let mut png = Vec::new();
    image.write_png(&mut png).expect("encoding into memory cannot fail");
    std::hint::black_box(&png);
    t.elapsed().as_secs_f64()
}

/// Runs `settings` once with every phase timed (no counters), on what `setup` started. `rays` is the
/// workload's ray set. Builds and traces run in the setup's pool. With `min_sample_s` above 0 the trace is one
/// sample of at least that long (the job traced again until then; `trace_s` is the median pass), taken again, up
/// to [`STEAL_ATTEMPTS`] times, when the hypervisor stole time during it; 0 traces once, as every earlier row did.
pub fn timed(
    settings: &Settings,
    file: Option<&Scene>,
    rays: Option<&RaySet>,
    setup: &Setup,
    min_sample_s: f64,
) -> Result<Timing, Error> {
    let t = Instant::now();
    let scene = make_scene(settings, file);
    let scene_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let backend = backend::of(settings.accel);
    let built = if backend.own_threads() {
        backend.build(settings, &scene.geometry(), setup)? // on its own threads (Embree's TBB)
    } else {
        // The others build in the pool: the phase function runs there (installing from inside the pool again, as
        // the backends' builds do, runs in place), where callgrind sees the building thread enter it.
        setup.install(|| bvhlab_phase_build(|| backend.build(settings, &scene.geometry(), setup)))?
    };
    let build_s = t.elapsed().as_secs_f64();
    let (job, strategy) = (scene.job(settings, rays), settings.strategy());
    // One sample: steal is read outside the phase function (callgrind counts what runs inside it), and only for
    // long samples.
    let take_sample = || {
        let steal = (min_sample_s > 0.0).then(steal_ticks).flatten();
        let t = Instant::now();
        let (passes, output, median) =
            setup.install(|| bvhlab_phase_trace(|| repeat(t, min_sample_s, || built.structure.run(&job, &strategy))));
        let seconds = median.unwrap_or_else(|| t.elapsed().as_secs_f64());
        let stolen = steal.and_then(|a| steal_ticks().map(|b| b.saturating_sub(a) as f64 * STAT_TICK_S));
        (seconds, passes, stolen, output)
    };
    let (mut trace_s, mut trace_passes, mut steal_s, mut output) = take_sample();
    for _ in 1..if min_sample_s > 0.0 { STEAL_ATTEMPTS } else { 1 } {
        if steal_s.is_none_or(|s| s == 0.0) {
            break;
        }
        let again = take_sample();
        if again.2 <= steal_s {
            (trace_s, trace_passes, steal_s, output) = again;
        }
    }
    let encode_s = match &output {
        Output::Image(image) => encode_seconds(image),
        Output::Answers(_) => 0.0,
    };
    let output_hash = output.hash();
    // The harness's own cost: the `null` backend over the same rays, strategy and pool (ray sets only).
    let overhead_s = match (&output, rays) {
        (Output::Answers(_), Some(set)) => {
            let t = Instant::now();
            for _ in 0..trace_passes {
                std::hint::black_box(setup.install(|| trace::<_, NoCounters>(&Null, set, &settings.strategy())));
            }
            Some(t.elapsed().as_secs_f64() / f64::from(trace_passes))
        }
        _ => None,
    };
    Ok(Timing {
        setup_s: setup.setup_s,
        scene_s,
        build_s,
        trace_s,
        overhead_s,
        encode_s,
        trace_passes,
        steal_s,
        output_hash,
        scene_fingerprint: scene.fingerprint(),
        stats: built.structure.stats(),
        peer_info: built.peer_info,
        simd_kernel: built.simd_kernel.to_string(),
    })
}

/// Runs `settings` once with work counters (untimed): counters, output hash, and (when asked for) the answers to
/// `answer_rays` (the workload's own set, or the primary set for the render workload) for validation.
pub fn counted(
    settings: &Settings,
    file: Option<&Scene>,
    rays: Option<&RaySet>,
    answer_rays: Option<&RaySet>,
) -> Result<(WorkCounters, u64, Option<RayAnswers>), Error> {
    let scene = make_scene(settings, file);
    let setup = Setup::start(settings)?;
    let built = backend::of(settings.accel).build(settings, &scene.geometry(), &setup)?;
    let (job, strategy) = (scene.job(settings, rays), settings.strategy());
    let (output, c) = setup.install(|| bvhlab_phase_trace(|| built.structure.run_counted(&job, &strategy)));
    let hash = output.hash();
    let answers = match (output, rays, answer_rays) {
        (_, _, None) => None,
        (Output::Answers(a), Some(r), Some(want)) if std::ptr::eq(r, want) => Some(a),
        (_, _, Some(want)) => Some(setup.install(|| built.answers(want, &strategy))),
    };
    Ok((c, hash, answers))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_repeats_the_job_until_its_floor_and_at_least_once() {
        let mut calls = 0;
        let (passes, last, median) = repeat(Instant::now(), 0.0, || {
            calls += 1;
            calls
        });
        assert_eq!((passes, last, median), (1, 1, None), "no floor: one pass, timed as every earlier row");
        let mut calls = 0;
        let start = Instant::now();
        let (passes, last, median) = repeat(start, 0.02, || {
            std::thread::sleep(std::time::Duration::from_millis(5));
            calls += 1;
            calls
        });
        assert!(start.elapsed().as_secs_f64() >= 0.02 && passes >= 4, "{passes} passes");
        assert!(median.is_some_and(|m| m >= 0.005), "a pass sleeps 5 ms: {median:?}");
        assert_eq!(last, passes, "the last pass's output is kept");
    }

    #[test]
    fn timings_round_trip_through_json() {
        let t = Timing {
            setup_s: 0.0625,
            scene_s: 0.125,
            build_s: 1e-5,
            trace_s: 3.25,
            overhead_s: Some(0.002),
            encode_s: 0.0,
            trace_passes: 3,
            steal_s: Some(0.01),
            output_hash: 0xdead_beef_0123_4567,
            scene_fingerprint: 42,
            stats: TreeStats { nodes: 7, leaves: 4, depth: 2, bytes: 1024, sah_cost: 3.5 },
            peer_info: "embree 4.4.0 native width 8 (avx/avx2), threads=1".into(),
            simd_kernel: "avx2".into(),
        };
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(serde_json::from_str::<Timing>(&json).unwrap(), t);
        assert!(serde_json::from_str::<Timing>("{\"scene_s\": 1}").is_err());
    }
}
