//! [`Triangle`] as an [`ExactPrimitive`]: its f64 test ([`ExactTriangleTest`]) and the screen f64 brute force
//! runs first.
//!
//! The triangles are kept in Morton order of their centroids in chunks of [`CHUNK`], each with the box of its
//! vertices; a chunk is skipped when the ray's line misses that box widened by `(64u + 1e-9)·F` (`F` bounding the
//! distance from the origin to any point of the box). The watertight test decides as for vertices moved by a few
//! `u·|pᵢ − o|₁` in ray space (see [`ExactTriangleTest`]), and Möller–Trumbore likewise wherever `det` is more
//! than rounding, so neither reports a triangle whose line passes farther than that: a skipped chunk holds none.
//! The one exception is a ray lying in a triangle's plane to within rounding (`|det| ≤ 3Δ`), where
//! Möller–Trumbore's `det` is noise and it may report a triangle anywhere along the line; such a report from a
//! skipped chunk is judged wrong. Every triangle of a kept chunk gets the full evaluation.

use super::chunk_box::{ChunkBox, morton_order};
use super::{ExactAnswer, ExactPrimitive};
use crate::geometry::{ExactTriangleTest, Ray, Triangle, U_F32};

/// Triangles per chunk (Morton order).
const CHUNK: usize = 64;

/// A scene's triangles laid out for the screen: in Morton order of their centroids, in boxed chunks.
#[derive(Clone, Debug)]
pub struct TriangleLayout {
    /// Scene index of the triangle at each position of the layout.
    order: Vec<u32>,
    /// The box of each chunk's vertices.
    chunks: Vec<ChunkBox>,
}

impl TriangleLayout {
    /// Lays out `triangles` for the screen.
    pub fn new(triangles: &[Triangle]) -> Self {
        let centroids: Vec<[f64; 3]> = triangles.iter().map(|t| t.centroid().as_dvec3().to_array()).collect();
        let order = morton_order(&centroids);
        let chunks = order
            .chunks(CHUNK)
            .map(|chunk| {
                let vertices = chunk.iter().flat_map(|&i| triangles[i as usize].p.map(|p| p.as_dvec3()));
                let (x, (y, z)): (Vec<f64>, (Vec<f64>, Vec<f64>)) = vertices.map(|p| (p.x, (p.y, p.z))).unzip();
                ChunkBox::of(&x, &y, &z)
            })
            .collect();
        Self { order, chunks }
    }

    /// Ascending scene indices of the triangles of the chunks kept for `ray`; `skip` skips the chunks the line
    /// misses (module documentation), else every triangle is kept.
    fn screened(&self, ray: &Ray, skip: bool) -> Vec<u32> {
        let (o, n) = (ray.origin.as_dvec3().to_array(), ray.dir.as_dvec3().normalize().to_array());
        let widen = |far: f64| (64.0 * U_F32 + 1e-9) * far;
        let mut kept: Vec<u32> = (self.order.chunks(CHUNK).zip(&self.chunks))
            .filter(|(_, b)| !skip || b.meets_line(o, n, widen))
            .flat_map(|(chunk, _)| chunk.iter().copied())
            .collect();
        kept.sort_unstable();
        kept
    }
}

impl ExactPrimitive for Triangle {
    type Layout = TriangleLayout;

    fn layout(prims: &[Self]) -> TriangleLayout {
        TriangleLayout::new(prims)
    }

    fn screen(layout: &TriangleLayout, ray: &Ray) -> Vec<u32> {
        layout.screened(ray, true)
    }

    fn exact(&self, ray: &Ray) -> ExactAnswer {
        let test = ExactTriangleTest::new(self, ray);
        let (t_min, t_max) = (ray.t_min as f64, ray.t_max as f64);
        ExactAnswer { hit: test.exact_hit(t_min, t_max), outcomes: test.f32_outcomes(t_min, t_max) }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::Hit;
    use crate::agreement::{Answer, BruteForce64, Outcome, Tolerated, Verdict, arbitrate};
    use crate::geometry::TriangleTest;
    use crate::rng::SplitMix64;
    use crate::scene::SceneKind;
    use crate::scene::{random_triangles, tessellate};

    /// The paper's scene tessellated (closed meshes) plus random triangles, and rays at them: through vertices and
    /// points of edges (shared edges of the closed meshes included) from random origins, through random interior
    /// points, and from far away.
    fn triangles_and_rays() -> (Vec<Triangle>, Vec<Ray>) {
        let scene = SceneKind::RandomSpheres.generate(200, 3);
        let mut triangles: Vec<Triangle> = tessellate(&scene.spheres, 8).triangles().collect();
        triangles.extend(random_triangles(2_000, 5).triangles());
        let mut rng = SplitMix64::new(9);
        let mut rays = Vec::new();
        for i in 0..6_000 {
            let tri = triangles[rng.below(triangles.len() as u64) as usize];
            let (b1, b2) = (rng.next_f64() as f32, rng.next_f64() as f32);
            let aim = match i % 3 {
                0 => tri.p[rng.below(3) as usize],
                1 => tri.p[0].lerp(tri.p[1], b1),
                _ if b1 + b2 <= 1.0 => tri.p[0] + (tri.p[1] - tri.p[0]) * b1 + (tri.p[2] - tri.p[0]) * b2,
                _ => tri.centroid(),
            };
            let s = [20.0, 40.0, 1e4][i % 3];
            let origin = Vec3::new(rng.range(-s, s) as f32, rng.range(0.0, s) as f32, rng.range(-s, 10.0) as f32);
            rays.push(Ray::new(origin, aim - origin));
        }
        (triangles, rays)
    }

    /// Skipping chunks changes nothing but the documented exception: the same candidates as keeping every
    /// triangle, except triangles whose plane holds the ray to within rounding (`T` infinite), counted and printed.
    #[test]
    fn skipping_chunks_keeps_every_candidate() {
        let (triangles, rays) = triangles_and_rays();
        let layout = TriangleLayout::new(&triangles);
        let in_plane = |ray: &Ray, i: u32| ExactTriangleTest::new(&triangles[i as usize], ray).t_bound.is_infinite();
        let candidates = |ray: &Ray, skip: bool| -> Vec<u32> {
            let kept = layout.screened(ray, skip);
            kept.into_iter().filter(|&i| triangles[i as usize].exact(ray).outcomes.may_hit()).collect()
        };
        let (mut total, mut screened, mut excepted) = (0, 0, 0);
        // Every fourth ray (all three kinds of aim and origin scale, as 4 and 3 are coprime): keeping every
        // triangle costs an f64 test of every triangle per ray.
        let rays: Vec<Ray> = rays.into_iter().step_by(4).collect();
        for ray in &rays {
            let (skipped, all) = (candidates(ray, true), candidates(ray, false));
            for &i in all.iter().filter(|i| !skipped.contains(i)) {
                assert!(in_plane(ray, i), "skipped candidate {i} for {ray:?}");
                excepted += 1;
            }
            total += all.len();
            screened += layout.screened(ray, true).len();
        }
        eprintln!("{total} candidates over {} rays; {excepted} skipped in-plane triangles", rays.len());
        assert!(total > rays.len(), "{total} candidates over {} rays", rays.len());
        assert!(excepted * 100 < total, "the exception must stay rare");
        assert!(screened < rays.len() * triangles.len() / 4, "the screen must skip most chunks");
    }

    /// f32 brute force with either test is acceptable to f64 on every ray; rays through edges and vertices where
    /// it differs from f64 are ties or leaks (tolerated, counted and printed), never wrong; the watertight test
    /// never leaks, and Möller–Trumbore leaks on these rays aimed at shared vertices and edges.
    #[test]
    fn f32_brute_force_with_either_test_is_acceptable_to_f64() {
        let (triangles, rays) = triangles_and_rays();
        let exact = BruteForce64::new(&triangles);
        let candidates = exact.candidates(&rays);
        for test in TriangleTest::ALL {
            let (mut ties, mut leaks, mut grazing) = (0, 0, 0);
            for (ray, c) in rays.iter().zip(&candidates) {
                let closest = (0..triangles.len() as u32)
                    .filter_map(|prim| {
                        triangles[prim as usize].intersect(test, ray, ray.t_max).map(|h| Hit { t: h.t, prim })
                    })
                    .min_by(|a, b| a.t.total_cmp(&b.t));
                let verdict = c.verdict(&Answer::Closest(closest));
                assert_ne!(verdict, Verdict::Wrong, "{}: {closest:?} for {ray:?}", test.name());
                let occluded = c.verdict(&Answer::Occluded(closest.is_some()));
                assert_ne!(occluded, Verdict::Wrong, "{}: occlusion for {ray:?}", test.name());
                let f64_answer = Answer::Closest(c.exact_closest().map(|(prim, t)| Hit { t: t as f32, prim }));
                match arbitrate(c, &f64_answer, &Answer::Closest(closest)) {
                    Outcome::Agree => {}
                    Outcome::Tolerated(Tolerated::Tie) => ties += 1,
                    Outcome::Tolerated(Tolerated::Leak) => leaks += 1,
                    Outcome::Tolerated(Tolerated::Grazing) => grazing += 1,
                    Outcome::Mismatch(side) => panic!("{}: {side:?} for {ray:?}", test.name()),
                }
            }
            eprintln!("{}: {ties} ties, {leaks} leaks, {grazing} grazing in {} rays", test.name(), rays.len());
            match test {
                TriangleTest::Watertight => assert_eq!(leaks, 0, "a watertight test does not leak"),
                TriangleTest::MollerTrumbore => assert!(leaks > 0, "Möller–Trumbore leaks at shared edges"),
            }
        }
    }
}
