//! A rough time estimate for `harness validate`: a cost model with per-ray constants from this project's
//! benchmarks on a 2-core dev machine (within about 2× elsewhere).

use schema::{Accel, SceneName, Settings, Workload};
use tracer::accel::{AccelKind, Traversal};

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
    let parallel = 0.9 * s.strategy().threads.min(cores).max(1) as f64;
    let build = if s.accel == Accel::Ours(AccelKind::List) { 0.0 } else { 2e-7 * n * n.log2().max(1.0) / 10.0 };
    // Triangle builds: box references, and the peers' spatial-split builds (tinybvh BuildHQ about 1.5 s at 268k).
    let build = if s.scene.is_triangles() { build * 5.0 } else { build };
    let encode = if s.workload == Workload::Render { pixels * 3e-8 } else { 0.0 };
    rays * per_ray / parallel + build + encode + 1e-7 * n
}

/// Primitives the scene of `s` holds: its spheres, their tessellation (224 triangles a sphere), its random
/// triangles, or, for a mesh (not loaded when estimating), 200,000, the order of the data sets measured here.
fn primitives(s: &Settings) -> f64 {
    let objects = s.objects.max(1) as f64;
    match s.scene {
        SceneName::TessellatedSpheres => objects * 224.0,
        SceneName::Mesh => 2e5,
        _ => objects,
    }
}
