//! Random triangles: `n` free triangles uniformly placed in the paper's scene box.
//!
//! Sizes follow the random-sphere scene: `s = 0.6 * cbrt(volume / n) * U(0.5, 1.5)` (capped at 6, twice the
//! sphere radius, so a triangle spans about a sphere's diameter). Per triangle, in order: `s`, the center's x, z,
//! y (as the spheres draw theirs), then each vertex as the center plus `s * U(−1, 1)` per axis. The RNG is seeded
//! with the seed itself. Triangles share no vertices: positions `3i, 3i + 1, 3i + 2` are triangle `i`'s.

use glam::Vec3;

use super::mesh::Mesh;
use crate::rng::SplitMix64;
use crate::scene::{SCENE_BOX, radius_scale};

/// `n` random triangles drawn from `seed` (see the module documentation).
pub fn random_triangles(n: usize, seed: u64) -> Mesh {
    let mut rng = SplitMix64::new(seed);
    let scale = 0.6 * radius_scale(n);
    let (lo, hi) = (SCENE_BOX.min, SCENE_BOX.max);
    let mut mesh = Mesh { positions: Vec::with_capacity(3 * n), indices: Vec::with_capacity(n) };
    for i in 0..n as u32 {
        let s = (scale * rng.range(0.5, 1.5)).min(6.0);
        let x = rng.range(lo.x as f64, hi.x as f64);
        let z = rng.range(lo.z as f64, hi.z as f64);
        let y = rng.range(lo.y as f64, hi.y as f64);
        for _ in 0..3 {
            let offset = [(); 3].map(|_| s * rng.range(-1.0, 1.0));
            mesh.positions.push(Vec3::new((x + offset[0]) as f32, (y + offset[1]) as f32, (z + offset[2]) as f32));
        }
        mesh.indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_mesh_and_another_seed_another() {
        let mesh = random_triangles(1000, 42);
        assert_eq!(mesh, random_triangles(1000, 42));
        assert_ne!(mesh, random_triangles(1000, 43));
        assert_eq!((mesh.indices.len(), mesh.positions.len()), (1000, 3000));
        let reach = crate::geometry::Aabb { min: SCENE_BOX.min - 6.0, max: SCENE_BOX.max + 6.0 };
        assert!(mesh.positions.iter().all(|&p| reach.contains(p)));
        let first = random_triangles(10, 42);
        assert_ne!(first.positions[..3], mesh.positions[..3], "sizes depend on n, as for spheres");
    }
}
