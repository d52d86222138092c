//! Large scenes from one model: `copies` copies of a mesh laid out on a square grid in its ground plane, each
//! turned about the up axis by a seeded number of quarter turns, so a city becomes a bigger city of varied blocks
//! (and a scanned model a field of them).
//!
//! The layout is a pure function of the mesh, its up axis and `copies`: quarter turns only swap and negate
//! coordinates (exact in f32), the turns come from [`SplitMix64`] seeded with [`TILE_SEED`], and each copy is placed
//! by one f32 addition per coordinate, so the same inputs give bit-identical meshes on every machine.

use glam::Vec3;

use super::mesh::Mesh;
use super::mesh_scene::horizontal;
use crate::rng::SplitMix64;

/// The seed of the copies' quarter turns.
pub const TILE_SEED: u64 = 0x7115;

/// Space between neighbouring copies, as a fraction of a grid cell (a street between two tiles of a city).
const GAP: f32 = 0.05;

impl Mesh {
    /// `copies` copies of this mesh on a ⌈√copies⌉-wide square grid in the plane normal to the unit axis `up`,
    /// row by row, each turned by 0–3 seeded quarter turns about `up`; copy 0 is this mesh unturned, at the
    /// grid's first cell.
    pub fn tiled(&self, copies: u32, up: Vec3) -> Mesh {
        let (a, b) = horizontal(up);
        let bounds = self.bounds();
        let extent = bounds.extent();
        // Square cells fit a copy in any of its four turns.
        let cell = a.dot(extent).abs().max(b.dot(extent).abs()) * (1.0 + GAP);
        let width = (copies as f64).sqrt().ceil() as u32;
        let mut rng = SplitMix64::new(TILE_SEED);
        let mut out = Mesh {
            positions: Vec::with_capacity(self.positions.len() * copies as usize),
            indices: Vec::with_capacity(self.indices.len() * copies as usize),
        };
        for k in 0..copies {
            let turns = if k == 0 { 0 } else { rng.below(4) as u32 };
            let turned = |p: Vec3| turn(p, a, b, turns);
            // The turned copy's own box (a quarter turn only swaps and negates coordinates, so it is the model's box
            // turned, exactly), then the shift that centres it in its cell (the up coordinate unchanged).
            let (p, q) = (turned(bounds.min), turned(bounds.max));
            let (lo, hi) = (p.min(q), p.max(q));
            let centre = |axis: Vec3, index: u32| {
                let at = axis.dot(lo) + 0.5 * (axis.dot(hi) - axis.dot(lo));
                axis * (cell * (index as f32 + 0.5) - at)
            };
            let shift = centre(a, k % width) + centre(b, k / width);
            let offset = out.positions.len() as u32;
            out.positions.extend(self.positions.iter().map(|&p| turned(p) + shift));
            out.indices.extend(self.indices.iter().map(|t| t.map(|i| i + offset)));
        }
        out
    }
}

/// `p` turned by `turns` quarter turns from axis `a` toward axis `b` (both unit axes): exact, by swaps and signs.
fn turn(p: Vec3, a: Vec3, b: Vec3, turns: u32) -> Vec3 {
    let (pa, pb) = (a.dot(p), b.dot(p));
    let rest = p - a * pa - b * pb;
    let (na, nb) = match turns % 4 {
        0 => (pa, pb),
        1 => (-pb, pa),
        2 => (-pa, -pb),
        _ => (pb, -pa),
    };
    rest + a * na + b * nb
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> Mesh {
        // A unit-square floor and a tall sliver, not symmetric under a quarter turn.
        Mesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.5, 0.2, 3.0),
            ],
            indices: vec![[0, 1, 2], [0, 1, 3]],
        }
    }

    #[test]
    fn copies_are_exact_turns_of_the_model_in_their_own_cells() {
        let m = block();
        let t = m.tiled(5, Vec3::Z);
        assert_eq!(t.triangle_count(), 10);
        assert_eq!(t.positions.len(), 20);
        let cell = 2.0 * (1.0 + GAP);
        for k in 0..5usize {
            let copy = &t.positions[4 * k..4 * k + 4];
            // Same heights, same shape up to a quarter turn: every edge length is the model's.
            for (p, q) in copy.iter().zip(&m.positions) {
                assert_eq!(p.z, q.z);
            }
            for (i, j) in [(0, 1), (0, 2), (1, 3)] {
                let d = (copy[i] - copy[j]).length();
                let e = (m.positions[i] - m.positions[j]).length();
                assert!((d - e).abs() < 1e-5, "copy {k}: edge {i}-{j} {d} vs {e}");
            }
            // Inside its own cell of the 3-wide grid.
            let (cx, cy) = ((k % 3) as f32, (k / 3) as f32);
            for p in copy {
                assert!(p.x >= cx * cell - 1e-5 && p.x <= (cx + 1.0) * cell + 1e-5, "copy {k}: {p}");
                assert!(p.y >= cy * cell - 1e-5 && p.y <= (cy + 1.0) * cell + 1e-5, "copy {k}: {p}");
            }
            assert_eq!(t.indices[2 * k], [0, 1, 2].map(|i| i + 4 * k as u32));
        }
        // Copy 0 is the model moved, unturned.
        assert_eq!(t.positions[1] - t.positions[0], m.positions[1] - m.positions[0]);
    }

    #[test]
    fn the_same_inputs_give_the_same_mesh_and_the_turns_vary() {
        let m = block();
        let (x, y) = (m.tiled(16, Vec3::Y), m.tiled(16, Vec3::Y));
        assert_eq!(x.fingerprint(), y.fingerprint());
        assert_ne!(x.fingerprint(), m.tiled(16, Vec3::Z).fingerprint());
        // Not every copy has the same orientation: the direction of edge 0-1 takes more than one value.
        let directions: std::collections::BTreeSet<[i32; 3]> = (0..16)
            .map(|k| {
                let d = (x.positions[4 * k + 1] - x.positions[4 * k]).round();
                [d.x as i32, d.y as i32, d.z as i32]
            })
            .collect();
        assert!(directions.len() > 1, "{directions:?}");
    }

    #[test]
    fn one_copy_is_the_model_moved() {
        let m = block();
        let t = m.tiled(1, Vec3::Z);
        assert_eq!(t.indices, m.indices);
        let shift = t.positions[0] - m.positions[0];
        for (p, q) in t.positions.iter().zip(&m.positions) {
            assert!((*p - *q - shift).length() < 1e-6);
        }
    }
}
