//! What the agreement check needs of a primitive kind: its f64 test, with the rounding bound of its f32 test.

use std::fmt::Debug;

use crate::geometry::{F32Outcomes, Ray};

/// A primitive kind whose f32 ray test f64 brute force can arbitrate ([`crate::geometry::Sphere`], and
/// [`crate::geometry::Triangle`] under either [`crate::geometry::TriangleTest`]).
pub trait ExactPrimitive: Clone + Debug + Send + Sync {
    /// A scene's primitives laid out for [`ExactPrimitive::screen`].
    type Layout: Clone + Debug + Send + Sync;

    /// Lays out a scene's primitives.
    fn layout(prims: &[Self]) -> Self::Layout;

    /// Ascending indices of the primitives of `layout` the f32 test may report on `ray`, and possibly more: every
    /// primitive left out it surely misses.
    fn screen(layout: &Self::Layout, ray: &Ray) -> Vec<u32>;

    /// `ray` against this primitive in f64, within the ray's `(t_min, t_max)`.
    fn exact(&self, ray: &Ray) -> ExactAnswer;
}

/// One ray against one primitive in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactAnswer {
    /// The exact hit, if any.
    pub hit: Option<f64>,
    /// What the f32 test may and must report: the exact answer widened by its rounding bound.
    pub outcomes: F32Outcomes,
}
