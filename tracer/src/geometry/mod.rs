//! Rays, boxes and spheres: the primitives every accelerator and renderer shares.

mod aabb;
mod exact;
mod ray;
mod sphere;

pub use aabb::{Aabb, RayBoxTester};
pub use exact::{ExactTest, F32Outcomes, U_F32, U_F64};
pub use ray::Ray;
pub use sphere::Sphere;
