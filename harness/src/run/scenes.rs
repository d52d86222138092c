//! Scenes: a configuration's spheres or triangle mesh, made from its settings (and a sphere file's spheres), and the
//! job a scene gives a workload.

use schema::SceneName;
use schema::{Settings, Workload};
use tracer::geometry::{TrianglePrimitive, WatertightTriangle};
use tracer::job::Job;
use tracer::rays::RaySet;
use tracer::render::RenderSettings;
use tracer::scene::{MeshScene, Scene, SceneKind, random_triangles, tessellate};

use crate::backend::Geometry;

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
