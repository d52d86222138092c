//! The agreement check: an accelerator's answers against brute force's ([`List`]), ray by ray.

use crate::accel::{AccelVisitor, Accelerator, BuiltAccel, Hit, List};
use crate::counters::NoCounters;
use crate::geometry::{ExactTest, Ray, Sphere};
use crate::render::PrimaryHits;

use super::every_tree;

/// How closely an accelerator's answers must match brute force's. Hit/miss and occlusion must always be equal;
/// the tolerance says how close a hit's `t` must be, and whether rays f32 cannot decide are excused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tolerance {
    /// Bit-identical `t`; nothing excused. For backends whose leaves call our own [`Sphere::intersect`].
    Exact,
    /// `|t - t_bf| <= 1e-4 * |t_bf| + 1e-7`; nothing excused. For the tracer's own trees.
    RelativeToT,
    /// `|t - t_bf| <= 1e-4 * max(|t_bf|, scale)`, where `scale = (|o - c| + r) / |d|` is the hit sphere's distance
    /// scale (a ray-sphere root's rounding error scales with the operands, not with `t`); and a hit/miss or
    /// occlusion disagreement on a ray that grazes a sphere within the f32 rounding bound of [`Sphere::intersect`]
    /// (`|g| ≤ B`, [`ExactTest`]) is excused (printed, not failed). For backends with their own ray-sphere test.
    RelativeToScale,
}

impl Tolerance {
    /// True when `got` is close enough to brute force's `want` (both hits of `ray`).
    fn same_t(self, spheres: &[Sphere], ray: &Ray, want: Hit, got: Hit) -> bool {
        match self {
            Tolerance::Exact => got.t.to_bits() == want.t.to_bits(),
            Tolerance::RelativeToT => (got.t - want.t).abs() <= 1e-4 * want.t.abs() + 1e-7,
            Tolerance::RelativeToScale => {
                let s = &spheres[want.prim as usize];
                let scale = ((ray.origin - s.center).length() + s.radius) / ray.dir.length();
                (got.t - want.t).abs() <= 1e-4 * want.t.abs().max(scale)
            }
        }
    }

    fn excuses_grazing(self) -> bool {
        self == Tolerance::RelativeToScale
    }
}

/// How far from tangent the ray's line passes sphere `s` (`|g|`, `g = (r² − p²) / r²` in f64), if it grazes it
/// ahead of the origin within the f32 rounding bound `B` of [`Sphere::intersect`], where f32 cannot tell a hit
/// from a miss ([`ExactTest::is_grazing`]).
fn grazing_offset(s: &Sphere, ray: &Ray) -> Option<f64> {
    let e = ExactTest::new(s, ray);
    (e.is_grazing() && e.t_closest > ray.t_min as f64).then_some(e.g.abs())
}

/// The first sphere the ray grazes (see [`grazing_offset`]) and its offset from tangent.
fn grazes(spheres: &[Sphere], ray: &Ray) -> Option<(usize, f64)> {
    spheres.iter().enumerate().find_map(|(i, s)| grazing_offset(s, ray).map(|rel| (i, rel)))
}

/// For a closest-hit disagreement: a sphere of either answer that the ray grazes (or, when one answer is a
/// miss, any sphere it grazes), and its offset.
fn hit_grazes(spheres: &[Sphere], ray: &Ray, want: Option<Hit>, got: Option<Hit>) -> Option<(usize, f64)> {
    [want, got]
        .into_iter()
        .flatten()
        .find_map(|h| grazing_offset(&spheres[h.prim as usize], ray).map(|rel| (h.prim as usize, rel)))
        .or_else(|| if want.is_none() || got.is_none() { grazes(spheres, ray) } else { None })
}

/// Brute force's answers (closest hit and occlusion) to a ray set, computed once and compared with any
/// number of accelerators built over the same spheres.
#[derive(Clone, Debug)]
pub struct Reference<'a> {
    spheres: &'a [Sphere],
    rays: &'a [Ray],
    closest: Vec<Option<Hit>>,
    occluded: Vec<bool>,
}

impl<'a> Reference<'a> {
    /// Traces `rays` through a [`List`] of `spheres`.
    pub fn new(spheres: &'a [Sphere], rays: &'a [Ray]) -> Self {
        let list = List::build(spheres);
        let closest = rays.iter().map(|r| list.intersect(r, &mut NoCounters)).collect();
        let occluded = rays.iter().map(|r| list.occluded(r, &mut NoCounters)).collect();
        Self { spheres, rays, closest, occluded }
    }

    /// Starts comparing answers to these rays; `what` names the backend in the failure message.
    pub fn compare(&self, what: &str, tol: Tolerance) -> Comparison<'_, 'a> {
        Comparison { reference: self, what: what.to_owned(), tol, bad: Vec::new(), excused: Vec::new() }
    }

    /// Panics (listing the disagreements) unless `accel` answers every ray like brute force: closest hit and
    /// occlusion, within `tol`, one ray at a time and as one batch (the path ray sets are traced and timed with:
    /// packets, where the structure has them).
    #[track_caller]
    pub fn assert_agrees<A: Accelerator>(&self, what: &str, accel: &A, tol: Tolerance) {
        let mut comparison = self.compare(what, tol);
        for (i, ray) in self.rays.iter().enumerate() {
            comparison.closest(i, accel.intersect(ray, &mut NoCounters));
            comparison.occluded(i, accel.occluded(ray, &mut NoCounters));
        }
        comparison.finish();
        let mut batch = self.compare(&format!("{what} (batch)"), tol);
        let mut hits = vec![PrimaryHits::MISS; self.rays.len()];
        accel.intersect_batch(self.rays, &mut hits, &mut NoCounters);
        let mut occluded = vec![false; self.rays.len()];
        accel.occluded_batch(self.rays, &mut occluded, &mut NoCounters);
        for (i, (hit, occluded)) in hits.into_iter().zip(occluded).enumerate() {
            batch.closest(i, (hit.prim != PrimaryHits::MISS.prim).then_some(hit));
            batch.occluded(i, occluded);
        }
        batch.finish();
    }

    /// [`Reference::assert_agrees`] for whichever structure `accel` holds.
    #[track_caller]
    pub fn assert_built_agrees(&self, what: &str, accel: &BuiltAccel, tol: Tolerance) {
        struct Check<'c, 'r, 'a>(&'r Reference<'a>, &'c str, Tolerance);
        impl AccelVisitor for Check<'_, '_, '_> {
            type Output = ();
            #[track_caller]
            fn visit<A: Accelerator>(self, accel: &A) {
                self.0.assert_agrees(self.1, accel, self.2);
            }
        }
        accel.visit(Check(self, what, tol));
    }
}

/// Answers being compared with a [`Reference`], one at a time (for backends answered in batches, e.g.
/// packets); [`Comparison::finish`] fails if any disagreed.
#[must_use = "call `finish` to fail on disagreements"]
#[derive(Debug)]
pub struct Comparison<'r, 'a> {
    reference: &'r Reference<'a>,
    what: String,
    tol: Tolerance,
    bad: Vec<String>,
    excused: Vec<String>,
}

impl Comparison<'_, '_> {
    /// Compares `got` with brute force's closest hit of ray `i`.
    pub fn closest(&mut self, i: usize, got: Option<Hit>) {
        let (spheres, ray, want) = (self.reference.spheres, &self.reference.rays[i], self.reference.closest[i]);
        let agrees = match (want, got) {
            (None, None) => true,
            (Some(w), Some(g)) => self.tol.same_t(spheres, ray, w, g),
            _ => false,
        };
        if !agrees {
            let grazing = if self.tol.excuses_grazing() { hit_grazes(spheres, ray, want, got) } else { None };
            self.record(i, grazing, format!("closest {got:?} vs brute force {want:?}"));
        }
    }

    /// Compares `got` with brute force's occlusion of ray `i`.
    pub fn occluded(&mut self, i: usize, got: bool) {
        let want = self.reference.occluded[i];
        if got != want {
            let (spheres, ray) = (self.reference.spheres, &self.reference.rays[i]);
            let grazing = if self.tol.excuses_grazing() { grazes(spheres, ray) } else { None };
            self.record(i, grazing, format!("occluded {got} vs brute force {want}"));
        }
    }

    fn record(&mut self, i: usize, grazing: Option<(usize, f64)>, text: String) {
        let ray = &self.reference.rays[i];
        match grazing {
            Some((s, rel)) => self.excused.push(format!("ray {i} {ray:?} grazes sphere {s} (|g| = {rel:.1e}): {text}")),
            None => self.bad.push(format!("ray {i} {ray:?}: {text}")),
        }
    }

    /// Prints the excused disagreements and panics with the others (the first 8 shown), if any.
    #[track_caller]
    pub fn finish(self) {
        let Self { what, tol, bad, excused, reference, .. } = self;
        if !excused.is_empty() {
            eprintln!(
                "{what}: {} hit/miss disagreement(s) on rays grazing a sphere within f32's rounding bound (excused):\n  {}",
                excused.len(),
                excused.join("\n  ")
            );
        }
        assert!(
            bad.is_empty(),
            "{what}: {} disagreement(s) with brute force over {} rays ({tol:?}):\n{}",
            bad.len(),
            reference.rays.len(),
            bad[..bad.len().min(8)].join("\n")
        );
    }
}

/// Builds every tree configuration ([`every_tree`]) over `spheres` and checks each against brute force on
/// `rays` with [`Tolerance::RelativeToT`]; `label` starts the failure message, followed by the configuration.
#[track_caller]
pub fn assert_every_tree_agrees(label: &str, spheres: &[Sphere], rays: &[Ray]) {
    let reference = Reference::new(spheres, rays);
    for params in every_tree() {
        let accel = BuiltAccel::build(spheres, &params);
        reference.assert_built_agrees(&format!("{label} {params:?}"), &accel, Tolerance::RelativeToT);
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::TreeStats;
    use crate::counters::Counters;
    use crate::testing::sphere_ray_mix;

    /// Brute force with its hit distances scaled and, optionally, every occlusion answer negated.
    struct Skewed {
        list: List,
        t_scale: f32,
        flip_occlusion: bool,
    }

    impl Accelerator for Skewed {
        fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
            self.list.intersect(ray, counters).map(|h| Hit { t: h.t * self.t_scale, ..h })
        }
        fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
            self.list.occluded(ray, counters) != self.flip_occlusion
        }
        fn stats(&self) -> TreeStats {
            self.list.stats()
        }
    }

    fn spheres() -> Vec<Sphere> {
        crate::scene::SceneKind::RandomSpheres.generate(40, 3).spheres
    }

    fn check(t_scale: f32, flip_occlusion: bool, tol: Tolerance) {
        let spheres = spheres();
        let rays = sphere_ray_mix(&spheres, 9, 200);
        let accel = Skewed { list: List::build(&spheres), t_scale, flip_occlusion };
        Reference::new(&spheres, &rays).assert_agrees("skewed", &accel, tol);
    }

    #[test]
    fn brute_force_agrees_with_itself_under_every_tolerance() {
        for tol in [Tolerance::Exact, Tolerance::RelativeToT, Tolerance::RelativeToScale] {
            check(1.0, false, tol);
        }
    }

    #[test]
    #[should_panic(expected = "disagreement(s) with brute force")]
    fn exact_rejects_one_ulp() {
        check(1.0 + f32::EPSILON, false, Tolerance::Exact);
    }

    #[test]
    fn relative_to_t_accepts_1e_5() {
        check(1.0 + 1e-5, false, Tolerance::RelativeToT);
    }

    #[test]
    #[should_panic(expected = "closest Some")]
    fn relative_to_t_rejects_1e_3() {
        check(1.0 + 1e-3, false, Tolerance::RelativeToT);
    }

    #[test]
    #[should_panic(expected = "occluded")]
    fn occlusion_must_match_exactly() {
        check(1.0, true, Tolerance::RelativeToScale);
    }

    /// A ray exactly tangent to a sphere: brute force hits it, a backend that misses is excused only by
    /// [`Tolerance::RelativeToScale`].
    #[test]
    fn only_relative_to_scale_excuses_grazing_rays() {
        let spheres = [Sphere::new(Vec3::ZERO, 1.0)];
        let rays = [Ray::new(Vec3::new(1.0, 0.0, -5.0), Vec3::Z)];
        let reference = Reference::new(&spheres, &rays);
        assert!(reference.closest[0].is_some() && reference.occluded[0]);
        let misses = |tol| {
            let mut c = reference.compare("misses", tol);
            c.closest(0, None);
            c.occluded(0, false);
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| c.finish())).is_ok()
        };
        assert!(misses(Tolerance::RelativeToScale));
        assert!(!misses(Tolerance::RelativeToT));
        assert!(!misses(Tolerance::Exact));
    }
}
