//! Backends: what runs a configuration's `accel`. Each backend is one module implementing [`Backend`] — whether
//! it can run here (and how to install it), whether it needs a process of its own, and how it starts, builds and
//! describes itself in a row — plus its entry in the schema (its `accel` names and the settings that apply to it).
//! The rest of the harness reaches backends only through [`of`] and [`ALL`].
//!
//! - [`ours`]: the tracer's structures (list, pointer BVH, flat BVH, wide BVH);
//! - [`obvhs`]: obvhs 0.4's BVH2 and CWBVH;
//! - [`embree`]: Embree 4, single rays and packets, loaded at run time;
//! - [`tinybvh`]: tinybvh through the harness's shim (triangle scenes only);
//! - [`null`]: every ray misses at once: the harness's own cost per ray.
//!
//! Every backend builds over a [`Geometry`]: spheres or a triangle mesh. What a backend cannot build, or a
//! workload that a scene kind has not, is skipped like an unavailable backend ([`scene_support`]).

mod embree;
mod null;
mod obvhs;
mod ours;
mod setup;
mod structure;
mod tinybvh;
pub mod workload;

use std::fmt;

use schema::{Accel, Named, PeerKind, Settings, Workload};
use tracer::geometry::Sphere;
use tracer::scene::mesh::Mesh;

use crate::error::Error;
pub use setup::Setup;
pub use structure::Built;

/// What the harness needs of a backend.
pub trait Backend: Sync {
    /// Its name in `harness list`.
    fn name(&self) -> &'static str;
    /// True for the `accel` values it runs.
    fn runs(&self, accel: Accel) -> bool;
    /// What it is on this machine (version, where it was found), or why it cannot run here at all.
    fn here(&self) -> Result<String, Unavailable>;
    /// Whether `settings` can run on this machine (by default: whether the backend can, [`Backend::here`]).
    fn available(&self, _settings: &Settings) -> Result<(), Unavailable> {
        self.here().map(|_| ())
    }
    /// False for a backend whose answers are not answers (the `null` backend): it is counted and timed, never
    /// validated (`validation = unchecked`).
    fn answers(&self) -> bool {
        true
    }
    /// True when it builds and traces on threads of its own whose limit is process-wide (Embree's TBB): each
    /// configuration is then timed in a worker process of its own, and built outside the harness's pool.
    fn own_threads(&self, _settings: &Settings) -> bool {
        false
    }
    /// Starts what it needs once per process and configuration, before any timed phase (part of `setup_s`).
    fn start(&self, _settings: &Settings) -> Result<Option<Box<dyn std::any::Any + Send + Sync>>, Error> {
        Ok(None)
    }
    /// Builds its structure over `geometry` with what `setup` started.
    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error>;
}

/// What a structure is built over.
#[derive(Clone, Copy, Debug)]
pub enum Geometry<'a> {
    /// A sphere scene's spheres.
    Spheres(&'a [Sphere]),
    /// A triangle scene's mesh.
    Triangles(&'a Mesh),
}

/// Whether `settings`' backend and workload can run on its scene kind: the render workload of timed runs shades
/// spheres only (`harness render` draws triangle scenes too), and tinybvh traces triangles only (nothing installed
/// changes either).
pub fn scene_support(settings: &Settings) -> Result<(), Unavailable> {
    if settings.scene.is_triangles() && settings.workload == Workload::Render {
        let why = "the render workload shades sphere scenes only (triangle scenes run the ray sets)";
        return Err(Unavailable { reason: why.into(), installable: false });
    }
    accel_support(settings)
}

/// Whether `settings`' backend builds on its scene kind: tinybvh traces triangles only.
pub fn accel_support(settings: &Settings) -> Result<(), Unavailable> {
    if !settings.scene.is_triangles() && settings.accel == Accel::Peer(PeerKind::TinyBvh) {
        let why = "tinybvh traces triangles only (sphere scenes have no tinybvh structure)";
        return Err(Unavailable { reason: why.into(), installable: false });
    }
    Ok(())
}

/// Why a backend (or one of its settings) cannot run here.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unavailable {
    /// What is missing and, when it can be installed, how: one line.
    pub reason: String,
    /// True when installing something makes it available (`--require-all` refuses to skip it then); false when
    /// nothing can (the CPU lacks an instruction set).
    pub installable: bool,
}

impl fmt::Display for Unavailable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.reason)
    }
}

/// Every backend, in the order `harness list` shows them.
pub const ALL: &[&dyn Backend] =
    &[&ours::Ours, &obvhs::Obvhs, &embree::Embree, &tinybvh::TinyBvhBackend, &null::NullBackend];

/// The backend that runs `accel`.
pub fn of(accel: Accel) -> &'static dyn Backend {
    *ALL.iter().find(|b| b.runs(accel)).unwrap_or_else(|| panic!("no backend runs accel {}", accel.name()))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use schema::{SceneName, TinyBvhLayout, TinyBvhQuality, ValidationStatus};
    use tracer::geometry::TriangleTest;
    use tracer::scene::View;

    use super::*;
    use crate::config::Experiment;
    use crate::plan::Plan;
    use crate::run::{Existing, RUNS_CSV, sweep};

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("bvhlab-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_config_with_every_triangle_setting_parses_and_plans() {
        let dir = temp("mesh-settings");
        let obj = dir.join("quad.obj");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n").unwrap();
        let text = format!(
            "name = \"m\"\n[sweep]\nscene = [\"mesh\", \"tessellated-spheres\", \"random-triangles\"]\nmesh = {:?}\n\
             workload = \"ambient-occlusion\"\ntriangle_test = [\"moller-trumbore\", \"watertight\"]\n\
             view = [\"overview\", \"street\"]\ntinybvh_layout = \"bvh8-cpu\"\ntinybvh_build = \"high\"\n\
             [[series]]\nlabel = \"ours\"\naccel = \"flat-bvh\"\n[[series]]\nlabel = \"tiny\"\naccel = \"tinybvh\"\n",
            obj.to_str().unwrap()
        );
        let exp = Experiment::parse(Path::new("m.toml"), &text).unwrap();
        let plan = Plan::new(&exp, 1).unwrap();
        let ours: Vec<_> = plan.configurations.iter().filter(|c| c.series == "ours").collect();
        assert_eq!(ours.len(), 3 * 2 * 2, "scenes × tests × views");
        let tiny: Vec<_> = plan.configurations.iter().filter(|c| c.series == "tiny").collect();
        assert_eq!(tiny.len(), 3 * 2, "the triangle test is the tracer's: not tinybvh's");
        for c in &plan.configurations {
            let s = &c.settings;
            assert_eq!(s.mesh.is_some(), s.scene == SceneName::Mesh, "{s:?}");
            assert!(s.view.is_some());
            assert_eq!(s.triangle_test.is_some(), c.series == "ours");
            assert_eq!(s.tinybvh_layout, (c.series == "tiny").then_some(TinyBvhLayout::Bvh8Cpu));
            assert_eq!(s.tinybvh_build, (c.series == "tiny").then_some(TinyBvhQuality::High));
            assert_eq!(s.seed == 0, s.scene == SceneName::Mesh, "a mesh has no seed");
        }
        assert!(ours.iter().any(|c| c.settings.triangle_test == Some(TriangleTest::MollerTrumbore)));
        assert!(ours.iter().any(|c| c.settings.view == Some(View::Street)));
        // Sphere scenes keep their settings (and ids): no triangle setting applies to them.
        let spheres = Experiment::parse(Path::new("s.toml"), "name = \"s\"\n[sweep]\nview = \"street\"\n").unwrap();
        let s = &Plan::new(&spheres, 1).unwrap().configurations[0].settings;
        assert_eq!((s.view, s.triangle_test, &s.mesh), (None, None, &None));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Embree runs in worker processes of the harness binary: `harness/tests/harness/cli.rs` runs it on meshes.
    #[test]
    fn a_quick_run_over_tessellated_spheres_validates_every_configuration() {
        let text = "name = \"tess\"\nsample_ms = 0\nprocesses = 1\nrepetitions = 1\nwarmups = 0\n[sweep]\nscene = [\"tessellated-spheres\", \"random-triangles\"]\n\
                    objects = 30\nwidth = 24\nheight = 16\ntriangle_test = [\"moller-trumbore\", \"watertight\"]\n\
                    workload = [\"primary\", \"shadow\", \"diffuse\", \"ambient-occlusion\", \"render\"]\n\
                    accel = [\"list\", \"bvh\", \"flat-bvh\", \"wide-bvh\", \"obvhs-bvh2\", \"obvhs-cwbvh\", \"tinybvh\"]\ntinybvh_layout = [\"bvh\", \"bvh4-cpu\", \"bvh8-cpu\"]\n\
                    node_width = [4, 8]\nleaf_block = [4, 8, 16]\n";
        let exp = Experiment::parse(Path::new("tess.toml"), text).unwrap();
        let mut plan = Plan::new(&exp, 1).unwrap();
        plan.skip_unavailable("tess.toml", false).unwrap();
        assert!(
            plan.notes.iter().any(|n| n.contains("the render workload shades sphere scenes only")),
            "renders of triangles are skipped with the reason: {:?}",
            plan.notes
        );
        let dir = temp("tess");
        sweep(&exp, &plan, &dir, Existing::Replace).unwrap();
        let rows = schema::row::read_rows(&std::fs::read_to_string(dir.join(RUNS_CSV)).unwrap()).unwrap();
        assert_eq!(rows.len(), plan.runs.len());
        assert!(rows.len() >= 2 * 4 * (2 * (3 + 2 * 3) + 2), "{}", rows.len());
        for r in &rows {
            assert_eq!((r.validation, r.mismatches), (ValidationStatus::Exact, 0), "{r:?}");
            assert!(r.rays > 0 && r.tree_bytes > 0, "{r:?}");
            assert_ne!(r.workload, schema::Workload::Render);
        }
        let tiny = Accel::Peer(PeerKind::TinyBvh);
        if of(tiny).here().is_ok() {
            assert!(rows.iter().any(|r| r.accel == tiny), "tinybvh ran");
        }
        std::fs::remove_dir_all(&dir).unwrap();
        // tinybvh on spheres is skipped, with the reason.
        let exp =
            Experiment::parse(Path::new("s.toml"), "name = \"s\"\n[sweep]\naccel = [\"tinybvh\", \"flat-bvh\"]\n")
                .unwrap();
        let mut plan = Plan::new(&exp, 1).unwrap();
        plan.skip_unavailable("s.toml", false).unwrap();
        assert!(plan.notes.iter().any(|n| n.contains("tinybvh traces triangles only")), "{:?}", plan.notes);
    }

    #[test]
    fn every_accel_has_exactly_one_backend() {
        for &accel in Accel::ALL {
            let n = ALL.iter().filter(|b| b.runs(accel)).count();
            assert_eq!(n, 1, "accel {} is run by {n} backends", accel.name());
        }
    }
}
