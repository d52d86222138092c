//! `harness render`: one image, its timings, tree statistics and (optionally) work counters.

use std::io::BufWriter;
use std::time::Instant;

use tracer::accel::wide::Kernel;
use tracer::accel::{AccelParams, AccelVisitor, Accelerator, BuiltAccel, BvhParams, WideParams};
use tracer::counters::{Counters, NoCounters, WorkCounters};
use tracer::executor::Strategy;
use tracer::render::{Image, RenderSettings, render};
use tracer::scene::{Scene, sphere_file};

use crate::cli::RenderArgs;
use crate::error::Error;
use schema::SceneName;

/// Logical cores available to this process.
pub fn available_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Makes the scene the arguments describe.
fn scene(args: &RenderArgs) -> Result<Scene, Error> {
    let scene = match args.scene {
        SceneName::Generated(kind) => kind.generate(args.objects, args.seed),
        SceneName::SphereFile => {
            let path =
                args.file.as_ref().ok_or_else(|| Error::Input("--scene sphere-file needs --file PATH".into()))?;
            let text = std::fs::read_to_string(path)
                .map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
            sphere_file::parse(&text).map_err(|e| Error::Input(format!("{}: {e}", path.display())))?
        }
    };
    Ok(Scene { camera: scene.camera.with_resolution(args.width, args.height), ..scene })
}

struct Render<'a, C> {
    scene: &'a Scene,
    settings: RenderSettings,
    strategy: Strategy,
    _counters: std::marker::PhantomData<C>,
}

impl<C: Counters> AccelVisitor for Render<'_, C> {
    type Output = (Image, C);
    fn visit<A: Accelerator>(self, accel: &A) -> (Image, C) {
        render(self.scene, accel, &self.settings, &self.strategy)
    }
}

/// Runs the command.
pub fn run(args: &RenderArgs) -> Result<(), Error> {
    if !args.simd_kernel.is_available() {
        let allowed: Vec<&str> = std::iter::once(Kernel::Auto).chain(Kernel::available()).map(Kernel::name).collect();
        let kernel = args.simd_kernel.name();
        return Err(Error::Input(format!(
            "--simd-kernel {kernel}: not available on this CPU (allowed here: {})",
            allowed.join(", ")
        )));
    }
    let t0 = Instant::now();
    let scene = scene(args)?;
    let scene_s = t0.elapsed().as_secs_f64();
    let params = AccelParams {
        kind: args.accel,
        bvh: BvhParams {
            leaf_size: args.leaf_size,
            split: args.split,
            sah_bins: args.sah_bins,
            traversal: args.traversal,
            ..BvhParams::default()
        },
        wide: WideParams {
            width: args.node_width,
            leaf_block: args.leaf_block,
            kernel: args.simd_kernel,
            order: args.child_order,
            ..WideParams::default()
        },
    };
    let threads = args.threads.map_or_else(available_threads, |t| t as usize);
    let strategy = Strategy::new(args.strategy, threads);
    let settings = RenderSettings { max_depth: args.max_depth };

    let t1 = Instant::now();
    let accel = BuiltAccel::build(&scene.spheres, &params);
    let build_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let (image, _) =
        accel.visit(Render::<NoCounters> { scene: &scene, settings, strategy, _counters: Default::default() });
    let render_s = t2.elapsed().as_secs_f64();

    let t3 = Instant::now();
    let file = std::fs::File::create(&args.out)
        .map_err(|e| Error::Input(format!("{}: cannot create: {e}", args.out.display())))?;
    image
        .write_png(BufWriter::new(file))
        .map_err(|e| Error::Run(format!("{}: PNG encoding failed: {e}", args.out.display())))?;
    let encode_s = t3.elapsed().as_secs_f64();

    let stats = accel.stats();
    say!("scene        {} spheres, fingerprint {:016x}", scene.spheres.len(), scene.fingerprint());
    match accel.kernel_name() {
        Some(kernel) => say!("accel        {} {:?} {:?} (kernel {kernel})", args.accel.name(), params.bvh, params.wide),
        None => say!("accel        {} {:?}", args.accel.name(), params.bvh),
    }
    say!("strategy     {strategy}");
    say!(
        "tree         {} nodes, {} leaves, depth {}, {} bytes, SAH cost {:.2}",
        stats.nodes,
        stats.leaves,
        stats.depth,
        stats.bytes,
        stats.sah_cost
    );
    say!(
        "time         scene {:.4} s, build {:.4} s, render {:.4} s, encode {:.4} s",
        scene_s,
        build_s,
        render_s,
        encode_s
    );
    if args.count {
        let (_, c) =
            accel.visit(Render::<WorkCounters> { scene: &scene, settings, strategy, _counters: Default::default() });
        let (nodes, boxes, prims) = c.per_ray();
        say!("rays         {} ({:.2} Mrays/s)", c.rays, c.rays as f64 / render_s / 1e6);
        say!("per ray      {nodes:.2} nodes, {boxes:.2} box tests, {prims:.2} sphere tests");
    }
    say!("image        {}×{} hash {:016x} -> {}", image.width, image.height, image.hash(), args.out.display());
    Ok(())
}
