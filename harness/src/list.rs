//! `harness list`: every setting a config or `harness render --set` accepts, from the schema (key, allowed
//! values, default), and what this machine has: each backend's availability (and the SIMD kernels), and cores.

use schema::{Accel, Axis, Named};

/// Prints the lists.
pub fn run() {
    for &axis in Axis::ALL {
        say!("{:<22} {} (default {})", axis.key(), axis.allowed(), axis.default_value());
    }
    for backend in crate::backend::ALL {
        let accels: Vec<&str> = Accel::ALL.iter().filter(|&&a| backend.runs(a)).map(|a| a.name()).collect();
        let here = backend.here().unwrap_or_else(|e| format!("unavailable: {e}"));
        say!("{:<22} {}: {here}", backend.name(), accels.join(", "));
    }
    say!("{:<22} {} logical cores", "threads here", crate::plan::available_threads());
}
