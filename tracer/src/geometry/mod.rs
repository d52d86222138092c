//! Rays, boxes and spheres: the primitives every accelerator and renderer shares.

mod aabb;
mod ray;
mod sphere;

pub use aabb::{Aabb, RayBoxTester};
pub use ray::Ray;
pub use sphere::Sphere;
