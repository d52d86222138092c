//! The slice of the Embree 4 C ABI this binding uses: handles, enums, structs and function-pointer types.
//!
//! Facts from Embree v4.4.0's `include/embree4/*.h` (see /work/shared/embree4-abi.md); every struct size and
//! alignment is pinned by a compile-time assert below.
#![allow(non_snake_case, non_camel_case_types, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// Opaque `RTCDevice` handle.
pub type RTCDevice = *mut c_void;
/// Opaque `RTCScene` handle.
pub type RTCScene = *mut c_void;
/// Opaque `RTCGeometry` handle.
pub type RTCGeometry = *mut c_void;

/// `RTC_INVALID_GEOMETRY_ID`.
pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// `RTCError::RTC_ERROR_NONE`.
pub const RTC_ERROR_NONE: u32 = 0;

/// `RTCDeviceProperty::RTC_DEVICE_PROPERTY_VERSION` (e.g. 40400 for 4.4.0).
pub const RTC_DEVICE_PROPERTY_VERSION: u32 = 0;
/// `RTCDeviceProperty::RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED`.
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED: u32 = 32;
/// `RTCDeviceProperty::RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED`.
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED: u32 = 33;
/// `RTCDeviceProperty::RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED`.
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED: u32 = 34;
/// `RTCDeviceProperty::RTC_DEVICE_PROPERTY_TASKING_SYSTEM` (0 internal, 1 TBB, 2 PPL).
pub const RTC_DEVICE_PROPERTY_TASKING_SYSTEM: u32 = 128;

/// `RTCBuildQuality::RTC_BUILD_QUALITY_LOW`.
pub const RTC_BUILD_QUALITY_LOW: u32 = 0;
/// `RTCBuildQuality::RTC_BUILD_QUALITY_MEDIUM` (the default).
pub const RTC_BUILD_QUALITY_MEDIUM: u32 = 1;
/// `RTCBuildQuality::RTC_BUILD_QUALITY_HIGH`.
pub const RTC_BUILD_QUALITY_HIGH: u32 = 2;

/// `RTCSceneFlags::RTC_SCENE_FLAG_NONE`.
pub const RTC_SCENE_FLAG_NONE: u32 = 0;
/// `RTCSceneFlags::RTC_SCENE_FLAG_ROBUST`.
pub const RTC_SCENE_FLAG_ROBUST: u32 = 4;

/// `RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE`.
pub const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
/// `RTCGeometryType::RTC_GEOMETRY_TYPE_SPHERE_POINT`.
pub const RTC_GEOMETRY_TYPE_SPHERE_POINT: u32 = 50;
/// `RTCBufferType::RTC_BUFFER_TYPE_INDEX`.
pub const RTC_BUFFER_TYPE_INDEX: u32 = 0;
/// `RTCBufferType::RTC_BUFFER_TYPE_VERTEX`.
pub const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
/// `RTCFormat::RTC_FORMAT_UINT3`: three `u32` (a triangle's vertex indices).
pub const RTC_FORMAT_UINT3: u32 = 0x5003;
/// `RTCFormat::RTC_FORMAT_FLOAT3`: three `f32` (a vertex position).
pub const RTC_FORMAT_FLOAT3: u32 = 0x9003;
/// `RTCFormat::RTC_FORMAT_FLOAT4`.
pub const RTC_FORMAT_FLOAT4: u32 = 0x9004;

/// `RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT`.
pub const RTC_RAY_QUERY_FLAG_INCOHERENT: u32 = 0;
/// `RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_COHERENT`.
pub const RTC_RAY_QUERY_FLAG_COHERENT: u32 = 1 << 16;
/// `RTCFeatureFlags::RTC_FEATURE_FLAG_ALL`.
pub const RTC_FEATURE_FLAG_ALL: u32 = 0xffff_ffff;

/// A valid lane in the `valid` mask of the packet queries.
pub const LANE_ACTIVE: c_int = -1;
/// An inactive lane.
pub const LANE_INACTIVE: c_int = 0;

/// The `valid` lane mask of `rtcIntersect8` (one `c_int` per lane), aligned like its packet: Embree's wide kernels
/// load it with aligned vector loads.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ValidMask8(pub [c_int; 8]);

/// The `valid` lane mask of `rtcIntersect16`, aligned to 64 bytes (AVX-512 loads it aligned: a 4-byte aligned
/// stack array crashed `rtcIntersect16` on an AVX-512 CPU).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ValidMask16(pub [c_int; 16]);

/// The byte alignment Embree requires of an N-lane packet and of its `valid` mask: 4 × N (16, 32 or 64).
pub const fn packet_alignment(lanes: usize) -> usize {
    4 * lanes
}

/// `ptr` as handed to Embree, after checking it has `align` bytes of alignment; a misaligned pointer panics with
/// what it was (every machine checks, not only those whose wide loads would fault).
#[inline(always)]
#[track_caller]
pub fn aligned<T>(ptr: *const T, align: usize, what: &str) -> *const T {
    assert!((ptr as usize).is_multiple_of(align), "Embree needs {what} aligned to {align} bytes, got address {ptr:p}");
    ptr
}

/// [`aligned`] for a pointer Embree writes through.
#[inline(always)]
#[track_caller]
pub fn aligned_mut<T>(ptr: *mut T, align: usize, what: &str) -> *mut T {
    aligned(ptr.cast_const(), align, what).cast_mut()
}

/// `struct RTCRay`: one ray (48 bytes, align 16).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// `struct RTCHit` of Embree 4.3+ (48 bytes, align 16): includes `instPrimID`, which the library writes.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: u32,
    pub geomID: u32,
    pub instID: [u32; 1],
    pub instPrimID: [u32; 1],
}

/// `struct RTCRayHit`: a ray and its hit (96 bytes, align 16).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// `struct RTCRayN` (N = 8 or 16): N rays as structure of arrays, each field `[T; N]`, N × 48 bytes. Embree aligns
/// the C struct to N × 4 bytes; here the packets [`RTCRayHit8`] and [`RTCRayHit16`] carry that alignment, and this
/// part sits at their offset 0 (its size is a multiple of the alignment, so the hit part is aligned too).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayN<const N: usize> {
    pub org_x: [f32; N],
    pub org_y: [f32; N],
    pub org_z: [f32; N],
    pub tnear: [f32; N],
    pub dir_x: [f32; N],
    pub dir_y: [f32; N],
    pub dir_z: [f32; N],
    pub time: [f32; N],
    pub tfar: [f32; N],
    pub mask: [u32; N],
    pub id: [u32; N],
    pub flags: [u32; N],
}

impl<const N: usize> RTCRayN<N> {
    /// N inactive lanes: harmless, well-formed rays (`tfar` = -inf, so nothing can be hit).
    pub const INACTIVE: Self = Self {
        org_x: [0.0; N],
        org_y: [0.0; N],
        org_z: [0.0; N],
        tnear: [0.0; N],
        dir_x: [0.0; N],
        dir_y: [0.0; N],
        dir_z: [1.0; N],
        time: [0.0; N],
        tfar: [-f32::INFINITY; N],
        mask: [u32::MAX; N],
        id: [0; N],
        flags: [0; N],
    };
}

/// `struct RTCHitN` (N = 8 or 16) of Embree 4.3+: N hits as structure of arrays, N × 36 bytes, with `instPrimID`
/// (see [`RTCRayN`] for the alignment).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCHitN<const N: usize> {
    pub Ng_x: [f32; N],
    pub Ng_y: [f32; N],
    pub Ng_z: [f32; N],
    pub u: [f32; N],
    pub v: [f32; N],
    pub primID: [u32; N],
    pub geomID: [u32; N],
    pub instID: [[u32; N]; 1],
    pub instPrimID: [[u32; N]; 1],
}

impl<const N: usize> RTCHitN<N> {
    /// N empty hits (`geomID` = `RTC_INVALID_GEOMETRY_ID`).
    pub const EMPTY: Self = Self {
        Ng_x: [0.0; N],
        Ng_y: [0.0; N],
        Ng_z: [0.0; N],
        u: [0.0; N],
        v: [0.0; N],
        primID: [RTC_INVALID_GEOMETRY_ID; N],
        geomID: [RTC_INVALID_GEOMETRY_ID; N],
        instID: [[RTC_INVALID_GEOMETRY_ID; N]],
        instPrimID: [[RTC_INVALID_GEOMETRY_ID; N]],
    };
}

/// `struct RTCRay8` (384 bytes; aligned to 32 inside [`RTCRayHit8`]).
pub type RTCRay8 = RTCRayN<8>;
/// `struct RTCHit8` (288 bytes; aligned to 32 inside [`RTCRayHit8`]).
pub type RTCHit8 = RTCHitN<8>;
/// `struct RTCRay16` (768 bytes; aligned to 64 inside [`RTCRayHit16`]).
pub type RTCRay16 = RTCRayN<16>;
/// `struct RTCHit16` (576 bytes; aligned to 64 inside [`RTCRayHit16`]).
pub type RTCHit16 = RTCHitN<16>;

/// `struct RTCRayHit8`: 8 rays and their hits (672 bytes, align 32), what `rtcIntersect8` takes.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit8 {
    pub ray: RTCRay8,
    pub hit: RTCHit8,
}

/// `struct RTCRayHit16`: 16 rays and their hits (1344 bytes, align 64), what `rtcIntersect16` takes.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit16 {
    pub ray: RTCRay16,
    pub hit: RTCHit16,
}

/// A packet `RTCRayHitN` of N lanes, aligned as `rtcIntersectN` requires: what the width-generic query code fills
/// and reads.
pub trait RTCRayHitN<const N: usize>: Copy {
    /// The `valid` mask type of this width ([`ValidMask8`], [`ValidMask16`]).
    type Valid: Copy;
    /// N inactive lanes and empty hits.
    const INACTIVE: Self;
    /// A mask with every lane inactive.
    const NO_LANES: Self::Valid;
    /// The lanes of a mask.
    fn lanes(valid: &mut Self::Valid) -> &mut [c_int; N];
    /// The rays, to fill the active lanes.
    fn ray_mut(&mut self) -> &mut RTCRayN<N>;
    /// The rays (`tfar` is the hit distance after the query) and their hits.
    fn parts(&self) -> (&RTCRayN<N>, &RTCHitN<N>);
}

macro_rules! ray_hit_n {
    ($($packet:ident, $valid:ident = $n:literal),+) => {$(
        impl RTCRayHitN<$n> for $packet {
            type Valid = $valid;
            const INACTIVE: Self = Self { ray: RTCRayN::INACTIVE, hit: RTCHitN::EMPTY };
            const NO_LANES: $valid = $valid([LANE_INACTIVE; $n]);
            #[inline(always)]
            fn lanes(valid: &mut $valid) -> &mut [c_int; $n] {
                &mut valid.0
            }
            #[inline(always)]
            fn ray_mut(&mut self) -> &mut RTCRayN<$n> {
                &mut self.ray
            }
            #[inline(always)]
            fn parts(&self) -> (&RTCRayN<$n>, &RTCHitN<$n>) {
                (&self.ray, &self.hit)
            }
        }
    )+};
}

ray_hit_n!(RTCRayHit8, ValidMask8 = 8, RTCRayHit16, ValidMask16 = 16);

/// `struct RTCIntersectArguments` (32 bytes); `RTCOccludedArguments` has the same layout.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCIntersectArguments {
    pub flags: u32,
    pub feature_mask: u32,
    pub context: *mut c_void,
    pub filter: *const c_void,
    pub intersect: *const c_void,
}

/// `struct RTCOccludedArguments` (32 bytes).
pub type RTCOccludedArguments = RTCIntersectArguments;

const _: () = assert!(size_of::<RTCRay>() == 48 && align_of::<RTCRay>() == 16);
const _: () = assert!(size_of::<RTCHit>() == 48 && align_of::<RTCHit>() == 16);
const _: () = assert!(size_of::<RTCRayHit>() == 96 && align_of::<RTCRayHit>() == 16);
const _: () = assert!(std::mem::offset_of!(RTCRayHit, hit) == 48);
const _: () = assert!(std::mem::offset_of!(RTCHit, instPrimID) == 32);
const _: () = assert!(size_of::<RTCRay8>() == 384 && size_of::<RTCHit8>() == 288);
const _: () = assert!(size_of::<RTCRayHit8>() == 384 + 288 && align_of::<RTCRayHit8>() == 32);
const _: () = assert!(std::mem::offset_of!(RTCRayHit8, hit) == 384);
const _: () = assert!(std::mem::offset_of!(RTCHit8, instPrimID) == 8 * 32);
const _: () = assert!(size_of::<RTCRay16>() == 768 && size_of::<RTCHit16>() == 576);
const _: () = assert!(size_of::<RTCRayHit16>() == 768 + 576 && align_of::<RTCRayHit16>() == 64);
const _: () = assert!(std::mem::offset_of!(RTCRayHit16, hit) == 768);
const _: () = assert!(std::mem::offset_of!(RTCHit16, instPrimID) == 16 * 32);
const _: () = assert!(size_of::<RTCIntersectArguments>() == 32 && align_of::<RTCIntersectArguments>() == 8);
const _: () = assert!(align_of::<ValidMask8>() == packet_alignment(8) && size_of::<ValidMask8>() == 32);
const _: () = assert!(align_of::<ValidMask16>() == packet_alignment(16) && size_of::<ValidMask16>() == 64);
const _: () =
    assert!(align_of::<RTCRayHit8>() == packet_alignment(8) && align_of::<RTCRayHit16>() == packet_alignment(16));

/// `RTCErrorFunction`: `void (*)(void* userPtr, RTCError code, const char* str)`.
pub type RTCErrorFunction = unsafe extern "C" fn(user: *mut c_void, code: u32, message: *const c_char);

/// `rtcNewDevice`.
pub type FnNewDevice = unsafe extern "C" fn(config: *const c_char) -> RTCDevice;
/// `rtcReleaseDevice`.
pub type FnReleaseDevice = unsafe extern "C" fn(device: RTCDevice);
/// `rtcGetDeviceError`.
pub type FnGetDeviceError = unsafe extern "C" fn(device: RTCDevice) -> u32;
/// `rtcGetDeviceLastErrorMessage`.
pub type FnGetDeviceLastErrorMessage = unsafe extern "C" fn(device: RTCDevice) -> *const c_char;
/// `rtcSetDeviceErrorFunction`.
pub type FnSetDeviceErrorFunction =
    unsafe extern "C" fn(device: RTCDevice, function: Option<RTCErrorFunction>, user: *mut c_void);
/// `RTCMemoryMonitorFunction`: `bool (*)(void* userPtr, ssize_t bytes, bool post)`: called with `+bytes` before
/// Embree allocates and `-bytes` after it frees; returning `false` cancels the allocation. `ssize_t` is `isize` on
/// every target the harness builds for (LP64 Linux), and C's `bool` is Rust's `bool` (one byte, 0 or 1).
pub type RTCMemoryMonitorFunction = unsafe extern "C" fn(user: *mut c_void, bytes: isize, post: bool) -> bool;
/// `rtcSetDeviceMemoryMonitorFunction`.
pub type FnSetDeviceMemoryMonitorFunction =
    unsafe extern "C" fn(device: RTCDevice, function: Option<RTCMemoryMonitorFunction>, user: *mut c_void);
/// `rtcGetDeviceProperty`.
pub type FnGetDeviceProperty = unsafe extern "C" fn(device: RTCDevice, property: u32) -> isize;
/// `rtcNewScene`.
pub type FnNewScene = unsafe extern "C" fn(device: RTCDevice) -> RTCScene;
/// `rtcReleaseScene`.
pub type FnReleaseScene = unsafe extern "C" fn(scene: RTCScene);
/// `rtcSetSceneBuildQuality`.
pub type FnSetSceneBuildQuality = unsafe extern "C" fn(scene: RTCScene, quality: u32);
/// `rtcSetSceneFlags`.
pub type FnSetSceneFlags = unsafe extern "C" fn(scene: RTCScene, flags: u32);
/// `rtcCommitScene`.
pub type FnCommitScene = unsafe extern "C" fn(scene: RTCScene);
/// `rtcNewGeometry`.
pub type FnNewGeometry = unsafe extern "C" fn(device: RTCDevice, kind: u32) -> RTCGeometry;
/// `rtcSetNewGeometryBuffer`.
pub type FnSetNewGeometryBuffer = unsafe extern "C" fn(
    geometry: RTCGeometry,
    kind: u32,
    slot: c_uint,
    format: u32,
    byte_stride: usize,
    item_count: usize,
) -> *mut c_void;
/// `rtcCommitGeometry`.
pub type FnCommitGeometry = unsafe extern "C" fn(geometry: RTCGeometry);
/// `rtcAttachGeometry`.
pub type FnAttachGeometry = unsafe extern "C" fn(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
/// `rtcReleaseGeometry`.
pub type FnReleaseGeometry = unsafe extern "C" fn(geometry: RTCGeometry);
/// `rtcIntersect1`.
pub type FnIntersect1 = unsafe extern "C" fn(scene: RTCScene, rayhit: *mut RTCRayHit, args: *mut RTCIntersectArguments);
/// `rtcOccluded1`.
pub type FnOccluded1 = unsafe extern "C" fn(scene: RTCScene, ray: *mut RTCRay, args: *mut RTCOccludedArguments);
/// `rtcIntersect8` / `rtcIntersect16` on the packet type `P` (`valid`: one `c_int` per lane).
pub type FnIntersectN<P> =
    unsafe extern "C" fn(valid: *const c_int, scene: RTCScene, rayhit: *mut P, args: *mut RTCIntersectArguments);
/// `rtcIntersect8`.
pub type FnIntersect8 = FnIntersectN<RTCRayHit8>;
/// `rtcIntersect16`.
pub type FnIntersect16 = FnIntersectN<RTCRayHit16>;

/// Opaque `RTCBVH` handle (the builder API's BVH object: owns what its thread-local allocators hand out).
pub type RTCBVH = *mut c_void;
/// Opaque `RTCThreadLocalAllocator` handle, passed to the builder's node and leaf callbacks.
pub type RTCThreadLocalAllocator = *mut c_void;

/// `struct RTCBounds` (32 bytes, align 16): a box, with a padding float after each corner.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RTCBounds {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub align0: f32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub align1: f32,
}

/// `struct RTCBuildPrimitive` (32 bytes, align 32): a primitive's box and its ids, what `rtcBuildBVH` sorts.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RTCBuildPrimitive {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub geomID: u32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub primID: u32,
}

/// `RTCCreateNodeFunction`: a new inner node of `child_count` children.
pub type RTCCreateNodeFunction =
    unsafe extern "C" fn(alloc: RTCThreadLocalAllocator, child_count: c_uint, user: *mut c_void) -> *mut c_void;
/// `RTCSetNodeChildrenFunction`: the node's children, once built.
pub type RTCSetNodeChildrenFunction =
    unsafe extern "C" fn(node: *mut c_void, children: *mut *mut c_void, child_count: c_uint, user: *mut c_void);
/// `RTCSetNodeBoundsFunction`: the boxes of the node's children.
pub type RTCSetNodeBoundsFunction =
    unsafe extern "C" fn(node: *mut c_void, bounds: *const *const RTCBounds, child_count: c_uint, user: *mut c_void);
/// `RTCCreateLeafFunction`: a leaf over `count` primitives.
pub type RTCCreateLeafFunction = unsafe extern "C" fn(
    alloc: RTCThreadLocalAllocator,
    prims: *const RTCBuildPrimitive,
    count: usize,
    user: *mut c_void,
) -> *mut c_void;
/// `RTCSplitPrimitiveFunction`: the boxes of a primitive's parts on either side of the plane `dim = pos`.
pub type RTCSplitPrimitiveFunction = unsafe extern "C" fn(
    prim: *const RTCBuildPrimitive,
    dim: c_uint,
    pos: f32,
    left: *mut RTCBounds,
    right: *mut RTCBounds,
    user: *mut c_void,
);
/// `RTCProgressMonitorFunction`.
pub type RTCProgressMonitorFunction = unsafe extern "C" fn(user: *mut c_void, n: f64) -> bool;

/// `struct RTCBuildArguments` (136 bytes): `rtcDefaultBuildArguments` is an inline header function, not exported,
/// so every field is filled by the caller.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCBuildArguments {
    pub byteSize: usize,
    pub buildQuality: u32,
    pub buildFlags: u32,
    pub maxBranchingFactor: c_uint,
    pub maxDepth: c_uint,
    pub sahBlockSize: c_uint,
    pub minLeafSize: c_uint,
    pub maxLeafSize: c_uint,
    pub traversalCost: f32,
    pub intersectionCost: f32,
    pub bvh: RTCBVH,
    pub primitives: *mut RTCBuildPrimitive,
    pub primitiveCount: usize,
    pub primitiveArrayCapacity: usize,
    pub createNode: Option<RTCCreateNodeFunction>,
    pub setNodeChildren: Option<RTCSetNodeChildrenFunction>,
    pub setNodeBounds: Option<RTCSetNodeBoundsFunction>,
    pub createLeaf: Option<RTCCreateLeafFunction>,
    pub splitPrimitive: Option<RTCSplitPrimitiveFunction>,
    pub buildProgress: Option<RTCProgressMonitorFunction>,
    pub userPtr: *mut c_void,
}

const _: () = assert!(size_of::<RTCBounds>() == 32 && align_of::<RTCBounds>() == 16);
const _: () = assert!(size_of::<RTCBuildPrimitive>() == 32 && align_of::<RTCBuildPrimitive>() == 32);
const _: () = assert!(size_of::<RTCBuildArguments>() == 136 && std::mem::offset_of!(RTCBuildArguments, bvh) == 48);
const _: () = assert!(std::mem::offset_of!(RTCBuildArguments, createNode) == 80);

/// `rtcNewBVH`.
pub type FnNewBvh = unsafe extern "C" fn(device: RTCDevice) -> RTCBVH;
/// `rtcBuildBVH`: the root node or leaf (null on error).
pub type FnBuildBvh = unsafe extern "C" fn(args: *const RTCBuildArguments) -> *mut c_void;
/// `rtcThreadLocalAlloc`: memory owned by the BVH, freed by `rtcReleaseBVH`.
pub type FnThreadLocalAlloc =
    unsafe extern "C" fn(alloc: RTCThreadLocalAllocator, bytes: usize, align: usize) -> *mut c_void;
/// `rtcReleaseBVH`.
pub type FnReleaseBvh = unsafe extern "C" fn(bvh: RTCBVH);
