//! The workloads a built structure runs — the render, or a ray set — and the two phase functions around a
//! structure's build and trace that `harness instructions` counts.

use schema::{Settings, Workload};
use tracer::accel::{AccelVisitor, Accelerator};
use tracer::counters::Counters;
use tracer::geometry::WatertightTriangle;
use tracer::rays::{RayAnswers, RaySet, trace};
use tracer::render::{RenderSettings, render, render_mesh};
use tracer::scene::{MeshScene, Scene};

/// What a workload produced: the rendered image or the ray set's answers. Hashed only after the trace phase's
/// clock has stopped (hashing every answer is not the backend's work: it cost ~8 ns per ray, more than the whole
/// rest of the harness's path).
pub enum Output {
    Image(tracer::render::Image),
    Answers(RayAnswers),
}

impl Output {
    /// The image hash or the ray-set answer hash.
    pub fn hash(&self) -> u64 {
        match self {
            Output::Image(image) => image.hash(),
            Output::Answers(answers) => answers.hash(),
        }
    }
}

/// What a render draws.
#[derive(Clone, Copy)]
pub enum Shaded<'a> {
    /// A sphere scene, Whitted-shaded.
    Spheres(&'a Scene),
    /// A triangle scene, flat-shaded: its camera and light, and its triangles in mesh order for their normals (a
    /// structure's hits name them by index, whatever its triangle test).
    Triangles(&'a MeshScene, &'a [WatertightTriangle]),
}

/// Runs the workload with counters `C`: its output and the counters.
pub struct Work<'a, C> {
    /// The scene of a render (ray sets need none).
    scene: Option<Shaded<'a>>,
    settings: &'a Settings,
    rays: Option<&'a RaySet>,
    _c: std::marker::PhantomData<C>,
}

impl<'a, C> Work<'a, C> {
    pub fn new(scene: Option<Shaded<'a>>, settings: &'a Settings, rays: Option<&'a RaySet>) -> Self {
        Self { scene, settings, rays, _c: std::marker::PhantomData }
    }
}

impl<C: Counters> AccelVisitor for Work<'_, C> {
    type Output = (Output, C);
    fn visit<A: Accelerator>(self, accel: &A) -> Self::Output {
        let s = self.settings;
        match s.workload {
            Workload::Render => {
                let (image, c) = match self.scene.expect("renders come with their scene") {
                    Shaded::Spheres(scene) => bvhlab_phase_trace(|| {
                        render::<_, C>(scene, accel, &RenderSettings { max_depth: s.max_depth }, &s.strategy())
                    }),
                    Shaded::Triangles(scene, triangles) => bvhlab_phase_trace(|| {
                        render_mesh::<_, _, C>(triangles, &scene.camera, scene.light, accel, &s.strategy())
                    }),
                };
                (Output::Image(image), c)
            }
            Workload::Rays(_) => {
                let set = self.rays.expect("ray-set workloads come with their rays");
                let (answers, c) = bvhlab_phase_trace(|| trace::<_, C>(accel, set, &s.strategy()));
                (Output::Answers(answers), c)
            }
        }
    }
}

/// The build phase of a timed run, a function of its own that `harness instructions` counts under callgrind
/// (`--toggle-collect=*bvhlab_phase_build*`: callgrind toggles collection per thread on entering and leaving it,
/// so it runs in the thread that builds). Never inlined, and the result passes `black_box` so the call is no
/// tail call: both keep the function a call callgrind sees enter and leave.
#[inline(never)]
pub fn bvhlab_phase_build<R>(f: impl FnOnce() -> R) -> R {
    std::hint::black_box(f())
}

/// The trace phase (the ray set, or the render without PNG encoding): see [`bvhlab_phase_build`].
#[inline(never)]
pub fn bvhlab_phase_trace<R>(f: impl FnOnce() -> R) -> R {
    std::hint::black_box(f())
}
