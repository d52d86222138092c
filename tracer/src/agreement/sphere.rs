//! [`Sphere`] as an [`ExactPrimitive`]: its f64 test ([`ExactTest`]) and the screen f64 brute force runs first.
//!
//! Most spheres are far from a given ray, and brute force need not look at them one by one to know it. The
//! spheres are kept in Morton order in chunks of [`CHUNK`], each with the box of its centers; a chunk is
//! skipped when the ray's line misses that box widened by `2·r_max + 32u·F + 1e-9·F` (`F` bounding the
//! distance from the origin to any of its spheres): a sphere f32 may report (`g ≥ −B`) has the line within
//! `p ≤ 1.01·r + 14.1u·F` of its center (from `P² − r² ≤ B·r² ≈ 3u·P² + 4u·F·P + 100u²F²`), so a skipped
//! chunk holds none, and the answer is brute force's. Within a chunk a cheap vectorizable f64 screen keeps
//! every sphere with `p² ≤ r²(1 + M)`, `M = 12u·F₁/r + 24u + (256u² + 16u₆₄)·F₁²/r²` (`F₁ = |o − c|₁ ≥ F`),
//! which exceeds both `B` wherever `p ≤ √2·r` (`B·r² ≈ 5.7u·F·r + 11u·r² + O(u²F²)` there) and the screen's own
//! f64 error (`≤ 6u₆₄·F²`); beyond `p = √2·r`, `p² − r²` outgrows `B·r²` as long as `F < 10⁶·r`, and every
//! sphere with `F ≥ 10⁶·r` is kept. Only the kept spheres get the full evaluation ([`ExactTest::new`]).

use super::chunk_box::{ChunkBox, morton_order};
use super::{ExactAnswer, ExactPrimitive};
use crate::geometry::{ExactTest, Ray, Sphere, U_F32, U_F64};

/// Spheres per chunk (Morton order).
const CHUNK: usize = 256;

/// A scene's spheres laid out for the screen: in Morton order, by coordinate, in boxed chunks.
#[derive(Clone, Debug)]
pub struct SphereLayout {
    /// Scene index of the sphere at each position of the layout.
    order: Vec<u32>,
    cx: Vec<f64>,
    cy: Vec<f64>,
    cz: Vec<f64>,
    r: Vec<f64>,
    chunks: Vec<SphereChunk>,
}

/// The box of a chunk's centers and its largest radius.
#[derive(Clone, Copy, Debug)]
struct SphereChunk {
    centers: ChunkBox,
    r_max: f64,
}

/// The screen's per-ray constants: origin and unit direction in f64.
struct Screen {
    o: [f64; 3],
    n: [f64; 3],
}

impl Screen {
    fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3().normalize());
        Self { o: o.to_array(), n: d.to_array() }
    }

    /// Marks in `keep` the spheres of the chunk that may be within the grazing bound (module documentation);
    /// true when it marked any.
    #[inline(always)]
    fn run(&self, cx: &[f64], cy: &[f64], cz: &[f64], r: &[f64], keep: &mut [u8]) -> bool {
        const K1: f64 = 12.0 * U_F32;
        const K2: f64 = 24.0 * U_F32;
        const K3: f64 = 256.0 * U_F32 * U_F32 + 16.0 * U_F64;
        let ([ox, oy, oz], [nx, ny, nz]) = (self.o, self.n);
        let n = keep.len();
        let (cx, cy, cz, r) = (&cx[..n], &cy[..n], &cz[..n], &r[..n]);
        let mut any = 0u8;
        for j in 0..n {
            let (fx, fy, fz, rj) = (cx[j] - ox, cy[j] - oy, cz[j] - oz, r[j]);
            let b = fx * nx + fy * ny + fz * nz;
            let ff = fx * fx + fy * fy + fz * fz;
            let f1 = fx.abs() + fy.abs() + fz.abs();
            let excess = ff - b * b - rj * rj;
            let margin = (K1 * f1 + K2 * rj) * rj + K3 * f1 * f1;
            let k = ((excess <= margin) | (f1 > 1e6 * rj)) as u8;
            keep[j] = k;
            any |= k;
        }
        any != 0
    }
}

impl SphereChunk {
    fn of(cx: &[f64], cy: &[f64], cz: &[f64], r: &[f64]) -> Self {
        Self { centers: ChunkBox::of(cx, cy, cz), r_max: r.iter().fold(0.0, |m, &x| m.max(x)) }
    }

    /// False when the ray's line misses the box widened so that it holds every sphere f32 may report
    /// (module documentation): the chunk can be skipped.
    fn may_hold_candidates(&self, s: &Screen) -> bool {
        self.centers.meets_line(s.o, s.n, |far| 2.0 * self.r_max + (32.0 * U_F32 + 1e-9) * far)
    }
}

impl SphereLayout {
    /// Lays out `spheres` for the screen.
    pub fn new(spheres: &[Sphere]) -> Self {
        let centers: Vec<[f64; 3]> = spheres.iter().map(|s| s.center.as_dvec3().to_array()).collect();
        let order = morton_order(&centers);
        let coord = |k: usize| order.iter().map(|&i| centers[i as usize][k]).collect::<Vec<f64>>();
        let (cx, cy, cz) = (coord(0), coord(1), coord(2));
        let r: Vec<f64> = order.iter().map(|&i| spheres[i as usize].radius as f64).collect();
        let chunks = (0..spheres.len())
            .step_by(CHUNK)
            .map(|a| {
                let b = (a + CHUNK).min(spheres.len());
                SphereChunk::of(&cx[a..b], &cy[a..b], &cz[a..b], &r[a..b])
            })
            .collect();
        Self { order, cx, cy, cz, r, chunks }
    }

    /// Ascending scene indices of the spheres the screen keeps for `ray`; `skip` skips the chunks that hold none
    /// (else every sphere is screened).
    fn screened(&self, ray: &Ray, skip: bool) -> Vec<u32> {
        let screen = Screen::new(ray);
        let mut kept = Vec::new();
        let mut keep = [0u8; CHUNK];
        for (k, chunk) in self.chunks.iter().enumerate() {
            if skip && !chunk.may_hold_candidates(&screen) {
                continue;
            }
            let (a, b) = (k * CHUNK, ((k + 1) * CHUNK).min(self.order.len()));
            let keep = &mut keep[..b - a];
            if screen.run(&self.cx[a..b], &self.cy[a..b], &self.cz[a..b], &self.r[a..b], keep) {
                kept.extend(keep.iter().enumerate().filter(|(_, k)| **k != 0).map(|(j, _)| self.order[a + j]));
            }
        }
        kept.sort_unstable();
        kept
    }
}

impl ExactPrimitive for Sphere {
    type Layout = SphereLayout;

    fn layout(prims: &[Self]) -> SphereLayout {
        SphereLayout::new(prims)
    }

    fn screen(layout: &SphereLayout, ray: &Ray) -> Vec<u32> {
        layout.screened(ray, true)
    }

    fn exact(&self, ray: &Ray) -> ExactAnswer {
        let test = ExactTest::new(self, ray);
        let (t_min, t_max) = (ray.t_min as f64, ray.t_max as f64);
        ExactAnswer { hit: test.exact_hit(t_min, t_max), outcomes: test.f32_outcomes(t_min, t_max) }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::rng::SplitMix64;
    use crate::scene::SceneKind;

    /// The screen keeps every sphere the full evaluation could need (`g ≥ −B`), at every distance and size.
    #[test]
    fn the_screen_keeps_every_sphere_within_the_grazing_bound() {
        let mut rng = SplitMix64::new(3);
        let mut p = |s: f64| Vec3::new(rng.range(-s, s) as f32, rng.range(-s, s) as f32, rng.range(-s, s) as f32);
        let mut near = 0;
        for i in 0..100_000 {
            let scale = [1.0, 30.0, 1e3, 1e5][i % 4];
            let r = (p(1.0).x.abs() * 0.5 * [1.0, 1e-2, 1e-4][i % 3] as f32).max(1e-6);
            let center = p(scale);
            let origin = p(scale);
            // Aim close to the silhouette: offsets from the center around r.
            let side = p(1.0).normalize() * r * (1.0 + p(1.0).x * [1e-1, 1e-4, 1e-6][i % 3] as f32);
            let ray = Ray::new(origin, center + side - origin);
            let sphere = Sphere::new(center, r);
            let layout = SphereLayout::new(&[sphere]);
            let test = ExactTest::new(&sphere, &ray);
            let mut keep = [0u8; 1];
            assert_eq!(Screen::new(&ray).run(&layout.cx, &layout.cy, &layout.cz, &layout.r, &mut keep), keep[0] == 1);
            if test.may_cross() {
                near += 1;
                assert_eq!(
                    keep[0], 1,
                    "screened out a sphere with g = {:e} >= -B = {:e}: {ray:?}",
                    test.g, -test.g_bound
                );
            }
        }
        assert!(near > 10_000, "{near}");
    }

    /// Skipping chunks changes nothing: the same candidates as screening every sphere, on rays of every kind
    /// (including grazing ones) through a clustered scene, plus rays from far away.
    #[test]
    fn skipping_chunks_keeps_every_candidate() {
        let scene = SceneKind::ClusteredSpheres.generate(20_000, 2);
        let layout = SphereLayout::new(&scene.spheres);
        let mut rays = crate::testing::scene_ray_mix(&scene, 4);
        let mut rng = SplitMix64::new(8);
        for _ in 0..50 {
            let far = Vec3::new(rng.range(-1e4, 1e4) as f32, rng.range(-1e4, 1e4) as f32, 5e3);
            let s = scene.spheres[rng.below(scene.spheres.len() as u64) as usize];
            rays.push(Ray::new(far, s.center + Vec3::X * s.radius - far));
        }
        let candidates = |ray: &Ray, skip: bool| -> Vec<u32> {
            let kept = layout.screened(ray, skip);
            kept.into_iter().filter(|&i| scene.spheres[i as usize].exact(ray).outcomes.may_hit()).collect()
        };
        let mut total = 0;
        for ray in &rays {
            let (skipped, all) = (candidates(ray, true), candidates(ray, false));
            assert_eq!(skipped, all, "{ray:?}");
            total += all.len();
        }
        assert!(total > rays.len() / 2, "{total} candidates over {} rays", rays.len());
    }
}
