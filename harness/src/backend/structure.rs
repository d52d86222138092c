//! A built backend as the harness times it: a [`Structure`] that runs one job per dynamic call, around loops
//! monomorphized for the concrete structure and counters (the hot loop has no dynamic dispatch). The tracer's own
//! structures come compiled from the tracer ([`tracer::structure`]); a peer's are compiled here, by [`Concrete`].

use tracer::accel::{Accelerator, TreeStats};
use tracer::counters::{NoCounters, WorkCounters};
use tracer::executor::Strategy;
use tracer::job::{self, Job, Output};
use tracer::rays::{RayAnswers, RaySet};
pub use tracer::structure::Structure;

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

    /// The answers to `rays` (for validation).
    pub fn answers(&self, rays: &RaySet, strategy: &Strategy) -> RayAnswers {
        match self.structure.run(&Job::Rays(rays), strategy) {
            Output::Answers(answers) => answers,
            Output::Image(_) => unreachable!("a ray set's job answers its rays"),
        }
    }
}

/// Any one [`Accelerator`] (a peer's), with the job loops compiled for it.
struct Concrete<A>(A);

impl<A: Accelerator> Structure for Concrete<A> {
    fn run(&self, job: &Job<'_>, strategy: &Strategy) -> Output {
        job::run::<A, NoCounters>(&self.0, job, strategy).0
    }
    fn run_counted(&self, job: &Job<'_>, strategy: &Strategy) -> (Output, WorkCounters) {
        job::run::<A, WorkCounters>(&self.0, job, strategy)
    }
    fn stats(&self) -> TreeStats {
        self.0.stats()
    }
}
