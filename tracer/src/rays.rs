//! Fixed ray sets: the same rays for every accelerator and peer, generated once per scene.
//!
//! - `primary`: one camera ray per pixel, closest hit.
//! - `shadow`: from each primary hit point toward the scene's first light, any hit (segments).
//! - `diffuse`: one cosine-distributed bounce from each primary hit point, closest hit (incoherent).
//! - `ambient-occlusion`: one cosine-distributed segment from each primary hit point, any hit, of length
//!   [`AO_LENGTH`] (1/20) of the diagonal of the scene's bounding box.
//!
//! Sets are made over any [`Primitive`] ([`RaySet::generate_over`]); sphere scenes keep their own normals
//! ([`RaySet::generate`], `Sphere::normal_at`), so their rays are what they always were.
//!
//! Hit points come from a reference accelerator's primary hits (every structure agrees with brute force),
//! and directions are sampled with [`SplitMix64`] using only `+ − × ÷` and `sqrt`, so a ray set is the same
//! on every machine. [`trace`] runs a set under a [`Strategy`] through [`Accelerator::intersect_batch`] /
//! [`Accelerator::occluded_batch`].

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::accel::{Accelerator, Hit};
use crate::counters::Counters;
use crate::executor::Strategy;
use crate::fingerprint::Fnv64;
use crate::geometry::{Aabb, Primitive, Ray};
use crate::render::PrimaryHits;
use crate::rng::SplitMix64;
use crate::scene::{Camera, Scene};

/// Which ray set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RayKind {
    /// Camera rays, closest hit.
    Primary,
    /// Primary hit points to the first light, any hit.
    Shadow,
    /// Cosine-distributed bounces from primary hit points, closest hit.
    Diffuse,
    /// Cosine-distributed segments of [`AO_LENGTH`] of the scene's diagonal from primary hit points, any hit.
    AmbientOcclusion,
}

/// Length of ambient-occlusion rays as a fraction of the diagonal of the scene's bounding box: 1/20.
pub const AO_LENGTH: f32 = 0.05;

impl RayKind {
    /// Every kind.
    pub const ALL: [RayKind; 4] = [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse, RayKind::AmbientOcclusion];

    /// The kebab-case name used in configs.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
            RayKind::AmbientOcclusion => "ambient-occlusion",
        }
    }

    /// True for any-hit (occlusion) queries.
    pub fn is_occlusion(self) -> bool {
        matches!(self, RayKind::Shadow | RayKind::AmbientOcclusion)
    }
}

/// A fixed list of rays and the query to ask of each.
#[derive(Clone, Debug, PartialEq)]
pub struct RaySet {
    /// What the set is.
    pub kind: RayKind,
    /// The rays.
    pub rays: Vec<Ray>,
}

/// The answers to a ray set: closest hits (miss = [`PrimaryHits::MISS`]) or occlusion flags.
#[derive(Clone, Debug, PartialEq)]
pub enum RayAnswers {
    /// One closest hit per ray.
    Closest(Vec<Hit>),
    /// One occlusion flag per ray.
    Occluded(Vec<bool>),
}

impl RayAnswers {
    /// Stable hash of every answer (hit distance bits and sphere index, or the flag).
    pub fn hash(&self) -> u64 {
        let mut h = Fnv64::default();
        match self {
            RayAnswers::Closest(hits) => hits.iter().for_each(|x| {
                h.f32(x.t).u32(x.prim);
            }),
            RayAnswers::Occluded(flags) => flags.iter().for_each(|&f| {
                h.bytes(&[f as u8]);
            }),
        }
        h.finish()
    }

    /// Number of rays that hit something.
    pub fn hit_count(&self) -> usize {
        match self {
            RayAnswers::Closest(hits) => hits.iter().filter(|h| h.prim != PrimaryHits::MISS.prim).count(),
            RayAnswers::Occluded(flags) => flags.iter().filter(|&&f| f).count(),
        }
    }
}

/// An orthonormal basis around unit `n` (Duff et al. 2017), branch-free and transcendental-free.
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// A cosine-distributed unit vector around `n` (Malley's method with a rejection-sampled disk).
fn cosine_direction(n: Vec3, rng: &mut SplitMix64) -> Vec3 {
    let (x, y) = loop {
        let (x, y) = (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        if x * x + y * y < 1.0 {
            break (x as f32, y as f32);
        }
    };
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let (t, b) = basis(n);
    (t * x + b * y + n * z).normalize()
}

impl RaySet {
    /// One closest-hit ray per pixel of the scene's camera, in [`RaySet::TILE`]-pixel square tiles: tiles
    /// row-major, pixels row-major inside a tile (edge tiles cut at the image's border).
    ///
    /// So 8, 16 and 64 consecutive rays of a full tile are a row, two rows and the whole tile: coherent packets
    /// for every backend that traces rays in packets, and the wide BVH's tile packets ([`crate::accel::wide::tile`]).
    pub fn primary(scene: &Scene) -> Self {
        Self::primary_of(&scene.camera)
    }

    /// [`RaySet::primary`] of any camera.
    pub fn primary_of(cam: &Camera) -> Self {
        let rays = cam.rays();
        let rays = Self::tile_order(cam.width, cam.height).map(|(x, y)| rays.ray(x, y)).collect();
        RaySet { kind: RayKind::Primary, rays }
    }

    /// Side of the square pixel tiles primary rays come in.
    pub const TILE: u32 = 8;

    /// The pixels of a `width` × `height` image in the order of [`RaySet::primary`].
    pub fn tile_order(width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
        let t = Self::TILE;
        (0..height.div_ceil(t)).flat_map(move |ty| {
            (0..width.div_ceil(t)).flat_map(move |tx| {
                let (xs, ys) = (tx * t..(tx * t + t).min(width), ty * t..(ty * t + t).min(height));
                ys.flat_map(move |y| xs.clone().map(move |x| (x, y)))
            })
        })
    }

    /// Hit points and normals (facing the ray, from `normal(prim, point, ray direction)`) of the primary rays
    /// that hit, in their order; each point is lifted off the surface along its normal.
    fn surface_points(primary: &RaySet, hits: &[Hit], normal: impl Fn(u32, Vec3, Vec3) -> Vec3) -> Vec<(Vec3, Vec3)> {
        primary
            .rays
            .iter()
            .zip(hits)
            .filter(|(_, h)| h.prim != PrimaryHits::MISS.prim)
            .map(|(r, h)| {
                let p = r.at(h.t);
                let n = normal(h.prim, p, r.dir);
                (p + n * (1e-4 * p.abs().max_element().max(1.0)), n)
            })
            .collect()
    }

    /// From every surface point toward `light` (segments ending at the light); empty without a light.
    fn shadow(points: Vec<(Vec3, Vec3)>, light: Option<Vec3>) -> Self {
        let rays = match light {
            None => vec![],
            Some(light) => points
                .into_iter()
                .map(|(o, _)| {
                    let to = light - o;
                    let d = to.length();
                    Ray::segment(o, to / d.max(f32::MIN_POSITIVE), d)
                })
                .collect(),
        };
        RaySet { kind: RayKind::Shadow, rays }
    }

    /// One cosine-distributed bounce from every surface point, drawn from `seed`.
    fn diffuse(points: Vec<(Vec3, Vec3)>, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let rays = points.into_iter().map(|(o, n)| Ray::new(o, cosine_direction(n, &mut rng))).collect();
        RaySet { kind: RayKind::Diffuse, rays }
    }

    /// One cosine-distributed segment of [`AO_LENGTH`] × the diagonal of `bounds` from every surface point.
    fn ambient_occlusion(points: Vec<(Vec3, Vec3)>, bounds: Aabb, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed);
        let length = AO_LENGTH * bounds.extent().length();
        let rays = points.into_iter().map(|(o, n)| Ray::segment(o, cosine_direction(n, &mut rng), length)).collect();
        RaySet { kind: RayKind::AmbientOcclusion, rays }
    }

    /// The secondary set of `kind` from `primary` and `reference`'s hits on it.
    fn secondary<A: Accelerator>(
        kind: RayKind,
        primary: RaySet,
        reference: &A,
        light: Option<Vec3>,
        bounds: impl FnOnce() -> Aabb,
        normal: impl Fn(u32, Vec3, Vec3) -> Vec3,
        seed: u64,
    ) -> Self {
        if kind == RayKind::Primary {
            return primary;
        }
        let hits = match trace::<_, crate::counters::NoCounters>(reference, &primary, &Strategy::SERIAL).0 {
            RayAnswers::Closest(h) => h,
            RayAnswers::Occluded(_) => unreachable!("primary rays ask for closest hits"),
        };
        let points = Self::surface_points(&primary, &hits, normal);
        match kind {
            RayKind::Primary => unreachable!(),
            RayKind::Shadow => Self::shadow(points, light),
            RayKind::Diffuse => Self::diffuse(points, seed),
            RayKind::AmbientOcclusion => Self::ambient_occlusion(points, bounds(), seed),
        }
    }

    /// The set of `kind` for a sphere scene, using `reference`'s primary hits for the secondary sets (the
    /// spheres' normals `Sphere::normal_at`, turned to face the ray; shadow rays go to the first light).
    pub fn generate<A: Accelerator>(kind: RayKind, scene: &Scene, reference: &A, seed: u64) -> Self {
        let normal = |prim: u32, p: Vec3, dir: Vec3| {
            let n = scene.spheres[prim as usize].normal_at(p);
            if n.dot(dir) > 0.0 { -n } else { n }
        };
        let light = scene.lights.first().map(|l| l.position);
        Self::secondary(kind, Self::primary(scene), reference, light, || scene.bounds(), normal, seed)
    }

    /// The set of `kind` over any primitives `prims` seen by `camera`, shadow rays toward `light`, using
    /// `reference`'s (built over `prims`) primary hits; normals from [`Primitive::normal`].
    pub fn generate_over<P: Primitive, A: Accelerator>(
        kind: RayKind,
        camera: &Camera,
        light: Vec3,
        prims: &[P],
        reference: &A,
        seed: u64,
    ) -> Self {
        let normal = |prim: u32, p: Vec3, dir: Vec3| prims[prim as usize].normal(p, -dir);
        let bounds = || prims.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
        Self::secondary(kind, Self::primary_of(camera), reference, Some(light), bounds, normal, seed)
    }
}

/// Rays per unit of work handed to the executor (a multiple of 64, so that packets of 8, 16 and 64 rays fill).
pub const RAYS_PER_CHUNK: usize = 256;

/// Traces every ray of `set` with `accel` under `strategy`; answers are in ray order.
pub fn trace<A: Accelerator, C: Counters>(accel: &A, set: &RaySet, strategy: &Strategy) -> (RayAnswers, C) {
    let n = set.rays.len();
    let rows = |out_len: usize| out_len.div_ceil(RAYS_PER_CHUNK) * RAYS_PER_CHUNK;
    let rays_of = |row: usize, len: usize| {
        let start = (row * RAYS_PER_CHUNK).min(n);
        &set.rays[start..(start + len).min(n)]
    };
    if set.kind.is_occlusion() {
        let mut out = vec![false; rows(n)];
        let c = strategy.run_rows(RAYS_PER_CHUNK, &mut out, |row, chunk, c: &mut C| {
            let rays = rays_of(row, chunk.len());
            accel.occluded_batch(rays, &mut chunk[..rays.len()], c);
        });
        out.truncate(n);
        (RayAnswers::Occluded(out), c)
    } else {
        let mut out = vec![PrimaryHits::MISS; rows(n)];
        let c = strategy.run_rows(RAYS_PER_CHUNK, &mut out, |row, chunk, c: &mut C| {
            let rays = rays_of(row, chunk.len());
            accel.intersect_batch(rays, &mut chunk[..rays.len()], c);
        });
        out.truncate(n);
        (RayAnswers::Closest(out), c)
    }
}

impl RaySet {
    /// The first bytes of [`RaySet::to_bytes`].
    const MAGIC: &'static [u8; 8] = b"BVHLRAYS";

    /// The set as bytes: a tag, its kind, its length and each ray's eight `f32`s (origin, direction, `t_min`,
    /// `t_max`), little-endian; [`RaySet::from_bytes`] reads them back bit for bit.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(17 + self.rays.len() * 32);
        bytes.extend_from_slice(Self::MAGIC);
        bytes.push(RayKind::ALL.iter().position(|&k| k == self.kind).expect("every kind is in ALL") as u8);
        bytes.extend_from_slice(&(self.rays.len() as u64).to_le_bytes());
        for r in &self.rays {
            for v in [r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.t_min, r.t_max] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        bytes
    }

    /// The set [`RaySet::to_bytes`] wrote; `None` for any other bytes.
    pub fn from_bytes(bytes: &[u8]) -> Option<RaySet> {
        let rest = bytes.strip_prefix(Self::MAGIC)?;
        let (&kind, rest) = rest.split_first()?;
        let kind = *RayKind::ALL.get(kind as usize)?;
        let (len, rest) = rest.split_at_checked(8)?;
        let len = usize::try_from(u64::from_le_bytes(len.try_into().ok()?)).ok()?;
        if rest.len() != len.checked_mul(32)? {
            return None;
        }
        let rays = rest
            .chunks_exact(32)
            .map(|ray| {
                let f = |i: usize| f32::from_le_bytes(ray[4 * i..4 * i + 4].try_into().expect("four bytes"));
                Ray { origin: Vec3::new(f(0), f(1), f(2)), dir: Vec3::new(f(3), f(4), f(5)), t_min: f(6), t_max: f(7) }
            })
            .collect();
        Some(RaySet { kind, rays })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_set_reads_back_from_its_bytes_bit_for_bit() {
        let rays = vec![
            Ray {
                origin: Vec3::new(1.0, -2.5, 3e-7),
                dir: Vec3::new(0.0, -0.0, 1.0),
                t_min: 1e-4,
                t_max: f32::INFINITY,
            },
            Ray { origin: Vec3::new(f32::MAX, 0.1, -7.0), dir: Vec3::new(0.6, 0.8, 0.0), t_min: 0.0, t_max: 2.5 },
        ];
        for kind in RayKind::ALL {
            let set = RaySet { kind, rays: rays.clone() };
            let back = RaySet::from_bytes(&set.to_bytes()).expect("reads back");
            assert_eq!(back.kind, kind);
            let bits = |s: &RaySet| s.to_bytes();
            assert_eq!(bits(&back), bits(&set));
            assert_eq!(back.rays[0].dir.y.to_bits(), (-0.0f32).to_bits());
        }
        let bytes = RaySet { kind: RayKind::Diffuse, rays }.to_bytes();
        assert!(RaySet::from_bytes(&bytes[..bytes.len() - 1]).is_none(), "cut short");
        assert!(RaySet::from_bytes(b"not rays").is_none());
        let mut wrong_kind = bytes.clone();
        wrong_kind[8] = 9;
        assert!(RaySet::from_bytes(&wrong_kind).is_none());
    }

    #[test]
    fn tile_order_covers_every_pixel_once_tile_by_tile() {
        for (w, h) in [(16, 8), (20, 13), (1, 1), (7, 9)] {
            let order: Vec<(u32, u32)> = RaySet::tile_order(w, h).collect();
            let mut sorted = order.clone();
            sorted.sort_by_key(|&(x, y)| (y, x));
            let row_major: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
            assert_eq!(sorted, row_major, "{w}x{h}: every pixel once");
        }
        let order: Vec<(u32, u32)> = RaySet::tile_order(20, 13).collect();
        assert_eq!(order[..10], [(0, 0), (1, 0), (2, 0), (3, 0), (4, 0), (5, 0), (6, 0), (7, 0), (0, 1), (1, 1)]);
        assert!(order[..64].iter().all(|&(x, y)| x < 8 && y < 8), "the first 64 rays are the first tile");
        assert_eq!(order[128..132], [(16, 0), (17, 0), (18, 0), (19, 0)], "the third tile is cut at the border");
        assert_eq!(order[132], (16, 1));
    }

    #[test]
    fn basis_is_orthonormal_and_cosine_directions_face_the_normal() {
        let mut rng = SplitMix64::new(3);
        for n in [Vec3::X, -Vec3::Z, Vec3::Z, Vec3::new(0.3, -0.8, 0.52).normalize()] {
            let (t, b) = basis(n);
            for (u, v) in [(t, b), (t, n), (b, n)] {
                assert!(u.dot(v).abs() < 1e-5);
            }
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            for _ in 0..100 {
                let d = cosine_direction(n, &mut rng);
                assert!(d.dot(n) >= -1e-6 && (d.length() - 1.0).abs() < 1e-5);
            }
        }
    }
}
