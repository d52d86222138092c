//! One run: generate the scene, build the accelerator, trace (and encode), each phase timed; and the
//! separate counted pass that gives the deterministic work counters.

use std::time::Instant;

use tracer::accel::{AccelVisitor, Accelerator, BuiltAccel, TreeStats};
use tracer::counters::{Counters, NoCounters, WorkCounters};
use tracer::render::{RenderSettings, render, trace_primary};
use tracer::scene::Scene;

use crate::config::axes::Workload;
use crate::plan::{SceneSource, Settings};

/// Wall times of one run, and what it produced.
#[derive(Clone, Debug)]
pub struct Timing {
    pub scene_s: f64,
    pub build_s: f64,
    pub trace_s: f64,
    pub encode_s: f64,
    /// Image hash (render) or primary-hit hash (primary).
    pub output_hash: u64,
    pub scene_fingerprint: u64,
    pub stats: TreeStats,
}

impl Timing {
    /// Sum of the phases.
    pub fn total_s(&self) -> f64 {
        self.scene_s + self.build_s + self.trace_s + self.encode_s
    }
}

fn make_scene(s: &Settings) -> Scene {
    let scene = match &s.scene {
        SceneSource::Generated(kind) => kind.generate(s.objects, s.seed),
        SceneSource::File(scene) => Scene::clone(scene),
    };
    Scene { camera: scene.camera.with_resolution(s.width, s.height), ..scene }
}

/// Traces the workload with counters `C`; returns the output hash, the encoded PNG size and the counters.
struct Trace<'a, C> {
    scene: &'a Scene,
    settings: &'a Settings,
    encode: Option<&'a mut f64>,
    _c: std::marker::PhantomData<C>,
}

impl<C: Counters> AccelVisitor for Trace<'_, C> {
    type Output = (u64, C);
    fn visit<A: Accelerator>(self, accel: &A) -> (u64, C) {
        let s = self.settings;
        match s.workload {
            Workload::Render => {
                let (image, c) = render::<_, C>(self.scene, accel, &RenderSettings { max_depth: s.max_depth }, &s.strategy);
                if let Some(encode_s) = self.encode {
                    let t = Instant::now();
                    let mut png = Vec::new();
                    image.write_png(&mut png).expect("encoding into memory cannot fail");
                    std::hint::black_box(&png);
                    *encode_s = t.elapsed().as_secs_f64();
                }
                (image.hash(), c)
            }
            Workload::Primary => {
                let (hits, c) = trace_primary::<_, C>(&self.scene.camera, accel, &s.strategy);
                (hits.hash(), c)
            }
        }
    }
}

/// Runs `settings` once with every phase timed (no counters).
pub fn timed(settings: &Settings) -> Timing {
    let t = Instant::now();
    let scene = make_scene(settings);
    let scene_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let accel = BuiltAccel::build(&scene.spheres, &settings.accel);
    let build_s = t.elapsed().as_secs_f64();
    let mut encode_s = 0.0;
    let t = Instant::now();
    let (output_hash, _) = accel.visit(Trace::<NoCounters> { scene: &scene, settings, encode: Some(&mut encode_s), _c: Default::default() });
    let trace_s = t.elapsed().as_secs_f64() - encode_s;
    Timing { scene_s, build_s, trace_s, encode_s, output_hash, scene_fingerprint: scene.fingerprint(), stats: accel.stats() }
}

/// Runs `settings` once with work counters (untimed); returns the counters and the output hash.
pub fn counted(settings: &Settings) -> (WorkCounters, u64) {
    let scene = make_scene(settings);
    let accel = BuiltAccel::build(&scene.spheres, &settings.accel);
    let (hash, c) = accel.visit(Trace::<WorkCounters> { scene: &scene, settings, encode: None, _c: Default::default() });
    (c, hash)
}
