//! Rays, boxes, spheres and triangles: the primitives every accelerator and renderer shares, and triangle meshes.

mod aabb;
mod exact;
mod exact_triangle;
mod moller_trumbore;
mod random_triangles;
mod ray;
mod sphere;
mod tessellate;
mod triangle;
mod triangle_mesh;
mod triangle_test;
mod watertight;

pub use aabb::{Aabb, RayBoxTester};
pub use exact::{ExactTest, F32Outcomes, U_F32, U_F64};
pub use exact_triangle::ExactTriangleTest;
pub use random_triangles::random_triangles;
pub use ray::Ray;
pub use sphere::Sphere;
pub use tessellate::tessellate;
pub use triangle::{Triangle, TriangleHit};
pub use triangle_mesh::TriangleMesh;
pub use triangle_test::TriangleTest;
