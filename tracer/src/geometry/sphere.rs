use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{Aabb, Ray};

/// A sphere: the only primitive of the paper's scenes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[repr(C)]
pub struct Sphere {
    /// Center.
    pub center: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

impl Sphere {
    /// A sphere at `center` with radius `radius`.
    pub fn new(center: Vec3, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Relative widening of [`Sphere::bounds`]: `(|center| + radius)` times this on every side.
    pub const BOUNDS_PAD: f32 = 4.0 * f32::EPSILON;

    /// Bounding box, widened by a few ulps so that rounding never puts a surface point outside it.
    pub fn bounds(&self) -> Aabb {
        let r = Vec3::splat(self.radius);
        let pad = (self.center.abs() + r) * Self::BOUNDS_PAD;
        Aabb { min: self.center - r - pad, max: self.center + r + pad }
    }

    /// Nearest `t` in `(ray.t_min, t_max)` where the ray meets the surface.
    ///
    /// The numerically robust form (Haines et al., Ray Tracing Gems ch. 7): the discriminant comes from
    /// the ray's perpendicular offset to the center, and the two roots from `q` and `c / q`, so neither
    /// small far spheres nor near-tangent rays lose hits to cancellation.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let d = ray.dir;
        let f = ray.origin - self.center;
        let a = d.dot(d);
        let b = f.dot(d);
        let r2 = self.radius * self.radius;
        let offset = f - d * (b / a);
        let disc = a * (r2 - offset.dot(offset));
        if disc < 0.0 {
            return None;
        }
        let c = f.dot(f) - r2;
        let q = -(b + disc.sqrt().copysign(b));
        let (r0, r1) = (c / q, q / a);
        let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
        if near > ray.t_min && near < t_max {
            Some(near)
        } else if far > ray.t_min && far < t_max {
            Some(far)
        } else {
            None
        }
    }

    /// Outward unit normal at surface point `p`.
    pub fn normal_at(&self, p: Vec3) -> Vec3 {
        (p - self.center) / self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_front_then_back_from_inside() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -10.0), 2.0);
        let r = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert_eq!(s.intersect(&r, f32::INFINITY), Some(8.0));
        let inside = Ray::new(Vec3::new(0.0, 0.0, -10.0), -Vec3::Z);
        assert_eq!(s.intersect(&inside, f32::INFINITY), Some(2.0));
        assert_eq!(s.intersect(&r, 7.0), None);
        assert_eq!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY), None);
    }

    #[test]
    fn non_unit_directions_scale_t() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -10.0), 2.0);
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(s.intersect(&r, f32::INFINITY), Some(4.0));
    }

    #[test]
    fn small_far_sphere_is_hit_where_the_textbook_form_cancels() {
        // A sphere of radius 1e-3 at distance 1e4: b*b - c loses every digit of r^2 in f32.
        let s = Sphere::new(Vec3::new(0.0, 0.0, -1.0e4), 1.0e-3);
        let r = Ray::new(Vec3::ZERO, -Vec3::Z);
        let t = s.intersect(&r, f32::INFINITY).expect("robust form must hit");
        assert!((t - (1.0e4 - 1.0e-3)).abs() <= 1.0e-4 * 1.0e4);
        let (f, d) = (r.origin - s.center, r.dir);
        let textbook_disc = f.dot(d) * f.dot(d) - (f.dot(f) - s.radius * s.radius);
        assert!(textbook_disc <= 0.0, "the test must exercise the cancellation it guards against");
    }

    #[test]
    fn bounds_contain_the_sphere() {
        let s = Sphere::new(Vec3::new(1.0e3, -2.0, 3.5), 0.25);
        let b = s.bounds();
        for p in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            assert!(b.contains(s.center + p * s.radius));
        }
    }
}
