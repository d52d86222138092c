//! Timing configurations in other processes (Embree: TBB's thread limit is process-wide; `ab`: another build).
//!
//! The protocol is JSON lines: each request line on the worker's stdin is answered by one [`Timing`] line on
//! its stdout. A worker serves one configuration at a time like the harness itself does: the first request
//! starts the backend ([`Setup`], reported as `setup_s`) and makes the ray set, and every request after it
//! with the same settings is one more warm run in the same process (the sweep keeps one worker per
//! configuration for its warm-ups and all its repetitions). A request may also be one step of a run whose passes
//! take turns with other configurations' ([`Step`]): prepare (answered `null`), a pass (answered with its
//! seconds), finish (answered with the [`Timing`]). A worker that fails prints why on stderr and exits.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use schema::Settings;
use serde::{Deserialize, Serialize};
use tracer::rays::RaySet;

use super::scenes::make_scene;
use super::trial::{self, Timing};
use crate::backend::Setup;
use crate::error::Error;
use crate::plan::{Configuration, Plan, SphereFile};

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
    /// The workload's ray set as the harness wrote it ([`RaySet::to_bytes`]; absent: the worker makes it, as
    /// earlier revisions' workers do), so that a worker started for a few runs does not make it again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rays_file: Option<PathBuf>,
    /// Which part of a timed run this request asks for (absent: all of it).
    #[serde(default, skip_serializing_if = "Step::is_whole")]
    pub step: Step,
}

/// A part of a timed run, for runs whose passes take turns with other configurations' ([`trial::sample`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Step {
    /// The whole run: prepare, one sample, finish (what earlier revisions' workers do with every request).
    #[default]
    Whole,
    /// Make the scene and build the structure.
    Prepare,
    /// One pass of the trace.
    Pass,
    /// The timing from the passes the sample kept.
    Finish { passes: Vec<f64>, steal_s: Option<f64>, sample_configs: u32 },
}

impl Step {
    fn is_whole(&self) -> bool {
        *self == Step::Whole
    }
}

/// The worker request of a configuration.
pub fn worker_request(plan: &Plan, c: &Configuration) -> WorkerRequest {
    WorkerRequest {
        settings: c.settings.clone(),
        sphere_file: plan.sphere_file.as_ref().map(|f| f.path.clone()),
        sample_s: plan.sample_s,
        rays_file: None,
        step: Step::Whole,
    }
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
    /// The run under way, between its `Prepare` and its `Finish`.
    trial: Option<trial::Trial>,
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
        let rays = match (s.workload, &request.rays_file) {
            (schema::Workload::Rays(k), Some(path)) => Some(read_rays(path, k)?),
            (schema::Workload::Rays(k), None) => Some(super::rays::generate(k, &make_scene(s, scene), s.seed)),
            (schema::Workload::Render, _) => None,
        };
        Ok(Session { request: request.clone(), setup, file, rays, trial: None })
    }

    /// True when `request` asks for this session's configuration (whatever its sample length).
    fn serves(&self, request: &WorkerRequest) -> bool {
        self.request == WorkerRequest { sample_s: self.request.sample_s, ..request.clone() }
    }

    /// Answers `step` of a run with samples of `sample_s`: the JSON of what it gives.
    fn answer(&mut self, step: Step, sample_s: f64) -> Result<String, Error> {
        let cx = trial::Context {
            settings: &self.request.settings,
            file: self.file.as_ref().map(|f| &*f.scene),
            rays: self.rays.as_ref(),
            setup: &self.setup,
        };
        let out_of_order = || Error::Input("stdin: a pass or finish request before its prepare".into());
        Ok(match step {
            Step::Whole => {
                let timing = trial::timed(cx.settings, cx.file, cx.rays, cx.setup, sample_s)?;
                serde_json::to_string(&timing).expect("timings serialize")
            }
            Step::Prepare => {
                self.trial = Some(trial::Trial::prepare(&cx)?);
                "null".into()
            }
            Step::Pass => self.trial.as_mut().ok_or_else(out_of_order)?.pass(&cx).to_string(),
            Step::Finish { passes, steal_s, sample_configs } => {
                let trial = self.trial.take().ok_or_else(out_of_order)?;
                serde_json::to_string(&trial.finish(&cx, &passes, steal_s, sample_configs)).expect("timings serialize")
            }
        })
    }
}

/// The ray set of kind `kind` in the file `path` names.
fn read_rays(path: &Path, kind: tracer::rays::RayKind) -> Result<RaySet, Error> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::Run(format!("{}: cannot read the ray set: {e}", path.display())))?;
    RaySet::from_bytes(&bytes).filter(|set| set.kind == kind).ok_or_else(|| {
        Error::Run(format!(
            "{}: not a ray set of kind {} (`rays_file` of the worker request)",
            path.display(),
            kind.name()
        ))
    })
}

/// The worker side: answers every request line of `input` with a timing line on `output`, until end of input.
pub fn serve(input: impl BufRead, mut output: impl Write) -> Result<(), Error> {
    let mut session: Option<Session> = None;
    for line in input.lines() {
        let line = line.map_err(|e| Error::Input(format!("stdin: {e}")))?;
        if line.trim().is_empty() {
            continue;
        }
        let mut request: WorkerRequest =
            serde_json::from_str(&line).map_err(|e| Error::Input(format!("stdin: not a worker request: {e}")))?;
        let step = std::mem::take(&mut request.step);
        if session.as_ref().is_none_or(|s| !s.serves(&request)) {
            drop(session.take()); // the old configuration's pool and device go before the new ones start
            session = Some(Session::start(&request)?);
        }
        let json = session.as_mut().expect("started above").answer(step, request.sample_s)?;
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

    /// Sends `request` without waiting for its timing ([`Worker::end`] takes it), so that several workers work at
    /// once.
    pub fn begin(&mut self, request: &WorkerRequest) {
        self.send(request);
    }

    /// The timing of the request [`Worker::begin`] sent.
    pub fn end(&mut self) -> Result<Timing, Error> {
        self.receive()
    }

    /// Asks for `step` of a run of `request` (a run whose passes take turns with others'): its answer.
    pub fn step<T: serde::de::DeserializeOwned>(&mut self, request: &WorkerRequest, step: Step) -> Result<T, Error> {
        self.send(&WorkerRequest { step, ..request.clone() });
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

    fn receive<T: serde::de::DeserializeOwned>(&mut self) -> Result<T, Error> {
        let mut answer = String::new();
        if self.stdout.read_line(&mut answer).is_ok()
            && let Ok(t) = serde_json::from_str::<T>(answer.trim())
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
                rays_file: None,
                step: Step::Whole,
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
            rays_file: Some("rays.bin".into()),
            step: Step::Whole,
        };
        let json = serde_json::to_string(&request).unwrap();
        assert!(json.contains("\"accel\":\"flat-bvh\""), "settings are spelled as in rows: {json}");
        assert_eq!(serde_json::from_str::<WorkerRequest>(&json).unwrap(), request);
    }

    /// Settings of a small sphere scene traced with ray set `kind`.
    fn small(kind: tracer::rays::RayKind) -> Settings {
        let s = Settings {
            objects: 50,
            width: 16,
            height: 12,
            workload: schema::Workload::Rays(kind),
            ..Settings::default()
        };
        s.normalized()
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
            WorkerRequest {
                settings: s.normalized(),
                sphere_file: None,
                sample_s: 0.0,
                rays_file: None,
                step: Step::Whole,
            }
        };
        let (a, b) = (settings(50), settings(60));
        let warm = WorkerRequest { sample_s: 0.0005, ..a.clone() };
        let t = answers(&[&a, &warm, &a, &b]);
        assert_eq!(t.len(), 4);
        assert!(t[0].setup_s > 0.0);
        assert!(
            t[..3].iter().all(|x| x.setup_s == t[0].setup_s && x.output_hash == t[0].output_hash),
            "one session, whatever the sample's length: {t:?}"
        );
        assert_ne!(t[3].output_hash, t[0].output_hash, "another configuration, another scene");
        assert_ne!(t[3].setup_s, t[0].setup_s, "another configuration starts its own setup");
    }

    #[test]
    fn a_worker_given_the_ray_set_answers_as_one_that_makes_it() {
        let s = small(tracer::rays::RayKind::Diffuse);
        let dir = std::env::temp_dir().join(format!("bvhlab-worker-rays-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (rays, wrong) = (dir.join("diffuse.bin"), dir.join("primary.bin"));
        let made = |kind| super::super::rays::generate(kind, &make_scene(&s, None), s.seed).to_bytes();
        std::fs::write(&rays, made(tracer::rays::RayKind::Diffuse)).unwrap();
        std::fs::write(&wrong, made(tracer::rays::RayKind::Primary)).unwrap();
        let own =
            WorkerRequest { settings: s.clone(), sphere_file: None, sample_s: 0.0, rays_file: None, step: Step::Whole };
        let given = WorkerRequest { rays_file: Some(rays), ..own.clone() };
        let t = answers(&[&own, &given]);
        assert_eq!(t[0].output_hash, t[1].output_hash, "the same rays, the same answers");
        for bad in [wrong, dir.join("missing.bin")] {
            let line = serde_json::to_string(&WorkerRequest { rays_file: Some(bad), ..own.clone() }).unwrap() + "\n";
            assert!(serve(line.as_bytes(), &mut Vec::new()).is_err(), "another kind's rays, or none, are refused");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_run_taken_in_steps_answers_as_a_whole_run_does() {
        let s = small(tracer::rays::RayKind::Primary);
        let whole = WorkerRequest { settings: s, sphere_file: None, sample_s: 0.0, rays_file: None, step: Step::Whole };
        let step = |step| serde_json::to_string(&WorkerRequest { step, ..whole.clone() }).unwrap() + "\n";
        let finish = Step::Finish { passes: vec![0.003, 0.001, 0.002], steal_s: Some(0.0), sample_configs: 2 };
        let input = [step(Step::Whole), step(Step::Prepare), step(Step::Pass), step(Step::Pass), step(finish)].concat();
        let mut out = Vec::new();
        serve(input.as_bytes(), &mut out).unwrap();
        let lines: Vec<String> = String::from_utf8(out).unwrap().lines().map(str::to_string).collect();
        assert_eq!(lines.len(), 5, "{lines:?}");
        assert_eq!(lines[1], "null", "prepare");
        assert!(lines[2..4].iter().all(|l| l.parse::<f64>().is_ok_and(|s| s > 0.0)), "passes: {lines:?}");
        let (alone, stepped): (Timing, Timing) =
            (serde_json::from_str(&lines[0]).unwrap(), serde_json::from_str(&lines[4]).unwrap());
        assert_eq!(stepped.output_hash, alone.output_hash, "the same answers");
        assert_eq!(stepped.setup_s, alone.setup_s, "in the same session");
        assert_eq!((stepped.trace_s, stepped.trace_passes, stepped.sample_configs), (0.002, 3, 2), "the kept passes");
        assert_eq!((alone.trace_passes, alone.sample_configs), (1, 1));
        let early = [step(Step::Pass)].concat();
        assert!(serve(early.as_bytes(), &mut Vec::new()).is_err(), "a pass before its prepare is refused");
    }
}
