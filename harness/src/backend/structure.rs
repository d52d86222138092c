//! A built backend as the harness traces it: one dynamic call per workload, around a loop monomorphized for the
//! concrete structure and counters (the hot loop has no dynamic dispatch).

use tracer::accel::wide::WidePrimitive;
use tracer::accel::{AccelVisitor, Accelerator, BuiltAccel, TreeStats};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::executor::Strategy;
use tracer::rays::{RayAnswers, RaySet, trace};

use super::workload::{Output, Work};

/// A built structure of any backend.
pub trait Structure: Send + Sync {
    /// Runs the workload uncounted (the timed pass).
    fn run(&self, work: Work<'_, NoCounters>) -> Output;
    /// Runs the workload with work counters (the counted pass).
    fn run_counted(&self, work: Work<'_, WorkCounters>) -> (Output, WorkCounters);
    /// The answers to `rays` (for validation).
    fn answers(&self, rays: &RaySet, strategy: &Strategy) -> RayAnswers;
    /// Size and quality of the structure (peers report what they can).
    fn stats(&self) -> TreeStats;
}

/// What a backend built, with what its rows say about it.
pub struct Built {
    pub structure: Box<dyn Structure>,
    /// Library facts for the row's `peer_info` (`-` for the tracer's structures).
    pub peer_info: String,
    /// The SIMD kernel that runs (`-` for structures without SIMD kernels).
    pub simd_kernel: &'static str,
}

impl Built {
    /// A peer's structure with its library facts and no SIMD kernel of ours.
    pub fn peer(accel: impl Accelerator + 'static, peer_info: String) -> Built {
        Built { structure: Box::new(Concrete(accel)), peer_info, simd_kernel: "-" }
    }
}

/// Hands the concrete structure to a visitor.
trait Visit: Send + Sync {
    fn visit<V: AccelVisitor>(&self, visitor: V) -> V::Output;
}

/// Any one [`Accelerator`].
pub(super) struct Concrete<A>(pub A);

impl<A: Accelerator> Visit for Concrete<A> {
    fn visit<V: AccelVisitor>(&self, visitor: V) -> V::Output {
        visitor.visit(&self.0)
    }
}

impl<P: WidePrimitive> Visit for BuiltAccel<P> {
    fn visit<V: AccelVisitor>(&self, visitor: V) -> V::Output {
        BuiltAccel::visit(self, visitor)
    }
}

/// The answers to a ray set.
struct Answers<'a>(&'a RaySet, &'a Strategy);

impl AccelVisitor for Answers<'_> {
    type Output = RayAnswers;
    fn visit<A: Accelerator>(self, a: &A) -> RayAnswers {
        trace::<_, NoCounters>(a, self.0, self.1).0
    }
}

/// The structure's statistics.
struct Stats;

impl AccelVisitor for Stats {
    type Output = TreeStats;
    fn visit<A: Accelerator>(self, a: &A) -> TreeStats {
        a.stats()
    }
}

impl<T: Visit> Structure for T {
    fn run(&self, work: Work<'_, NoCounters>) -> Output {
        self.visit(work).0
    }
    fn run_counted(&self, work: Work<'_, WorkCounters>) -> (Output, WorkCounters) {
        self.visit(work)
    }
    fn answers(&self, rays: &RaySet, strategy: &Strategy) -> RayAnswers {
        self.visit(Answers(rays, strategy))
    }
    fn stats(&self) -> TreeStats {
        self.visit(Stats)
    }
}
