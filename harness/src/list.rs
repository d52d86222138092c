//! `harness list`: every name a config or the command line accepts.

use schema::{Accel, Axis, Named, ObvhsQuality, PeerKind, SceneName, Workload};
use tracer::accel::{Split, Traversal};
use tracer::executor::StrategyKind;

fn line<T: Named>(what: &str, names: &[T]) {
    println!("{what:<12} {}", names.iter().map(|n| n.name()).collect::<Vec<_>>().join(", "));
}

/// Prints the lists.
pub fn run() {
    line("scenes", SceneName::ALL);
    let ours: Vec<Accel> = Accel::ALL.iter().copied().filter(|a| a.peer().is_none()).collect();
    line("accels", &ours);
    line("peers", PeerKind::ALL);
    let names = |peers: &[&PeerKind]| peers.iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
    let obvhs: Vec<&PeerKind> = PeerKind::ALL.iter().filter(|p| p.is_obvhs()).collect();
    let embree: Vec<&PeerKind> = PeerKind::ALL.iter().filter(|p| p.needs_embree()).collect();
    println!(
        "{:<12} {}: built in (obvhs 0.4; {}: {})",
        "",
        names(&obvhs),
        Axis::obvhs_build.key(),
        ObvhsQuality::names()
    );
    match crate::peers::embree_status() {
        Ok(info) => println!("{:<12} {}: available (Embree {} from {})", "", names(&embree), info.version, info.path),
        Err(e) => println!("{:<12} {}: unavailable: {e}", "", names(&embree)),
    }
    line("workloads", Workload::ALL);
    line("splits", &Split::ALL);
    line("traversals", &Traversal::ALL);
    line("strategies", &StrategyKind::ALL);
    println!("{:<12} {} logical cores on this machine", "threads", crate::render::available_threads());
}
