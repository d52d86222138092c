//! The backend one configuration runs: a tracer structure or a peer, built over one scene's spheres.

use tracer::accel::{AccelVisitor, Accelerator, BuiltAccel, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};
use tracer::render::PrimaryHits;

use crate::error::Error;
use crate::peers::{EmbreeConfig, EmbreeDevice, EmbreeSpheres, ObvhsBvh2, ObvhsCwbvh, PeerKind};
use schema::Settings;

/// Embree queried 16 rays at a time (`rtcIntersect16`) for closest hits; occlusion stays `rtcOccluded1`.
pub struct EmbreePackets(pub EmbreeSpheres);

impl Accelerator for EmbreePackets {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        self.0.intersect(ray, counters)
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.0.occluded(ray, counters)
    }

    fn stats(&self) -> TreeStats {
        self.0.stats()
    }

    fn intersect_batch<C: Counters>(&self, rays: &[Ray], out: &mut [Hit], counters: &mut C) {
        for (rays, out) in rays.chunks(16).zip(out.chunks_mut(16)) {
            let hits = self.0.intersect16(rays);
            for (o, h) in out.iter_mut().zip(hits) {
                counters.ray();
                *o = h.unwrap_or(PrimaryHits::MISS);
            }
        }
    }
}

/// A built backend of any kind.
pub enum Backend {
    Ours(BuiltAccel),
    ObvhsBvh2(ObvhsBvh2),
    ObvhsCwbvh(ObvhsCwbvh),
    Embree(EmbreeSpheres),
    EmbreePackets(EmbreePackets),
}

impl Backend {
    /// Builds the backend `settings` names; peers build with `settings.strategy.threads` threads.
    pub fn build(settings: &Settings, spheres: &[Sphere]) -> Result<Backend, Error> {
        let Some(peer) = settings.peer() else {
            return Ok(Backend::Ours(BuiltAccel::build(spheres, &settings.accel_params())));
        };
        let threads = settings.strategy().threads.max(1);
        Ok(match peer {
            PeerKind::ObvhsBvh2 | PeerKind::ObvhsCwbvh => {
                // obvhs builds with rayon: inside this pool it uses exactly the configured threads.
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("building a rayon pool");
                let preset = settings.obvhs_build.unwrap_or_default();
                pool.install(|| match peer {
                    PeerKind::ObvhsBvh2 => Backend::ObvhsBvh2(ObvhsBvh2::build(spheres, preset)),
                    _ => Backend::ObvhsCwbvh(ObvhsCwbvh::build(spheres, preset)),
                })
            }
            PeerKind::Embree | PeerKind::EmbreePackets => {
                let quality = settings.embree_build.unwrap_or_default();
                let isa = settings.embree_isa.and_then(|i| i.pinned()).map(str::to_string);
                let config = EmbreeConfig { threads: Some(threads), isa, quality };
                let device = EmbreeDevice::new(&config).map_err(|e| Error::Run(format!("embree: {e}")))?;
                let scene =
                    EmbreeSpheres::build(&device, spheres, quality).map_err(|e| Error::Run(format!("embree: {e}")))?;
                if peer == PeerKind::Embree {
                    Backend::Embree(scene)
                } else {
                    Backend::EmbreePackets(EmbreePackets(scene))
                }
            }
        })
    }

    /// Calls `visitor` with the concrete backend.
    pub fn visit<V: AccelVisitor>(&self, visitor: V) -> V::Output {
        match self {
            Backend::Ours(a) => a.visit(visitor),
            Backend::ObvhsBvh2(a) => visitor.visit(a),
            Backend::ObvhsCwbvh(a) => visitor.visit(a),
            Backend::Embree(a) => visitor.visit(a),
            Backend::EmbreePackets(a) => visitor.visit(a),
        }
    }

    /// Size and quality of the built structure (peers report what they can).
    pub fn stats(&self) -> TreeStats {
        struct Stats;
        impl AccelVisitor for Stats {
            type Output = TreeStats;
            fn visit<A: Accelerator>(self, a: &A) -> TreeStats {
                a.stats()
            }
        }
        self.visit(Stats)
    }

    /// Peer library facts for the row (`-` for the tracer's structures).
    pub fn peer_info(&self) -> String {
        match self {
            Backend::Ours(_) => "-".into(),
            Backend::ObvhsBvh2(_) | Backend::ObvhsCwbvh(_) => "obvhs 0.4".into(),
            Backend::Embree(s) | Backend::EmbreePackets(EmbreePackets(s)) => {
                let i = s.device_info();
                let isa = match i.native_packet {
                    16 => "avx512",
                    8 => "avx/avx2",
                    _ => "sse",
                };
                format!("embree {} native width {} ({isa}), {}", i.version, i.native_packet, i.config)
            }
        }
    }
}
