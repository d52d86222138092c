//! The declaration: every column of a row, identity first, then the settings (the axes of a sweep), then
//! the measures. Adding a setting is one entry here (plus the tracer code that uses it).

use tracer::accel::bvh::{SahCosts, SpatialAlpha};
use tracer::accel::wide::{AnyHitOrdering, ChildOrdering, Kernel};
use tracer::accel::{AccelKind, AccelParams, BvhParams, Split, Traversal, WideParams};
use tracer::executor::{Strategy, StrategyKind};
use tracer::geometry::TriangleTest;
use tracer::scene::{SceneKind, View};

use crate::names::{
    Accel, EmbreeIsa, EmbreePacket, EmbreeQuality, LeafBlock, MeshSource, NodeWidth, ObvhsQuality, Packet, PeerKind,
    SahBlock, SceneName, Threads, TinyBvhLayout, TinyBvhQuality, TreeBuilder, ValidationStatus, Workload, WrongSide,
};
use crate::row::Cell;

declare_columns! {
    identity {
        /// Experiment name from the config.
        experiment: String;
        /// 16 hex digits, stable hash of the series and the settings; equal for all repetitions of one configuration.
        config_id: String;
        /// Series label.
        series: String;
        /// 0-based repetition index within the configuration.
        repetition: u32;
    }
    settings {
        /// Scene generator, or `sphere-file` (then objects and seed come from the file); triangle scenes:
        /// `tessellated-spheres` (the random-spheres scene, each sphere a UV sphere of 16 slices and 8 rings),
        /// `random-triangles`, or `mesh` (the data set or file named by `mesh`).
        scene: SceneName = SceneName::Generated(SceneKind::RandomSpheres);
        /// Number of spheres (tessellated for `tessellated-spheres`; triangles for `random-triangles`).
        objects: u64 = 1000, range(0, 10_000_000), applies not_mesh_scene else 0, unit "spheres";
        /// Scene seed (0 for sphere files).
        seed: u64 = 1, range(0, i64::MAX), applies generated_scene else 0;
        /// Acceleration structure: the tracer's or a peer's.
        accel: Accel = Accel::Ours(AccelKind::FlatBvh);
        /// Split rule of the tracer's trees.
        split: Option<Split> = Some(BvhParams::default().split), applies tree else None;
        /// Largest leaf of the tracer's trees.
        leaf_size: Option<u32> = Some(BvhParams::default().leaf_size),
            range(*BvhParams::LEAF_SIZES.start(), *BvhParams::LEAF_SIZES.end()), applies tree else None, unit "spheres";
        /// Bins per axis of the binned SAH split (and of spatial-sah's object and spatial binning).
        sah_bins: Option<u32> = Some(BvhParams::default().sah_bins),
            range(*BvhParams::SAH_BINS.start(), *BvhParams::SAH_BINS.end()), applies binned_sah else None;
        /// Child visiting order of the tracer's binary trees (the wide BVH has `child_order`).
        traversal: Option<Traversal> = Some(BvhParams::default().traversal), applies binary_tree else None;
        /// Parallel strategy.
        strategy: StrategyKind = StrategyKind::Serial;
        /// Worker threads as configured: a count, or `all` (the machine's logical cores, resolved into `threads_used`,
        /// so the configuration id is the same on every machine); 1 for serial.
        threads: Threads = Threads::All, range(1, 4096), applies parallel else Threads::Count(1);
        /// Image width.
        width: u32 = 320, range(1, 16384), unit "px";
        /// Image height.
        height: u32 = 240, range(1, 16384), unit "px";
        /// Reflection bounces of the render workload.
        max_depth: u32 = 3, range(0, 64), applies render else 0;
        /// `render` (full shading and PNG encoding) or a fixed ray set: `primary`, `shadow`, `diffuse`.
        workload: Workload = Workload::Render;
        /// obvhs build preset.
        obvhs_build: Option<ObvhsQuality> = Some(ObvhsQuality::Medium), applies obvhs else None;
        /// Embree build quality.
        embree_build: Option<EmbreeQuality> = Some(EmbreeQuality::Medium), applies embree else None;
        /// Instruction set Embree is pinned to (`default`: Embree's choice).
        embree_isa: Option<EmbreeIsa> = Some(EmbreeIsa::Default), applies embree else None;
        /// SAH cost of visiting a node, relative to a sphere test's cost, that the SAH splits build with.
        sah_traversal_cost: Option<f32> = Some(SahCosts::UNIT.traversal),
            range(*BvhParams::SAH_COSTS.start(), *BvhParams::SAH_COSTS.end()), applies sah_split else None, added 2;
        /// SAH cost of a sphere test that the SAH splits build with.
        sah_intersection_cost: Option<f32> = Some(SahCosts::UNIT.intersection),
            range(*BvhParams::SAH_COSTS.start(), *BvhParams::SAH_COSTS.end()), applies sah_split else None, added 2;
        /// Children per node of the wide BVH (4 or 8).
        node_width: Option<NodeWidth> = Some(NodeWidth(WideParams::default().width)), applies wide else None, added 2;
        /// Spheres per SIMD leaf block of the wide BVH (4, 8 or 16).
        leaf_block: Option<LeafBlock> = Some(LeafBlock(WideParams::default().leaf_block)), applies wide else None,
            added 2, unit "spheres";
        /// Primitives the binary build's SAH counts a leaf in blocks of, a node of at most that many always a leaf
        /// (capped at `leaf_block`: the default, 16, is the leaf block). The collapse still makes every subtree of at
        /// most `leaf_block` primitives one leaf, so a smaller block changes which primitives share a leaf: Embree's
        /// triangle builders count blocks of 4 under 8-wide nodes.
        sah_block: Option<SahBlock> = Some(SahBlock(WideParams::default().sah_block)), applies wide_own_tree else None,
            added 17, unit "spheres";
        /// SIMD kernel of the wide BVH's traversal (`auto`: the best this CPU has; the one that ran is in
        /// `simd_kernel_used`).
        simd_kernel: Option<Kernel> = Some(WideParams::default().kernel), applies wide else None, added 2;
        /// Order in which the wide BVH visits a node's children: stored, nearest entry first, or by ray octant.
        child_order: Option<ChildOrdering> = Some(WideParams::default().order), applies wide else None, added 2;
        /// Order in which the wide BVH's any-hit (occlusion) rays visit a node's children: `child-order` (as
        /// `child_order`) or `none` (stored order: no entry distances sorted for a ray that stops at its first hit).
        any_hit_order: Option<AnyHitOrdering> = Some(WideParams::default().any_hit_order), applies wide else None,
            added 10;
        /// How the wide BVH traces a ray set's rays (renders trace one at a time): `single` (one at a time),
        /// `masked-8` or `masked-16` (packets of 8 or 16 rays with an active mask), or `tile-8x8` (frustum-culled
        /// packets of an 8×8 tile of camera rays). Rows before this column had it in `packet_size` (1, 8, 16, 64).
        packet: Option<Packet> = Packet::of_rays(WideParams::default().packet), applies wide_ray_set else None,
            added 6, id packet_size_cell;
        /// Rays of `embree-packets`' queries on a ray set: 8 (`rtcIntersect8`) or 16 (`rtcIntersect16`). Rows
        /// before this column had it in `packet_size`.
        embree_packet: Option<EmbreePacket> = Some(EmbreePacket(16)), applies embree_packet_ray_set else None,
            added 6, unit "rays";
        /// The triangle mesh of `scene = "mesh"`: a data set name (`harness fetch NAME`) or an `.obj` or `.ply` file
        /// or folder of `.ply` files; `MODEL*N` is N copies of one tiled into a bigger city (docs/meshes.md).
        mesh: Option<MeshSource> = None, applies mesh_scene else None, added 7;
        /// Ray–triangle test of the tracer's structures on triangle scenes (peers run their own).
        triangle_test: Option<TriangleTest> = Some(TriangleTest::Watertight), applies ours_on_triangles else None,
            added 7;
        /// Camera of triangle scenes, computed from the mesh: `overview` (from outside, the whole model in frame) or
        /// `street` (for cities: at eye height on open ground, looking level along the longest line of sight; a
        /// model without open ground is seen from outside at its floor's height).
        view: Option<View> = Some(View::Overview), applies triangle_scene else None, added 7;
        /// tinybvh's layout: `bvh` (binary), `bvh4-cpu` or `bvh8-cpu` (wide).
        tinybvh_layout: Option<TinyBvhLayout> = Some(TinyBvhLayout::Bvh), applies tinybvh else None, added 7;
        /// tinybvh's builder: `default` (binned SAH) or `high` (spatial splits).
        tinybvh_build: Option<TinyBvhQuality> = Some(TinyBvhQuality::Default), applies tinybvh else None, added 7;
        /// Overlap threshold of `spatial-sah`: a node tries spatial splits where its best object split's children
        /// overlap by more than this fraction of the root's surface area (0: wherever they overlap, 1: never).
        spatial_alpha: Option<f32> = Some(BvhParams::default().spatial_alpha.0),
            range(*BvhParams::SPATIAL_ALPHAS.start(), *BvhParams::SPATIAL_ALPHAS.end()), applies spatial_sah else None,
            added 9;
        /// Most rounds of reinsertion run on the tracer's binary tree after it is built (0: off): each round moves
        /// every subtree, largest first, to where the tree's SAH cost is least; rounds stop early when one lowers the
        /// cost by less than 0.1%. The wide BVH collapses the optimized tree.
        reinsertion: u32 = BvhParams::default().reinsertion,
            range(*BvhParams::REINSERTION_ROUNDS.start(), *BvhParams::REINSERTION_ROUNDS.end()), applies tree else 0,
            added 9;
        /// Who builds the binary tree the wide BVH collapses, on triangle scenes: `ours` (by `split` and the
        /// settings above) or a peer's builder, its tree then collapsed and traced by ours: `tinybvh` (its `Build`,
        /// binned SAH), `tinybvh-high` (its `BuildHQ`, spatial splits), `embree` or `embree-high` (Embree's
        /// `rtcBuildBVH`, binned SAH or spatial splits, with its internal triangle builder's block of 4 and leaves of
        /// 4 to 28); `split`, `leaf_size`, `sah_bins` and `spatial_alpha` then do not shape the tree. `build_s` is the
        /// peer's build plus our collapse.
        tree_builder: Option<TreeBuilder> = Some(TreeBuilder::Ours), applies wide_on_triangles else None, added 16;
    }
    measures {
        /// Wall time of the backend's one-time start-up in the process that times the configuration: thread pool,
        /// and for Embree finding and loading the library and `rtcNewDevice`; in no other phase and not in `total_s`.
        setup_s: Option<f64>, Metric, unit "s", decimals 9, added 2;
        /// Wall time of scene generation; empty where validation failed (never timed).
        scene_s: Option<f64>, Metric, unit "s", decimals 9;
        /// Wall time of building the structure; empty where validation failed (never timed).
        build_s: Option<f64>, Metric, unit "s", decimals 9;
        /// Wall time of tracing (rendering without encoding, or the ray set); empty where validation failed (never timed).
        trace_s: Option<f64>, Metric, unit "s", decimals 9;
        /// The harness's own cost of the trace: wall time of the `null` backend (every ray misses, nothing read)
        /// tracing the same rays under the same strategy in the same process, right after the timed trace; the
        /// trace_s of every backend includes this much. Empty for renders, where validation failed, and in rows
        /// recorded before this column.
        overhead_s: Option<f64>, Metric, unit "s", decimals 9, added 5;
        /// Wall time of PNG encoding (0 for ray sets); empty where validation failed (never timed).
        encode_s: Option<f64>, Metric, unit "s", decimals 9;
        /// scene_s + build_s + trace_s + encode_s (not setup_s); empty where validation failed (never timed).
        total_s: Option<f64>, Metric, unit "s", decimals 9;
        /// Rays traced (from the counted pass).
        rays: u64, Counter, unit "rays";
        /// Rays / trace_s / 1e6; empty where validation failed.
        mrays_per_s: Option<f64>, Metric, unit "Mrays/s", decimals 6;
        /// Nodes visited per ray (counted pass).
        nodes_per_ray: f64, Counter, decimals 6;
        /// Ray-box tests per ray (counted pass).
        box_tests_per_ray: f64, Counter, decimals 6;
        /// Ray-sphere tests per ray (counted pass).
        prim_tests_per_ray: f64, Counter, decimals 6;
        /// Nodes of the built structure.
        tree_nodes: u64, Counter;
        /// Leaves of the built structure.
        tree_leaves: u64, Counter;
        /// Depth of the built structure.
        tree_depth: u64, Counter;
        /// Bytes of the built structure as traversal holds it: its nodes and its leaves' primitive data (copies or
        /// index arrays it owns), never the scene's input. Ours: the node array plus the leaf layout (flat BVH:
        /// primitive copies and scene indices; wide BVH: leaf blocks, primitive copies with their indices, padding
        /// lanes included; pointer BVH: boxed nodes and primitives; list: the primitives). Embree: what its memory
        /// monitor saw `rtcCommitScene` allocate net of what it freed (nodes, leaves with its triangle copies,
        /// allocator slack), not its copies of the input buffers, made before the commit (so sphere leaves' points,
        /// read from that copy, are not counted); rows before #62 held the input's bytes. tinybvh: plain layout,
        /// nodes, index array and its 48-byte-a-triangle soup; BVH4/BVH8_CPU, the 64-byte blocks traversal reads
        /// (nodes, leaf triangles, primitive ids), not the intermediate trees it keeps. obvhs: nodes, primitive
        /// index array and its primitive copies in tree order.
        tree_bytes: u64, Counter, unit "bytes";
        /// SAH cost of the built structure (unit traversal and intersection costs).
        sah_cost: f64, Counter, decimals 6;
        /// 16 hex digits: image hash (render) or hash of the ray set's answers.
        image_hash: String, Counter;
        /// 16 hex digits: the scene's fingerprint.
        scene_fingerprint: String, Counter;
        /// Commit of the working tree (`unknown` outside git).
        git_commit: String, Provenance;
        /// True when the tree had uncommitted changes.
        git_dirty: bool, Provenance;
        /// `rustc --version` of the compiler that built the harness.
        rustc: String, Provenance;
        /// CPU model name.
        cpu_model: String, Provenance;
        /// Logical cores of the machine.
        logical_cores: u32, Provenance;
        /// Worker threads the run used: `threads` with `all` resolved to the machine's logical cores (0: recorded
        /// before this column, when `threads` held the resolved count).
        threads_used: u32, Provenance, added 2;
        /// 1-minute load average just before the run.
        load_avg_1m: f64, Provenance, decimals 2;
        /// RFC 3339 UTC time the run started.
        timestamp: String, Provenance;
        /// Harness crate version.
        harness_version: String, Provenance;
        /// `exact` when the backend agreed with the reference, `FAILED` (and no timings) when it did not, `unchecked`
        /// for a backend that answers nothing (`null`).
        validation: ValidationStatus, Validation;
        /// The reference the backend was validated against.
        validated_against: String, Validation;
        /// Rays whose answers disagreed with the reference and that f64 brute force did not excuse as grazing.
        mismatches: u64, Validation;
        /// Rays whose answers disagreed with the reference where f64 brute force shows a grazing ray: the hit/miss
        /// decision or the distance lies within the f32 rounding bound of the test (tolerated).
        grazing: u64, Validation, added 2;
        /// Rays where the backend and the reference hit at the same distance but name different primitives, each
        /// allowed there by f64: an edge or vertex shared by two triangles (tolerated).
        ties: u64, Validation, added 8;
        /// Rays that crossed an edge or vertex shared by two or more triangles where the backend missed them all
        /// (a miss or a later hit), within each triangle's rounding bound: leaks of a test that is not watertight.
        leaks: u64, Validation, added 8;
        /// Rays of the reference's answers checked against f64 brute force before it was trusted.
        reference_checked: u64, Validation, added 2;
        /// Which answers f64 brute force showed wrong on the rays counted in `mismatches`: `-` (none), `backend`,
        /// `reference` or `both`.
        wrong_side: WrongSide, Validation, added 2;
        /// Peer library facts (`-` for the tracer's structures).
        peer_info: String, Provenance = "-".to_string();
        /// CPU vendor as the kernel reports it (`vendor_id`).
        cpu_vendor: String, Provenance, added 2;
        /// CPU family, model and stepping numbers, `family/model/stepping`.
        cpu_signature: String, Provenance, added 2;
        /// The instruction-set extensions that matter here that the CPU has (of sse4.2, avx, avx2, fma, avx512f/bw/dq/vl).
        cpu_isa: String, Provenance, added 2;
        /// Cache sizes, e.g. `L1d 32K L1i 32K L2 1024K L3 32768K`.
        cpu_caches: String, Provenance, added 2;
        /// True when the kernel reports a hypervisor (a virtual machine).
        hypervisor: bool, Provenance, added 2;
        /// Kernel release.
        kernel: String, Provenance, added 2;
        /// The target features the harness was compiled with (of the same list as `cpu_isa`).
        target_features: String, Provenance, added 2;
        /// 12 hex digits identifying the machine: a hash of every column from `cpu_model` to here, cores and rustc.
        /// Rows of different machines are never pooled into one point (empty: recorded before this column).
        machine_id: String, Provenance, added 2;
        /// The kernel's random id of the boot the run happened in (`/proc/sys/kernel/random/boot_id`, empty elsewhere):
        /// virtual machines of one kind share every fact in `machine_id`, so absolute times gate only within one boot.
        boot_id: String, Provenance, added 3;
        /// The shard this row ran in, `I/N` (`harness run --shard`; empty for an unsharded run).
        shard: String, Provenance, added 3;
        /// The Slurm job id it ran under (`SLURM_ARRAY_JOB_ID`, else `SLURM_JOB_ID`; empty outside Slurm).
        slurm_job_id: String, Provenance, added 3;
        /// The node it ran on: `SLURMD_NODENAME`, else the host name for a sharded run (empty otherwise).
        node: String, Provenance, added 3;
        /// 16 hex digits: hash of the `Cargo.lock` the harness was built with (empty: recorded before this column).
        cargo_lock: String, Provenance, added 3;
        /// The SIMD kernel that ran: `simd_kernel` with `auto` resolved on the machine (`scalar`, `avx2`, `avx512`);
        /// `-` for structures without SIMD kernels.
        simd_kernel_used: String, Provenance = "-".to_string(), added 2;
        /// How many repetitions the configuration got: `fixed N`, or `auto MIN..MAX width W METRIC` (timed until the
        /// 95% interval of the median of METRIC was at most W of the median wide, at least MIN and at most MAX times).
        repetition_rule: String, Provenance = "-".to_string(), added 4;
        /// Relative width (hi - lo) / median of the 95% bootstrap interval of the configuration's median of the
        /// metric in `repetition_rule`, over its repetitions up to this one (empty for the first).
        interval_width: Option<f64>, Metric, decimals 6, added 4;
        /// Passes of the job in the timed trace: with the experiment's `sample_ms`, the job is traced again until
        /// the sample lasted that long; `trace_s` (and so `mrays_per_s`) is then the median pass, `overhead_s` the
        /// mean (1: one pass; 0 where validation failed).
        trace_passes: u32, Provenance = 1, added 10;
        /// Configurations whose trace passes took turns in the timed sample, this one included: with `sample_ms`
        /// and interleaved rounds, the series of one point are built together and traced a pass of each in turn,
        /// so that a change in the machine's speed reaches all of them alike (1: sampled alone, as earlier rows).
        sample_configs: u32, Provenance = 1, added 11;
        /// The hypervisor's steal time, summed over all CPUs, during the kept trace sample (`/proc/stat`, 10-ms
        /// ticks); a long sample (`sample_ms`) that saw steal is taken again, up to 3 times, keeping the one with the
        /// least. Empty for one-pass samples, where the kernel does not report it, and in earlier rows.
        steal_s: Option<f64>, Metric, unit "s", decimals 2, added 10;
        /// Whether the timing process's large blocks lay on transparent huge pages: `malloc` (`--huge-pages`:
        /// glibc's malloc asked for them, `GLIBC_TUNABLES=glibc.malloc.hugetlb=1:glibc.malloc.arena_max=1`, for every
        /// backend that allocates through it; Embree's allocator asks on its own), `always` (the kernel gives them to
        /// every large mapping), `no` (4-KiB pages but for Embree's own requests: the default, the kernel's mode
        /// `never`, or no glibc 2.35+); `-` in rows recorded before this column.
        huge_pages: String, Provenance = "-".to_string(), added 12;
        /// The operating system's id of the process that timed the run: the harness, or the worker it ran in
        /// (every backend with `processes` above 1, each worker timing one block of a configuration's runs; Embree always).
        /// Runs of one process share its offset (the layout its memory happened to get), so the intervals resample
        /// processes, not runs, where a series was timed in several. 0 for untimed runs and in earlier rows.
        process_id: u32, Provenance = 0, added 13;
        /// Primitives of the scene as traced: spheres, or triangles (a mesh's as loaded, degenerate ones included;
        /// a tessellated or random-triangle scene's as made), for every backend. 0 in rows recorded before this
        /// column (their size was implied by `objects` and `scene_fingerprint` only).
        primitives: u64, Counter, added 14;
        /// Peak resident memory of the process that timed the run (Linux `getrusage`'s `ru_maxrss`), after the
        /// run: a worker's (with `processes` above 1, and Embree always: its scene, rays and this backend's trees)
        /// or the harness's own (every scene, reference and tree made so far). Empty where the system does not say
        /// and in rows recorded before this column.
        peak_rss_bytes: Option<f64>, Metric, unit "bytes", decimals 0, added 15;
    }
}

// Where each setting applies (the `applies` predicates of the declaration).

/// Every axis the `applies` predicates below read (a test checks that no other axis changes what applies), so
/// that [`crate::applicability`] enumerates only these.
pub const APPLICABILITY_INPUTS: &[Axis] =
    &[Axis::scene, Axis::accel, Axis::split, Axis::strategy, Axis::workload, Axis::tree_builder];

/// Generated scenes have a seed; sphere files and meshes do not.
fn generated_scene(s: &Settings) -> bool {
    !matches!(s.scene, SceneName::SphereFile | SceneName::Mesh)
}

/// A mesh's size is its own.
fn not_mesh_scene(s: &Settings) -> bool {
    s.scene != SceneName::Mesh
}

/// Only `scene = "mesh"` names a mesh.
fn mesh_scene(s: &Settings) -> bool {
    s.scene == SceneName::Mesh
}

/// Scenes of triangles have views.
fn triangle_scene(s: &Settings) -> bool {
    s.scene.is_triangles()
}

/// The tracer's structures choose their triangle test.
fn ours_on_triangles(s: &Settings) -> bool {
    triangle_scene(s) && s.accel.peer().is_none()
}

/// The wide BVH over triangles (whose binary tree another builder may make).
fn wide_on_triangles(s: &Settings) -> bool {
    wide(s) && ours_on_triangles(s)
}

/// tinybvh's settings.
fn tinybvh(s: &Settings) -> bool {
    s.accel == Accel::Peer(PeerKind::TinyBvh)
}

/// The tracer's trees have tree settings.
fn tree(s: &Settings) -> bool {
    s.accel.is_tree() && !peer_builds_tree(s)
}

/// A peer's builder makes the wide BVH's binary tree (`tree_builder`): our split settings do not shape it.
fn peer_builds_tree(s: &Settings) -> bool {
    wide_on_triangles(s) && s.tree_builder.is_some_and(TreeBuilder::is_peer)
}

/// Only the binary trees have the `traversal` order.
fn binary_tree(s: &Settings) -> bool {
    s.accel.is_binary_tree()
}

/// The wide BVH's own settings.
fn wide(s: &Settings) -> bool {
    s.accel.is_wide()
}

/// A wide BVH over a binary tree of our own builders.
fn wide_own_tree(s: &Settings) -> bool {
    wide(s) && tree(s)
}

/// The wide BVH's packets are for ray sets: renders trace one ray at a time.
fn wide_ray_set(s: &Settings) -> bool {
    wide(s) && s.workload != Workload::Render
}

/// Embree's packet queries are for ray sets too.
fn embree_packet_ray_set(s: &Settings) -> bool {
    s.accel == Accel::Peer(PeerKind::EmbreePackets) && s.workload != Workload::Render
}

/// Only the binned SAH splits (binned and spatial) have bins.
fn binned_sah(s: &Settings) -> bool {
    tree(s) && s.split.is_some_and(Split::is_binned)
}

/// Only spatial splits have an overlap threshold.
fn spatial_sah(s: &Settings) -> bool {
    tree(s) && s.split == Some(Split::SpatialSah)
}

/// Only the SAH splits have cost constants.
fn sah_split(s: &Settings) -> bool {
    tree(s) && s.split.is_some_and(Split::is_sah)
}

/// Serial runs use one thread.
fn parallel(s: &Settings) -> bool {
    s.strategy != StrategyKind::Serial
}

/// Only rendering reflects.
fn render(s: &Settings) -> bool {
    s.workload == Workload::Render
}

/// obvhs's presets.
fn obvhs(s: &Settings) -> bool {
    s.accel.peer().is_some_and(PeerKind::is_obvhs)
}

/// Embree's settings.
fn embree(s: &Settings) -> bool {
    s.accel.peer().is_some_and(PeerKind::needs_embree)
}

/// `packet`'s cell in the configuration id: the integer `packet_size` it replaced (`0` where it does not apply), so
/// configurations recorded before keep their ids.
fn packet_size_cell(packet: &Option<Packet>) -> Cell {
    Cell::Int(packet.map_or(0, |p| i64::from(p.rays())))
}

/// A setting of earlier row formats that later ones replaced: configs that name it are refused with the new keys,
/// and rows that have its column read into them.
pub struct Replaced {
    /// Its config key and row column.
    pub key: &'static str,
    /// The settings that replaced it.
    pub by: &'static [Axis],
    /// Sets them from a row's cell of the old column (normalization then drops those that do not apply).
    pub read: fn(&mut Settings, &str),
}

/// Every replaced setting.
pub const REPLACED: &[Replaced] =
    &[Replaced { key: "packet_size", by: &[Axis::packet, Axis::embree_packet], read: read_packet_size }];

impl Replaced {
    /// The replaced setting `key`, if it is one.
    pub fn of(key: &str) -> Option<&'static Replaced> {
        REPLACED.iter().find(|r| r.key == key)
    }

    /// What to write instead, for error messages.
    pub fn instead(&self) -> String {
        let by: Vec<String> = self.by.iter().map(|a| format!("{} (allowed: {})", a.key(), a.allowed())).collect();
        format!("replaced by {}", by.join(" and "))
    }
}

/// `packet_size` (row formats 4 and 5): the wide BVH's rays traced together, or `embree-packets`' width.
fn read_packet_size(settings: &mut Settings, cell: &str) {
    let Ok(rays) = cell.parse::<u32>() else { return };
    if let Some(p) = Packet::of_rays(rays) {
        settings.packet = Some(p);
    }
    if let Some(e) = EmbreePacket::new(rays) {
        settings.embree_packet = Some(e);
    }
}

impl Settings {
    /// The tracer's structure and tree parameters (a peer's settings give the list, which is never built).
    pub fn accel_params(&self) -> AccelParams {
        let default = BvhParams::default();
        let kind = match self.accel {
            Accel::Ours(kind) => kind,
            Accel::Peer(_) => AccelKind::List,
        };
        let bvh = BvhParams {
            leaf_size: self.leaf_size.unwrap_or(default.leaf_size),
            split: self.split.unwrap_or(default.split),
            sah_bins: self.sah_bins.unwrap_or(default.sah_bins),
            traversal: self.traversal.unwrap_or(default.traversal),
            reinsertion: self.reinsertion,
            sah_costs: SahCosts {
                traversal: self.sah_traversal_cost.unwrap_or(default.sah_costs.traversal),
                intersection: self.sah_intersection_cost.unwrap_or(default.sah_costs.intersection),
            },
            spatial_alpha: SpatialAlpha(self.spatial_alpha.unwrap_or(default.spatial_alpha.0)),
        };
        let wide_default = WideParams::default();
        let wide = WideParams {
            width: self.node_width.map_or(wide_default.width, |w| w.0),
            leaf_block: self.leaf_block.map_or(wide_default.leaf_block, |b| b.0),
            kernel: self.simd_kernel.unwrap_or(wide_default.kernel),
            order: self.child_order.unwrap_or(wide_default.order),
            any_hit_order: self.any_hit_order.unwrap_or(wide_default.any_hit_order),
            packet: self.packet.map_or(wide_default.packet, Packet::rays),
            sah_block: self.sah_block.map_or(wide_default.sah_block, |b| b.0),
        };
        AccelParams { kind, bvh, wide }
    }

    /// The strategy and its thread count (`threads = "all"`: this machine's logical cores, as a plan resolves it).
    pub fn strategy(&self) -> Strategy {
        Strategy::new(self.strategy, self.threads.here() as usize)
    }

    /// The peer backend, if the accelerator is one.
    pub fn peer(&self) -> Option<PeerKind> {
        self.accel.peer()
    }
}
