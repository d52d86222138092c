//! Rays, boxes, spheres and triangles: the primitives every accelerator and renderer shares, and triangle meshes.

mod aabb;
mod exact;
mod exact_triangle;
mod moller_trumbore;
mod primitive;
mod ray;
mod sphere;
mod triangle;
mod triangle_test;
mod watertight;

pub use aabb::{Aabb, RayBoxTester};
pub use exact::{ExactTest, F32Outcomes, U_F32, U_F64};
pub use exact_triangle::ExactTriangleTest;
pub use primitive::{MollerTrumboreTriangle, Primitive, TrianglePrimitive, WatertightTriangle};
pub use ray::Ray;
pub use sphere::Sphere;
pub use triangle::{Triangle, TriangleHit};
pub use triangle_test::TriangleTest;
