//! The watertight ray–triangle test of Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection" (JCGT 2013).
//!
//! The vertices are moved into *ray space*: translated to the origin, the axes permuted so that `kz` is the
//! direction's dominant axis (`kx`, `ky` swapped when `d[kz] < 0`, keeping the winding), and sheared so that the
//! ray runs along `z`: `x = a[kx] − Sx·a[kz]`, `y = a[ky] − Sy·a[kz]` with `Sx = d[kx] / d[kz]`,
//! `Sy = d[ky] / d[kz]`, and `z = Sz·a[kz]`, `Sz = 1 / d[kz]`. The ray then pierces the triangle where the
//! 2D edge functions `U = E(p1, p2)`, `V = E(p2, p0)`, `W = E(p0, p1)`, `E(p, q) = q.x·p.y − q.y·p.x`, share a
//! sign (either sign: both sides are hit); `U, V, W` over `det = U + V + W` are the barycentrics, and
//! `t = (U·z0 + V·z1 + W·z2) / det`. A shared edge is sheared identically in both triangles and `E(q, p)` is
//! exactly `−E(p, q)`, so a ray cannot slip between them; where an edge function rounds to exactly 0 it is
//! recomputed in f64 (products of f32 are exact there), so a ray through a shared vertex is decided consistently.

use super::{Ray, Triangle, TriangleHit};

/// The 2D edge function `q.x·p.y − q.y·p.x` of points in ray space.
#[inline(always)]
fn edge(p: (f32, f32), q: (f32, f32)) -> f32 {
    q.0 * p.1 - q.1 * p.0
}

/// [`edge`] with the products exact: in f64, rounded once to f32.
#[inline(always)]
fn edge_f64(p: (f32, f32), q: (f32, f32)) -> f32 {
    (q.0 as f64 * p.1 as f64 - q.1 as f64 * p.0 as f64) as f32
}

impl Triangle {
    /// Nearest hit with `t` in `(ray.t_min, t_max)` by the watertight test (see the module documentation).
    #[inline(always)]
    pub fn intersect_watertight(&self, ray: &Ray, t_max: f32) -> Option<TriangleHit> {
        let d = ray.dir;
        let kz = d.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
        let [a, b, c] = self.p.map(|p| p - ray.origin);
        let shear = |v: glam::Vec3| (v[kx] - sx * v[kz], v[ky] - sy * v[kz]);
        let (a2, b2, c2) = (shear(a), shear(b), shear(c));
        let (mut u, mut v, mut w) = (edge(b2, c2), edge(c2, a2), edge(a2, b2));
        if u == 0.0 || v == 0.0 || w == 0.0 {
            (u, v, w) = (edge_f64(b2, c2), edge_f64(c2, a2), edge_f64(a2, b2));
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
        let inv_det = 1.0 / det;
        let t = t_scaled * inv_det;
        (t > ray.t_min && t < t_max).then_some(TriangleHit { t, b1: v * inv_det, b2: w * inv_det })
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::{Sphere, TriangleTest};
    use crate::rng::SplitMix64;
    use crate::scene::tessellate;

    /// Rays through every vertex of closed tessellated spheres and through seven points on each edge, from outside
    /// toward the center and from the center outward: the watertight test never lets one through; Möller–Trumbore's
    /// leaks are counted and printed.
    #[test]
    fn rays_through_shared_edges_and_vertices_of_a_closed_mesh_never_leak() {
        let mut rng = SplitMix64::new(22);
        let mut leaks = [0usize; 2];
        let mut rays = 0;
        for k in 0..12 {
            let scale = [1.0, 30.0, 300.0][k % 3];
            let center = Vec3::new(rng.range(-scale, scale) as f32, rng.range(-scale, scale) as f32, -scale as f32);
            let sphere = Sphere::new(center, rng.range(0.05, 3.0) as f32);
            let mesh = tessellate(&[sphere], [3, 5, 8, 16, 33, 64][k % 6]);
            let triangles: Vec<Triangle> = mesh.triangles().collect();
            // The triangles around each vertex: a ray aimed at a vertex or an edge is tried against those first, so
            // that only a ray that misses them all is tried against every triangle (the answer is the same).
            let mut around: Vec<Vec<usize>> = vec![Vec::new(); mesh.positions.len()];
            for (j, corners) in mesh.indices.iter().enumerate() {
                corners.iter().for_each(|&v| around[v as usize].push(j));
            }
            // Each target with the two vertices whose triangles it lies on (the same twice for a vertex).
            let mut targets: Vec<(Vec3, [u32; 2])> =
                mesh.positions.iter().enumerate().map(|(v, &p)| (p, [v as u32; 2])).collect();
            for &[a, b, c] in &mesh.indices {
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    let (pp, qp) = (mesh.positions[p as usize], mesh.positions[q as usize]);
                    targets.extend((1..8).map(|i| (pp.lerp(qp, i as f32 / 8.0), [p, q])));
                }
            }
            for (target, ends) in targets {
                let near = || ends.iter().flat_map(|&v| &around[v as usize]).map(|&j| &triangles[j]);
                let outside = center + (target - center) * [1.5f32, 3.0, 10.0][rays % 3];
                for ray in [Ray::new(outside, center - outside), Ray::new(center, target - center)] {
                    rays += 1;
                    for (n, test) in TriangleTest::ALL.into_iter().enumerate() {
                        let hits = |t: &Triangle| t.intersect(test, &ray, f32::INFINITY).is_some();
                        if !(near().any(hits) || triangles.iter().any(hits)) {
                            leaks[n] += 1;
                        }
                    }
                }
            }
        }
        for (n, test) in TriangleTest::ALL.into_iter().enumerate() {
            eprintln!("{}: {} leaks in {rays} rays through shared edges and vertices", test.name(), leaks[n]);
        }
        assert!(rays > 100_000, "{rays}");
        assert_eq!(leaks[TriangleTest::ALL.iter().position(|&t| t == TriangleTest::Watertight).unwrap()], 0);
        assert!(leaks.iter().all(|&l| l < rays));
    }
}
