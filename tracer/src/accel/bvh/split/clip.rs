//! Clipping a primitive's part inside a box at an axis-aligned plane: the two boxes a spatial split gives it.
//!
//! Triangles are clipped exactly: the triangle polygon is clipped to the box, then to either side of the plane
//! (Sutherland–Hodgman, in f64), and each side's polygon bounded, rounded outward to f32 and cut to the box and its
//! half-space. So each box holds every point of the triangle that lies in the given box on its side of the plane.
//! Other primitives (spheres) clip their box only.

use glam::{DVec3, Vec3A};

use super::Box3A;
use crate::geometry::Triangle;

/// Most vertices of a triangle clipped by seven planes (each adds at most one).
const MAX_VERTICES: usize = 10;

/// A convex polygon of at most [`MAX_VERTICES`] vertices.
#[derive(Clone, Copy)]
struct Polygon {
    vertices: [DVec3; MAX_VERTICES],
    len: usize,
}

impl Polygon {
    const EMPTY: Polygon = Polygon { vertices: [DVec3::ZERO; MAX_VERTICES], len: 0 };

    fn triangle(t: &Triangle) -> Self {
        let mut poly = Polygon::EMPTY;
        for (v, p) in poly.vertices.iter_mut().zip(t.p) {
            *v = p.as_dvec3();
        }
        poly.len = 3;
        poly
    }

    fn vertices(&self) -> &[DVec3] {
        &self.vertices[..self.len]
    }

    /// The part inside `within` (Sutherland–Hodgman against its six planes). A plane that no vertex lies beyond
    /// leaves the polygon as it is (the clip would copy every vertex in order), so it is skipped.
    fn clip_to_box(&mut self, within: &Box3A) {
        let mut out = Polygon::EMPTY;
        for a in 0..3 {
            for (pos, below) in [(within.min[a] as f64, false), (within.max[a] as f64, true)] {
                let beyond = |v: &DVec3| if below { v[a] > pos } else { v[a] < pos };
                if self.vertices().iter().any(beyond) {
                    let [lo, hi] = if below { [Some(&mut out), None] } else { [None, Some(&mut out)] };
                    self.split_into(a, pos, lo, hi);
                    std::mem::swap(self, &mut out);
                }
            }
        }
    }

    /// The parts on the side of `axis = pos` where `coordinate <= pos` (into `below`) and where `>= pos` (into
    /// `above`), in one pass over the edges; either may be left out.
    fn split_into(&self, axis: usize, pos: f64, mut below: Option<&mut Polygon>, mut above: Option<&mut Polygon>) {
        if let Some(p) = below.as_deref_mut() {
            p.len = 0;
        }
        if let Some(p) = above.as_deref_mut() {
            p.len = 0;
        }
        for i in 0..self.len {
            let (a, b) = (self.vertices[i], self.vertices[(i + 1) % self.len]);
            let crossing = || {
                let t = (pos - a[axis]) / (b[axis] - a[axis]);
                let mut p = a + (b - a) * t;
                p[axis] = pos;
                p
            };
            if let Some(out) = below.as_deref_mut() {
                let (ia, ib) = (a[axis] <= pos, b[axis] <= pos);
                if ia {
                    out.push(a);
                }
                if ia != ib {
                    out.push(crossing());
                }
            }
            if let Some(out) = above.as_deref_mut() {
                let (ia, ib) = (a[axis] >= pos, b[axis] >= pos);
                if ia {
                    out.push(a);
                }
                if ia != ib {
                    out.push(crossing());
                }
            }
        }
    }

    fn push(&mut self, v: DVec3) {
        // A convex polygon clipped by one plane gains at most one vertex; the bound holds by construction.
        if self.len < MAX_VERTICES {
            self.vertices[self.len] = v;
            self.len += 1;
        }
    }

    /// Bounds rounded outward to f32 (one ulp beyond the nearest f32, covering the f64 rounding); empty if no vertex.
    /// Rounding to the nearest f32 and stepping one ulp are monotonic, so they are applied once, to the f64 bounds:
    /// the same box as rounding every vertex.
    fn bounds(&self) -> Box3A {
        let Some((first, rest)) = self.vertices[..self.len].split_first() else { return Box3A::EMPTY };
        let (lo, hi) = rest.iter().fold((*first, *first), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
        Box3A {
            min: Vec3A::from_array(lo.as_vec3a().to_array().map(f32::next_down)),
            max: Vec3A::from_array(hi.as_vec3a().to_array().map(f32::next_up)),
        }
    }

    /// [`bounds`](Self::bounds) cut to `within` (empty where they do not meet).
    fn bounds_in(&self, within: &Box3A) -> Box3A {
        let b = self.bounds();
        Box3A { min: b.min.max(within.min), max: b.max.min(within.max) }
    }
}

/// `within` cut to the half-space `coordinate <= pos` (`[0]`) and `>= pos` (`[1]`); either may be empty.
#[inline]
pub fn box_halves(within: &Box3A, axis: usize, pos: f32) -> [Box3A; 2] {
    let (mut left, mut right) = (*within, *within);
    left.max[axis] = left.max[axis].min(pos);
    right.min[axis] = right.min[axis].max(pos);
    [left, right]
}

/// The boxes of the parts of `t` inside `within` below and above the plane `axis = pos` (empty where none).
pub fn triangle_halves(t: &Triangle, within: &Box3A, axis: usize, pos: f32) -> [Box3A; 2] {
    let mut poly = Polygon::triangle(t);
    poly.clip_to_box(within);
    let (mut below, mut above) = (Polygon::EMPTY, Polygon::EMPTY);
    poly.split_into(axis, pos as f64, Some(&mut below), Some(&mut above));
    let halves = box_halves(within, axis, pos);
    let parts = [below, above];
    [0, 1].map(|k| parts[k].bounds_in(&halves[k]))
}

/// [`Referenced::slab_parts`](super::Referenced::slab_parts) of a box: `within` cut to each slab it reaches.
pub fn box_slab_parts(within: &Box3A, axis: usize, planes: &[f32], mut part: impl FnMut(usize, Box3A)) {
    let mut rest = *within;
    for (i, &pos) in planes.iter().enumerate() {
        let [below, above] = box_halves(&rest, axis, pos);
        if !is_empty(&below) {
            part(i, below);
        }
        rest = above;
        if is_empty(&rest) {
            return;
        }
    }
    part(planes.len(), rest);
}

/// [`Referenced::slab_parts`](super::Referenced::slab_parts) of a triangle: its polygon clipped to `within` once, then
/// cut at each plane in turn, each slab's part bounded as in [`triangle_halves`].
pub fn triangle_slab_parts(
    t: &Triangle,
    within: &Box3A,
    axis: usize,
    planes: &[f32],
    mut part: impl FnMut(usize, Box3A),
) {
    let mut poly = Polygon::triangle(t);
    poly.clip_to_box(within);
    let (mut below, mut above) = (Polygon::EMPTY, Polygon::EMPTY);
    let mut slab = *within;
    for (i, &pos) in planes.iter().enumerate() {
        let [below_box, above_box] = box_halves(&slab, axis, pos);
        poly.split_into(axis, pos as f64, Some(&mut below), Some(&mut above));
        let b = below.bounds_in(&below_box);
        if !is_empty(&b) {
            part(i, b);
        }
        std::mem::swap(&mut poly, &mut above);
        slab = above_box;
        if poly.len == 0 {
            return;
        }
    }
    let b = poly.bounds_in(&slab);
    if !is_empty(&b) {
        part(planes.len(), b);
    }
}

/// True when the box holds no point.
#[inline(always)]
pub fn is_empty(b: &Box3A) -> bool {
    b.min.cmpgt(b.max).any()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::rng::SplitMix64;

    fn boxed(t: &Triangle) -> Box3A {
        let b = t.bounds();
        Box3A { min: b.min.into(), max: b.max.into() }
    }

    fn contains(b: &Box3A, p: Vec3) -> bool {
        Vec3A::from(p).cmpge(b.min).all() && Vec3A::from(p).cmple(b.max).all()
    }

    /// Points of the triangle on either side of the plane lie in that side's box, and the boxes are tight: no wider
    /// than the triangle's own box cut at the plane, and narrower on some axis for a long diagonal triangle.
    #[test]
    fn halves_hold_every_point_of_their_side() {
        let mut rng = SplitMix64::new(17);
        let mut f = |s: f64| ((rng.next_f64() - 0.5) * s) as f32;
        for i in 0..2_000 {
            let s = [1.0, 1e3, 1e-2][i % 3];
            let t =
                Triangle::new(Vec3::new(f(s), f(s), f(s)), Vec3::new(f(s), f(s), f(s)), Vec3::new(f(s), f(s), f(s)));
            let within = boxed(&t);
            let axis = i % 3;
            let pos = within.min[axis] + (within.max[axis] - within.min[axis]) * 0.37;
            let halves = triangle_halves(&t, &within, axis, pos);
            for k in 0..200 {
                let (mut b1, mut b2) = ((k as f32 * 0.618).fract(), (k as f32 * 0.414).fract());
                if b1 + b2 > 1.0 {
                    (b1, b2) = (1.0 - b1, 1.0 - b2);
                }
                let p = t.p[0] + (t.p[1] - t.p[0]) * b1 + (t.p[2] - t.p[0]) * b2;
                // Points exactly representable are checked on the side the f32 coordinate says.
                let side = (p[axis] > pos) as usize;
                if p[axis] != pos && within.min.cmple(Vec3A::from(p)).all() && within.max.cmpge(Vec3A::from(p)).all() {
                    assert!(contains(&halves[side], p), "{t:?} {axis} {pos}: {p} not in {:?}", halves[side]);
                }
            }
            for (h, cut) in halves.iter().zip(box_halves(&within, axis, pos)) {
                assert!(is_empty(h) || (h.min.cmpge(cut.min).all() && h.max.cmple(cut.max).all()), "{t:?}");
            }
        }
        let long = Triangle::new(Vec3::ZERO, Vec3::new(10.0, 10.0, 0.0), Vec3::new(10.0, 10.1, 0.0));
        let [left, right] = triangle_halves(&long, &boxed(&long), 0, 5.0);
        assert!(left.max.y < 5.2 && right.min.y > 4.9, "{left:?} {right:?}");
    }

    /// Every point of the triangle lies in the part of the slab its coordinate falls in.
    #[test]
    fn slab_parts_hold_every_point_of_their_slab() {
        let mut rng = SplitMix64::new(23);
        let mut f = |s: f64| ((rng.next_f64() - 0.5) * s) as f32;
        for i in 0..1_000 {
            let t = Triangle::new(Vec3::new(f(8.0), f(8.0), f(8.0)), Vec3::new(f(8.0), f(8.0), f(8.0)), Vec3::ZERO);
            let within = boxed(&t);
            let axis = i % 3;
            let (lo, hi) = (within.min[axis], within.max[axis]);
            let planes: Vec<f32> = (1..7).map(|k| lo + (hi - lo) * (k as f32 / 7.0)).collect();
            let mut parts = [Box3A::EMPTY; 7];
            triangle_slab_parts(&t, &within, axis, &planes, |k, b| parts[k] = b);
            for k in 0..300 {
                let (mut b1, mut b2) = ((k as f32 * 0.618).fract(), (k as f32 * 0.414).fract());
                if b1 + b2 > 1.0 {
                    (b1, b2) = (1.0 - b1, 1.0 - b2);
                }
                let p = t.p[0] + (t.p[1] - t.p[0]) * b1 + (t.p[2] - t.p[0]) * b2;
                let slab = planes.iter().filter(|&&q| q < p[axis]).count();
                if planes.contains(&p[axis]) {
                    continue;
                }
                assert!(contains(&parts[slab], p), "{t:?} axis {axis}: {p} not in slab {slab} {:?}", parts[slab]);
            }
        }
    }

    #[test]
    fn a_triangle_on_one_side_leaves_the_other_half_empty() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let within = Box3A { min: Vec3A::splat(-1.0), max: Vec3A::splat(2.0) };
        let [left, right] = triangle_halves(&t, &within, 2, 0.5);
        assert!(!is_empty(&left) && is_empty(&right));
    }
}
