//! Embree 4 as a peer, through a small hand-written binding loaded at run time (no link-time dependency).
//!
//! - [`abi`]: the C structs, constants and function types, sizes pinned at compile time;
//! - [`library`]: finding `libembree4` (`EMBREE_LIB`, the system, an `embreex` wheel) and resolving symbols;
//! - [`device`]: devices, their configuration and error capture;
//! - [`scene`]: a committed scene of sphere points ([`EmbreeSpheres`]) or triangles ([`EmbreeTriangles`]),
//!   implementing [`tracer::accel::Accelerator`], with 8- and 16-wide packet queries;
//! - [`tree`]: Embree's builder (`rtcBuildBVH`) making a binary tree for our tracer (`tree_builder`).

pub mod abi;
pub mod device;
pub mod library;
pub mod scene;
pub mod tree;

#[cfg(test)]
mod tests;

pub use device::{EmbreeConfig, EmbreeDevice};
pub use library::{EmbreeLibrary, EmbreeUnavailable};
pub use scene::{EmbreeGeometry, EmbreeScene, EmbreeSpheres, EmbreeTriangles, SpherePoints, Triangles};
