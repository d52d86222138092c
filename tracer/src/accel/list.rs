use super::{Accelerator, Hit, TreeStats};
use crate::counters::Counters;
use crate::geometry::{Ray, Sphere};

/// Brute force: every ray tests every sphere. The reference every other structure must agree with.
#[derive(Clone, Debug)]
pub struct List {
    spheres: Vec<Sphere>,
}

impl List {
    /// Copies the spheres; nothing else to build.
    pub fn build(spheres: &[Sphere]) -> Self {
        Self { spheres: spheres.to_vec() }
    }
}

impl Accelerator for List {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (i, s) in self.spheres.iter().enumerate() {
            counters.prim_test();
            if let Some(t) = s.intersect(ray, t_max) {
                t_max = t;
                best = Some(Hit { t, prim: i as u32 });
            }
        }
        best
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.spheres.iter().any(|s| {
            counters.prim_test();
            s.intersect(ray, ray.t_max).is_some()
        })
    }

    fn stats(&self) -> TreeStats {
        TreeStats::list(self.spheres.len(), std::mem::size_of_val(self.spheres.as_slice()))
    }
}
