//! Peer backends: other people's ray-tracing BVHs behind the tracer's [`tracer::accel::Accelerator`] trait,
//! so every renderer and kernel runs on them unchanged.
//!
//! - [`obvhs`]: obvhs 0.4's BVH2 and compressed wide BVH8, over spheres (our ray-sphere test in the leaves) or
//!   over triangle meshes (obvhs's own triangle builder and ray-triangle test);
//! - [`embree`]: Embree 4, loaded at run time, over sphere points or triangle meshes (its native triangles);
//!   single rays and 8- and 16-wide packets;
//! - [`tinybvh`]: tinybvh 1.6.8 (triangle meshes) through our own C shim over the header the `tinybvh-rs` crate
//!   bundles, compiled per x86-64 ISA level and chosen at run time; its binary BVH, BVH4_CPU and BVH8_CPU.
//!
//! Peers cannot report node, box or primitive counts (obvhs leaves count primitive tests; Embree and tinybvh count
//! nothing).

pub mod embree;
pub mod obvhs;
pub mod tinybvh;

#[cfg(test)]
pub(crate) mod testing;

use serde::{Deserialize, Serialize};

pub use self::embree::{EmbreeConfig, EmbreeDevice, EmbreeLibrary, EmbreeSpheres, EmbreeTriangles, EmbreeUnavailable};
pub use self::obvhs::{ObvhsBvh2, ObvhsCwbvh, ObvhsLeaf, RtTriangle};
pub use self::tinybvh::{TinyBvh, TinyBvhError, TinyIsa, TinyLayout, TinyQuality};
pub use schema::PeerKind;

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
