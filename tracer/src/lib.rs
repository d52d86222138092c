//! The ray tracer under study: the seed paper's sphere tracer with a parameterized BVH.
//!
//! Data flows scene → accelerator → executor → renderer:
//! - [`scene`] makes deterministic scenes from a seed (or parses a sphere file);
//! - [`accel`] builds an acceleration structure ([`accel::List`], [`accel::Bvh`], [`accel::FlatBvh`]);
//! - [`executor`] runs rows of an image under a parallel [`executor::Strategy`];
//! - [`render`] shades full Whitted images or runs the primary-ray kernel;
//! - [`rays`] holds fixed ray sets (primary, shadow, diffuse) traced identically by every backend;
//! - [`agreement`] is the one definition of an answer agreeing with brute force (tolerance, f64 arbitration).
//!
//! [`testing`] holds the agreement check against brute force, the ray mixes and the test scenes that every
//! backend's tests share (always compiled: a feature for it changed the whole chain's feature set between the
//! release build and the test build, so the test command compiled every crate above the tracer again).
//!
//! The crate does no file or terminal I/O; [`render::Image::write_png`] encodes into any writer.

pub mod accel;
pub mod agreement;
pub mod counters;
pub mod executor;
pub mod fingerprint;
pub mod geometry;
pub mod job;
pub mod parallel;
pub mod pinning;
pub mod rays;
pub mod render;
pub mod rng;
pub mod scene;
pub mod structure;
pub mod testing;

pub use glam::Vec3;
