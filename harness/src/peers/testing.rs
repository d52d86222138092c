//! Test helpers for the peers: the Embree device, and brute force over a triangle mesh. The test scenes and
//! meshes, ray mixes and agreement check against brute force are the tracer's own, shared with its tests:
//! `tracer::testing`.

use std::io::Write;

use tracer::geometry::{Ray, Triangle, WatertightTriangle};
use tracer::scene::mesh::Mesh;
use tracer::testing::Reference;

use super::embree::{EmbreeConfig, EmbreeDevice, EmbreeLibrary};

/// The Embree device for a test, or `None` (after saying so) when Embree is missing and not required.
/// With `BVHLAB_REQUIRE_EMBREE=1` a missing Embree fails the test.
pub fn embree_device(test: &str) -> Option<EmbreeDevice> {
    let required = std::env::var("BVHLAB_REQUIRE_EMBREE").is_ok_and(|v| v == "1");
    match EmbreeLibrary::shared() {
        Ok(_) => Some(
            EmbreeDevice::new(&EmbreeConfig { threads: Some(2), ..EmbreeConfig::default() }).expect("Embree device"),
        ),
        Err(e) if required => panic!("{test}: BVHLAB_REQUIRE_EMBREE=1 but {e}"),
        Err(e) => {
            // Straight to stderr, past libtest's output capture, so the skip is always visible.
            let _ = writeln!(std::io::stderr(), "{test}: skipped: {e}");
            None
        }
    }
}

/// f32 brute force's answers (the watertight test) to `rays` over `mesh`'s triangles: the reference peers on
/// triangles are compared with under `Strictness::Arbitrated`, f64 brute force arbitrating.
pub fn triangle_reference<'a>(mesh: &Mesh, rays: &'a [Ray]) -> Reference<'a, Triangle> {
    let triangles: Vec<Triangle> = mesh.triangles().collect();
    Reference::triangles::<WatertightTriangle>(&triangles, rays)
}
