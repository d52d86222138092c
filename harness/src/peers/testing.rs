//! Test helpers for the peers that only Embree needs. The test scenes, ray mixes and agreement check against
//! brute force are the tracer's own, shared with its tests: `tracer::testing` (the `testing` feature).

use std::io::Write;

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
