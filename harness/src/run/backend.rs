//! The backend one configuration runs: a tracer structure or a peer, built over one scene's spheres.

use tracer::accel::{AccelVisitor, Accelerator, BuiltAccel, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};
use tracer::render::PrimaryHits;

use crate::error::Error;
use crate::peers::{EmbreeConfig, EmbreeDevice, EmbreeSpheres, ObvhsBvh2, ObvhsCwbvh, PeerKind};
use schema::{PacketSize, Settings};

/// Embree queried in packets for closest hits, `rtcIntersect8` or `rtcIntersect16` (`packet_size`); occlusion stays
/// `rtcOccluded1`.
pub struct EmbreePackets {
    pub scene: EmbreeSpheres,
    pub width: EmbreePacketWidth,
}

/// The lanes of `embree-packets`' queries (`packet_size`, [`PacketSize::EMBREE`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreePacketWidth {
    /// `rtcIntersect8`.
    Eight,
    /// `rtcIntersect16`.
    Sixteen,
}

impl EmbreePacketWidth {
    /// The width `settings` give `embree-packets` (normalized settings hold 8 or 16; anything else is an error).
    pub fn of(settings: &Settings) -> Result<Self, Error> {
        match settings.packet_size.unwrap_or(PacketSize::EMBREE_DEFAULT) {
            PacketSize(8) => Ok(EmbreePacketWidth::Eight),
            PacketSize(16) => Ok(EmbreePacketWidth::Sixteen),
            PacketSize(n) => Err(Error::Run(format!(
                "embree-packets: packet_size {n} is not allowed (allowed: {})",
                PacketSize::embree_allowed()
            ))),
        }
    }
}

impl EmbreePackets {
    /// Traces `rays` in packets of N with `query` (one of the scene's `intersectN`), no allocation.
    #[inline(always)]
    fn batch<const N: usize, C: Counters>(
        &self,
        query: impl Fn(&EmbreeSpheres, &[Ray]) -> [Option<Hit>; N],
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

impl Accelerator for EmbreePackets {
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
            EmbreePacketWidth::Eight => self.batch(EmbreeSpheres::intersect8, rays, out, counters),
            EmbreePacketWidth::Sixteen => self.batch(EmbreeSpheres::intersect16, rays, out, counters),
        }
    }
}

/// What a backend starts once per process and configuration, before any timed phase (the `setup_s` phase):
/// the rayon pool of the configured threads that builds and traces run in, and for Embree the library
/// (found and loaded once per process) and a device.
pub struct Setup {
    pool: rayon::ThreadPool,
    embree: Option<EmbreeDevice>,
    /// Wall time of starting all of it.
    pub setup_s: f64,
}

impl Setup {
    /// Starts what `settings` needs, timed.
    pub fn start(settings: &Settings) -> Result<Setup, Error> {
        let t = std::time::Instant::now();
        let threads = settings.strategy().threads.max(1);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::Run(format!("cannot start a pool of {threads} threads: {e}")))?;
        // Every worker thread started before the clock stops.
        pool.broadcast(|_| ());
        let embree = match settings.peer() {
            Some(peer) if peer.needs_embree() => {
                let quality = settings.embree_build.unwrap_or_default();
                let isa = settings.embree_isa.and_then(|i| i.pinned()).map(str::to_string);
                let config = EmbreeConfig { threads: Some(threads), isa, quality };
                Some(EmbreeDevice::new(&config).map_err(|e| Error::Run(format!("embree: {e}")))?)
            }
            _ => None,
        };
        Ok(Setup { pool, embree, setup_s: t.elapsed().as_secs_f64() })
    }

    /// Runs `f` in the pool (builds and traces run here, so the tracer's executor reuses the pool).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
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
    /// Builds the backend `settings` names over `spheres` with what `setup` started: ours and obvhs in its
    /// pool (so with the configured threads), Embree on its device (TBB, the configured threads).
    pub fn build(settings: &Settings, spheres: &[Sphere], setup: &Setup) -> Result<Backend, Error> {
        let Some(peer) = settings.peer() else {
            return Ok(setup.install(|| Backend::Ours(BuiltAccel::build(spheres, &settings.accel_params()))));
        };
        Ok(match peer {
            PeerKind::ObvhsBvh2 | PeerKind::ObvhsCwbvh => {
                let preset = settings.obvhs_build.unwrap_or_default();
                setup.install(|| match peer {
                    PeerKind::ObvhsBvh2 => Backend::ObvhsBvh2(ObvhsBvh2::build(spheres, preset)),
                    _ => Backend::ObvhsCwbvh(ObvhsCwbvh::build(spheres, preset)),
                })
            }
            PeerKind::Embree | PeerKind::EmbreePackets => {
                let device = setup.embree.as_ref().expect("an Embree configuration's setup starts a device");
                let quality = settings.embree_build.unwrap_or_default();
                let width = (peer == PeerKind::EmbreePackets).then(|| EmbreePacketWidth::of(settings)).transpose()?;
                let scene =
                    EmbreeSpheres::build(device, spheres, quality).map_err(|e| Error::Run(format!("embree: {e}")))?;
                match width {
                    None => Backend::Embree(scene),
                    Some(width) => Backend::EmbreePackets(EmbreePackets { scene, width }),
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

    /// The SIMD kernel the structure runs (`scalar`, `avx2`, `avx512`), `-` for those without SIMD kernels.
    pub fn simd_kernel(&self) -> &'static str {
        match self {
            Backend::Ours(a) => a.kernel_name().unwrap_or("-"),
            _ => "-",
        }
    }

    /// Peer library facts for the row (`-` for the tracer's structures).
    pub fn peer_info(&self) -> String {
        match self {
            Backend::Ours(_) => "-".into(),
            Backend::ObvhsBvh2(_) | Backend::ObvhsCwbvh(_) => "obvhs 0.4".into(),
            Backend::Embree(s) | Backend::EmbreePackets(EmbreePackets { scene: s, .. }) => {
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
