//! A rough time estimate for `harness validate`: a cost model with per-ray constants from this project's
//! benchmarks on a 2-core dev machine (within about 2× elsewhere).

use schema::{Accel, EmbreeQuality, ObvhsQuality, PeerKind, SceneName, Settings, TinyBvhQuality, Workload};
use tracer::accel::{AccelKind, Split, Traversal};

use super::Plan;
use crate::config::Experiment;
use crate::run::checked_count;
use std::collections::{BTreeMap, BTreeSet};

/// Seconds one run of `s` is expected to take on a machine with `cores` cores.
pub fn estimate_seconds(s: &Settings, cores: usize) -> f64 {
    let pixels = s.width as f64 * s.height as f64;
    let rays = match s.workload {
        Workload::Rays(_) => pixels,
        Workload::Render => pixels * 2.6,
    };
    let n = primitives(s);
    // Renders: shading and a shadow ray per hit; fitted to `paper` on the 2-core AVX2 dev machine (2026-11-23).
    let render_ray = |accel: Accel| match accel {
        Accel::Ours(AccelKind::List) => 7e-8 + 5.8e-9 * n,
        _ => 7e-8 + 3.5e-8 * n.log2().max(1.0),
    };
    let per_ray = match (s.accel, s.traversal) {
        (accel, _) if s.workload == Workload::Render => render_ray(accel),
        (Accel::Peer(_), _) => 25e-9 * n.log2().max(1.0),
        (Accel::Ours(AccelKind::List), _) => 2.5e-9 * n,
        (Accel::Ours(AccelKind::WideBvh), _) | (_, Some(Traversal::FrontToBack)) => 25e-9 * n.log2().max(1.0),
        (_, _) => 25e-9 * n.log2().max(1.0) * (1.0 + n.log10().max(0.0)),
    };
    let threads = s.strategy().threads.min(cores).max(1);
    let parallel = 0.9 * threads as f64;
    let build = if s.accel == Accel::Ours(AccelKind::List) {
        0.0
    } else if s.scene.is_triangles() {
        triangle_build_seconds(s, n, threads, cores)
    } else {
        2e-8 * n * n.log2().max(1.0)
    };
    let encode = if s.workload == Workload::Render { pixels * 3e-8 } else { 0.0 };
    rays * per_ray / parallel + build + encode + 1e-7 * n
}

/// Seconds a triangle build of `n` triangles takes at `threads` threads: a per-builder cost per `n log2 n` at one
/// thread, measured on San Francisco tiled to 5.6 M triangles (`munich*` and `san-francisco*` rows of
/// `results/scale`, 2-core AMD EPYC), divided by the builder's parallel speedup.
fn triangle_build_seconds(s: &Settings, n: f64, threads: usize, cores: usize) -> f64 {
    let per = match s.accel {
        Accel::Ours(_) => match s.split {
            Some(Split::SpatialSah) => 3.5e-8,
            Some(Split::SweepSah) => 6e-8,
            Some(Split::BinnedSah) => 1.8e-8,
            _ => 1e-8,
        },
        Accel::Peer(PeerKind::Embree | PeerKind::EmbreePackets) => match s.embree_build {
            Some(EmbreeQuality::High) => 5.6e-8,
            Some(EmbreeQuality::Low) => 2.2e-8,
            _ => 1.8e-8,
        },
        Accel::Peer(PeerKind::TinyBvh) => match s.tinybvh_build {
            Some(TinyBvhQuality::High) => 8.6e-8,
            _ => 4.9e-8,
        },
        Accel::Peer(PeerKind::ObvhsBvh2 | PeerKind::ObvhsCwbvh) => match s.obvhs_build {
            Some(ObvhsQuality::VerySlow) => 3e-7,
            Some(ObvhsQuality::Slow) => 1.5e-7,
            Some(ObvhsQuality::Medium) => 4e-8,
            Some(ObvhsQuality::Fast) => 2e-8,
            _ => 1e-8,
        },
        Accel::Peer(PeerKind::Null) => 0.0,
    };
    // Our spatial build is serial; tinybvh's builds use every core whatever the setting; the rest scale.
    let used = match (s.accel, s.split) {
        (Accel::Ours(_), Some(Split::SpatialSah)) => 1,
        (Accel::Peer(PeerKind::TinyBvh), _) => cores.max(1),
        _ => threads,
    };
    let speedup = 1.0 + 0.6 * (used.saturating_sub(1)) as f64;
    per * n * n.log2().max(1.0) / speedup
}

/// The estimated wall time of `plan` when every configuration runs `repetitions` (its warm-ups besides): each
/// run its cost model's time plus its sample (`sample_ms`: a run traces at least that long); with `processes`
/// above 1 each worker's start and warm-up (its mesh loaded, an untimed build and an untimed pass: about a run);
/// and each ray set's validation once ([`validation_seconds`]).
pub fn plan_seconds(exp: &Experiment, plan: &Plan, cores: usize, repetitions: u32) -> f64 {
    let planned: BTreeSet<usize> = plan.runs.iter().map(|r| r.config).collect();
    let runs: f64 = planned
        .iter()
        .map(|&c| {
            let s = &plan.configurations[c].settings;
            round_seconds(exp, s, cores) * f64::from(exp.warmups + repetitions)
        })
        .sum();
    let sets: BTreeMap<String, f64> = planned
        .iter()
        .map(|&c| {
            let s = &plan.configurations[c].settings;
            let key = format!(
                "{:?} {:?} {} {} {:?} {}x{} {:?}",
                s.scene,
                s.mesh,
                s.objects,
                s.seed,
                s.view,
                s.width,
                s.height,
                s.workload.validation_kind()
            );
            (key, validation_seconds(s, cores))
        })
        .collect();
    runs + sets.values().sum::<f64>()
}

/// Wall seconds one recorded run of `s` costs in `exp`: the run, its sample, and its share of a worker's start
/// and warm-up when `processes` is above 1.
pub fn round_seconds(exp: &Experiment, s: &Settings, cores: usize) -> f64 {
    let run = estimate_seconds(s, cores);
    let per_worker = exp.repetitions.max().div_ceil(exp.processes.max(1)).max(1);
    let workers = if exp.processes > 1 { (run + worker_start_seconds(s)) / f64::from(per_worker) } else { 0.0 };
    run + exp.sample_s + workers
}

/// Seconds validating a ray set of `s` once costs: the reference's answers (f32 brute force up to
/// [`BRUTE_FORCE_MAX`](crate::run::BRUTE_FORCE_MAX) primitives, else a binned flat BVH) and f64 brute force on
/// [`checked_count`] of its rays (about 1 ns a ray and primitive on one core).
pub fn validation_seconds(s: &Settings, cores: usize) -> f64 {
    let n = primitives(s);
    let rays = s.width as f64 * s.height as f64;
    let parallel = 0.9 * cores.max(1) as f64;
    let reference = if n <= crate::run::BRUTE_FORCE_MAX as f64 {
        rays * n * 1e-9 / parallel
    } else {
        1.8e-8 * n * n.log2() + rays * 25e-9 * n.log2() / parallel
    };
    reference + checked_count(rays as usize, n as usize) as f64 * n * 1e-9 / parallel
}

/// Seconds a worker process takes to start beyond its warm-up run: exec, the request, the ray file, and loading
/// its scene's mesh (about 0.3 µs a triangle from the cache, tiling included).
pub fn worker_start_seconds(s: &Settings) -> f64 {
    let mesh = if s.scene == SceneName::Mesh { 3e-7 * primitives(s) } else { 0.0 };
    0.02 + mesh
}

/// Primitives the scene of `s` holds: its spheres, their tessellation (224 triangles a sphere), its random
/// triangles, or, for a mesh (not loaded when estimating), a data set's registered triangles (times a tiling's
/// copies), else 200,000, the order of the data sets measured here.
pub fn primitives(s: &Settings) -> f64 {
    let objects = s.objects.max(1) as f64;
    match s.scene {
        SceneName::TessellatedSpheres => objects * 224.0,
        SceneName::Mesh => s.mesh.as_ref().and_then(|m| crate::meshes::triangles(&m.0)).map_or(2e5, |n| n as f64),
        _ => objects,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::{MeshSource, Threads};

    fn mesh(name: &str, accel: Accel) -> Settings {
        let mut s =
            Settings { scene: SceneName::Mesh, mesh: Some(MeshSource(name.into())), accel, ..Settings::default() };
        s.threads = Threads::Count(1);
        s
    }

    #[test]
    fn a_tiled_data_set_counts_its_copies_and_builds_cost_per_builder() {
        let ours = |split| Settings { split: Some(split), ..mesh("san-francisco*21", Accel::Ours(AccelKind::WideBvh)) };
        assert_eq!(primitives(&mesh("san-francisco*21", Accel::Ours(AccelKind::WideBvh))), 21.0 * 268_041.0);
        assert_eq!(primitives(&mesh("some/file.obj", Accel::Ours(AccelKind::WideBvh))), 2e5);
        let n = 21.0 * 268_041.0;
        let (spatial, binned) = (ours(Split::SpatialSah), ours(Split::BinnedSah));
        let build = |s: &Settings| triangle_build_seconds(s, n, 1, 2);
        assert!(build(&spatial) > build(&binned));
        let obvhs = Settings { obvhs_build: Some(ObvhsQuality::Slow), ..mesh("x", Accel::Peer(PeerKind::ObvhsCwbvh)) };
        assert!(build(&obvhs) > build(&spatial));
        // Our spatial build is serial: more threads do not help it; the binned build's do.
        assert_eq!(triangle_build_seconds(&spatial, n, 2, 2), build(&spatial));
        assert!(triangle_build_seconds(&binned, n, 2, 2) < build(&binned));
    }
}
