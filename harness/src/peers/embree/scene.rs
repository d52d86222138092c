//! A committed Embree scene of sphere points: single-ray and 8- and 16-wide packet queries.

use std::ffi::c_int;
use std::sync::Arc;

use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};

use super::abi::*;
use super::device::{DeviceInfo, DeviceInner, EmbreeDevice, EmbreeError, EmbreeQuality};

/// Our spheres as one Embree `RTC_GEOMETRY_TYPE_SPHERE_POINT` geometry (geomID 0) in a committed scene.
pub struct EmbreeSpheres {
    device: Arc<DeviceInner>,
    scene: RTCScene,
    count: usize,
}

// SAFETY: a committed Embree scene is immutable and Embree documents concurrent rtcIntersect*/rtcOccluded*
// calls on it from any number of threads as safe; the handle is only released in Drop (exclusive access).
unsafe impl Send for EmbreeSpheres {}
// SAFETY: see `Send`; queries take `&self` and only read the scene.
unsafe impl Sync for EmbreeSpheres {}

impl std::fmt::Debug for EmbreeSpheres {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmbreeSpheres").field("spheres", &self.count).finish_non_exhaustive()
    }
}

impl Drop for EmbreeSpheres {
    fn drop(&mut self) {
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

impl EmbreeSpheres {
    /// Builds (commits) the scene; Embree errors reported during the build become `Err`.
    ///
    /// The commit runs on TBB's pool, not rayon's: do not build while rayon traces, or the pools oversubscribe.
    pub fn build(device: &EmbreeDevice, spheres: &[Sphere], quality: EmbreeQuality) -> Result<Self, EmbreeError> {
        let inner = device.inner.clone();
        let api = inner.lib.api;
        inner.take_error();
        // SAFETY: a live device.
        let scene = unsafe { (api.new_scene)(inner.raw) };
        if scene.is_null() {
            let why = inner.take_error().unwrap_or_else(|| "rtcNewScene returned null".into());
            return Err(EmbreeError::Api(why));
        }
        // From here on `Drop` releases the scene on every path.
        let this = Self { device: inner, scene, count: spheres.len() };
        // SAFETY: a live scene and enum values from the headers.
        unsafe {
            (api.set_scene_build_quality)(scene, super::device::build_quality(quality));
            (api.set_scene_flags)(scene, RTC_SCENE_FLAG_NONE);
        }
        if !spheres.is_empty() {
            this.attach_spheres(spheres)?;
        }
        // SAFETY: a live scene; this is the BVH build.
        unsafe { (api.commit_scene)(scene) };
        match this.device.take_error() {
            Some(why) => Err(EmbreeError::Api(why)),
            None => Ok(this),
        }
    }

    fn attach_spheres(&self, spheres: &[Sphere]) -> Result<(), EmbreeError> {
        let api = self.device.lib.api;
        // SAFETY: a live device and a geometry type from the headers.
        let geometry = unsafe { (api.new_geometry)(self.device.raw, RTC_GEOMETRY_TYPE_SPHERE_POINT) };
        if geometry.is_null() {
            return Err(EmbreeError::Api(self.device.take_error().unwrap_or_else(|| "rtcNewGeometry failed".into())));
        }
        // One FLOAT4 (x, y, z, r) per sphere, in a buffer Embree allocates (and pads for 16-byte loads) and owns.
        // SAFETY: a live geometry; stride 16 and `len` items of FLOAT4.
        let buffer = unsafe {
            (api.set_new_geometry_buffer)(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 16, spheres.len())
        } as *mut [f32; 4];
        let result = if buffer.is_null() {
            Err(EmbreeError::Api(self.device.take_error().unwrap_or_else(|| "rtcSetNewGeometryBuffer failed".into())))
        } else {
            let buffer = aligned_mut(buffer, 16, "the FLOAT4 vertex buffer Embree returned");
            // SAFETY: Embree returned a writable buffer of `len` FLOAT4 items, 16-byte aligned (checked).
            let items = unsafe { std::slice::from_raw_parts_mut(buffer, spheres.len()) };
            for (item, s) in items.iter_mut().zip(spheres) {
                *item = [s.center.x, s.center.y, s.center.z, s.radius];
            }
            // SAFETY: a live geometry and scene; the scene keeps its own reference after attaching.
            unsafe {
                (api.commit_geometry)(geometry);
                (api.attach_geometry)(self.scene, geometry);
            }
            Ok(())
        };
        // SAFETY: drops our reference; the scene (if attached) holds the geometry from now on.
        unsafe { (api.release_geometry)(geometry) };
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

impl Accelerator for EmbreeSpheres {
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

    /// Embree does not expose its tree: only the input bytes are known (nodes, depth and SAH report 0).
    fn stats(&self) -> TreeStats {
        TreeStats { nodes: 0, leaves: 0, depth: 0, bytes: self.count * 16, sah_cost: 0.0 }
    }
}
