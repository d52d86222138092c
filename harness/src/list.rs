//! `harness list`: every name a config or the command line accepts.

use tracer::accel::{AccelKind, Split, Traversal};
use tracer::executor::StrategyKind;
use tracer::scene::SceneKind;

fn line(what: &str, names: impl IntoIterator<Item = &'static str>) {
    println!("{what:<12} {}", names.into_iter().collect::<Vec<_>>().join(", "));
}

/// Prints the lists.
pub fn run() {
    line("scenes", SceneKind::ALL.iter().map(|k| k.name()).chain(["sphere-file"]));
    line("accels", AccelKind::ALL.iter().map(|k| k.name()));
    line("peers", crate::peers::PeerKind::ALL.iter().map(|k| k.name()));
    println!("{:<12} obvhs-bvh2, obvhs-cwbvh: built in (obvhs 0.4; obvhs_build: {})", "", crate::config::axes::Axis::ObvhsBuild.names().join(", "));
    match crate::peers::embree_status() {
        Ok(info) => println!("{:<12} embree, embree-packets: available (Embree {} from {})", "", info.version, info.path),
        Err(e) => println!("{:<12} embree, embree-packets: unavailable: {e}", ""),
    }
    line("workloads", crate::config::axes::Workload::ALL.iter().map(|w| w.name()));
    line("splits", Split::ALL.iter().map(|k| k.name()));
    line("traversals", Traversal::ALL.iter().map(|k| k.name()));
    line("strategies", StrategyKind::ALL.iter().map(|k| k.name()));
    println!("{:<12} {} logical cores on this machine", "threads", crate::render::available_threads());
}
