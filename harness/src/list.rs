//! `harness list`: every setting a config or `harness render --set` accepts, from the schema (key, allowed
//! values, default), and what this machine has: the peers' availability, the SIMD kernels and cores.

use schema::{Axis, Named, PeerKind};
use tracer::accel::WideParams;
use tracer::accel::wide::Kernel;

/// Prints the lists.
pub fn run() {
    for &axis in Axis::ALL {
        say!("{:<22} {} (default {})", axis.key(), axis.allowed(), axis.default_value());
    }
    let names = |peers: &[&PeerKind]| peers.iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
    let obvhs: Vec<&PeerKind> = PeerKind::ALL.iter().filter(|p| p.is_obvhs()).collect();
    let embree: Vec<&PeerKind> = PeerKind::ALL.iter().filter(|p| p.needs_embree()).collect();
    say!("{:<22} {}: built in (obvhs 0.4)", "peers here", names(&obvhs));
    match crate::peers::embree_status() {
        Ok(info) => say!("{:<22} {}: available (Embree {} from {})", "", names(&embree), info.version, info.path),
        Err(e) => say!("{:<22} {}: unavailable: {e}", "", names(&embree)),
    }
    let here: Vec<&str> = Kernel::available().into_iter().map(Kernel::name).collect();
    let auto: Vec<String> = WideParams::LEAF_BLOCKS
        .iter()
        .map(|&b| format!("{} for blocks of {b}", Kernel::Auto.resolve_for(b).name()))
        .collect();
    say!("{:<22} {}; auto = {}", "kernels here", here.join(", "), auto.join(", "));
    say!("{:<22} {} logical cores", "threads here", crate::render::available_threads());
}
