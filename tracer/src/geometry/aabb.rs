use glam::Vec3;

use super::Ray;

/// An axis-aligned bounding box; the empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box containing nothing; the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The box of one point.
    pub fn point(p: Vec3) -> Self {
        Self { min: p, max: p }
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Side lengths (zero for an empty box).
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() { Vec3::ZERO } else { self.max - self.min }
    }

    /// Surface area (zero for an empty box).
    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index (0, 1, 2) of the longest side.
    pub fn longest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// The box's center.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// A ray prepared for many slab tests: origin and reciprocal direction computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayBoxTester {
    origin: Vec3,
    inv_dir: Vec3,
    t_min: f32,
}

impl RayBoxTester {
    /// Error bound on the far slab distance (pbrt's `1 + 2 * gamma(3)`): keeps grazing hits inside their box.
    pub(crate) const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

    /// Prepares `ray` for box tests. Zero direction components become ±1e-30, so reciprocals stay finite
    /// and no slab distance is ever NaN (a ray that parallel crosses no slab plane within any float range).
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let nonzero = |d: f32| if d.abs() < 1e-30 { 1e-30f32.copysign(d) } else { d };
        let d = ray.dir;
        Self {
            origin: ray.origin,
            inv_dir: Vec3::new(nonzero(d.x), nonzero(d.y), nonzero(d.z)).recip(),
            t_min: ray.t_min,
        }
    }

    /// The reciprocal direction the slab tests use (zero components replaced as [`RayBoxTester::new`] says).
    #[inline(always)]
    pub(crate) fn inv_dir(&self) -> Vec3 {
        self.inv_dir
    }

    /// Entry distance into `b` when the ray meets it before `t_max`, else `f32::INFINITY`.
    ///
    /// Plain compares instead of IEEE `min`/`max` (one instruction each): exact here because no slab
    /// distance is NaN (see [`RayBoxTester::new`]).
    #[inline(always)]
    pub fn entry(&self, b: &Aabb, t_max: f32) -> f32 {
        #[inline(always)]
        fn lo(a: f32, b: f32) -> f32 {
            if a < b { a } else { b }
        }
        #[inline(always)]
        fn hi(a: f32, b: f32) -> f32 {
            if a > b { a } else { b }
        }
        let (o, inv) = (self.origin, self.inv_dir);
        let (x0, x1) = ((b.min.x - o.x) * inv.x, (b.max.x - o.x) * inv.x);
        let (y0, y1) = ((b.min.y - o.y) * inv.y, (b.max.y - o.y) * inv.y);
        let (z0, z1) = ((b.min.z - o.z) * inv.z, (b.max.z - o.z) * inv.z);
        let near = hi(hi(lo(x0, x1), lo(y0, y1)), hi(lo(z0, z1), self.t_min));
        let far = lo(lo(hi(x0, x1), hi(y0, y1)), hi(z0, z1)) * Self::FAR_SCALE;
        if near <= far && near <= t_max { near } else { f32::INFINITY }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_test_hits_misses_and_respects_t_max() {
        let b = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        let hit = RayBoxTester::new(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z));
        assert_eq!(hit.entry(&b, f32::INFINITY), 4.0);
        assert_eq!(hit.entry(&b, 3.0), f32::INFINITY);
        let inside = RayBoxTester::new(&Ray::new(Vec3::ZERO, Vec3::X));
        assert_eq!(inside.entry(&b, f32::INFINITY), 0.0);
        let miss = RayBoxTester::new(&Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z));
        assert_eq!(miss.entry(&b, f32::INFINITY), f32::INFINITY);
        let behind = RayBoxTester::new(&Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z));
        assert_eq!(behind.entry(&b, f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn empty_box_has_no_area_or_extent() {
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert_eq!(Aabb::EMPTY.extent(), Vec3::ZERO);
    }
}
