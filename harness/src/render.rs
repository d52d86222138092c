//! `harness render`: one image of one configuration — any backend, every setting from the schema (`--set
//! KEY=VALUE`, the keys, defaults and allowed values of a config's `[sweep]`) — with its timings, structure
//! statistics and (optionally) work counters. It builds and renders through the same setup and backend path as a
//! timed run. Sphere scenes are Whitted-shaded; triangle scenes flat-shaded (grey, one light with hard shadows,
//! [`tracer::render::render_mesh`]).

use std::io::BufWriter;
use std::time::Instant;

use schema::columns::Replaced;
use schema::{Axis, Named, Raw, SceneName, Settings, Workload};
use tracer::scene::{Scene, sphere_file};

use tracer::job::Output;

use crate::backend::workload::bvhlab_phase_trace;
use crate::backend::{self, Setup};
use crate::cli::RenderArgs;
use crate::error::Error;
use crate::run::scenes::{SceneData, make_scene};

/// A `--set` value as a config value: an integer, else a number, else text.
fn raw(text: &str) -> Raw<'_> {
    match (text.parse::<i64>(), text.parse::<f64>()) {
        (Ok(i), _) => Raw::Int(i),
        (_, Ok(x)) => Raw::Float(x),
        _ => Raw::Str(text),
    }
}

/// The settings of `--set KEY=VALUE` pairs over the schema's defaults, for the render workload, normalized.
pub fn settings_of(pairs: &[String]) -> Result<Settings, Error> {
    let mut settings = Settings::default();
    for pair in pairs {
        let keys = || Axis::ALL.iter().map(|a| a.key()).collect::<Vec<_>>().join(", ");
        let Some((key, value)) = pair.split_once('=') else {
            return Err(Error::Input(format!("--set {pair}: expected KEY=VALUE (allowed keys: {})", keys())));
        };
        if let Some(replaced) = Replaced::of(key.trim()) {
            return Err(Error::Input(format!("--set {key}: {}", replaced.instead())));
        }
        let axis = Axis::from_key(key.trim())
            .ok_or_else(|| Error::Input(format!("--set {key}: unknown key (allowed: {})", keys())))?;
        if axis == Axis::workload {
            return Err(Error::Input(format!("--set {key}: render draws an image (allowed: the other keys)")));
        }
        let value = axis.parse(raw(value.trim())).map_err(|why| Error::Input(format!("--set {key}: {why}")))?;
        settings.set(value);
    }
    settings.workload = Workload::Render;
    Ok(settings.normalized())
}

/// The scene file of a `sphere-file` scene (`--file`), read and parsed.
fn scene_file(settings: &Settings, args: &RenderArgs) -> Result<Option<Scene>, Error> {
    if settings.scene != SceneName::SphereFile {
        return Ok(None);
    }
    let path = args.file.as_ref().ok_or_else(|| Error::Input("--set scene=sphere-file needs --file PATH".into()))?;
    let text =
        std::fs::read_to_string(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    sphere_file::parse(&text).map(Some).map_err(|e| Error::Input(format!("{}: {e}", path.display())))
}

/// Loads a mesh scene's mesh (once per process, as planning does), so that a missing or bad one is one line.
fn load_mesh(settings: &Settings) -> Result<(), Error> {
    match (settings.scene, &settings.mesh) {
        (SceneName::Mesh, None) => {
            Err(Error::Input("--set scene=mesh needs --set mesh=NAME (a data set name or an .obj/.ply path)".into()))
        }
        (SceneName::Mesh, Some(m)) => crate::meshes::load_source(&m.0).map(|_| ()).map_err(|e| match e {
            Error::Input(why) => Error::Input(format!("--set mesh: {why}")),
            other => other,
        }),
        _ => Ok(()),
    }
}

/// The settings that apply to this configuration, as `key=value` (no `max_depth` for triangle scenes: their flat
/// shading has no reflections).
fn describe(settings: &Settings) -> String {
    let shown = |a: Axis| a != Axis::workload && !(a == Axis::max_depth && settings.scene.is_triangles());
    let applies = Axis::ALL.iter().filter(|&&a| settings.applies(a) && shown(a));
    applies.map(|&a| format!("{}={}", a.key(), settings.get(a))).collect::<Vec<_>>().join(" ")
}

/// Runs the command.
pub fn run(args: &RenderArgs) -> Result<(), Error> {
    let settings = settings_of(&args.set)?;
    let backend = backend::of(settings.accel);
    let refused = |e: backend::Unavailable| Error::Input(format!("--set accel={}: {e}", settings.accel.name()));
    backend::accel_support(&settings).map_err(refused)?;
    backend.available(&settings).map_err(refused)?;
    let file = scene_file(&settings, args)?;
    load_mesh(&settings)?;
    let setup = Setup::start(&settings)?;
    let t0 = Instant::now();
    let scene = make_scene(&settings, file.as_ref());
    // A triangle scene's triangles for their normals: every backend's hits name triangles by their mesh index.
    let triangles = scene.triangles();
    let scene_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let built = setup.build(backend, &settings, &scene.geometry())?;
    let build_s = t1.elapsed().as_secs_f64();
    let (job, strategy) = (scene.render(&settings, &triangles), settings.strategy());
    let t2 = Instant::now();
    let output = setup.install(|| bvhlab_phase_trace(|| built.structure.run(&job, &strategy)));
    let render_s = t2.elapsed().as_secs_f64();
    let Output::Image(image) = output else { unreachable!("the render workload draws an image") };

    let t3 = Instant::now();
    let out = std::fs::File::create(&args.out)
        .map_err(|e| Error::Input(format!("{}: cannot create: {e}", args.out.display())))?;
    image
        .write_png(BufWriter::new(out))
        .map_err(|e| Error::Run(format!("{}: PNG encoding failed: {e}", args.out.display())))?;
    let encode_s = t3.elapsed().as_secs_f64();

    let stats = built.structure.stats();
    let (count, what) = match &scene {
        SceneData::Spheres(s) => (s.spheres.len(), "spheres".to_string()),
        SceneData::Triangles(t) => {
            (t.mesh.triangle_count(), format!("triangles ({} degenerate)", crate::meshes::degenerate(&t.mesh)))
        }
    };
    say!("scene        {count} {what}, fingerprint {:016x}", scene.fingerprint());
    say!("settings     {}", describe(&settings));
    say!("backend      {}: kernel {}, {}", backend.name(), built.simd_kernel, built.peer_info);
    say!("strategy     {}", settings.strategy());
    say!(
        "structure    {} nodes, {} leaves, depth {}, {} bytes, SAH cost {:.2}",
        stats.nodes,
        stats.leaves,
        stats.depth,
        stats.bytes,
        stats.sah_cost
    );
    say!("time         scene {scene_s:.4} s, build {build_s:.4} s, render {render_s:.4} s, encode {encode_s:.4} s");
    if args.count {
        let (_, c) = setup.install(|| bvhlab_phase_trace(|| built.structure.run_counted(&job, &strategy)));
        let (nodes, boxes, prims) = c.per_ray();
        let prim = if triangles.is_empty() { "sphere" } else { "triangle" };
        say!("rays         {} ({:.2} Mrays/s)", c.rays, c.rays as f64 / render_s / 1e6);
        say!("per ray      {nodes:.2} nodes, {boxes:.2} box tests, {prims:.2} {prim} tests (peers count none)");
    }
    say!("image        {}×{} hash {:016x} -> {}", image.width, image.height, image.hash(), args.out.display());
    Ok(())
}
