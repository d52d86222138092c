//! What every structure needs of a primitive: its box, the point splits sort it by, and its ray test.
//!
//! [`Sphere`] is one; a triangle is one once its test is chosen: [`MollerTrumboreTriangle`] and
//! [`WatertightTriangle`] are the same [`Triangle`] with a different [`Primitive::intersect`], so that every
//! structure compiles one loop per test and chooses none per primitive.

use glam::Vec3;

use super::{Aabb, Ray, Sphere, Triangle, TriangleTest};

/// A primitive the structures are built over and trace.
pub trait Primitive: Copy + Send + Sync + std::fmt::Debug + 'static {
    /// What the primitive is, for messages and rows (`sphere`, `moller-trumbore`, `watertight`).
    const NAME: &'static str;
    /// Bounding box, widened by a few ulps so that rounding never puts a surface point outside it.
    fn bounds(&self) -> Aabb;
    /// The point split rules sort the primitive by.
    fn centroid(&self) -> Vec3;
    /// Nearest `t` in `(ray.t_min, t_max)` where the ray meets the primitive.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32>;
    /// Unit surface normal at `point` on the primitive, facing `toward` (the side a ray came from).
    fn normal(&self, point: Vec3, toward: Vec3) -> Vec3;
}

impl Primitive for Sphere {
    const NAME: &'static str = "sphere";

    #[inline(always)]
    fn bounds(&self) -> Aabb {
        Sphere::bounds(self)
    }

    #[inline(always)]
    fn centroid(&self) -> Vec3 {
        self.center
    }

    #[inline(always)]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        Sphere::intersect(self, ray, t_max)
    }

    fn normal(&self, point: Vec3, toward: Vec3) -> Vec3 {
        let n = (point - self.center).normalize();
        if n.dot(toward) < 0.0 { -n } else { n }
    }
}

/// A triangle with its test chosen at compile time: what a structure over triangles is built from.
pub trait TrianglePrimitive: Primitive {
    /// The test [`Primitive::intersect`] runs.
    const TEST: TriangleTest;
    /// The triangle.
    fn triangle(&self) -> &Triangle;
    /// Wraps a triangle.
    fn of(triangle: Triangle) -> Self;
    /// Wraps every triangle of a list.
    fn all(triangles: impl IntoIterator<Item = Triangle>) -> Vec<Self> {
        triangles.into_iter().map(Self::of).collect()
    }
}

macro_rules! triangle_primitive {
    ($(#[$doc:meta])* $name:ident, $test:expr, $method:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[repr(transparent)]
        pub struct $name(pub Triangle);

        impl Primitive for $name {
            const NAME: &'static str = $test.name();

            #[inline(always)]
            fn bounds(&self) -> Aabb {
                self.0.bounds()
            }

            /// The center of the triangle's box (the point Embree's builders sort by).
            #[inline(always)]
            fn centroid(&self) -> Vec3 {
                let b = self.0.bounds();
                (b.min + b.max) * 0.5
            }

            #[inline(always)]
            fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
                self.0.$method(ray, t_max).map(|h| h.t)
            }

            fn normal(&self, _point: Vec3, toward: Vec3) -> Vec3 {
                self.0.normal_toward(toward)
            }
        }

        impl TrianglePrimitive for $name {
            const TEST: TriangleTest = $test;

            #[inline(always)]
            fn triangle(&self) -> &Triangle {
                &self.0
            }

            #[inline(always)]
            fn of(triangle: Triangle) -> Self {
                Self(triangle)
            }
        }
    };
}

triangle_primitive!(
    /// A triangle traced with the Möller–Trumbore test.
    MollerTrumboreTriangle,
    TriangleTest::MollerTrumbore,
    intersect_moller_trumbore
);
triangle_primitive!(
    /// A triangle traced with the watertight test of Woop, Benthin and Wald.
    WatertightTriangle,
    TriangleTest::Watertight,
    intersect_watertight
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_primitives_run_their_test_and_sort_by_their_box_center() {
        let tri = Triangle::new(Vec3::new(0.0, 0.0, -4.0), Vec3::new(2.0, 0.0, -4.0), Vec3::new(0.0, 2.0, -4.0));
        let ray = Ray::new(Vec3::new(0.5, 0.25, 0.0), -Vec3::Z);
        assert_eq!(MollerTrumboreTriangle(tri).intersect(&ray, f32::INFINITY), Some(4.0));
        assert_eq!(WatertightTriangle(tri).intersect(&ray, f32::INFINITY), Some(4.0));
        let c = WatertightTriangle(tri).centroid();
        assert!((c - Vec3::new(1.0, 1.0, -4.0)).abs().max_element() < 1e-5, "{c}");
        assert_eq!(MollerTrumboreTriangle::NAME, "moller-trumbore");
        assert_eq!(WatertightTriangle(tri).normal(Vec3::ZERO, Vec3::Z), Vec3::Z);
        assert_eq!(WatertightTriangle(tri).normal(Vec3::ZERO, -Vec3::Z), -Vec3::Z);
    }
}
