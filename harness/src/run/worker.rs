//! Timing configurations in other processes (Embree: TBB's thread limit is process-wide; `ab`: another build).
//!
//! The protocol is JSON lines: each request line on the worker's stdin is answered by one [`Timing`] line on
//! its stdout. A worker serves one configuration at a time like the harness itself does: the first request
//! starts the backend ([`Setup`], reported as `setup_s`) and makes the ray set, and every request after it
//! with the same settings is one more warm run in the same process (the sweep keeps one worker per
//! configuration for its warm-ups and all its repetitions). A worker that fails prints why on stderr and exits.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use schema::Settings;
use serde::{Deserialize, Serialize};
use tracer::rays::RaySet;

use super::measure::{self, Timing};
use crate::backend::Setup;
use crate::error::Error;
use crate::plan::SphereFile;

/// What a worker is asked to time.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorkerRequest {
    /// The configuration's settings.
    pub settings: Settings,
    /// The sphere file of a `sphere-file` scene.
    pub sphere_file: Option<PathBuf>,
    /// The shortest timed sample in seconds (0, and absent in earlier revisions' requests: one pass).
    #[serde(default)]
    pub sample_s: f64,
}

/// The JSON line of a request: today's settings, and beside them the ones earlier revisions named otherwise (a
/// worker ignores fields its schema does not declare, but needs every one it does): `packet_size`, the rays traced
/// together, which 96801f6 split into `packet` (the wide BVH's) and `embree_packet`; `0` where neither applies.
pub fn request_line(request: &WorkerRequest) -> String {
    let mut json = serde_json::to_value(request).expect("settings serialize");
    let s = &request.settings;
    let embree = s.embree_packet.and_then(|p| schema::AxisType::number(&p)).map(|n| n as u32);
    let packet_size = s.packet.map(|p| p.rays()).or(embree).unwrap_or(0);
    json["settings"]["packet_size"] = serde_json::Value::String(packet_size.to_string());
    json.to_string()
}

/// Today's settings an earlier revision declared under another name: (today's, then).
pub const RENAMED: [(&str, &str); 2] = [("packet", "packet_size"), ("embree_packet", "packet_size")];

/// The state a worker keeps between requests for the same configuration.
struct Session {
    request: WorkerRequest,
    setup: Setup,
    file: Option<SphereFile>,
    rays: Option<RaySet>,
}

impl Session {
    fn start(request: &WorkerRequest) -> Result<Session, Error> {
        let s = &request.settings;
        let setup = Setup::start(s)?;
        let file = match &request.sphere_file {
            Some(path) => Some(SphereFile::read("worker request", path)?),
            None => None,
        };
        let scene = file.as_ref().map(|f| &*f.scene);
        let rays = match s.workload {
            schema::Workload::Rays(k) => Some(super::validate::generate(k, &measure::make_scene(s, scene), s.seed)),
            schema::Workload::Render => None,
        };
        Ok(Session { request: request.clone(), setup, file, rays })
    }

    fn time(&self) -> Result<Timing, Error> {
        let scene = self.file.as_ref().map(|f| &*f.scene);
        measure::timed(&self.request.settings, scene, self.rays.as_ref(), &self.setup, self.request.sample_s)
    }
}

/// The worker side: answers every request line of `input` with a timing line on `output`, until end of input.
pub fn serve(input: impl BufRead, mut output: impl Write) -> Result<(), Error> {
    let mut session: Option<Session> = None;
    for line in input.lines() {
        let line = line.map_err(|e| Error::Input(format!("stdin: {e}")))?;
        if line.trim().is_empty() {
            continue;
        }
        let request: WorkerRequest =
            serde_json::from_str(&line).map_err(|e| Error::Input(format!("stdin: not a worker request: {e}")))?;
        if session.as_ref().is_none_or(|s| s.request != request) {
            drop(session.take()); // the old configuration's pool and device go before the new ones start
            session = Some(Session::start(&request)?);
        }
        let timing = session.as_ref().expect("started above").time()?;
        let json = serde_json::to_string(&timing).expect("timings serialize");
        writeln!(output, "{json}").and_then(|()| output.flush()).map_err(|e| Error::Run(format!("stdout: {e}")))?;
    }
    Ok(())
}

/// A worker process kept for one configuration: its warm-ups and repetitions are all timed in it.
pub struct Worker {
    binary: PathBuf,
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
}

impl Worker {
    /// Starts `binary`'s `worker` command (in `dir`, when given).
    pub fn start(binary: &Path, dir: Option<&Path>) -> Result<Worker, Error> {
        let mut cmd = Command::new(binary);
        cmd.arg("worker").stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped());
        if let Some(dir) = dir {
            cmd.current_dir(dir);
        }
        let mut child =
            cmd.spawn().map_err(|e| Error::Run(format!("{}: cannot start a worker process: {e}", binary.display())))?;
        let stdin = child.stdin.take();
        let stdout = BufReader::new(child.stdout.take().expect("piped"));
        Ok(Worker { binary: binary.to_path_buf(), child, stdin, stdout })
    }

    /// Times `request` once more in this worker.
    pub fn time(&mut self, request: &WorkerRequest) -> Result<Timing, Error> {
        self.send(request);
        self.receive()
    }

    fn send(&mut self, request: &WorkerRequest) {
        let json = request_line(request);
        if let Some(stdin) = self.stdin.as_mut()
            && writeln!(stdin, "{json}").and_then(|()| stdin.flush()).is_err()
        {
            self.stdin = None; // the worker is gone: `receive` says why
        }
    }

    fn receive(&mut self) -> Result<Timing, Error> {
        let mut answer = String::new();
        if self.stdout.read_line(&mut answer).is_ok()
            && let Ok(t) = serde_json::from_str::<Timing>(answer.trim())
        {
            return Ok(t);
        }
        Err(self.failure())
    }

    /// Why the worker stopped answering: the last line it wrote on stderr.
    fn failure(&mut self) -> Error {
        self.stdin = None;
        let _ = self.child.wait();
        let mut stderr = String::new();
        if let Some(mut e) = self.child.stderr.take() {
            let _ = e.read_to_string(&mut stderr);
        }
        Error::Run(format!(
            "{} worker failed (a base revision needs the JSON `harness worker`): {}",
            self.binary.display(),
            stderr.trim().lines().last().unwrap_or("no output")
        ))
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.stdin = None; // end of input: the worker exits
        let _ = self.child.wait();
    }
}

/// Times `request` once in a fresh worker process of `binary` (run in `dir`, when given). Its input ends after
/// the one request, as workers of base revisions before the JSON-lines protocol expect.
pub fn time(binary: &Path, dir: Option<&Path>, request: &WorkerRequest) -> Result<Timing, Error> {
    let mut worker = Worker::start(binary, dir)?;
    worker.send(request);
    worker.stdin = None;
    worker.receive()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_carry_the_packet_size_earlier_revisions_declared() {
        let mut s = Settings::default().normalized();
        let line = |s: &Settings| {
            let json: serde_json::Value = serde_json::from_str(&request_line(&WorkerRequest {
                settings: s.clone(),
                sphere_file: None,
                sample_s: 0.0,
            }))
            .unwrap();
            assert_eq!(
                serde_json::from_value::<WorkerRequest>(json.clone()).unwrap().settings,
                *s,
                "today's worker reads it as it is"
            );
            json["settings"]["packet_size"].as_str().unwrap().to_string()
        };
        assert_eq!(line(&s), "0", "no packets on the flat BVH");
        s.accel = schema::Accel::Ours(tracer::accel::AccelKind::WideBvh);
        s.workload = schema::Workload::Rays(tracer::rays::RayKind::Primary);
        for (packet, rays) in [("single", "1"), ("masked-8", "8"), ("masked-16", "16"), ("tile-8x8", "64")] {
            s.packet = Some(<schema::Packet as schema::Named>::from_name(packet).unwrap());
            assert_eq!(line(&s.clone().normalized()), rays, "{packet}");
        }
    }

    #[test]
    fn requests_round_trip_through_json() {
        let request = WorkerRequest {
            settings: Settings::default().normalized(),
            sphere_file: Some("spheres.csv".into()),
            sample_s: 0.0,
        };
        let json = serde_json::to_string(&request).unwrap();
        assert!(json.contains("\"accel\":\"flat-bvh\""), "settings are spelled as in rows: {json}");
        assert_eq!(serde_json::from_str::<WorkerRequest>(&json).unwrap(), request);
    }

    /// The JSON lines a worker answers to `requests`.
    fn answers(requests: &[&WorkerRequest]) -> Vec<Timing> {
        let input: String = requests.iter().map(|r| serde_json::to_string(r).unwrap() + "\n").collect();
        let mut out = Vec::new();
        serve(input.as_bytes(), &mut out).unwrap();
        String::from_utf8(out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect()
    }

    #[test]
    fn a_worker_sets_up_once_per_configuration_and_answers_every_request() {
        let settings = |objects| {
            let s = Settings {
                objects,
                width: 16,
                height: 12,
                workload: schema::Workload::Rays(tracer::rays::RayKind::Primary),
                ..Settings::default()
            };
            WorkerRequest { settings: s.normalized(), sphere_file: None, sample_s: 0.0 }
        };
        let (a, b) = (settings(50), settings(60));
        let t = answers(&[&a, &a, &a, &b]);
        assert_eq!(t.len(), 4);
        assert!(t[0].setup_s > 0.0);
        assert!(t[..3].iter().all(|x| x.setup_s == t[0].setup_s && x.output_hash == t[0].output_hash), "{t:?}");
        assert_ne!(t[3].output_hash, t[0].output_hash, "another configuration, another scene");
        assert_ne!(t[3].setup_s, t[0].setup_s, "another configuration starts its own setup");
    }
}
