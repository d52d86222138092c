//! Peer backends: other people's ray-tracing BVHs behind the tracer's [`tracer::accel::Accelerator`] trait,
//! so every renderer and kernel runs on them unchanged.
//!
//! - [`obvhs`]: obvhs 0.4's BVH2 and compressed wide BVH8, with our ray-sphere test in the leaves;
//! - [`embree`]: Embree 4 (sphere points), loaded at run time; single rays and 16-wide packets.
//!
//! Peers cannot report node, box or primitive counts (obvhs leaves count primitive tests; Embree counts nothing).

pub mod embree;
pub mod obvhs;

#[cfg(test)]
mod testing;

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

pub use self::embree::{EmbreeConfig, EmbreeDevice, EmbreeLibrary, EmbreeQuality, EmbreeSpheres, EmbreeUnavailable};
pub use self::obvhs::{ObvhsBvh2, ObvhsCwbvh, ObvhsQuality};

/// Which peer backend to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PeerKind {
    /// [`ObvhsBvh2`].
    ObvhsBvh2,
    /// [`ObvhsCwbvh`].
    ObvhsCwbvh,
    /// [`EmbreeSpheres`] queried one ray at a time (`rtcIntersect1` / `rtcOccluded1`).
    Embree,
    /// [`EmbreeSpheres`] queried 16 rays at a time ([`EmbreeSpheres::intersect16`]).
    EmbreePackets,
}

impl PeerKind {
    /// Every peer, in the order tools list them.
    pub const ALL: [PeerKind; 4] = [PeerKind::ObvhsBvh2, PeerKind::ObvhsCwbvh, PeerKind::Embree, PeerKind::EmbreePackets];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PeerKind::ObvhsBvh2 => "obvhs-bvh2",
            PeerKind::ObvhsCwbvh => "obvhs-cwbvh",
            PeerKind::Embree => "embree",
            PeerKind::EmbreePackets => "embree-packets",
        }
    }

    /// True for the peers that need the Embree library.
    pub fn needs_embree(self) -> bool {
        matches!(self, PeerKind::Embree | PeerKind::EmbreePackets)
    }
}

impl fmt::Display for PeerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is no peer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownPeer(pub String);

impl fmt::Display for UnknownPeer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<_> = PeerKind::ALL.iter().map(|p| p.name()).collect();
        write!(f, "unknown peer `{}` (known: {})", self.0, names.join(", "))
    }
}

impl std::error::Error for UnknownPeer {}

impl FromStr for PeerKind {
    type Err = UnknownPeer;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        PeerKind::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| UnknownPeer(s.to_string()))
    }
}

/// Where the Embree library was found and its version, for `harness list`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EmbreeInfo {
    /// The library file (or name) loaded.
    pub path: String,
    /// Its version, `major.minor.patch`.
    pub version: String,
}

/// Loads Embree (the default search) and asks a one-thread device for its version.
pub fn embree_status() -> Result<EmbreeInfo, EmbreeUnavailable> {
    let lib = EmbreeLibrary::shared()?;
    let path = lib.path.clone();
    let device = EmbreeDevice::with_library(lib, &EmbreeConfig { threads: Some(1), ..EmbreeConfig::default() })
        .map_err(|e| EmbreeUnavailable { tried: vec![format!("{path}: {e}")] })?;
    Ok(EmbreeInfo { path, version: device.info().version.clone() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peer_names_round_trip() {
        for p in PeerKind::ALL {
            assert_eq!(p.name().parse::<PeerKind>(), Ok(p));
            let toml = toml::to_string(&std::collections::BTreeMap::from([("peer", p)])).unwrap();
            assert_eq!(toml.trim(), format!("peer = \"{}\"", p.name()));
        }
        assert!("embree4".parse::<PeerKind>().unwrap_err().to_string().contains("embree-packets"));
    }
}
