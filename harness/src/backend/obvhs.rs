//! obvhs 0.4's BVH2 and compressed wide BVH8 (bindings in [`crate::peers::obvhs`]).

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;
use crate::peers::{ObvhsBvh2, ObvhsCwbvh};
use schema::{Accel, PeerKind, Settings};

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

    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error> {
        let preset = settings.obvhs_build.unwrap_or_default();
        let cwbvh = settings.accel == Accel::Peer(PeerKind::ObvhsCwbvh);
        Ok(setup.install(|| match (*geometry, cwbvh) {
            (Geometry::Spheres(s), true) => Built::peer(ObvhsCwbvh::build(s, preset), VERSION.into()),
            (Geometry::Spheres(s), false) => Built::peer(ObvhsBvh2::build(s, preset), VERSION.into()),
            (Geometry::Triangles(m), true) => Built::peer(ObvhsCwbvh::build_mesh(m, preset), VERSION.into()),
            (Geometry::Triangles(m), false) => Built::peer(ObvhsBvh2::build_mesh(m, preset), VERSION.into()),
        }))
    }
}
