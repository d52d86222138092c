//! obvhs 0.4's BVH2 and compressed wide BVH8 (bindings in [`crate::peers::obvhs`]).

use schema::{Accel, PeerKind, Settings};
use tracer::geometry::Sphere;

use super::{Backend, Built, Setup, Unavailable};
use crate::error::Error;
use crate::peers::{ObvhsBvh2, ObvhsCwbvh};

/// obvhs, built into the harness.
pub struct Obvhs;

/// The row's `peer_info` of obvhs's structures.
const VERSION: &str = "obvhs 0.4";

impl Backend for Obvhs {
    fn name(&self) -> &'static str {
        "obvhs"
    }

    fn runs(&self, accel: Accel) -> bool {
        matches!(accel, Accel::Peer(PeerKind::ObvhsBvh2 | PeerKind::ObvhsCwbvh))
    }

    fn here(&self) -> Result<String, Unavailable> {
        Ok(format!("built in ({VERSION})"))
    }

    fn build(&self, settings: &Settings, spheres: &[Sphere], setup: &Setup) -> Result<Built, Error> {
        let preset = settings.obvhs_build.unwrap_or_default();
        Ok(setup.install(|| match settings.accel {
            Accel::Peer(PeerKind::ObvhsCwbvh) => Built::peer(ObvhsCwbvh::build(spheres, preset), VERSION.into()),
            _ => Built::peer(ObvhsBvh2::build(spheres, preset), VERSION.into()),
        }))
    }
}
