//! Backends: what runs a configuration's `accel`. Each backend is one module implementing [`Backend`] — whether
//! it can run here (and how to install it), whether it needs a process of its own, and how it starts, builds and
//! describes itself in a row — plus its entry in the schema (its `accel` names and the settings that apply to it).
//! The rest of the harness reaches backends only through [`of`] and [`ALL`].
//!
//! - [`ours`]: the tracer's structures (list, pointer BVH, flat BVH, wide BVH);
//! - [`obvhs`]: obvhs 0.4's BVH2 and CWBVH;
//! - [`embree`]: Embree 4, single rays and packets, loaded at run time;
//! - [`null`]: every ray misses at once: the harness's own cost per ray.

mod embree;
mod null;
mod obvhs;
mod ours;
mod setup;
mod structure;
pub mod workload;

use std::fmt;

use schema::{Accel, Named, Settings};
use tracer::geometry::Sphere;

use crate::error::Error;
pub use setup::Setup;
pub use structure::Built;

/// What the harness needs of a backend.
pub trait Backend: Sync {
    /// Its name in `harness list`.
    fn name(&self) -> &'static str;
    /// True for the `accel` values it runs.
    fn runs(&self, accel: Accel) -> bool;
    /// What it is on this machine (version, where it was found), or why it cannot run here at all.
    fn here(&self) -> Result<String, Unavailable>;
    /// Whether `settings` can run on this machine (by default: whether the backend can, [`Backend::here`]).
    fn available(&self, _settings: &Settings) -> Result<(), Unavailable> {
        self.here().map(|_| ())
    }
    /// False for a backend whose answers are not answers (the `null` backend): it is counted and timed, never
    /// validated (`validation = unchecked`).
    fn answers(&self) -> bool {
        true
    }
    /// True when it builds and traces on threads of its own whose limit is process-wide (Embree's TBB): each
    /// configuration is then timed in a worker process of its own, and built outside the harness's pool.
    fn own_threads(&self) -> bool {
        false
    }
    /// Starts what it needs once per process and configuration, before any timed phase (part of `setup_s`).
    fn start(&self, _settings: &Settings) -> Result<Option<Box<dyn std::any::Any + Send + Sync>>, Error> {
        Ok(None)
    }
    /// Builds its structure over `spheres` with what `setup` started.
    fn build(&self, settings: &Settings, spheres: &[Sphere], setup: &Setup) -> Result<Built, Error>;
}

/// Why a backend (or one of its settings) cannot run here.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unavailable {
    /// What is missing and, when it can be installed, how: one line.
    pub reason: String,
    /// True when installing something makes it available (`--require-all` refuses to skip it then); false when
    /// nothing can (the CPU lacks an instruction set).
    pub installable: bool,
}

impl fmt::Display for Unavailable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.reason)
    }
}

/// Every backend, in the order `harness list` shows them.
pub const ALL: &[&dyn Backend] = &[&ours::Ours, &obvhs::Obvhs, &embree::Embree, &null::NullBackend];

/// The backend that runs `accel`.
pub fn of(accel: Accel) -> &'static dyn Backend {
    *ALL.iter().find(|b| b.runs(accel)).unwrap_or_else(|| panic!("no backend runs accel {}", accel.name()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_accel_has_exactly_one_backend() {
        for &accel in Accel::ALL {
            let n = ALL.iter().filter(|b| b.runs(accel)).count();
            assert_eq!(n, 1, "accel {} is run by {n} backends", accel.name());
        }
    }
}
