//! A ray prepared once for a whole traversal: what every kernel's box and sphere tests read.

use glam::Vec3;

use crate::geometry::{Ray, RayBoxTester};

/// A ray's origin, direction, reciprocal direction, slab rows and octant, computed once per ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayLanes {
    /// Origin x, y, z.
    pub origin: [f32; 3],
    /// Direction x, y, z.
    pub dir: [f32; 3],
    /// Reciprocal direction, exactly as [`RayBoxTester`] computes it (so slab distances are bit-identical).
    pub inv: [f32; 3],
    /// Per axis, the row of [`super::node::WideNode::bounds`] the ray enters through: the minima when the
    /// reciprocal direction is positive, else the maxima (the other row is the exit).
    pub near_rows: [usize; 3],
    /// Hits at or before this are ignored.
    pub t_min: f32,
    /// `dir · dir`, as [`crate::geometry::Sphere::intersect`] computes it.
    pub a: f32,
    /// Bit `axis` set when the direction is negative on that axis (0..8).
    pub octant: usize,
    /// The watertight triangle test's ray space, for leaves that read it (see
    /// [`super::leaf::WidePrimitive::prepare`]).
    pub shear: Shear,
}

/// The permutation and shear of the watertight test's ray space ([`crate::geometry::Triangle::intersect_watertight`]),
/// computed once per ray by the same operations.
#[derive(Clone, Copy, Debug, Default)]
pub struct Shear {
    /// `kx`, `ky`, `kz`: `kz` the direction's dominant axis, `kx` and `ky` swapped when it is negative.
    pub axes: [usize; 3],
    /// `Sx = d[kx] / d[kz]`, `Sy = d[ky] / d[kz]`, `Sz = 1 / d[kz]`.
    pub s: [f32; 3],
}

impl Shear {
    /// The ray space of direction `d`.
    #[inline(always)]
    pub fn new(d: glam::Vec3) -> Self {
        let kz = d.abs().max_position();
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self { axes: [kx, ky, kz], s: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]] }
    }
}

impl RayLanes {
    /// Prepares `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let inv = RayBoxTester::new(ray).inv_dir().to_array();
        let neg = inv.map(|i| (i < 0.0) as usize);
        Self {
            origin: ray.origin.to_array(),
            dir: ray.dir.to_array(),
            inv,
            near_rows: [neg[0], 2 + neg[1], 4 + neg[2]],
            t_min: ray.t_min,
            a: ray.dir.dot(ray.dir),
            octant: neg[0] | neg[1] << 1 | neg[2] << 2,
            shear: Shear::default(),
        }
    }
}

/// A ray of [`RayLanes`] as a [`Ray`] (`t_max` is the caller's).
impl RayLanes {
    /// The ray these lanes were prepared from (with an unbounded `t_max`).
    #[inline(always)]
    pub fn ray(&self) -> Ray {
        Ray {
            origin: Vec3::from_array(self.origin),
            dir: Vec3::from_array(self.dir),
            t_min: self.t_min,
            t_max: f32::INFINITY,
        }
    }
}

/// Interval bounds on the rays of a packet, per axis: what [`super::kernel::Ops::frustum_boxes`] tests a node
/// with (interval arithmetic over origins and reciprocal directions, Boulos et al. 2007).
///
/// On an axis where every ray's reciprocal direction has one sign, a ray's slab distances `(plane - o) * inv` are
/// monotone in `o` and in `inv`, and IEEE rounding keeps them so: the smallest entry of any ray is
/// `(near plane - origin_near) * inv_lo or inv_hi`, whichever is smaller, and the largest exit
/// `(far plane - origin_far) * inv_lo or inv_hi`, whichever is larger, computed with the same operations. An axis
/// whose signs differ is left out (it bounds nothing).
#[derive(Clone, Copy, Debug)]
pub struct FrustumLanes {
    /// Per axis, the entry row of the node bounds (as [`RayLanes::near_rows`]; every ray's on a used axis).
    pub near_rows: [usize; 3],
    /// Per axis, whether the rays' reciprocal directions share a sign (the axis is tested).
    pub used: [bool; 3],
    /// Per axis, the origin that gives the smallest entry: the largest origin when the rays go up the axis, else
    /// the smallest.
    pub origin_near: [f32; 3],
    /// Per axis, the origin that gives the largest exit: the smallest when the rays go up the axis, else the
    /// largest.
    pub origin_far: [f32; 3],
    /// Per axis, the smallest reciprocal direction.
    pub inv_lo: [f32; 3],
    /// Per axis, the largest reciprocal direction.
    pub inv_hi: [f32; 3],
    /// The smallest `t_min`.
    pub t_min: f32,
}

impl FrustumLanes {
    /// True when the rays' directions lie in one octant (every axis is tested).
    #[inline(always)]
    pub fn is_one_octant(&self) -> bool {
        self.used == [true; 3]
    }

    /// Bounds of `rays` (at least one).
    #[inline(always)]
    pub fn new(rays: &[RayLanes]) -> Self {
        let first = &rays[0];
        let mut f = Self {
            near_rows: first.near_rows,
            used: [true; 3],
            origin_near: first.origin,
            origin_far: first.origin,
            inv_lo: first.inv,
            inv_hi: first.inv,
            t_min: first.t_min,
        };
        let (mut o_lo, mut o_hi) = (first.origin, first.origin);
        for r in &rays[1..] {
            for axis in 0..3 {
                f.used[axis] &= r.near_rows[axis] == first.near_rows[axis];
                o_lo[axis] = o_lo[axis].min(r.origin[axis]);
                o_hi[axis] = o_hi[axis].max(r.origin[axis]);
                f.inv_lo[axis] = f.inv_lo[axis].min(r.inv[axis]);
                f.inv_hi[axis] = f.inv_hi[axis].max(r.inv[axis]);
            }
            f.t_min = f.t_min.min(r.t_min);
        }
        for axis in 0..3 {
            // Rays going up the axis (entry row the minima, even): the entry falls as the origin grows.
            let up = first.near_rows[axis].is_multiple_of(2);
            (f.origin_near[axis], f.origin_far[axis]) =
                if up { (o_hi[axis], o_lo[axis]) } else { (o_lo[axis], o_hi[axis]) };
        }
        f
    }
}
