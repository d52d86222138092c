//! Committed Embree scenes of one geometry each — sphere points ([`EmbreeSpheres`]) or triangles
//! ([`EmbreeTriangles`]) — with single-ray and 8- and 16-wide packet queries.
//!
//! Both are one type, [`EmbreeScene`], generic over an [`EmbreeGeometry`]: scene creation, commit, error
//! capture and every query are shared; the two differ only in the geometry they attach.

use std::ffi::c_int;
use std::marker::PhantomData;
use std::sync::Arc;

use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};
use tracer::scene::mesh::Mesh;

use super::abi::*;
use super::device::{DeviceInfo, DeviceInner, EmbreeDevice, EmbreeError, EmbreeQuality};

/// One kind of Embree geometry: what a scene of it is built from and how its buffers are filled.
pub trait EmbreeGeometry {
    /// What the scene is built from.
    type Input: ?Sized;
    /// The scene type's name, for `Debug`.
    const NAME: &'static str;
    /// Embree's `RTCGeometryType`.
    const TYPE: u32;
    /// Primitives in `input` (none: the scene is committed empty, no geometry attached).
    fn count(input: &Self::Input) -> usize;
    /// Bytes of the input as Embree's buffers hold it (the least [`EmbreeScene::input_bytes`] can be).
    fn bytes(input: &Self::Input) -> usize;
    /// Fills the buffers of a new geometry of type [`EmbreeGeometry::TYPE`] from `input`.
    fn fill(geometry: &mut NewGeometry<'_>, input: &Self::Input) -> Result<(), EmbreeError>;
}

/// Spheres as `RTC_GEOMETRY_TYPE_SPHERE_POINT`: one FLOAT4 vertex (x, y, z, radius) per sphere.
#[derive(Debug)]
pub enum SpherePoints {}

impl EmbreeGeometry for SpherePoints {
    type Input = [Sphere];
    const NAME: &'static str = "EmbreeSpheres";
    const TYPE: u32 = RTC_GEOMETRY_TYPE_SPHERE_POINT;

    fn count(spheres: &[Sphere]) -> usize {
        spheres.len()
    }

    fn bytes(spheres: &[Sphere]) -> usize {
        spheres.len() * 16
    }

    fn fill(geometry: &mut NewGeometry<'_>, spheres: &[Sphere]) -> Result<(), EmbreeError> {
        let items = geometry.buffer::<[f32; 4]>(RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT4, spheres.len(), "FLOAT4")?;
        for (item, s) in items.iter_mut().zip(spheres) {
            *item = [s.center.x, s.center.y, s.center.z, s.radius];
        }
        Ok(())
    }
}

/// A triangle mesh as `RTC_GEOMETRY_TYPE_TRIANGLE`: a FLOAT3 vertex buffer and a UINT3 index buffer.
#[derive(Debug)]
pub enum Triangles {}

impl EmbreeGeometry for Triangles {
    type Input = Mesh;
    const NAME: &'static str = "EmbreeTriangles";
    const TYPE: u32 = RTC_GEOMETRY_TYPE_TRIANGLE;

    fn count(mesh: &Mesh) -> usize {
        mesh.indices.len()
    }

    fn bytes(mesh: &Mesh) -> usize {
        mesh.positions.len() * 12 + mesh.indices.len() * 12
    }

    /// Checks every index first: Embree does not, and would read past the vertex buffer.
    fn fill(geometry: &mut NewGeometry<'_>, mesh: &Mesh) -> Result<(), EmbreeError> {
        let n = mesh.positions.len();
        if let Some((i, t)) = mesh.indices.iter().enumerate().find(|(_, t)| t.iter().any(|&k| k as usize >= n)) {
            return Err(EmbreeError::Input(format!("triangle {i} {t:?} indexes past the mesh's {n} vertices")));
        }
        let vertices = geometry.buffer::<[f32; 3]>(RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, n, "FLOAT3")?;
        for (v, p) in vertices.iter_mut().zip(&mesh.positions) {
            *v = p.to_array();
        }
        let indices =
            geometry.buffer::<[u32; 3]>(RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, mesh.indices.len(), "UINT3")?;
        indices.copy_from_slice(&mesh.indices);
        Ok(())
    }
}

/// A geometry being filled: hands out buffers Embree allocates (padded for its 16-byte loads) and owns.
pub struct NewGeometry<'a> {
    device: &'a DeviceInner,
    raw: RTCGeometry,
}

impl NewGeometry<'_> {
    /// A new buffer of `count` items of `T` (`format`, stride `size_of::<T>()`) in slot 0 of `kind`, checked to
    /// be 16-byte aligned; `what` names it in errors.
    fn buffer<T: Copy>(&mut self, kind: u32, format: u32, count: usize, what: &str) -> Result<&mut [T], EmbreeError> {
        let api = self.device.lib.api;
        // SAFETY: a live geometry of a type taking this buffer kind and format; the stride is the item size.
        let buffer = unsafe { (api.set_new_geometry_buffer)(self.raw, kind, 0, format, size_of::<T>(), count) };
        if buffer.is_null() {
            let why = self.device.take_error().unwrap_or_else(|| "rtcSetNewGeometryBuffer returned null".into());
            return Err(EmbreeError::Api(format!("{what} buffer of {count} items: {why}")));
        }
        let buffer = aligned_mut(buffer.cast::<T>(), 16, &format!("the {what} buffer Embree returned"));
        // SAFETY: Embree returned a writable buffer of `count` items of this stride, aligned (checked) beyond
        // `T`'s alignment, that lives as long as the geometry (we hold `&mut self` of it).
        Ok(unsafe { std::slice::from_raw_parts_mut(buffer, count) })
    }
}

/// A committed Embree scene holding one geometry of kind `G` (geomID 0): [`EmbreeSpheres`] or
/// [`EmbreeTriangles`].
pub struct EmbreeScene<G> {
    device: Arc<DeviceInner>,
    scene: RTCScene,
    /// Primitives in the geometry.
    count: usize,
    /// Bytes Embree allocated during `rtcCommitScene`, net of what it freed by the end of it (its memory monitor):
    /// the acceleration structure, nodes and leaves with their triangle or sphere copies, not the input buffers.
    bytes: usize,
    /// Bytes Embree allocated for the geometry's input buffers before the commit.
    input_bytes: usize,
    geometry: PhantomData<fn() -> G>,
}

/// Our spheres as one Embree `RTC_GEOMETRY_TYPE_SPHERE_POINT` geometry in a committed scene.
pub type EmbreeSpheres = EmbreeScene<SpherePoints>;

/// A triangle mesh as one Embree `RTC_GEOMETRY_TYPE_TRIANGLE` geometry in a committed scene; hits report the
/// triangle's index.
pub type EmbreeTriangles = EmbreeScene<Triangles>;

// SAFETY: a committed Embree scene is immutable and Embree documents concurrent rtcIntersect*/rtcOccluded*
// calls on it from any number of threads as safe; the handle is only released in Drop (exclusive access).
unsafe impl<G> Send for EmbreeScene<G> {}
// SAFETY: see `Send`; queries take `&self` and only read the scene.
unsafe impl<G> Sync for EmbreeScene<G> {}

impl<G: EmbreeGeometry> std::fmt::Debug for EmbreeScene<G> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct(G::NAME).field("primitives", &self.count).finish_non_exhaustive()
    }
}

impl<G> Drop for EmbreeScene<G> {
    fn drop(&mut self) {
        let _measuring = self.device.measuring();
        // SAFETY: `scene` came from rtcNewScene and is released once; the device outlives it (we hold an Arc).
        unsafe { (self.device.lib.api.release_scene)(self.scene) };
    }
}

/// A ray in Embree's layout with an empty hit.
#[inline(always)]
pub fn ray_hit(ray: &Ray) -> RTCRayHit {
    RTCRayHit {
        ray: rtc_ray(ray),
        hit: RTCHit { geomID: RTC_INVALID_GEOMETRY_ID, instID: [RTC_INVALID_GEOMETRY_ID], ..RTCHit::default() },
    }
}

/// Our ray in Embree's layout: `t_min`, `t_max` become `tnear`, `tfar`.
#[inline(always)]
fn rtc_ray(ray: &Ray) -> RTCRay {
    RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: ray.t_min,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar: ray.t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl<G: EmbreeGeometry> EmbreeScene<G> {
    /// Builds (commits) the scene; Embree errors reported during the build become `Err`.
    ///
    /// The commit runs on TBB's pool, not rayon's: do not build while rayon traces, or the pools oversubscribe.
    pub fn build(device: &EmbreeDevice, input: &G::Input, quality: EmbreeQuality) -> Result<Self, EmbreeError> {
        let inner = device.inner.clone();
        let api = inner.lib.api;
        // No other scene of this device is built or released until the measurement is taken (released before
        // `this` can drop: its Drop takes the same lock).
        let guard = device.inner.measuring();
        inner.take_error();
        // SAFETY: a live device.
        let scene = unsafe { (api.new_scene)(inner.raw) };
        if scene.is_null() {
            let why = inner.take_error().unwrap_or_else(|| "rtcNewScene returned null".into());
            return Err(EmbreeError::Api(why));
        }
        // From here on `Drop` releases the scene on every path.
        let mut this =
            Self { device: inner, scene, count: G::count(input), bytes: 0, input_bytes: 0, geometry: PhantomData };
        let measured = (|| {
            // SAFETY: a live scene and enum values from the headers.
            unsafe {
                (api.set_scene_build_quality)(scene, super::device::build_quality(quality));
                (api.set_scene_flags)(scene, RTC_SCENE_FLAG_NONE);
            }
            let start = this.device.memory_bytes();
            if this.count > 0 {
                this.attach(input)?;
            }
            let committing = this.device.memory_bytes();
            // SAFETY: a live scene; this is the BVH build.
            unsafe { (api.commit_scene)(scene) };
            let committed = this.device.memory_bytes();
            if let Some(why) = this.device.take_error() {
                return Err(EmbreeError::Api(why));
            }
            let bytes = |from: i64, to: i64| usize::try_from(to - from).unwrap_or(0);
            Ok((bytes(start, committing), bytes(committing, committed)))
        })();
        drop(guard);
        (this.input_bytes, this.bytes) = measured?;
        Ok(this)
    }

    /// Bytes Embree allocated for its own copies of the input (the buffers of `rtcSetNewGeometryBuffer`), before
    /// the commit: not part of [`Accelerator::stats`]'s bytes.
    pub fn input_bytes(&self) -> usize {
        self.input_bytes
    }

    /// Creates a geometry of type `G`, fills it from `input`, commits it and attaches it to the scene.
    fn attach(&self, input: &G::Input) -> Result<(), EmbreeError> {
        let api = self.device.lib.api;
        // SAFETY: a live device and a geometry type from the headers.
        let raw = unsafe { (api.new_geometry)(self.device.raw, G::TYPE) };
        if raw.is_null() {
            return Err(EmbreeError::Api(self.device.take_error().unwrap_or_else(|| "rtcNewGeometry failed".into())));
        }
        let result = G::fill(&mut NewGeometry { device: &self.device, raw }, input);
        if result.is_ok() {
            // SAFETY: a live, filled geometry and a live scene; the scene keeps its own reference after attaching.
            unsafe {
                (api.commit_geometry)(raw);
                (api.attach_geometry)(self.scene, raw);
            }
        }
        // SAFETY: drops our reference; the scene (if attached) holds the geometry from now on.
        unsafe { (api.release_geometry)(raw) };
        result
    }

    /// The committed scene's handle and the library's functions, for code that calls Embree directly (the plain
    /// loop of `examples/embree_loop.rs`). The handle lives as long as `self`.
    pub fn raw(&self) -> (RTCScene, &super::library::Api) {
        (self.scene, &self.device.lib.api)
    }

    /// What the device that built this scene reports (version, configuration, native packet width).
    pub fn device_info(&self) -> &DeviceInfo {
        &self.device.info
    }

    /// Closest hits of up to 8 rays with one `rtcIntersect8` call; lanes past `rays.len()` are `None`.
    #[inline]
    pub fn intersect8(&self, rays: &[Ray]) -> [Option<Hit>; 8] {
        self.intersect_packet::<8, RTCRayHit8>(self.device.lib.api.intersect8, rays)
    }

    /// Closest hits of up to 16 rays with one `rtcIntersect16` call; lanes past `rays.len()` are `None`.
    #[inline]
    pub fn intersect16(&self, rays: &[Ray]) -> [Option<Hit>; 16] {
        self.intersect_packet::<16, RTCRayHit16>(self.device.lib.api.intersect16, rays)
    }

    /// Closest hits of up to N rays with one `rtcIntersectN` call (`query`), the packet on the stack.
    #[inline(always)]
    fn intersect_packet<const N: usize, P: RTCRayHitN<N>>(
        &self,
        query: FnIntersectN<P>,
        rays: &[Ray],
    ) -> [Option<Hit>; N] {
        let mut call = PacketCall::<N, P>::new(rays);
        let (valid, packet) = call.pointers();
        // SAFETY: a committed scene; the packet and its mask have the alignment `rtcIntersectN` requires (checked
        // by `pointers`), N lanes each, and are fully initialized; NULL arguments = defaults.
        unsafe { query(valid, self.scene, packet, std::ptr::null_mut()) };
        call.hits()
    }
}

/// The arguments of one `rtcIntersectN` call: the `valid` lane mask and the ray packet, each of the packet
/// width's alignment type.
pub(super) struct PacketCall<const N: usize, P: RTCRayHitN<N>> {
    valid: P::Valid,
    packet: P,
}

impl<const N: usize, P: RTCRayHitN<N>> PacketCall<N, P> {
    /// Up to N rays in the first lanes; the rest inactive, holding a harmless, well-formed ray.
    #[inline(always)]
    pub(super) fn new(rays: &[Ray]) -> Self {
        assert!(rays.len() <= N, "intersect{N} takes at most {N} rays, got {}", rays.len());
        let mut call = Self { valid: P::NO_LANES, packet: P::INACTIVE };
        let lanes = P::lanes(&mut call.valid);
        let r = call.packet.ray_mut();
        for (i, ray) in rays.iter().enumerate() {
            lanes[i] = LANE_ACTIVE;
            (r.org_x[i], r.org_y[i], r.org_z[i]) = (ray.origin.x, ray.origin.y, ray.origin.z);
            (r.dir_x[i], r.dir_y[i], r.dir_z[i]) = (ray.dir.x, ray.dir.y, ray.dir.z);
            (r.tnear[i], r.tfar[i]) = (ray.t_min, ray.t_max);
        }
        call
    }

    /// The mask and packet pointers to hand to `rtcIntersectN`, checked to be aligned to 4 × N bytes.
    #[inline(always)]
    pub(super) fn pointers(&mut self) -> (*const c_int, *mut P) {
        let align = packet_alignment(N);
        let valid = aligned(std::ptr::from_ref(&self.valid).cast::<c_int>(), align, "the valid lane mask");
        (valid, aligned_mut(&raw mut self.packet, align, "the ray packet"))
    }

    /// The hits of the active lanes after the call (`None` for misses and inactive lanes).
    #[inline(always)]
    fn hits(&mut self) -> [Option<Hit>; N] {
        let lanes = *P::lanes(&mut self.valid);
        let (ray, hit) = self.packet.parts();
        std::array::from_fn(|i| {
            (lanes[i] == LANE_ACTIVE && hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
                .then(|| Hit { t: ray.tfar[i], prim: hit.primID[i] })
        })
    }
}

impl<G> Accelerator for EmbreeScene<G> {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, _counters: &mut C) -> Option<Hit> {
        let mut rh = ray_hit(ray);
        let rh_ptr = aligned_mut(&raw mut rh, align_of::<RTCRayHit>(), "RTCRayHit");
        // SAFETY: a committed scene and an initialized RTCRayHit, aligned as checked; NULL arguments = defaults.
        unsafe { (self.device.lib.api.intersect1)(self.scene, rh_ptr, std::ptr::null_mut()) };
        (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID).then_some(Hit { t: rh.ray.tfar, prim: rh.hit.primID })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, _counters: &mut C) -> bool {
        let mut r = rtc_ray(ray);
        let r_ptr = aligned_mut(&raw mut r, align_of::<RTCRay>(), "RTCRay");
        // SAFETY: a committed scene and an initialized RTCRay, aligned as checked; NULL arguments = defaults.
        unsafe { (self.device.lib.api.occluded1)(self.scene, r_ptr, std::ptr::null_mut()) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Embree does not expose its tree (nodes, depth and SAH report 0); its bytes are what its memory monitor saw
    /// `rtcCommitScene` allocate net of frees: nodes and leaves (with Embree's copies of the primitives), not the
    /// input buffers, which were allocated before the commit.
    fn stats(&self) -> TreeStats {
        TreeStats { nodes: 0, leaves: 0, depth: 0, bytes: self.bytes, sah_cost: 0.0 }
    }
}
