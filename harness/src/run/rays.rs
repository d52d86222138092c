//! Ray sets: each scene's set of a ray kind generated once, with the reference's answers to it ([`RayBank`]), and the
//! files that hand sets to workers ([`RayFiles`]).

use std::collections::HashMap;
use std::sync::Arc;

use schema::{SceneName, Settings, Workload};
use tracer::accel::{BvhParams, FlatBvh, Traversal};
use tracer::geometry::{TrianglePrimitive, WatertightTriangle};
use tracer::rays::{RayAnswers, RayKind, RaySet};
use tracer::scene::Scene;

use super::reference::{self, Exact, Reference};
use super::scenes::SceneData;
use crate::error::Error;

/// A scene's identity for caching: scene source, objects, seed and image size.
type SceneKey = (String, u64, u64, u32, u32);

/// A ray set with its reference answers and the reference's name.
type Entry = (Arc<RaySet>, Arc<RayAnswers>, &'static str);

/// Ray sets and reference answers, generated once per scene and ray kind; the reference's check against f64
/// brute force, made once per scene and ray kind when first asked for.
#[derive(Default)]
pub struct RayBank {
    sets: HashMap<(SceneKey, RayKind), Entry>,
    exact: HashMap<SceneKey, Arc<Exact>>,
    checked: HashMap<(SceneKey, RayKind), Arc<Reference>>,
}

impl RayBank {
    fn key(s: &Settings, file: Option<&Scene>) -> SceneKey {
        let source = match (s.scene, file) {
            (SceneName::SphereFile, Some(scene)) => format!("file:{:016x}", scene.fingerprint()),
            (SceneName::Mesh, _) => format!("mesh:{}", s.mesh.as_ref().map_or("-", |m| m.0.as_str())),
            (scene, _) => schema::Named::name(scene).to_string(),
        };
        let view = s.view.map_or("-", |v| v.name());
        (format!("{source} {view}"), s.objects, s.seed, s.width, s.height)
    }

    /// What validates configuration `s` over its scene `scene`: the ray set its workload traces (`None` for the
    /// render workload), and the reference its answers to its validation kind's set are judged against, checked
    /// against f64 brute force (`None` for a backend that gives no answers to check). A ray-set workload is
    /// validated on its own set.
    pub fn validation(
        &mut self,
        s: &Settings,
        file: Option<&Scene>,
        scene: &SceneData,
    ) -> (Option<Arc<RaySet>>, Option<Arc<Reference>>) {
        let traced = matches!(s.workload, Workload::Rays(_));
        let answers = crate::backend::of(s.accel).answers();
        if !traced && !answers {
            return (None, None);
        }
        let key = (Self::key(s, file), s.workload.validation_kind());
        let (set, answers_of_reference, name) = match self.sets.get(&key) {
            Some(entry) => entry.clone(),
            None => {
                let set = generate(key.1, scene, s.seed);
                let (answers, name) = reference::answers(scene, &set);
                let entry = (Arc::new(set), Arc::new(answers), name);
                self.exact.entry(key.0.clone()).or_insert_with(|| Arc::new(Exact::of(scene)));
                self.sets.insert(key.clone(), entry.clone());
                entry
            }
        };
        let reference = answers.then(|| match self.checked.get(&key) {
            Some(checked) => checked.clone(),
            None => {
                let exact = self.exact[&key.0].clone();
                let checked = Arc::new(Reference::check(set.clone(), answers_of_reference, name, exact));
                self.checked.insert(key, checked.clone());
                checked
            }
        });
        (traced.then_some(set), reference)
    }
}

/// The ray set of `kind` for `scene`; secondary rays start from primary hits found with a fast tracer tree
/// (every tree gives the same hits; over triangles the watertight test's), diffuse and ambient-occlusion
/// directions drawn from the scene seed.
pub fn generate(kind: RayKind, scene: &SceneData, seed: u64) -> RaySet {
    let params = BvhParams { traversal: Traversal::FrontToBack, ..BvhParams::default() };
    match scene {
        SceneData::Spheres(scene) => {
            RaySet::generate(kind, scene, &FlatBvh::build(&scene.spheres, &params), seed ^ 0xd1ff_u64)
        }
        SceneData::Triangles(t) => {
            let prims = WatertightTriangle::all(t.mesh.triangles());
            let fast = FlatBvh::build(&prims, &params);
            RaySet::generate_over(kind, &t.camera, t.light, &prims, &fast, seed ^ 0xd1ff_u64)
        }
    }
}

/// The ray sets the sweep's workers read instead of making them again (each worker started for a block of runs would
/// otherwise trace the scene's primary rays anew): written once each into a folder of the system's temporary
/// directory, removed when the sweep ends.
#[derive(Default)]
pub struct RayFiles {
    dir: Option<std::path::PathBuf>,
    written: Vec<(Arc<RaySet>, std::path::PathBuf)>,
}

impl RayFiles {
    /// The file that holds `rays`, written on first use.
    pub fn path_of(&mut self, rays: &Arc<RaySet>) -> Result<std::path::PathBuf, Error> {
        if let Some((_, path)) = self.written.iter().find(|(set, _)| Arc::ptr_eq(set, rays)) {
            return Ok(path.clone());
        }
        let io = |p: &std::path::Path, e: std::io::Error| Error::Run(format!("{}: cannot write: {e}", p.display()));
        let dir = match &self.dir {
            Some(dir) => dir.clone(),
            None => {
                // One folder per sweep, even where one process runs several at once.
                static SWEEPS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
                let sweep = SWEEPS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let dir = std::env::temp_dir().join(format!("bvhlab-rays-{}-{sweep}", std::process::id()));
                std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
                self.dir.insert(dir).clone()
            }
        };
        let path = dir.join(format!("{}.bin", self.written.len()));
        std::fs::write(&path, rays.to_bytes()).map_err(|e| io(&path, e))?;
        self.written.push((Arc::clone(rays), path.clone()));
        Ok(path)
    }
}

impl Drop for RayFiles {
    fn drop(&mut self) {
        if let Some(dir) = &self.dir {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}
