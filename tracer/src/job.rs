//! A job: one workload a built structure runs — a render of a sphere scene or of a triangle scene, or a ray set —
//! and what it produces. [`run`] runs a job on any [`Accelerator`], compiled for that accelerator and counters.

use crate::accel::Accelerator;
use crate::counters::Counters;
use crate::executor::Strategy;
use crate::geometry::WatertightTriangle;
use crate::rays::{RayAnswers, RaySet, trace};
use crate::render::{Image, RenderSettings, render, render_mesh};
use crate::scene::{MeshScene, Scene};

/// One workload over a built structure.
#[derive(Clone, Copy)]
pub enum Job<'a> {
    /// A sphere scene's image, Whitted-shaded.
    RenderSpheres(&'a Scene, RenderSettings),
    /// A triangle scene's image, flat-shaded; its triangles in mesh order give the normals (every structure's hits
    /// name triangles by their mesh index, whatever its triangle test).
    RenderTriangles(&'a MeshScene, &'a [WatertightTriangle]),
    /// The answers to a ray set.
    Rays(&'a RaySet),
}

/// What a job produced: the rendered image or the ray set's answers.
pub enum Output {
    /// A render's image.
    Image(Image),
    /// A ray set's answers.
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

/// Runs `job` on `accel` under `strategy` with counters `C`.
pub fn run<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
    match *job {
        Job::RenderSpheres(scene, settings) => render_spheres(accel, scene, &settings, strategy),
        Job::RenderTriangles(scene, triangles) => render_triangles(accel, scene, triangles, strategy),
        Job::Rays(set) => trace_rays(accel, set, strategy),
    }
}

#[cfg(not(test))]
/// Runs `job` on a structure over spheres: a triangle scene's render is not one of its jobs.
pub(crate) fn run_spheres<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
    match *job {
        Job::RenderSpheres(scene, settings) => render_spheres(accel, scene, &settings, strategy),
        Job::RenderTriangles(..) => panic!("a structure over spheres renders sphere scenes only"),
        Job::Rays(set) => trace_rays(accel, set, strategy),
    }
}

#[cfg(not(test))]
/// Runs `job` on a structure over triangles: a sphere scene's render is not one of its jobs.
pub(crate) fn run_triangles<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
    match *job {
        Job::RenderSpheres(..) => panic!("a structure over triangles renders triangle scenes only"),
        Job::RenderTriangles(scene, triangles) => render_triangles(accel, scene, triangles, strategy),
        Job::Rays(set) => trace_rays(accel, set, strategy),
    }
}

fn render_spheres<A: Accelerator, C: Counters>(
    accel: &A,
    scene: &Scene,
    settings: &RenderSettings,
    strategy: &Strategy,
) -> (Output, C) {
    let (image, c) = render::<_, C>(scene, accel, settings, strategy);
    (Output::Image(image), c)
}

fn render_triangles<A: Accelerator, C: Counters>(
    accel: &A,
    scene: &MeshScene,
    triangles: &[WatertightTriangle],
    strategy: &Strategy,
) -> (Output, C) {
    let (image, c) = render_mesh::<_, _, C>(triangles, &scene.camera, scene.light, accel, strategy);
    (Output::Image(image), c)
}

fn trace_rays<A: Accelerator, C: Counters>(accel: &A, set: &RaySet, strategy: &Strategy) -> (Output, C) {
    let (answers, c) = trace::<_, C>(accel, set, strategy);
    (Output::Answers(answers), c)
}
