//! Embree 4, loaded at run time (bindings in [`crate::peers::embree`]): `embree` queries one ray at a time
//! (`rtcIntersect1` / `rtcOccluded1`), `embree-packets` closest hits in packets of 8 or 16 (`embree_packet`).

use std::sync::OnceLock;

use schema::{Accel, EmbreePacket, PeerKind, Settings};
use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::Ray;
use tracer::render::PrimaryHits;

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;
use crate::peers::embree::{EmbreeGeometry, EmbreeScene};
use crate::peers::{EmbreeConfig, EmbreeDevice, EmbreeSpheres, EmbreeTriangles};

/// Embree 4, when a library is found.
pub struct Embree;

impl Backend for Embree {
    fn name(&self) -> &'static str {
        "Embree 4"
    }

    fn runs(&self, accel: Accel) -> bool {
        matches!(accel, Accel::Peer(PeerKind::Embree | PeerKind::EmbreePackets))
    }

    /// Loads the library once per process and asks a one-thread device for its version.
    fn here(&self) -> Result<String, Unavailable> {
        static HERE: OnceLock<Result<String, Unavailable>> = OnceLock::new();
        HERE.get_or_init(|| match crate::peers::embree_status() {
            Ok(info) => Ok(format!("Embree {} from {}", info.version, info.path)),
            Err(e) => Err(Unavailable { reason: e.to_string(), installable: true }),
        })
        .clone()
    }

    fn own_threads(&self, _settings: &Settings) -> bool {
        true
    }

    fn start(&self, settings: &Settings) -> Result<Option<Box<dyn std::any::Any + Send + Sync>>, Error> {
        let quality = settings.embree_build.unwrap_or_default();
        let isa = settings.embree_isa.and_then(|i| i.pinned()).map(str::to_string);
        let config = EmbreeConfig { threads: Some(settings.strategy().threads.max(1)), isa, quality };
        let device = EmbreeDevice::new(&config).map_err(|e| Error::Run(format!("embree: {e}")))?;
        Ok(Some(Box::new(device)))
    }

    /// Builds on Embree's device (its TBB threads).
    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error> {
        let device: &EmbreeDevice = setup.started().expect("Embree's setup starts a device");
        let quality = settings.embree_build.unwrap_or_default();
        let failed = |e| Error::Run(format!("embree: {e}"));
        match *geometry {
            Geometry::Spheres(s) => built(settings, EmbreeSpheres::build(device, s, quality).map_err(failed)?),
            Geometry::Triangles(m) => built(settings, EmbreeTriangles::build(device, m, quality).map_err(failed)?),
        }
    }
}

/// The row of a built Embree scene: single rays or packets.
fn built<G: EmbreeGeometry + 'static>(settings: &Settings, scene: EmbreeScene<G>) -> Result<Built, Error> {
    {
        let i = scene.device_info();
        let isa = match i.native_packet {
            16 => "avx512",
            8 => "avx/avx2",
            _ => "sse",
        };
        let info = format!("embree {} native width {} ({isa}), {}", i.version, i.native_packet, i.config);
        Ok(match settings.accel {
            Accel::Peer(PeerKind::EmbreePackets) => {
                Built::peer(EmbreePackets { scene, width: EmbreePacketWidth::of(settings) }, info)
            }
            _ => Built::peer(scene, info),
        })
    }
}

/// Embree queried in packets for closest hits, `rtcIntersect8` or `rtcIntersect16` (`embree_packet`); occlusion stays
/// `rtcOccluded1`.
pub struct EmbreePackets<G: EmbreeGeometry> {
    pub scene: EmbreeScene<G>,
    pub width: EmbreePacketWidth,
}

/// The lanes of `embree-packets`' queries ([`EmbreePacket`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreePacketWidth {
    /// `rtcIntersect8`.
    Eight,
    /// `rtcIntersect16`.
    Sixteen,
}

impl EmbreePacketWidth {
    /// The width `settings` give `embree-packets` (the schema allows 8 and 16; 16 where it does not apply).
    pub fn of(settings: &Settings) -> Self {
        match settings.embree_packet {
            Some(EmbreePacket(8)) => EmbreePacketWidth::Eight,
            _ => EmbreePacketWidth::Sixteen,
        }
    }
}

impl<G: EmbreeGeometry> EmbreePackets<G> {
    /// Traces `rays` in packets of N with `query` (one of the scene's `intersectN`), no allocation.
    #[inline(always)]
    fn batch<const N: usize, C: Counters>(
        &self,
        query: impl Fn(&EmbreeScene<G>, &[Ray]) -> [Option<Hit>; N],
        rays: &[Ray],
        out: &mut [Hit],
        counters: &mut C,
    ) {
        for (rays, out) in rays.chunks(N).zip(out.chunks_mut(N)) {
            let hits = query(&self.scene, rays);
            for (o, h) in out.iter_mut().zip(hits) {
                counters.ray();
                *o = h.unwrap_or(PrimaryHits::MISS);
            }
        }
    }
}

impl<G: EmbreeGeometry> Accelerator for EmbreePackets<G> {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.scene.intersect(ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.scene.occluded(ray, counters)
    }

    fn stats(&self) -> TreeStats {
        self.scene.stats()
    }

    fn intersect_batch<C: Counters>(&self, rays: &[Ray], out: &mut [Hit], counters: &mut C) {
        // The width is chosen once per batch; each arm is its own monomorphized loop.
        match self.width {
            EmbreePacketWidth::Eight => self.batch(EmbreeScene::<G>::intersect8, rays, out, counters),
            EmbreePacketWidth::Sixteen => self.batch(EmbreeScene::<G>::intersect16, rays, out, counters),
        }
    }
}
