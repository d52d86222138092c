//! The tracer's own structures: the brute-force list, the pointer BVH, the flat BVH and the wide BVH.

use schema::{Accel, Named, Settings, TreeBuilder};
use tracer::Vec3;
use tracer::accel::bvh::tree::FlatNode;
use tracer::accel::wide::Kernel;
use tracer::accel::{AccelParams, WideParams};
use tracer::geometry::Aabb;
use tracer::geometry::{MollerTrumboreTriangle, TrianglePrimitive, TriangleTest, WatertightTriangle};
use tracer::scene::mesh::Mesh;
use tracer::structure::{self, Primitives};

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;
use crate::peers::embree::tree::{self as embree_tree, TreeQuality as EmbreeTreeQuality};
use crate::peers::tinybvh::{TinyBvh, TinyLayout, TinyQuality};
use crate::peers::{EmbreeConfig, EmbreeDevice};

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

    /// A wide BVH runs only with a SIMD kernel this CPU has, and over a peer's tree only where the peer runs.
    fn available(&self, settings: &Settings) -> Result<(), Unavailable> {
        if matches!(settings.tree_builder, Some(TreeBuilder::TinyBvh | TreeBuilder::TinyBvhHigh))
            && crate::peers::tinybvh::TinyIsa::best().is_none()
        {
            return Err(Unavailable {
                reason: "tree_builder tinybvh: the tinybvh shim is not compiled or runs on no ISA level here".into(),
                installable: false,
            });
        }
        // Embree's backend loads the library once per process and remembers why it could not.
        if settings.tree_builder.is_some_and(TreeBuilder::is_embree)
            && let Err(e) = super::embree::Embree.here()
        {
            return Err(Unavailable { reason: format!("tree_builder embree: {}", e.reason), ..e });
        }
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

    /// Embree's builder runs on its TBB threads, whose limit is process-wide, and outside our pinned pool.
    fn own_threads(&self, settings: &Settings) -> bool {
        settings.tree_builder.is_some_and(TreeBuilder::is_embree)
    }

    /// Embree's device, for a tree Embree builds: its build threads the configuration's.
    fn start(&self, settings: &Settings) -> Result<Option<Box<dyn std::any::Any + Send + Sync>>, Error> {
        if !settings.tree_builder.is_some_and(TreeBuilder::is_embree) {
            return Ok(None);
        }
        let config = EmbreeConfig { threads: Some(settings.strategy().threads.max(1)), ..EmbreeConfig::default() };
        let device = EmbreeDevice::new(&config).map_err(|e| Error::Run(format!("tree_builder embree: {e}")))?;
        Ok(Some(Box::new(device)))
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
        let (structure, peer_info) = match (settings.tree_builder, geometry) {
            (Some(builder @ (TreeBuilder::TinyBvh | TreeBuilder::TinyBvhHigh)), Geometry::Triangles(mesh)) => {
                let quality = if builder == TreeBuilder::TinyBvh { TinyQuality::Default } else { TinyQuality::High };
                let structure = setup.install(|| peer_tree(prims, mesh, quality, &params))?;
                (structure, format!("tree from tinybvh 1.6.8 {quality:?} build, collapsed and traced by ours"))
            }
            (Some(builder @ (TreeBuilder::Embree | TreeBuilder::EmbreeHigh)), Geometry::Triangles(mesh)) => {
                let quality =
                    if builder == TreeBuilder::Embree { EmbreeTreeQuality::Medium } else { EmbreeTreeQuality::High };
                let device: &EmbreeDevice = setup.started().expect("the setup of an Embree tree starts a device");
                // Embree's build on the calling thread (its TBB workers), our collapse in the pool.
                let (nodes, order) = embree_tree::build(device, mesh, quality)
                    .map_err(|e| Error::Run(format!("tree_builder {}: {e}", builder.name())))?;
                let structure = setup
                    .install(|| structure::build_from_tree(prims, &nodes, &order, &params))
                    .map_err(|e| Error::Run(format!("tree_builder: Embree's tree refused: {e}")))?;
                let info = format!(
                    "tree from Embree {} rtcBuildBVH {quality:?}, collapsed and traced by ours",
                    device.info().version
                );
                (structure, info)
            }
            _ => (setup.install(|| structure::build(prims, &params)), "-".to_string()),
        };
        let simd_kernel = structure.simd_kernel().unwrap_or("-");
        Ok(Built { structure, peer_info, simd_kernel })
    }
}

/// Our wide BVH over tinybvh's binary tree of `mesh` (its plain layout built with `quality`): the tree copied out
/// of the shim, checked and laid out by the tracer, then collapsed as our own trees are.
fn peer_tree(
    prims: Primitives<'_>,
    mesh: &Mesh,
    quality: TinyQuality,
    params: &AccelParams,
) -> Result<Box<dyn structure::Structure>, Error> {
    let tiny = TinyBvh::build(mesh, TinyLayout::Bvh, quality).map_err(|e| Error::Run(format!("tree_builder: {e}")))?;
    let (nodes, order) = tiny.plain_tree().ok_or_else(|| Error::Run("tree_builder: no plain tree".into()))?;
    drop(tiny);
    let nodes: Vec<FlatNode> = nodes
        .iter()
        .map(|n| FlatNode {
            bounds: Aabb { min: Vec3::from_array(n.min), max: Vec3::from_array(n.max) },
            first: n.left_first,
            prim_count: if n.tri_count > 0 { n.tri_count } else { FlatNode::INTERIOR },
        })
        .collect();
    structure::build_from_tree(prims, &nodes, &order, params)
        .map_err(|e| Error::Run(format!("tree_builder: tinybvh's tree refused: {e}")))
}
