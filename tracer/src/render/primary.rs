//! The primary-ray kernel: one closest-hit query per pixel, no shading, for throughput in Mrays/s.

use crate::accel::{Accelerator, Hit};
use crate::counters::Counters;
use crate::executor::Strategy;
use crate::fingerprint::Fnv64;
use crate::scene::Camera;

/// The closest hit of every camera ray, row-major; a miss is `t = inf`, `prim = u32::MAX`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimaryHits {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// One entry per pixel.
    pub hits: Vec<Hit>,
}

impl PrimaryHits {
    /// The value stored for a ray that hits nothing.
    pub const MISS: Hit = Hit { t: f32::INFINITY, prim: u32::MAX };

    /// Number of rays that hit a sphere.
    pub fn hit_count(&self) -> usize {
        self.hits.iter().filter(|h| h.prim != u32::MAX).count()
    }

    /// Stable hash of every hit's distance bits and sphere index.
    pub fn hash(&self) -> u64 {
        let mut h = Fnv64::default();
        for hit in &self.hits {
            h.f32(hit.t).u32(hit.prim);
        }
        h.finish()
    }
}

impl Default for Hit {
    fn default() -> Self {
        PrimaryHits::MISS
    }
}

/// Traces one closest-hit ray per pixel of `camera` with `accel` under `strategy`.
pub fn trace_primary<A: Accelerator, C: Counters>(camera: &Camera, accel: &A, strategy: &Strategy) -> (PrimaryHits, C) {
    let rays = camera.rays();
    let mut hits = vec![PrimaryHits::MISS; camera.width as usize * camera.height as usize];
    let counters = strategy.run_rows(camera.width as usize, &mut hits, |y, row, counters: &mut C| {
        for (x, out) in row.iter_mut().enumerate() {
            counters.ray();
            *out = accel.intersect(&rays.ray(x as u32, y as u32), counters).unwrap_or(PrimaryHits::MISS);
        }
    });
    (PrimaryHits { width: camera.width, height: camera.height, hits }, counters)
}
