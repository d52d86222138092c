//! The one definition of "agrees with brute force", for the harness's validation and every test.
//!
//! A backend's answer to a ray is compared with a reference's (f32 brute force, or a tree checked against it):
//! - they *agree* ([`Answer::agrees`]) when hit/miss and occlusion are equal and a hit's `t` lies within
//!   [`t_tolerance`] of the reference's: [`T_TOLERANCE`] relative, with a floor of [`ORIGIN_ULPS`] ulps of the
//!   origin's magnitude for hits right at the origin (a bounce leaving a surface inside an overlapping sphere,
//!   where both distances are rounding noise of the coordinates). Primitive ids are not compared here;
//! - otherwise f64 brute force ([`BruteForce64`]) arbitrates ([`arbitrate`]): an answer is acceptable when it
//!   is the exact one or one that the f32 test's rounding bound allows ([`ExactPrimitive`]: for spheres
//!   [`crate::geometry::ExactTest`], a grazing ray `|g| ≤ B` or a root within `T`). Both acceptable: the
//!   disagreement is [`Tolerated`] and counted (a grazing ray, an edge tie or a leak); else it is a
//!   [`Outcome::Mismatch`] that names the [`WrongSide`]. A hit must name a primitive f64 allows at its `t`; two
//!   hits at the same `t` that name different primitives are a tie when f64 is asked.
//!
//! [`check`] runs both steps on one ray; the harness batches them (all disagreements of a ray set, its
//! reference's own check). [`Strictness::Identical`] is the tests' stricter option for backends whose leaves
//! call our own f32 test: bit-identical answers, nothing arbitrated.
//!
//! A primitive kind plugs in through [`ExactPrimitive`]: its f64 test with its f32 test's rounding bound, and a
//! layout that screens a scene's primitives per ray ([`crate::geometry::Sphere`]'s in `sphere.rs`;
//! [`crate::geometry::Triangle`]'s in `triangle.rs`, where a ray within rounding of an edge or vertex may report
//! either triangle, [`Tolerated::Tie`], or slip between them, [`Tolerated::Leak`]).

mod answer;
mod arbitrate;
mod brute_force;
mod chunk_box;
mod primitive;
mod sphere;
mod tolerance;
mod triangle;

pub use answer::{Answer, Strictness};
pub use arbitrate::{Outcome, Tolerated, Verdict, WrongSide, arbitrate};
pub use brute_force::{BruteForce64, Candidate, RayCandidates};
pub use primitive::{ExactAnswer, ExactPrimitive};
pub use sphere::SphereLayout;
pub use tolerance::{ORIGIN_ULPS, T_TOLERANCE, t_tolerance};
pub use triangle::TriangleLayout;

use crate::geometry::Ray;

/// The backend's answer `got` to `ray` against the trusted reference's `want`, under `strictness`, f64 brute
/// force over `brute` arbitrating a disagreement (under [`Strictness::Identical`], any difference is the
/// backend's mismatch).
pub fn check<P: ExactPrimitive>(
    brute: &BruteForce64<P>,
    ray: &Ray,
    want: &Answer,
    got: &Answer,
    strictness: Strictness,
) -> Outcome {
    if want.agrees(ray, got, strictness) {
        Outcome::Agree
    } else if strictness == Strictness::Identical {
        Outcome::Mismatch(WrongSide::Backend)
    } else {
        arbitrate(&brute.candidates_of(ray), want, got)
    }
}
