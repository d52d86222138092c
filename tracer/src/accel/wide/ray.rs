//! A ray prepared once for a whole traversal: what every kernel's box and sphere tests read.

use crate::geometry::{Ray, RayBoxTester};

/// A ray's origin, direction, reciprocal direction, slab rows and octant, computed once per ray.
#[derive(Clone, Copy, Debug)]
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
        }
    }
}
