//! tinybvh 1.6.8 as a peer: its binary BVH and its wide CPU layouts (BVH4_CPU, BVH8_CPU) over our triangle
//! meshes, through a C shim of our own (`shim.cpp`).
//!
//! **Why a shim.** The crates.io wrapper `tinybvh-rs` 0.1.0-beta.3 declares a 64-byte `Ray` where the header it
//! bundles has a 128-byte one (unsound: it segfaults), has no occlusion query and compiles with `-march=native`.
//! We keep its bundled header (`ffi/tinybvh/tiny_bvh.h`, found by `build.rs` through the lock file and cargo's unpacked sources) and call
//! it only through `shim.cpp`: rays and hits cross as the shim's own plain structs ([`TbRay`], [`TbHit`],
//! [`TbStats`]), their sizes asserted in C++ (`static_assert`) and here (`const` asserts), and checked against
//! each other at run time by the tests ([`TbAbi`]); tinybvh's `Ray` never leaves C++.
//!
//! **ISA variants.** tinybvh picks its code paths with `#ifdef` at compile time: without AVX2 and FMA it has no
//! BVH8_CPU (nor `BuildAVX`); BVH4_CPU needs SSE4.2; it has no AVX-512 code of its own. `build.rs` compiles the
//! shim three times, for x86-64-v2 (SSE4.2: plain BVH and BVH4_CPU), x86-64-v3 (AVX2 + FMA: all three, and the
//! AVX binned builder) and x86-64-v4 (AVX-512, the same code with the compiler free to use it), each in its own
//! namespace and symbol prefix with every other symbol made local, and its static initializer (tinybvh's SIMD
//! constants, compiled for that ISA) taken out of the program's startup and run on the variant's first use, so
//! no variant's code runs on a CPU that lacks its ISA (valgrind, which has no AVX-512, showed the startup case).
//! [`TinyIsa::best`] picks the highest level the CPU has (`is_x86_feature_detected!`), a build can ask for a
//! lower one ([`TinyBvh::build_with`]), and [`TinyBvh::kernel`] names the one that runs. A layout is available
//! only where its variant is: BVH8_CPU needs an AVX2 CPU. The cost: three compiles of the 9,000-line header
//! (about 12 s of CPU each, in parallel, cached by `build.rs` across reruns) and a 1.6 MB archive.
//!
//! **Rays.** Our ray is `origin + t·dir` for `t_min < t < t_max` with `dir` of any length; tinybvh's has no
//! `t_min`, normalizes its direction (hits are in units of the unit direction) and accepts hits at `t ≥ 0`
//! (plain BVH) or `t > 0` (BVH4_CPU, BVH8_CPU) up to its `hit.t`. The shim passes tinybvh's own constructor the
//! direction as given (so tinybvh normalizes it exactly as for its own callers) and `t_max·|dir|` (capped at
//! tinybvh's `BVH_FAR = 1e30`); for `t_min > 0` it first moves the origin to `origin + s·dir` with `s` the float
//! above `t_min` (so tinybvh's `t ≥ 0` means ours `t > t_min`, up to the rounding of the moved origin), and
//! converts hits back as `s + t/|dir|`. With `t_min = 0` the origin stays and the plain layout reports a hit at
//! exactly `t = 0` (a ray starting on a triangle), which ours excludes. `t_max` is exclusive: a closest hit at
//! exactly tinybvh's `hit.t` counts as a miss, and occlusion rays get the float below it. Rays that cannot hit
//! (zero direction, non-finite origin, empty interval) miss without calling tinybvh, whose ray validation would
//! end the process on a NaN. Distances carry one or two extra roundings; the agreement tests arbitrate them.
//!
//! **What the wrapper lacks.** tinybvh counts nothing ([`Counters`] sees only rays); its builds above 50,000
//! triangles start their own thread pool (all hardware threads, kept per calling thread for the process's
//! life), so the harness's thread count does not bind them; its triangle tests are Möller–Trumbore (not
//! watertight) with an absolute determinant cutoff of `1e-6` in the plain layout; its traversal stacks are
//! fixed arrays, so the shim refuses trees deeper than 60 binary levels ([`TinyBvhError::TooDeep`]) rather than
//! overrun them; and `build` copies the mesh into tinybvh's triangle soup (48 bytes a triangle).

use std::ffi::c_void;
use std::fmt;
use std::ptr::NonNull;

use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::Ray;
use tracer::scene::mesh::Mesh;

#[cfg(test)]
mod tests;

/// A ray as the shim takes it (`TbRay` in `shim.cpp`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TbRay {
    /// Start point.
    pub origin: [f32; 3],
    /// Direction, any length.
    pub dir: [f32; 3],
    /// Hits at or before this parameter are ignored.
    pub t_min: f32,
    /// Hits at or beyond this parameter are ignored.
    pub t_max: f32,
}
const _: () = assert!(size_of::<TbRay>() == 32 && align_of::<TbRay>() == 4);

impl From<&Ray> for TbRay {
    #[inline(always)]
    fn from(r: &Ray) -> Self {
        Self { origin: r.origin.to_array(), dir: r.dir.to_array(), t_min: r.t_min, t_max: r.t_max }
    }
}

/// A closest hit as the shim returns it (`TbHit`): `prim == u32::MAX` (and `t` infinite) for a miss.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TbHit {
    /// Ray parameter of the hit, in units of the ray's direction.
    pub t: f32,
    /// Triangle index in the mesh.
    pub prim: u32,
}
const _: () = assert!(size_of::<TbHit>() == 8 && align_of::<TbHit>() == 4);

/// What a build reports (`TbStats`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TbStats {
    /// Interior nodes plus leaves (binary), or wide nodes (wide layouts).
    pub nodes: u64,
    /// Leaves (binary), or child slots holding triangles (wide layouts).
    pub leaves: u64,
    /// Levels below the root of the deepest leaf.
    pub depth: u64,
    /// Bytes the traversal reads.
    pub bytes: u64,
    /// SAH cost with unit costs (0 for the wide layouts).
    pub sah_cost: f64,
}
const _: () = assert!(size_of::<TbStats>() == 40 && align_of::<TbStats>() == 8);

/// One node of tinybvh's plain binary tree as the shim copies it (`TbNode`): interior nodes' children are nodes
/// `left_first` and `left_first + 1`; a leaf (`tri_count > 0`) names `tri_count` primitive indices from `left_first`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TbNode {
    /// Box corner.
    pub min: [f32; 3],
    /// First child, or first primitive index of a leaf.
    pub left_first: u32,
    /// Box corner.
    pub max: [f32; 3],
    /// Primitives of a leaf; 0 for interior nodes.
    pub tri_count: u32,
}
const _: () = assert!(size_of::<TbNode>() == 32 && align_of::<TbNode>() == 4);

/// The sizes and version a shim variant was compiled with (`TbAbi`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TbAbi {
    /// `sizeof(TbRay)`.
    pub ray_size: u32,
    /// `alignof(TbRay)`.
    pub ray_align: u32,
    /// `sizeof(TbHit)`.
    pub hit_size: u32,
    /// `alignof(TbHit)`.
    pub hit_align: u32,
    /// `sizeof(TbStats)`.
    pub stats_size: u32,
    /// `alignof(TbStats)`.
    pub stats_align: u32,
    /// `sizeof(tinybvh::Ray)` (128 in 1.6.8).
    pub tiny_ray_size: u32,
    /// `alignof(tinybvh::Ray)` (64 in 1.6.8).
    pub tiny_ray_align: u32,
    /// tinybvh's version, `major·10000 + minor·100 + sub`.
    pub version: u32,
}

/// One compiled variant's entry points (`tinybvh_vN_*` in `shim.cpp`).
#[derive(Debug)]
#[cfg_attr(not(bvhlab_tinybvh), allow(dead_code))]
struct Kernel {
    /// Runs the variant's static initializer, once (`build.rs` moved it out of startup); call it first.
    init: fn(),
    abi: unsafe extern "C" fn(*mut TbAbi),
    layouts: unsafe extern "C" fn() -> u32,
    build: unsafe extern "C" fn(*const f32, *const u32, u32, u32, u32, *mut *mut c_void, *mut TbStats) -> i32,
    free: unsafe extern "C" fn(*mut c_void),
    intersect: unsafe extern "C" fn(*const c_void, *const TbRay) -> TbHit,
    occluded: unsafe extern "C" fn(*const c_void, *const TbRay) -> bool,
    intersect_batch: unsafe extern "C" fn(*const c_void, *const TbRay, usize, *mut TbHit),
    occluded_batch: unsafe extern "C" fn(*const c_void, *const TbRay, usize, *mut u8),
    plain_tree_size: unsafe extern "C" fn(*const c_void, *mut u32, *mut u32) -> i32,
    plain_tree_copy: unsafe extern "C" fn(*const c_void, *mut TbNode, *mut u32),
}

/// Declares variant `$v`'s entry points in module `$m` and its [`Kernel`] as `$m::KERNEL`.
#[cfg(bvhlab_tinybvh)]
macro_rules! variant {
    ($m:ident, $v:literal) => {
        mod $m {
            use std::ffi::c_void;
            use std::sync::Once;

            use super::{Kernel, TbAbi, TbHit, TbNode, TbRay, TbStats};

            unsafe extern "C" {
                /// Start of the variant's static initializers (`build.rs` moved them out of `.init_array`).
                #[link_name = concat!("tinybvh_", $v, "_ctors_begin")]
                static CTORS_BEGIN: u8;
                /// Their end.
                #[link_name = concat!("tinybvh_", $v, "_ctors_end")]
                static CTORS_END: u8;
                #[link_name = concat!("tinybvh_", $v, "_abi")]
                fn abi(out: *mut TbAbi);
                #[link_name = concat!("tinybvh_", $v, "_layouts")]
                fn layouts() -> u32;
                #[link_name = concat!("tinybvh_", $v, "_build")]
                fn build(
                    positions: *const f32,
                    indices: *const u32,
                    tris: u32,
                    layout: u32,
                    quality: u32,
                    out: *mut *mut c_void,
                    stats: *mut TbStats,
                ) -> i32;
                #[link_name = concat!("tinybvh_", $v, "_free")]
                fn free(accel: *mut c_void);
                #[link_name = concat!("tinybvh_", $v, "_intersect")]
                fn intersect(accel: *const c_void, ray: *const TbRay) -> TbHit;
                #[link_name = concat!("tinybvh_", $v, "_occluded")]
                fn occluded(accel: *const c_void, ray: *const TbRay) -> bool;
                #[link_name = concat!("tinybvh_", $v, "_intersect_batch")]
                fn intersect_batch(accel: *const c_void, rays: *const TbRay, n: usize, out: *mut TbHit);
                #[link_name = concat!("tinybvh_", $v, "_occluded_batch")]
                fn occluded_batch(accel: *const c_void, rays: *const TbRay, n: usize, out: *mut u8);
                #[link_name = concat!("tinybvh_", $v, "_plain_tree_size")]
                fn plain_tree_size(accel: *const c_void, nodes: *mut u32, indices: *mut u32) -> i32;
                #[link_name = concat!("tinybvh_", $v, "_plain_tree_copy")]
                fn plain_tree_copy(accel: *const c_void, nodes: *mut TbNode, indices: *mut u32);
            }

            /// Runs the static initializers once. Only called once the CPU is known to run this variant.
            fn init() {
                static INIT: Once = Once::new();
                INIT.call_once(|| {
                    // SAFETY: `build.rs` made the bytes between the two symbols the variant's former `.init_array`
                    // (checked there: a whole number of function pointers, relocated by the loader as before), so
                    // each is a `void (*)(void)` the C++ runtime would have called at startup; this CPU runs the
                    // variant's code, and `Once` runs them exactly once, before any other entry point.
                    unsafe {
                        let mut at = (&raw const CTORS_BEGIN).cast::<unsafe extern "C" fn()>();
                        let end = (&raw const CTORS_END).cast::<unsafe extern "C" fn()>();
                        while at < end {
                            (at.read())();
                            at = at.add(1);
                        }
                    }
                });
            }

            pub(super) static KERNEL: Kernel = Kernel {
                init,
                abi,
                layouts,
                build,
                free,
                intersect,
                occluded,
                intersect_batch,
                occluded_batch,
                plain_tree_size,
                plain_tree_copy,
            };
        }
    };
}

#[cfg(bvhlab_tinybvh)]
variant!(v2, "v2");
#[cfg(bvhlab_tinybvh)]
variant!(v3, "v3");
#[cfg(bvhlab_tinybvh)]
variant!(v4, "v4");

/// An x86-64 ISA level the shim is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TinyIsa {
    /// x86-64-v2: SSE4.2 and POPCNT (plain BVH, BVH4_CPU).
    V2,
    /// x86-64-v3: AVX2, FMA, BMI1/2 (also BVH8_CPU and the AVX builder).
    V3,
    /// x86-64-v4: AVX-512 F/BW/CD/DQ/VL (tinybvh's v3 code, compiled with AVX-512 allowed).
    V4,
}

impl TinyIsa {
    /// Every level, lowest first.
    pub const ALL: [TinyIsa; 3] = [TinyIsa::V2, TinyIsa::V3, TinyIsa::V4];

    /// The `-march` name, `x86-64-vN`.
    pub fn name(self) -> &'static str {
        match self {
            TinyIsa::V2 => "x86-64-v2",
            TinyIsa::V3 => "x86-64-v3",
            TinyIsa::V4 => "x86-64-v4",
        }
    }

    /// True when this CPU runs the level's code (and the shim was compiled for this target).
    pub fn supported(self) -> bool {
        #[cfg(all(bvhlab_tinybvh, target_arch = "x86_64"))]
        {
            use std::arch::is_x86_feature_detected as has;
            let v2 = has!("sse3")
                && has!("ssse3")
                && has!("sse4.1")
                && has!("sse4.2")
                && has!("popcnt")
                && has!("cmpxchg16b");
            let v3 = v2
                && has!("avx")
                && has!("avx2")
                && has!("bmi1")
                && has!("bmi2")
                && has!("fma")
                && has!("f16c")
                && has!("lzcnt")
                && has!("movbe")
                && has!("xsave");
            let v4 =
                v3 && has!("avx512f") && has!("avx512bw") && has!("avx512cd") && has!("avx512dq") && has!("avx512vl");
            match self {
                TinyIsa::V2 => v2,
                TinyIsa::V3 => v3,
                TinyIsa::V4 => v4,
            }
        }
        #[cfg(not(all(bvhlab_tinybvh, target_arch = "x86_64")))]
        {
            false
        }
    }

    /// The highest level this CPU runs, if any.
    pub fn best() -> Option<TinyIsa> {
        Self::ALL.into_iter().rev().find(|isa| isa.supported())
    }

    /// The lowest level whose variant has `layout`.
    pub fn lowest_for(layout: TinyLayout) -> TinyIsa {
        match layout {
            TinyLayout::Bvh | TinyLayout::Bvh4Cpu => TinyIsa::V2,
            TinyLayout::Bvh8Cpu => TinyIsa::V3,
        }
    }

    /// The variant's entry points, initialized, when this CPU runs them (`None` otherwise or when not compiled).
    fn runnable(self) -> Option<&'static Kernel> {
        let kernel = self.kernel().filter(|_| self.supported())?;
        (kernel.init)();
        Some(kernel)
    }

    /// The variant's entry points (`None` when the shim was not compiled); see [`TinyIsa::runnable`].
    fn kernel(self) -> Option<&'static Kernel> {
        #[cfg(bvhlab_tinybvh)]
        {
            Some(match self {
                TinyIsa::V2 => &v2::KERNEL,
                TinyIsa::V3 => &v3::KERNEL,
                TinyIsa::V4 => &v4::KERNEL,
            })
        }
        #[cfg(not(bvhlab_tinybvh))]
        {
            None
        }
    }

    /// The sizes and version this level's variant was compiled with (`None` where it cannot run).
    pub fn abi(self) -> Option<TbAbi> {
        let kernel = self.runnable()?;
        let mut abi = TbAbi::default();
        // SAFETY: the CPU runs this variant; `abi` only writes the struct, whose layout matches `TbAbi` in C++.
        unsafe { (kernel.abi)(&mut abi) };
        Some(abi)
    }

    /// True when this level's variant has `layout` compiled in (asked of the variant itself).
    pub fn has(self, layout: TinyLayout) -> bool {
        let Some(kernel) = self.runnable() else { return false };
        // SAFETY: the CPU runs this variant; `layouts` reads nothing.
        (unsafe { (kernel.layouts)() } >> layout as u32) & 1 == 1
    }
}

/// A tinybvh layout the shim traverses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TinyLayout {
    /// `BVH`: the binary tree of 32-byte nodes, one triangle test at a time.
    Bvh = 0,
    /// `BVH4_CPU`: 4-wide nodes (SSE), leaves of four triangles tested at once.
    Bvh4Cpu = 1,
    /// `BVH8_CPU`: 8-wide nodes (AVX2), leaves of four triangles tested at once.
    Bvh8Cpu = 2,
}

impl TinyLayout {
    /// Every layout.
    pub const ALL: [TinyLayout; 3] = [TinyLayout::Bvh, TinyLayout::Bvh4Cpu, TinyLayout::Bvh8Cpu];

    /// tinybvh's name for it.
    pub fn name(self) -> &'static str {
        match self {
            TinyLayout::Bvh => "BVH",
            TinyLayout::Bvh4Cpu => "BVH4_CPU",
            TinyLayout::Bvh8Cpu => "BVH8_CPU",
        }
    }
}

/// Which tinybvh builder makes the binary tree the layout is built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TinyQuality {
    /// `Build`: binned SAH (the AVX binner `BuildAVX` for the wide layouts where compiled, as tinybvh does).
    Default = 0,
    /// `BuildHQ`: the spatial-split SBVH (slower to build, references some triangles from several leaves).
    High = 1,
}

/// Why a tinybvh structure could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum TinyBvhError {
    /// The shim is not compiled for this target, or this CPU lacks the requested ISA level.
    Unavailable(String),
    /// The requested ISA level's variant does not have the layout.
    LayoutNeedsIsa(TinyLayout, TinyIsa),
    /// The mesh cannot be handed to tinybvh (index out of range, non-finite position, too many triangles).
    BadMesh(String),
    /// The tree is deeper than tinybvh's fixed traversal stacks allow.
    TooDeep,
    /// tinybvh could not allocate the structure.
    OutOfMemory,
}

impl fmt::Display for TinyBvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TinyBvhError::Unavailable(why) => write!(f, "tinybvh unavailable: {why}"),
            TinyBvhError::LayoutNeedsIsa(layout, isa) => {
                write!(f, "tinybvh {} is not compiled for {}", layout.name(), isa.name())
            }
            TinyBvhError::BadMesh(why) => write!(f, "mesh not accepted by tinybvh: {why}"),
            TinyBvhError::TooDeep => write!(f, "tinybvh tree deeper than its fixed traversal stacks allow"),
            TinyBvhError::OutOfMemory => write!(f, "tinybvh could not allocate the structure"),
        }
    }
}

impl std::error::Error for TinyBvhError {}

/// The most triangles the shim accepts (2^26).
pub const MAX_TRIANGLES: usize = 1 << 26;

/// Rays handed to the shim per batch call (copied to [`TbRay`] on the stack).
const BATCH: usize = 256;

/// A tinybvh structure over a triangle mesh: one [`TinyLayout`], traversed by one ISA variant's code.
pub struct TinyBvh {
    /// The shim's structure (owns tinybvh's copy of the triangles).
    handle: NonNull<c_void>,
    kernel: &'static Kernel,
    isa: TinyIsa,
    layout: TinyLayout,
    quality: TinyQuality,
    stats: TbStats,
}

// SAFETY: after `build` returns, the shim's structure is never written: tinybvh's `Intersect` and `IsOccluded`
// are `const` and keep their state (ray, stacks) on the calling thread's stack, so shared use from many threads
// is sound, and the structure owns all its memory, so it may be freed from any thread.
unsafe impl Send for TinyBvh {}
// SAFETY: as for `Send`.
unsafe impl Sync for TinyBvh {}

impl fmt::Debug for TinyBvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TinyBvh")
            .field("layout", &self.layout)
            .field("quality", &self.quality)
            .field("kernel", &self.kernel())
            .field("stats", &self.stats)
            .finish()
    }
}

impl TinyBvh {
    /// Builds `layout` over `mesh` with the highest ISA level this CPU runs ([`TinyIsa::best`]).
    pub fn build(mesh: &Mesh, layout: TinyLayout, quality: TinyQuality) -> Result<Self, TinyBvhError> {
        let isa = TinyIsa::best().ok_or_else(|| TinyBvhError::Unavailable(unavailable_reason()))?;
        Self::build_with(mesh, layout, quality, isa)
    }

    /// Builds `layout` over `mesh` with the variant compiled for `isa` (which this CPU must run).
    pub fn build_with(
        mesh: &Mesh,
        layout: TinyLayout,
        quality: TinyQuality,
        isa: TinyIsa,
    ) -> Result<Self, TinyBvhError> {
        if isa.kernel().is_none() {
            return Err(TinyBvhError::Unavailable(unavailable_reason()));
        }
        let Some(kernel) = isa.runnable() else {
            return Err(TinyBvhError::Unavailable(format!("this CPU does not run {}", isa.name())));
        };
        if !isa.has(layout) {
            return Err(TinyBvhError::LayoutNeedsIsa(layout, isa));
        }
        validate(mesh)?;
        let mut handle = std::ptr::null_mut();
        let mut stats = TbStats::default();
        // SAFETY: the CPU runs this variant (checked above). `positions` is `Vec<Vec3>` (glam's `Vec3` is
        // `repr(C)`, three `f32`s) and `indices` `Vec<[u32; 3]>`, so both are plain arrays of `3·len` values;
        // every index is below `positions.len()` (validate), which is what the shim reads. `handle` and `stats`
        // are valid for writes.
        let status = unsafe {
            (kernel.build)(
                mesh.positions.as_ptr().cast::<f32>(),
                mesh.indices.as_ptr().cast::<u32>(),
                mesh.indices.len() as u32,
                layout as u32,
                quality as u32,
                &mut handle,
                &mut stats,
            )
        };
        match (status, NonNull::new(handle)) {
            (0, Some(handle)) => Ok(Self { handle, kernel, isa, layout, quality, stats }),
            (1, _) => Err(TinyBvhError::LayoutNeedsIsa(layout, isa)),
            (2, _) => Err(TinyBvhError::BadMesh(format!("{} triangles", mesh.indices.len()))),
            (3, _) => Err(TinyBvhError::TooDeep),
            _ => Err(TinyBvhError::OutOfMemory),
        }
    }

    /// The ISA variant that traverses it, e.g. `x86-64-v3`.
    pub fn kernel(&self) -> &'static str {
        self.isa.name()
    }

    /// The ISA level that traverses it.
    pub fn isa(&self) -> TinyIsa {
        self.isa
    }

    /// The layout.
    pub fn layout(&self) -> TinyLayout {
        self.layout
    }

    /// The builder it was built with.
    pub fn quality(&self) -> TinyQuality {
        self.quality
    }

    /// The shim's statistics of the built structure.
    pub fn raw_stats(&self) -> TbStats {
        self.stats
    }

    /// The binary tree of the plain layout, copied out: its nodes (tinybvh's order; node 1 is its unused slot) and
    /// the primitive indices its leaves name. `None` for the other layouts. The copy is checked by its reader
    /// (`tracer::accel::bvh::tree::BuiltTree::from_external`) before any use.
    pub fn plain_tree(&self) -> Option<(Vec<TbNode>, Vec<u32>)> {
        let (mut nodes, mut indices) = (0u32, 0u32);
        // SAFETY: `handle` is this kernel's live structure; the shim writes the two counts and nothing else.
        let status = unsafe { (self.kernel.plain_tree_size)(self.handle.as_ptr(), &mut nodes, &mut indices) };
        if status != 0 {
            return None;
        }
        let mut node_copy = vec![TbNode::default(); nodes as usize];
        let mut index_copy = vec![0u32; indices as usize];
        // SAFETY: the two buffers hold exactly the counts the shim just gave for this unchanged structure (it is
        // never written after `build`), `TbNode` matches the shim's layout (size and alignment asserted on both
        // sides), and `Vec` gives pointers aligned for their element types.
        unsafe { (self.kernel.plain_tree_copy)(self.handle.as_ptr(), node_copy.as_mut_ptr(), index_copy.as_mut_ptr()) };
        Some((node_copy, index_copy))
    }
}

impl Drop for TinyBvh {
    fn drop(&mut self) {
        // SAFETY: `handle` came from this kernel's `build` and is freed once, here.
        unsafe { (self.kernel.free)(self.handle.as_ptr()) }
    }
}

/// Why no variant can run here.
fn unavailable_reason() -> String {
    if TinyIsa::V2.kernel().is_none() {
        "the tinybvh shim is only compiled for x86-64 Linux".into()
    } else {
        "this CPU lacks x86-64-v2 (SSE4.2, POPCNT)".into()
    }
}

/// Checks what the shim relies on: indices in range, finite positions, at most [`MAX_TRIANGLES`].
fn validate(mesh: &Mesh) -> Result<(), TinyBvhError> {
    if mesh.indices.len() > MAX_TRIANGLES {
        return Err(TinyBvhError::BadMesh(format!("{} triangles (at most {MAX_TRIANGLES})", mesh.indices.len())));
    }
    let n = mesh.positions.len();
    if let Some((t, tri)) = mesh.indices.iter().enumerate().find(|(_, tri)| tri.iter().any(|&i| i as usize >= n)) {
        return Err(TinyBvhError::BadMesh(format!("triangle {t} indexes {tri:?} among {n} positions")));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(TinyBvhError::BadMesh(format!("position {i} is not finite")));
    }
    Ok(())
}

impl Accelerator for TinyBvh {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, _counters: &mut C) -> Option<Hit> {
        let r = TbRay::from(ray);
        // SAFETY: `handle` is this kernel's live structure; the CPU runs the kernel (checked at build); `r` is a
        // valid `TbRay`.
        let hit = unsafe { (self.kernel.intersect)(self.handle.as_ptr(), &r) };
        (hit.prim != u32::MAX).then_some(Hit { t: hit.t, prim: hit.prim })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, _counters: &mut C) -> bool {
        let r = TbRay::from(ray);
        // SAFETY: as in `intersect`.
        unsafe { (self.kernel.occluded)(self.handle.as_ptr(), &r) }
    }

    fn stats(&self) -> TreeStats {
        let s = self.stats;
        TreeStats {
            nodes: s.nodes as usize,
            leaves: s.leaves as usize,
            depth: s.depth as usize,
            bytes: s.bytes as usize,
            sah_cost: s.sah_cost,
        }
    }

    /// One shim call per [`BATCH`] rays (misses as `PrimaryHits::MISS`: `t` infinite, `prim` `u32::MAX`).
    fn intersect_batch<C: Counters>(&self, rays: &[Ray], out: &mut [Hit], counters: &mut C) {
        let mut tb = [TbRay::default(); BATCH];
        let mut hits = [TbHit::default(); BATCH];
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let n = rays.len().min(out.len());
            for (t, r) in tb.iter_mut().zip(&rays[..n]) {
                counters.ray();
                *t = TbRay::from(r);
            }
            // SAFETY: as in `intersect`; `tb` and `hits` hold at least `n` elements.
            unsafe { (self.kernel.intersect_batch)(self.handle.as_ptr(), tb.as_ptr(), n, hits.as_mut_ptr()) };
            for (o, h) in out.iter_mut().zip(&hits[..n]) {
                *o = Hit { t: h.t, prim: h.prim };
            }
        }
    }

    /// One shim call per [`BATCH`] rays.
    fn occluded_batch<C: Counters>(&self, rays: &[Ray], out: &mut [bool], counters: &mut C) {
        let mut tb = [TbRay::default(); BATCH];
        let mut flags = [0u8; BATCH];
        for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let n = rays.len().min(out.len());
            for (t, r) in tb.iter_mut().zip(&rays[..n]) {
                counters.ray();
                *t = TbRay::from(r);
            }
            // SAFETY: as in `intersect`; `tb` and `flags` hold at least `n` elements.
            unsafe { (self.kernel.occluded_batch)(self.handle.as_ptr(), tb.as_ptr(), n, flags.as_mut_ptr()) };
            for (o, &f) in out.iter_mut().zip(&flags[..n]) {
                *o = f != 0;
            }
        }
    }
}
