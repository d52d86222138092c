//! Spheres as closed triangle meshes: the paper's sphere scenes over triangles.
//!
//! Each sphere becomes a UV sphere of `segments` slices around its vertical axis and `max(segments / 2, 2)`
//! rings from pole to pole: the two poles, and a ring of `segments` vertices at each inner latitude, shared by
//! every triangle that touches them; fans close the caps and each band between rings is split into two
//! triangles per slice. All triangles wind counter-clockwise seen from outside. Angles use [`cos_sin_turns`]
//! (only `+ − × ÷`), so the mesh is bit-identical on every machine, like the generated scenes.

use glam::Vec3;

use super::mesh::Mesh;
use crate::geometry::Sphere;

/// `(cos, sin)` of `turns` full turns by the Taylor series: only `+ − × ÷`, so bit-identical everywhere.
fn cos_sin_turns(turns: f64) -> (f64, f64) {
    let x = std::f64::consts::TAU * (turns - turns.round());
    let (mut cos, mut sin, mut term) = (0.0, 0.0, 1.0);
    for n in 0..32 {
        let signed = if n % 4 < 2 { term } else { -term };
        if n % 2 == 0 {
            cos += signed
        } else {
            sin += signed
        }
        term *= x / (n + 1) as f64;
    }
    (cos, sin)
}

/// Every sphere as a closed UV sphere of `segments` slices (at least 3; see the module documentation).
pub fn tessellate(spheres: &[Sphere], segments: u32) -> Mesh {
    let slices = segments.max(3);
    let rings = (slices / 2).max(2);
    let mut mesh = Mesh::default();
    for s in spheres {
        let (c, r) = (s.center.as_dvec3(), s.radius as f64);
        let at = |cos_theta: f64, sin_theta: f64, (cos_phi, sin_phi): (f64, f64)| {
            (c + glam::DVec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi) * r).as_vec3()
        };
        let north = mesh.positions.len() as u32;
        mesh.positions.push(s.center + Vec3::Y * s.radius);
        for i in 1..rings {
            let (cos_theta, sin_theta) = cos_sin_turns(i as f64 / (2 * rings) as f64);
            for j in 0..slices {
                mesh.positions.push(at(cos_theta, sin_theta, cos_sin_turns(j as f64 / slices as f64)));
            }
        }
        let south = mesh.positions.len() as u32;
        mesh.positions.push(s.center - Vec3::Y * s.radius);
        let ring = |i: u32, j: u32| north + 1 + i * slices + j % slices;
        for j in 0..slices {
            mesh.indices.push([north, ring(0, j + 1), ring(0, j)]);
            for i in 0..rings - 2 {
                let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j));
                mesh.indices.push([a, b, c]);
                mesh.indices.push([a, c, d]);
            }
            mesh.indices.push([south, ring(rings - 2, j), ring(rings - 2, j + 1)]);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    #[test]
    fn cos_sin_turns_matches_the_library() {
        for k in 0..=64 {
            let turns = k as f64 / 64.0 - 0.3;
            let (c, s) = cos_sin_turns(turns);
            let x = std::f64::consts::TAU * turns;
            assert!((c - x.cos()).abs() < 1e-14 && (s - x.sin()).abs() < 1e-14, "{turns}");
        }
    }

    /// Every edge is shared by exactly two triangles that run it in opposite directions (closed, consistently
    /// wound), no triangle repeats a vertex, and every vertex lies on its sphere.
    #[test]
    fn tessellated_spheres_are_closed_consistently_wound_meshes() {
        let spheres = [Sphere::new(Vec3::new(1.0, 2.0, -3.0), 0.5), Sphere::new(Vec3::new(-4.0, 0.5, -9.0), 2.0)];
        for segments in [3, 4, 7, 16] {
            let mesh = tessellate(&spheres, segments);
            let rings = (segments / 2).max(2);
            assert_eq!(mesh.indices.len(), 2 * (2 * segments * (rings - 1)) as usize);
            let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
            for &[a, b, c] in &mesh.indices {
                assert!(a != b && b != c && a != c);
                for e in [(a, b), (b, c), (c, a)] {
                    *directed.entry(e).or_default() += 1;
                }
            }
            for (&(a, b), &n) in &directed {
                assert_eq!((n, directed.get(&(b, a))), (1, Some(&1)), "edge {a}-{b} of {segments} segments");
            }
            let per_sphere = mesh.positions.len() / 2;
            for (k, p) in mesh.positions.iter().enumerate() {
                let s = spheres[k / per_sphere];
                assert!(((*p - s.center).length() - s.radius).abs() < 1e-5 * s.radius.max(1.0));
            }
            let per_sphere_triangles = mesh.indices.len() / 2;
            for (k, tri) in mesh.triangles().enumerate() {
                let normal = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]);
                assert!(normal.dot(tri.centroid() - spheres[k / per_sphere_triangles].center) > 0.0);
            }
        }
    }
}
