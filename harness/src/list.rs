//! `harness list`: every name a config or the command line accepts.

use schema::{Accel, Axis, Named, ObvhsQuality, PacketSize, PeerKind, SceneName, Workload};
use tracer::accel::wide::{ChildOrdering, Kernel};
use tracer::accel::{Split, Traversal, WideParams};
use tracer::executor::StrategyKind;

fn line<T: Named>(what: &str, names: &[T]) {
    say!("{what:<12} {}", names.iter().map(|n| n.name()).collect::<Vec<_>>().join(", "));
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
    say!("{:<12} {}: built in (obvhs 0.4; {}: {})", "", names(&obvhs), Axis::obvhs_build.key(), ObvhsQuality::names());
    match crate::peers::embree_status() {
        Ok(info) => say!("{:<12} {}: available (Embree {} from {})", "", names(&embree), info.version, info.path),
        Err(e) => say!("{:<12} {}: unavailable: {e}", "", names(&embree)),
    }
    line("workloads", Workload::ALL);
    line("splits", &Split::ALL);
    line("traversals", &Traversal::ALL);
    line("strategies", &StrategyKind::ALL);
    let ints = |v: &[u32]| v.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
    say!("{:<12} {} (wide-bvh {})", "node widths", ints(&WideParams::WIDTHS), Axis::node_width.key());
    say!("{:<12} {} (wide-bvh {})", "leaf blocks", ints(&WideParams::LEAF_BLOCKS), Axis::leaf_block.key());
    let here: Vec<&str> = Kernel::available().into_iter().map(Kernel::name).collect();
    let auto: Vec<String> = WideParams::LEAF_BLOCKS
        .iter()
        .map(|&b| format!("{} for blocks of {b}", Kernel::Auto.resolve_for(b).name()))
        .collect();
    say!(
        "{:<12} {} (wide-bvh {}; this CPU runs: {}; auto = {})",
        "kernels",
        Kernel::ALL.map(Kernel::name).join(", "),
        Axis::simd_kernel.key(),
        here.join(", "),
        auto.join(", ")
    );
    line("orders", &ChildOrdering::ALL);
    say!(
        "{:<12} {} (wide-bvh {}; {} {}, default {}; ray sets only)",
        "packets",
        ints(&WideParams::PACKETS),
        Axis::packet_size.key(),
        PeerKind::EmbreePackets.name(),
        PacketSize::embree_allowed(),
        PacketSize::EMBREE_DEFAULT
    );
    say!("{:<12} {} logical cores on this machine", "threads", crate::render::available_threads());
}
