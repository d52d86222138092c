//! One answer to one ray, and when two answers agree without asking f64.

use super::t_tolerance;
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::rays::RayAnswers;
use crate::render::PrimaryHits;

/// A backend's answer to one ray: its closest hit (`None` for a miss) or whether the ray is occluded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Answer {
    /// A closest-hit query's answer.
    Closest(Option<Hit>),
    /// An any-hit query's answer.
    Occluded(bool),
}

/// How close two answers must be to agree before f64 is asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strictness {
    /// Bit-identical `t` (and equal hit/miss, occlusion); the reference is trusted, so any difference is the
    /// candidate's mismatch, never arbitrated. A test option for backends whose leaves call our own f32 test
    /// ([`crate::geometry::Sphere::intersect`]): the tracer's trees, obvhs.
    Identical,
    /// The definition: equal hit/miss and occlusion, `t` within [`t_tolerance`] of the reference's; any other
    /// answer is arbitrated by f64 ([`super::arbitrate`]). What the harness validates every backend with.
    Arbitrated,
}

impl Answer {
    /// Answer `i` of a ray set's `answers`.
    pub fn of(answers: &RayAnswers, i: usize) -> Self {
        match answers {
            RayAnswers::Closest(hits) => Answer::closest(hits[i]),
            RayAnswers::Occluded(flags) => Answer::Occluded(flags[i]),
        }
    }

    /// A closest hit as the batch paths write it ([`PrimaryHits::MISS`] for a miss).
    pub fn closest(hit: Hit) -> Self {
        Answer::Closest((hit.prim != PrimaryHits::MISS.prim).then_some(hit))
    }

    /// True when both are hits that name different primitives (a tie, when they agree on `t`).
    pub fn names_another(&self, got: &Answer) -> bool {
        matches!((self, got), (Answer::Closest(Some(w)), Answer::Closest(Some(g))) if w.prim != g.prim)
    }

    /// True when `got` agrees with this (the reference's) answer to `ray` under `strictness`. Primitive ids are
    /// not compared (overlapping spheres may tie).
    pub fn agrees(&self, ray: &Ray, got: &Answer, strictness: Strictness) -> bool {
        match (self, got) {
            (Answer::Closest(None), Answer::Closest(None)) => true,
            (Answer::Closest(Some(w)), Answer::Closest(Some(g))) => match strictness {
                Strictness::Identical => g.t.to_bits() == w.t.to_bits(),
                Strictness::Arbitrated => (g.t - w.t).abs() <= t_tolerance(ray, w.t),
            },
            (Answer::Occluded(w), Answer::Occluded(g)) => w == g,
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn answers_agree_on_hit_miss_and_distance_within_the_tolerance() {
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let hit = |t| Answer::Closest(Some(Hit { t, prim: 1 }));
        let agrees = |w: Answer, g: Answer, s| w.agrees(&ray, &g, s);
        let arbitrated = Strictness::Arbitrated;
        assert!(agrees(hit(10.0), hit(10.0005), arbitrated), "1e-4 relative passes");
        assert!(!agrees(hit(10.0), hit(10.01), arbitrated), "1e-3 fails");
        assert!(!agrees(Answer::Closest(None), hit(3.0), arbitrated));
        assert!(agrees(hit(10.0), Answer::Closest(Some(Hit { t: 10.0, prim: 7 })), Strictness::Identical), "ids");
        assert!(!agrees(hit(10.0), hit(10.0f32.next_up()), Strictness::Identical), "one ulp");
        assert!(!agrees(Answer::Occluded(true), Answer::Occluded(false), arbitrated));
        assert!(!agrees(Answer::Occluded(true), hit(1.0), arbitrated), "not comparable");
        assert_eq!(Answer::closest(PrimaryHits::MISS), Answer::Closest(None));
    }
}
