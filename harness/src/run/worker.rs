//! Timing one configuration in a fresh process (Embree: TBB's thread limit is process-wide; `ab`: another
//! build). The request and the answer are one JSON document each, over the child's stdin and stdout.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use schema::Settings;
use serde::{Deserialize, Serialize};

use super::measure::{self, Timing};
use crate::error::Error;
use crate::plan::SphereFile;

/// What a worker is asked to time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorkerRequest {
    /// The configuration's settings.
    pub settings: Settings,
    /// The sphere file of a `sphere-file` scene.
    pub sphere_file: Option<PathBuf>,
}

/// Runs `request` in this process: the worker side.
pub fn serve(request: &WorkerRequest) -> Result<Timing, Error> {
    let s = &request.settings;
    let file = match &request.sphere_file {
        Some(path) => Some(SphereFile::read("worker request", path)?),
        None => None,
    };
    let scene = file.as_ref().map(|f| &*f.scene);
    let rays = match s.workload {
        schema::Workload::Rays(k) => Some(super::validate::generate(k, &measure::make_scene(s, scene), s.seed)),
        schema::Workload::Render => None,
    };
    measure::timed(s, scene, rays.as_ref())
}

/// Times `request` once with `binary`'s `worker` command (run in `dir`, when given).
pub fn time(binary: &Path, dir: Option<&Path>, request: &WorkerRequest) -> Result<Timing, Error> {
    let mut cmd = Command::new(binary);
    cmd.arg("worker").stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped());
    if let Some(dir) = dir {
        cmd.current_dir(dir);
    }
    let mut child =
        cmd.spawn().map_err(|e| Error::Run(format!("{}: cannot start a worker process: {e}", binary.display())))?;
    let json = serde_json::to_string(request).expect("settings serialize");
    child
        .stdin
        .take()
        .expect("piped")
        .write_all(json.as_bytes())
        .map_err(|e| Error::Run(format!("worker stdin: {e}")))?;
    let out = child.wait_with_output().map_err(|e| Error::Run(format!("worker: {e}")))?;
    let answer = String::from_utf8_lossy(&out.stdout);
    match (out.status.success(), answer.lines().last().map(serde_json::from_str::<Timing>)) {
        (true, Some(Ok(t))) => Ok(t),
        _ => Err(Error::Run(format!(
            "{} worker failed (a base revision needs the JSON `harness worker`): {}",
            binary.display(),
            String::from_utf8_lossy(&out.stderr).trim().lines().last().unwrap_or("no output")
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip_through_json() {
        let request =
            WorkerRequest { settings: Settings::default().normalized(), sphere_file: Some("spheres.csv".into()) };
        let json = serde_json::to_string(&request).unwrap();
        assert!(json.contains("\"accel\":\"flat-bvh\""), "settings are spelled as in rows: {json}");
        assert_eq!(serde_json::from_str::<WorkerRequest>(&json).unwrap(), request);
    }
}
