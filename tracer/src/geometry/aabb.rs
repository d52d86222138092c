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
    const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

    /// Prepares `ray` for box tests.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin, inv_dir: ray.dir.recip(), t_min: ray.t_min }
    }

    /// Entry distance into `b` when the ray meets it before `t_max`, else `f32::INFINITY`.
    #[inline(always)]
    pub fn entry(&self, b: &Aabb, t_max: f32) -> f32 {
        let t0 = (b.min - self.origin) * self.inv_dir;
        let t1 = (b.max - self.origin) * self.inv_dir;
        let near = t0.min(t1).max_element().max(self.t_min);
        let far = t0.max(t1).min_element() * Self::FAR_SCALE;
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
