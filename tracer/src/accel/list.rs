use super::{Accelerator, Hit, TreeStats};
use crate::counters::Counters;
use crate::geometry::{Primitive, Ray, Sphere};

/// Brute force: every ray tests every primitive. The reference every other structure must agree with.
#[derive(Clone, Debug)]
pub struct List<P = Sphere> {
    prims: Vec<P>,
}

impl<P: Primitive> List<P> {
    /// Copies the primitives; nothing else to build.
    pub fn build(prims: &[P]) -> Self {
        Self { prims: prims.to_vec() }
    }
}

impl<P: Primitive> Accelerator for List<P> {
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for (i, s) in self.prims.iter().enumerate() {
            counters.prim_test();
            if let Some(t) = s.intersect(ray, t_max) {
                t_max = t;
                best = Some(Hit { t, prim: i as u32 });
            }
        }
        best
    }

    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        self.prims.iter().any(|s| {
            counters.prim_test();
            s.intersect(ray, ray.t_max).is_some()
        })
    }

    fn stats(&self) -> TreeStats {
        TreeStats::list(self.prims.len(), std::mem::size_of_val(self.prims.as_slice()))
    }
}
