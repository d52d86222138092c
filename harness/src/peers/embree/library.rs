//! Finding and loading the Embree 4 shared library at run time, and resolving its symbols once.
//!
//! Search order ([`SearchInputs::from_environment`]):
//! 1. `EMBREE_LIB`, a file path — when set, it is the only candidate (a user who names a library means it);
//! 2. the system's `libembree4.so.4`, by name through the dynamic loader's own search;
//! 3. an installed `embreex` wheel: `<site-packages>/embreex.libs/libembree4*.so*`, for every site-packages
//!    directory `python3` reports (purelib, platlib, `site.getsitepackages()`, `site.getusersitepackages()`).

use std::ffi::OsStr;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, OnceLock};

use libloading::Library;

use super::abi::*;

/// The pip command that installs a loadable Embree 4 (quoted in every "not found" message).
pub const INSTALL_HINT: &str = "python3 -m pip install embreex==4.4.0.post1";

/// Embree 4 could not be loaded from any candidate; `tried` says what was tried and why each failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EmbreeUnavailable {
    /// One entry per candidate: `what: why`.
    pub tried: Vec<String>,
}

impl fmt::Display for EmbreeUnavailable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tried = if self.tried.is_empty() { "nothing".to_string() } else { self.tried.join("; ") };
        // One line: loader messages may carry newlines.
        let tried = tried.replace(['\n', '\r'], " ");
        write!(
            f,
            "Embree 4 not found (tried {tried}); install it with `{INSTALL_HINT}` or set EMBREE_LIB to a libembree4.so file"
        )
    }
}

impl std::error::Error for EmbreeUnavailable {}

/// Where to look for the library; [`SearchInputs::from_environment`] fills it from `EMBREE_LIB` and `python3`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SearchInputs {
    /// An explicit library file (`EMBREE_LIB`); when set, nothing else is tried.
    pub explicit: Option<PathBuf>,
    /// Library names handed to the dynamic loader as they are.
    pub system_names: Vec<String>,
    /// site-packages directories that may hold `embreex.libs/`.
    pub site_dirs: Vec<PathBuf>,
    /// Why site-packages could not be listed, if it could not (reported among the tried candidates).
    pub site_error: Option<String>,
}

impl SearchInputs {
    /// The default search: `EMBREE_LIB`, then `libembree4.so.4`, then the site-packages `python3` reports.
    pub fn from_environment() -> Self {
        if let Some(path) = std::env::var_os("EMBREE_LIB").filter(|p| !p.is_empty()) {
            return Self { explicit: Some(PathBuf::from(path)), ..Self::default() };
        }
        let (site_dirs, site_error) = match python_site_dirs() {
            Ok(dirs) => (dirs, None),
            Err(e) => (Vec::new(), Some(e)),
        };
        Self { explicit: None, system_names: vec!["libembree4.so.4".to_string()], site_dirs, site_error }
    }
}

/// site-packages directories reported by `python3`, deduplicated, in its order.
fn python_site_dirs() -> Result<Vec<PathBuf>, String> {
    const SCRIPT: &str = "import site, sysconfig\n\
        p = sysconfig.get_paths()\n\
        dirs = [p.get('purelib'), p.get('platlib')]\n\
        dirs += getattr(site, 'getsitepackages', lambda: [])()\n\
        dirs.append(site.getusersitepackages())\n\
        print('\\n'.join(d for d in dirs if d))";
    let out = Command::new("python3").args(["-c", SCRIPT]).output().map_err(|e| format!("python3: {e}"))?;
    if !out.status.success() {
        return Err(format!("python3 site query failed ({})", out.status));
    }
    let mut dirs: Vec<PathBuf> = Vec::new();
    for line in String::from_utf8_lossy(&out.stdout).lines().map(str::trim).filter(|l| !l.is_empty()) {
        let d = PathBuf::from(line);
        if !dirs.contains(&d) {
            dirs.push(d);
        }
    }
    Ok(dirs)
}

/// Files in `dir` named `libembree4*.so*`, sorted (the wheel's name carries a hash; match by pattern).
fn embree_files_in(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            p.file_name().and_then(OsStr::to_str).is_some_and(|n| n.starts_with("libembree4") && n.contains(".so"))
        })
        .collect();
    found.sort();
    found
}

/// The resolved entry points: plain function pointers, valid while the owning [`EmbreeLibrary`] lives.
#[derive(Clone, Copy, Debug)]
pub struct Api {
    pub new_device: FnNewDevice,
    pub release_device: FnReleaseDevice,
    pub get_device_error: FnGetDeviceError,
    pub get_device_last_error_message: FnGetDeviceLastErrorMessage,
    pub set_device_error_function: FnSetDeviceErrorFunction,
    pub set_device_memory_monitor_function: FnSetDeviceMemoryMonitorFunction,
    pub get_device_property: FnGetDeviceProperty,
    pub new_scene: FnNewScene,
    pub release_scene: FnReleaseScene,
    pub set_scene_build_quality: FnSetSceneBuildQuality,
    pub set_scene_flags: FnSetSceneFlags,
    pub commit_scene: FnCommitScene,
    pub new_geometry: FnNewGeometry,
    pub set_new_geometry_buffer: FnSetNewGeometryBuffer,
    pub commit_geometry: FnCommitGeometry,
    pub attach_geometry: FnAttachGeometry,
    pub release_geometry: FnReleaseGeometry,
    pub intersect1: FnIntersect1,
    pub occluded1: FnOccluded1,
    pub intersect8: FnIntersect8,
    pub intersect16: FnIntersect16,
    pub new_bvh: FnNewBvh,
    pub build_bvh: FnBuildBvh,
    pub thread_local_alloc: FnThreadLocalAlloc,
    pub release_bvh: FnReleaseBvh,
}

impl Api {
    /// Resolves every symbol; `Err` names the first one missing.
    ///
    /// # Safety
    /// `lib` must be an Embree 4 library, so that each symbol has the type declared in [`super::abi`].
    unsafe fn resolve(lib: &Library) -> Result<Self, String> {
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the caller guarantees the library is Embree 4, whose symbol has this type.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }.map_err(|e| format!("{}: {e}", $name))?
            };
        }
        Ok(Self {
            new_device: sym!("rtcNewDevice"),
            release_device: sym!("rtcReleaseDevice"),
            get_device_error: sym!("rtcGetDeviceError"),
            get_device_last_error_message: sym!("rtcGetDeviceLastErrorMessage"),
            set_device_error_function: sym!("rtcSetDeviceErrorFunction"),
            set_device_memory_monitor_function: sym!("rtcSetDeviceMemoryMonitorFunction"),
            get_device_property: sym!("rtcGetDeviceProperty"),
            new_scene: sym!("rtcNewScene"),
            release_scene: sym!("rtcReleaseScene"),
            set_scene_build_quality: sym!("rtcSetSceneBuildQuality"),
            set_scene_flags: sym!("rtcSetSceneFlags"),
            commit_scene: sym!("rtcCommitScene"),
            new_geometry: sym!("rtcNewGeometry"),
            set_new_geometry_buffer: sym!("rtcSetNewGeometryBuffer"),
            commit_geometry: sym!("rtcCommitGeometry"),
            attach_geometry: sym!("rtcAttachGeometry"),
            release_geometry: sym!("rtcReleaseGeometry"),
            intersect1: sym!("rtcIntersect1"),
            occluded1: sym!("rtcOccluded1"),
            intersect8: sym!("rtcIntersect8"),
            intersect16: sym!("rtcIntersect16"),
            new_bvh: sym!("rtcNewBVH"),
            build_bvh: sym!("rtcBuildBVH"),
            thread_local_alloc: sym!("rtcThreadLocalAlloc"),
            release_bvh: sym!("rtcReleaseBVH"),
        })
    }
}

/// A loaded Embree 4 library and its entry points; devices hold an `Arc` of it so it outlives them.
pub struct EmbreeLibrary {
    /// The entry points (valid while `_lib` is loaded).
    pub api: Api,
    /// The file or name it was loaded from.
    pub path: String,
    _lib: Library,
}

impl fmt::Debug for EmbreeLibrary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbreeLibrary").field("path", &self.path).finish_non_exhaustive()
    }
}

impl EmbreeLibrary {
    /// The process-wide library from the default search, loaded on first use (one Embree per process).
    pub fn shared() -> Result<Arc<EmbreeLibrary>, EmbreeUnavailable> {
        static SHARED: OnceLock<Result<Arc<EmbreeLibrary>, EmbreeUnavailable>> = OnceLock::new();
        SHARED.get_or_init(|| Self::load(&SearchInputs::from_environment()).map(Arc::new)).clone()
    }

    /// Tries the candidates `inputs` names, in order; the first that loads and has every symbol wins.
    pub fn load(inputs: &SearchInputs) -> Result<EmbreeLibrary, EmbreeUnavailable> {
        let mut tried = Vec::new();
        let mut candidates: Vec<(String, String)> = Vec::new(); // (label, what to dlopen)
        if let Some(path) = &inputs.explicit {
            candidates.push((format!("EMBREE_LIB={}", path.display()), path.display().to_string()));
        } else {
            for name in &inputs.system_names {
                candidates.push((format!("system {name}"), name.clone()));
            }
            for dir in &inputs.site_dirs {
                let libs = dir.join("embreex.libs");
                let files = embree_files_in(&libs);
                if files.is_empty() {
                    tried.push(format!("{}/libembree4*.so*: none", libs.display()));
                }
                candidates.extend(files.into_iter().map(|f| (f.display().to_string(), f.display().to_string())));
            }
            if let Some(e) = &inputs.site_error {
                tried.push(format!("embreex wheel: {e}"));
            }
        }
        for (label, target) in candidates {
            match Self::open(&target) {
                Ok(lib) => return Ok(lib),
                Err(why) => tried.push(format!("{label}: {why}")),
            }
        }
        Err(EmbreeUnavailable { tried })
    }

    fn open(target: &str) -> Result<EmbreeLibrary, String> {
        // SAFETY: loading runs the library's initializers; Embree's and TBB's are benign.
        let lib = unsafe { Library::new(target) }.map_err(|e| e.to_string())?;
        // SAFETY: a library exporting these names is taken to be Embree 4; Embree 3 exports most of them with
        // other query signatures, which `EmbreeDevice::new` rejects by version before any query runs.
        let api = unsafe { Api::resolve(&lib) }?;
        Ok(EmbreeLibrary { api, path: target.to_string(), _lib: lib })
    }
}
