//! The tracer's own structures: the brute-force list, the pointer BVH, the flat BVH and the wide BVH.

use schema::{Accel, Settings};
use tracer::accel::WideParams;
use tracer::accel::wide::Kernel;
use tracer::geometry::{MollerTrumboreTriangle, TrianglePrimitive, TriangleTest, WatertightTriangle};
use tracer::structure::{self, Primitives};

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
    /// compiled for it (in the tracer: [`tracer::structure`]).
    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error> {
        let params = settings.accel_params();
        let (moller_trumbore, watertight);
        let prims = match *geometry {
            Geometry::Spheres(spheres) => Primitives::Spheres(spheres),
            Geometry::Triangles(mesh) => match settings.triangle_test.unwrap_or(TriangleTest::Watertight) {
                TriangleTest::MollerTrumbore => {
                    moller_trumbore = MollerTrumboreTriangle::all(mesh.triangles());
                    Primitives::MollerTrumbore(&moller_trumbore)
                }
                TriangleTest::Watertight => {
                    watertight = WatertightTriangle::all(mesh.triangles());
                    Primitives::Watertight(&watertight)
                }
            },
        };
        let structure = setup.install(|| structure::build(prims, &params));
        let simd_kernel = structure.simd_kernel().unwrap_or("-");
        Ok(Built { structure, peer_info: "-".into(), simd_kernel })
    }
}
