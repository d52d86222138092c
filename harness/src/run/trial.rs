//! One run in this process: the scene made, the backend built and the trace (and encoding) timed, each phase
//! ([`Trial`], [`Timing`]); the counted pass that gives the deterministic work counters and the answers used to
//! validate a backend ([`counted`]).

use std::time::Instant;

use schema::Settings;
use serde::{Deserialize, Serialize};
use tracer::accel::{Null, TreeStats};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::job::Output;
use tracer::rays::{RayAnswers, RaySet, trace};
use tracer::scene::Scene;

use super::sample::{TakesPasses, sample};
use super::scenes::{SceneData, make_scene};
use crate::backend::workload::bvhlab_phase_trace;
use crate::backend::{self, Setup};
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
    /// Configurations whose passes took turns in the sample, this one included (1: it was sampled alone, as in
    /// answers of earlier workers).
    #[serde(default = "one")]
    pub sample_configs: u32,
    /// The hypervisor's steal time over all CPUs during the kept trace sample (`/proc/stat`, 10-ms ticks);
    /// `None` where the kernel does not report it and in answers of earlier workers.
    #[serde(default)]
    pub steal_s: Option<f64>,
    /// The operating system's id of the process that timed it (this one or a worker); 0 in answers of earlier
    /// workers.
    #[serde(default)]
    pub process_id: u32,
    /// Peak resident memory of the process that timed it, in bytes, after the run ([`peak_rss_bytes`]); `None`
    /// where the system does not say and in answers of earlier workers.
    #[serde(default)]
    pub peak_rss_bytes: Option<f64>,
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

/// What a trial runs with: its settings, a sphere-file scene's spheres, its workload's rays, and its setup.
#[derive(Clone, Copy)]
pub struct Context<'a> {
    pub settings: &'a Settings,
    pub file: Option<&'a Scene>,
    pub rays: Option<&'a RaySet>,
    pub setup: &'a Setup,
}

/// One timed run under way: its scene made and its structure built (each phase timed), ready for the passes of
/// its trace, which [`sample`] takes alone or in turn with other configurations' passes.
pub struct Trial {
    scene: SceneData,
    built: crate::backend::Built,
    scene_s: f64,
    build_s: f64,
    output: Option<Output>,
}

impl Trial {
    /// Makes the scene and builds the structure, each timed ([`Setup::build`]).
    pub fn prepare(cx: &Context) -> Result<Trial, Error> {
        let t = Instant::now();
        let scene = make_scene(cx.settings, cx.file);
        let scene_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let backend = backend::of(cx.settings.accel);
        let built = cx.setup.build(backend, cx.settings, &scene.geometry())?;
        let build_s = t.elapsed().as_secs_f64();
        Ok(Trial { scene, built, scene_s, build_s, output: None })
    }

    /// One pass of the trace in the setup's pool, timed; its output is kept.
    pub fn pass(&mut self, cx: &Context) -> f64 {
        let (job, strategy) = (self.scene.job(cx.settings, cx.rays), cx.settings.strategy());
        let t = Instant::now();
        let output = cx.setup.install(|| bvhlab_phase_trace(|| self.built.structure.run(&job, &strategy)));
        let seconds = t.elapsed().as_secs_f64();
        self.output = Some(output);
        seconds
    }

    /// The run's timing from the passes [`sample`] kept (`trace_s` their median, so one pass's own time) and the
    /// steal it saw, then the last pass's image encoded and the harness's own cost measured.
    pub fn finish(self, cx: &Context, passes: &[f64], steal_s: Option<f64>, sample_configs: u32) -> Timing {
        let output = self.output.expect("a trial is finished after its passes");
        let encode_s = match &output {
            Output::Image(image) => encode_seconds(image),
            Output::Answers(_) => 0.0,
        };
        let trace_passes = passes.len() as u32;
        // The harness's own cost: the `null` backend over the same rays, strategy and pool (ray sets only).
        let overhead_s = match (&output, cx.rays) {
            (Output::Answers(_), Some(set)) => {
                let t = Instant::now();
                for _ in 0..trace_passes {
                    std::hint::black_box(
                        cx.setup.install(|| trace::<_, NoCounters>(&Null, set, &cx.settings.strategy())),
                    );
                }
                Some(t.elapsed().as_secs_f64() / f64::from(trace_passes))
            }
            _ => None,
        };
        Timing {
            setup_s: cx.setup.setup_s,
            scene_s: self.scene_s,
            build_s: self.build_s,
            trace_s: report::stats::median(passes),
            overhead_s,
            encode_s,
            trace_passes,
            sample_configs,
            steal_s,
            process_id: std::process::id(),
            peak_rss_bytes: peak_rss_bytes(),
            output_hash: output.hash(),
            scene_fingerprint: self.scene.fingerprint(),
            stats: self.built.structure.stats(),
            peer_info: self.built.peer_info,
            simd_kernel: self.built.simd_kernel.to_string(),
        }
    }
}

/// This process's peak resident memory in bytes (`VmHWM` of `/proc/self/status`, Linux's `ru_maxrss`); `None`
/// where there is no such file.
pub fn peak_rss_bytes() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
    let kib: f64 = line.trim().strip_suffix("kB")?.trim().parse().ok()?;
    Some(kib * 1024.0)
}

/// A trial in this process with what it runs with, as [`sample`] takes it.
pub struct Local<'a> {
    pub trial: Trial,
    pub cx: Context<'a>,
}

impl TakesPasses for Local<'_> {
    fn pass(&mut self) -> Result<f64, Error> {
        Ok(self.trial.pass(&self.cx))
    }
}

impl Local<'_> {
    /// Its timing from the passes [`sample`] kept (see [`Trial::finish`]).
    pub fn finish(self, passes: &[f64], steal_s: Option<f64>, sample_configs: u32) -> Timing {
        self.trial.finish(&self.cx, passes, steal_s, sample_configs)
    }
}

impl Timing {
    /// Sum of the phases run for every repetition (not `setup_s`).
    pub fn total_s(&self) -> f64 {
        self.scene_s + self.build_s + self.trace_s + self.encode_s
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

/// Runs `settings` once with every phase timed (no counters), on what `setup` started, alone. `rays` is the
/// workload's ray set. With `min_sample_s` above 0 the trace is one [`sample`] of at least that long (`trace_s`
/// the median pass); 0 traces once, as every earlier row did.
pub fn timed(
    settings: &Settings,
    file: Option<&Scene>,
    rays: Option<&RaySet>,
    setup: &Setup,
    min_sample_s: f64,
) -> Result<Timing, Error> {
    let cx = Context { settings, file, rays, setup };
    let mut local = Local { trial: Trial::prepare(&cx)?, cx };
    let (passes, steal_s) = sample(&mut [&mut local], min_sample_s)?;
    Ok(local.finish(&passes[0], steal_s, 1))
}

/// Runs `settings` once over `scene` with work counters (untimed): counters, output hash, and (when asked for) the
/// answers to `answer_rays` (the workload's own set, or the primary set for the render workload) for validation.
pub fn counted(
    settings: &Settings,
    scene: &SceneData,
    rays: Option<&RaySet>,
    answer_rays: Option<&RaySet>,
) -> Result<(WorkCounters, u64, Option<RayAnswers>), Error> {
    let setup = Setup::start(settings)?;
    let built = setup.build(backend::of(settings.accel), settings, &scene.geometry())?;
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
    fn timings_round_trip_through_json() {
        let t = Timing {
            setup_s: 0.0625,
            scene_s: 0.125,
            build_s: 1e-5,
            trace_s: 3.25,
            overhead_s: Some(0.002),
            encode_s: 0.0,
            trace_passes: 3,
            sample_configs: 2,
            steal_s: Some(0.01),
            process_id: 4242,
            peak_rss_bytes: None,
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
