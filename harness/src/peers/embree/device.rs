//! An Embree device: its configuration string, error capture and what it reports about itself.

use std::ffi::{CStr, CString, c_char, c_void};
use std::fmt;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

pub use schema::EmbreeQuality;
use serde::{Deserialize, Serialize};

use super::abi::*;
use super::library::{EmbreeLibrary, EmbreeUnavailable};

/// Embree's `RTC_BUILD_QUALITY_*` value of a build quality.
pub(super) fn build_quality(quality: EmbreeQuality) -> u32 {
    match quality {
        EmbreeQuality::Low => RTC_BUILD_QUALITY_LOW,
        EmbreeQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
        EmbreeQuality::High => RTC_BUILD_QUALITY_HIGH,
    }
}

/// How to create a device.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EmbreeConfig {
    /// Build threads (`threads=N`); TBB applies the largest value over all live devices to the whole process.
    pub threads: Option<usize>,
    /// Instruction set to pin (`isa=`, e.g. `sse4.2`, `avx2`, `avx512`); `None` lets Embree pick the best.
    pub isa: Option<String>,
    /// The build quality the harness passes to [`super::EmbreeSpheres::build`].
    pub quality: EmbreeQuality,
}

impl EmbreeConfig {
    /// The device configuration string, e.g. `threads=1,isa=avx2`.
    pub fn config_string(&self) -> String {
        let mut parts = Vec::new();
        if let Some(t) = self.threads {
            parts.push(format!("threads={t}"));
        }
        if let Some(isa) = &self.isa {
            parts.push(format!("isa={isa}"));
        }
        parts.join(",")
    }
}

/// A device could not be made or a scene could not be built.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EmbreeError {
    /// The library was not found.
    Unavailable(EmbreeUnavailable),
    /// Embree reported an error (its code and message).
    Api(String),
    /// The input cannot be handed to Embree (e.g. a triangle indexing past the vertices).
    Input(String),
}

impl fmt::Display for EmbreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EmbreeError::Unavailable(e) => e.fmt(f),
            EmbreeError::Api(msg) => write!(f, "Embree error: {msg}"),
            EmbreeError::Input(msg) => write!(f, "invalid input for Embree: {msg}"),
        }
    }
}

impl std::error::Error for EmbreeError {}

impl From<EmbreeUnavailable> for EmbreeError {
    fn from(e: EmbreeUnavailable) -> Self {
        EmbreeError::Unavailable(e)
    }
}

/// What a device reports about itself, recorded with every Embree run.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// The library file it came from.
    pub path: String,
    /// `RTC_DEVICE_PROPERTY_VERSION` as `major.minor.patch`.
    pub version: String,
    /// The configuration string the device was created with.
    pub config: String,
    /// Widest native packet the device's ISA runs (16: AVX-512, 8: AVX/AVX2, 4: SSE); Embree reports this
    /// after applying `isa=`, so it is the only ISA evidence available without parsing `verbose=1` output.
    pub native_packet: u32,
    /// Tasking system (`internal`, `tbb` or `ppl`).
    pub tasking: String,
}

/// Shared state of a device; scenes hold an `Arc` of it so the device and library outlive them.
pub(super) struct DeviceInner {
    pub(super) lib: Arc<EmbreeLibrary>,
    pub(super) raw: RTCDevice,
    /// The last error the callback reported; boxed so its address (the callback's user pointer) is stable.
    errors: Box<Mutex<Option<String>>>,
    /// Bytes Embree holds on this device (allocations net of frees), kept by [`monitor_memory`], registered once
    /// per device; boxed so its address (the callback's user pointer) is stable.
    memory: Box<AtomicI64>,
    /// Held around every change to the device's memory that a measurement reads (a scene's build, a scene's
    /// release), so that one scene's measured bytes are not another's.
    measuring: Mutex<()>,
    pub(super) info: DeviceInfo,
}

// SAFETY: Embree devices are thread safe (any thread may create scenes on them or release them); the error
// slot is a Mutex, and the library handle is immutable after loading.
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send`; no method takes `&mut`.
unsafe impl Sync for DeviceInner {}

impl DeviceInner {
    /// Takes the error the callback captured since the last call, if any.
    pub(super) fn take_error(&self) -> Option<String> {
        self.errors.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    /// Bytes Embree's memory monitor reports the device holds now (allocations net of frees).
    pub(super) fn memory_bytes(&self) -> i64 {
        self.memory.load(Ordering::SeqCst)
    }

    /// Holds off other scenes' builds and releases on this device while one is measured.
    pub(super) fn measuring(&self) -> MutexGuard<'_, ()> {
        self.measuring.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` came from rtcNewDevice and is released once; every scene holding it is already dropped.
        unsafe { (self.lib.api.release_device)(self.raw) };
    }
}

unsafe extern "C" fn capture_error(user: *mut c_void, code: u32, message: *const c_char) {
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for the call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    // SAFETY: `user` is the `Mutex` boxed in `DeviceInner`, alive as long as the device.
    let slot = unsafe { &*(user as *const Mutex<Option<String>>) };
    *slot.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{} (code {code})", text.trim()));
}

/// Embree's memory monitor (`RTCMemoryMonitorFunction`): adds `bytes` (+ before an allocation, − after a free)
/// to the device's counter and allows every allocation. Embree calls it from its TBB build threads at once, hence
/// the atomic; it cannot panic, so nothing unwinds into C.
unsafe extern "C" fn monitor_memory(user: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: `user` is the `AtomicI64` boxed in `DeviceInner`, alive as long as the device (released in its Drop,
    // before the box is freed).
    let counter = unsafe { &*(user as *const AtomicI64) };
    counter.fetch_add(bytes as i64, Ordering::SeqCst);
    true
}

/// An Embree device (cheap to clone: all clones share one device).
#[derive(Clone)]
pub struct EmbreeDevice {
    pub(super) inner: Arc<DeviceInner>,
}

impl fmt::Debug for EmbreeDevice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbreeDevice").field("info", &self.inner.info).finish_non_exhaustive()
    }
}

impl EmbreeDevice {
    /// A device from the process-wide library ([`EmbreeLibrary::shared`]).
    pub fn new(config: &EmbreeConfig) -> Result<Self, EmbreeError> {
        Self::with_library(EmbreeLibrary::shared()?, config)
    }

    /// A device from an explicitly loaded library.
    pub fn with_library(lib: Arc<EmbreeLibrary>, config: &EmbreeConfig) -> Result<Self, EmbreeError> {
        let api = lib.api;
        let text = config.config_string();
        let c_text = CString::new(text.clone()).map_err(|_| EmbreeError::Api("NUL in device config".into()))?;
        // SAFETY: a valid C string; a null result is handled below.
        let raw = unsafe { (api.new_device)(c_text.as_ptr()) };
        if raw.is_null() {
            // SAFETY: rtcGetDeviceError(NULL) reports the error of the failed rtcNewDevice.
            let code = unsafe { (api.get_device_error)(std::ptr::null_mut()) };
            // SAFETY: as above; the message pointer is NUL-terminated or null.
            let msg = unsafe { (api.get_device_last_error_message)(std::ptr::null_mut()) };
            let msg = if msg.is_null() {
                String::new()
            } else {
                unsafe { CStr::from_ptr(msg) }.to_string_lossy().into_owned()
            };
            return Err(EmbreeError::Api(format!("rtcNewDevice(\"{text}\") failed: {} (code {code})", msg.trim())));
        }
        let property = |p: u32| -> isize {
            // SAFETY: a live device and a property id from the headers.
            unsafe { (api.get_device_property)(raw, p) }
        };
        let v = property(RTC_DEVICE_PROPERTY_VERSION);
        let native_packet = if property(RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0 {
            16
        } else if property(RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0 {
            8
        } else if property(RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED) != 0 {
            4
        } else {
            1
        };
        let tasking = match property(RTC_DEVICE_PROPERTY_TASKING_SYSTEM) {
            0 => "internal".to_string(),
            1 => "tbb".to_string(),
            2 => "ppl".to_string(),
            n => format!("unknown ({n})"),
        };
        let info = DeviceInfo {
            path: lib.path.clone(),
            version: format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100),
            config: text,
            native_packet,
            tasking,
        };
        let inner = DeviceInner {
            lib,
            raw,
            errors: Box::new(Mutex::new(None)),
            memory: Box::new(AtomicI64::new(0)),
            measuring: Mutex::new(()),
            info,
        };
        if !(40000..50000).contains(&v) {
            return Err(EmbreeError::Api(format!(
                "{} is Embree {}, not Embree 4",
                inner.info.path, inner.info.version
            )));
        }
        let user = &*inner.errors as *const Mutex<Option<String>> as *mut c_void;
        // SAFETY: the callback matches RTCErrorFunction; `user` stays valid until the device is released.
        unsafe { (api.set_device_error_function)(raw, Some(capture_error), user) };
        let user = &*inner.memory as *const AtomicI64 as *mut c_void;
        // SAFETY: the callback matches RTCMemoryMonitorFunction (checked against the ABI notes) and is thread safe;
        // `user` stays valid until the device is released. Registered before any scene exists, so every
        // allocation of the device's scenes is counted.
        unsafe { (api.set_device_memory_monitor_function)(raw, Some(monitor_memory), user) };
        Ok(Self { inner: Arc::new(inner) })
    }

    /// What the device reports about itself.
    pub fn info(&self) -> &DeviceInfo {
        &self.inner.info
    }
}
