//! The tracer's own structures: the brute-force list, the pointer BVH, the flat BVH and the wide BVH.

use schema::{Accel, Settings};
use tracer::accel::wide::Kernel;
use tracer::accel::wide::WidePrimitive;
use tracer::accel::{AccelParams, BuiltAccel, WideParams};
use tracer::geometry::{MollerTrumboreTriangle, TrianglePrimitive, TriangleTest, WatertightTriangle};

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;

/// The tracer under study.
pub struct Ours;

impl Backend for Ours {
    fn name(&self) -> &'static str {
        "bvhlab"
    }

    fn runs(&self, accel: Accel) -> bool {
        matches!(accel, Accel::Ours(_))
    }

    fn here(&self) -> Result<String, Unavailable> {
        let here: Vec<&str> = Kernel::available().into_iter().map(Kernel::name).collect();
        let auto: Vec<String> = WideParams::LEAF_BLOCKS
            .iter()
            .map(|&b| format!("{} for blocks of {b}", Kernel::Auto.resolve_for(b).name()))
            .collect();
        Ok(format!("built in; SIMD kernels here: {}; auto = {}", here.join(", "), auto.join(", ")))
    }

    /// A wide BVH runs only with a SIMD kernel this CPU has.
    fn available(&self, settings: &Settings) -> Result<(), Unavailable> {
        match settings.simd_kernel.filter(|k| !k.is_available()) {
            None => Ok(()),
            Some(kernel) => {
                let here: Vec<&str> =
                    std::iter::once(Kernel::Auto).chain(Kernel::available()).map(Kernel::name).collect();
                Err(Unavailable {
                    reason: format!("simd_kernel {}: this CPU lacks it (it runs: {})", kernel.name(), here.join(", ")),
                    installable: false,
                })
            }
        }
    }

    /// Chooses the primitive once: spheres, or the mesh's triangles with `triangle_test`; everything after is
    /// compiled for it.
    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error> {
        let params = settings.accel_params();
        Ok(match *geometry {
            Geometry::Spheres(spheres) => built(setup, spheres, &params),
            Geometry::Triangles(mesh) => match settings.triangle_test.unwrap_or(TriangleTest::Watertight) {
                TriangleTest::MollerTrumbore => built(setup, &MollerTrumboreTriangle::all(mesh.triangles()), &params),
                TriangleTest::Watertight => built(setup, &WatertightTriangle::all(mesh.triangles()), &params),
            },
        })
    }
}

/// The structure of `params` over `prims`, built in the setup's pool.
fn built<P: WidePrimitive>(setup: &Setup, prims: &[P], params: &AccelParams) -> Built {
    let accel = setup.install(|| BuiltAccel::build(prims, params));
    let simd_kernel = accel.kernel_name().unwrap_or("-");
    Built { structure: Box::new(accel), peer_info: "-".into(), simd_kernel }
}
