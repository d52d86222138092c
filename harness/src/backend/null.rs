//! The null backend: every ray misses at once ([`tracer::accel::Null`]), so a series of it times the harness's own
//! path per ray — the same ray set, executor, batch loop and answer writes as every backend, and nothing else.

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;
use schema::{Accel, PeerKind, Settings};
use tracer::accel::Null;

/// The harness's own cost.
pub struct NullBackend;

impl Backend for NullBackend {
    fn name(&self) -> &'static str {
        "null"
    }

    fn runs(&self, accel: Accel) -> bool {
        accel == Accel::Peer(PeerKind::Null)
    }

    fn here(&self) -> Result<String, Unavailable> {
        Ok("built in (answers nothing: the harness's own cost per ray)".into())
    }

    fn answers(&self) -> bool {
        false
    }

    fn build(&self, _settings: &Settings, _geometry: &Geometry<'_>, _setup: &Setup) -> Result<Built, Error> {
        Ok(Built::peer(Null, "-".into()))
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use schema::ValidationStatus;

    use crate::config::Experiment;
    use crate::plan::Plan;
    use crate::run::{Existing, RUNS_CSV, sweep};

    #[test]
    fn a_null_series_is_timed_and_counted_but_never_validated() {
        let text = "name = \"null\"\nsample_ms = 0\nprocesses = 1\nrepetitions = 2\nwarmups = 0\n[sweep]\nobjects = 50\nwidth = 16\nheight = 8\n\
                    workload = [\"primary\", \"render\"]\n[[series]]\nlabel = \"null\"\naccel = \"null\"\n";
        let exp = Experiment::parse(Path::new("null.toml"), text).unwrap();
        let plan = Plan::new(&exp, 1).unwrap();
        let dir = std::env::temp_dir().join(format!("bvhlab-null-{}", std::process::id()));
        sweep(&exp, &plan, &dir, Existing::Replace).unwrap();
        let rows = schema::row::read_rows(&std::fs::read_to_string(dir.join(RUNS_CSV)).unwrap()).unwrap();
        assert_eq!(rows.len(), 4);
        for r in &rows {
            assert_eq!((r.validation, r.mismatches, r.tree_nodes), (ValidationStatus::Unchecked, 0, 0), "{r:?}");
            assert!(r.trace_s.is_some_and(|t| t > 0.0) && r.rays >= 128, "{r:?}");
            assert_eq!(r.nodes_per_ray, 0.0, "a structure of nothing visits nothing");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
