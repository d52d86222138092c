//! A built structure of any kind behind one dynamic call per [`Job`]: what the harness builds and times.
//!
//! [`build`] and the [`Structure`] implementations of the tracer's own structures are not generic, so every loop
//! they reach — each structure kind, tree layout, child order, SIMD kernel and primitive, with and without work
//! counters — is compiled once, here in the tracer's library, and not again in each crate or test binary that
//! runs them. The per-ray loops stay monomorphized; the only dynamic call is the one per job.

use crate::accel::TreeStats;
#[cfg(not(test))]
use crate::accel::{AccelParams, BuiltAccel};
use crate::counters::WorkCounters;
use crate::executor::Strategy;
use crate::geometry::{MollerTrumboreTriangle, Sphere, WatertightTriangle};
use crate::job::{Job, Output};

/// A built structure that runs jobs.
pub trait Structure: Send + Sync {
    /// Runs `job` uncounted (the timed pass).
    fn run(&self, job: &Job<'_>, strategy: &Strategy) -> Output;
    /// Runs `job` with work counters (the counted pass).
    fn run_counted(&self, job: &Job<'_>, strategy: &Strategy) -> (Output, WorkCounters);
    /// Size and quality of the structure (peers report what they can).
    fn stats(&self) -> TreeStats;
    /// The SIMD kernel it runs (`avx2`, …); `None` for structures without SIMD kernels of ours.
    fn simd_kernel(&self) -> Option<&'static str> {
        None
    }
}

/// The primitives a structure is built over.
#[derive(Clone, Copy, Debug)]
pub enum Primitives<'a> {
    /// Spheres.
    Spheres(&'a [Sphere]),
    /// Triangles tested with Möller–Trumbore.
    MollerTrumbore(&'a [MollerTrumboreTriangle]),
    /// Triangles tested watertight.
    Watertight(&'a [WatertightTriangle]),
}

/// Builds the structure `params` names over `prims` (see [`BuiltAccel::build`]: in the current rayon pool).
#[cfg(not(test))] // the tracer's unit tests run none of it: their build leaves the whole job space out
pub fn build(prims: Primitives<'_>, params: &AccelParams) -> Box<dyn Structure> {
    match prims {
        Primitives::Spheres(p) => Box::new(BuiltAccel::build(p, params)),
        Primitives::MollerTrumbore(p) => Box::new(BuiltAccel::build(p, params)),
        Primitives::Watertight(p) => Box::new(BuiltAccel::build(p, params)),
    }
}

/// A wide BVH (`params`) over `prims` from a binary tree another builder made: its nodes and the primitive ids its
/// leaves name, checked and laid out by [`BuiltTree::from_external`](crate::accel::bvh::tree::BuiltTree), then
/// collapsed as the tracer's own trees are. Errors name what is wrong with the tree.
#[cfg(not(test))]
pub fn build_from_tree(
    prims: Primitives<'_>,
    nodes: &[crate::accel::bvh::tree::FlatNode],
    prim_order: &[u32],
    params: &AccelParams,
) -> Result<Box<dyn Structure>, String> {
    use crate::accel::bvh::tree::BuiltTree;
    fn wide<P: crate::accel::wide::WidePrimitive>(
        p: &[P],
        nodes: &[crate::accel::bvh::tree::FlatNode],
        order: &[u32],
        params: &AccelParams,
    ) -> Result<BuiltAccel<P>, String> {
        let built = BuiltTree::from_external(nodes, order, p)?;
        BuiltAccel::wide_from_tree(&built, params).map_err(|e| e.to_string())
    }
    Ok(match prims {
        Primitives::Spheres(p) => Box::new(wide(p, nodes, prim_order, params)?),
        Primitives::MollerTrumbore(p) => Box::new(wide(p, nodes, prim_order, params)?),
        Primitives::Watertight(p) => Box::new(wide(p, nodes, prim_order, params)?),
    })
}

/// The tracer's structures as [`Structure`]s: left out of the tracer's unit-test build, which runs none of them.
#[cfg(not(test))]
mod compiled {
    use std::marker::PhantomData;

    use super::Structure;
    use crate::accel::wide::WidePrimitive;
    use crate::accel::{AccelVisitor, Accelerator, BuiltAccel, TreeStats};
    use crate::counters::{Counters, NoCounters, WorkCounters};
    use crate::executor::Strategy;
    use crate::geometry::{MollerTrumboreTriangle, Sphere, WatertightTriangle};
    use crate::job::{Job, Output, run_spheres, run_triangles};

    /// Runs a job with counters `C` on the concrete structure over `P`.
    struct Runs<'a, P, C> {
        job: &'a Job<'a>,
        strategy: &'a Strategy,
        _types: PhantomData<(P, C)>,
    }

    impl<'a, P, C> Runs<'a, P, C> {
        fn new(job: &'a Job<'a>, strategy: &'a Strategy) -> Self {
            Self { job, strategy, _types: PhantomData }
        }
    }

    impl<P: Jobs, C: Counters> AccelVisitor for Runs<'_, P, C> {
        type Output = (Output, C);
        fn visit<A: Accelerator>(self, accel: &A) -> (Output, C) {
            P::run::<A, C>(accel, self.job, self.strategy)
        }
    }

    /// Which jobs a primitive's structures run: spheres render sphere scenes, triangles triangle scenes (so neither
    /// compiles the other's renderer).
    trait Jobs: WidePrimitive {
        fn run<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C);
    }

    impl Jobs for Sphere {
        fn run<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
            run_spheres(accel, job, strategy)
        }
    }

    impl Jobs for MollerTrumboreTriangle {
        fn run<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
            run_triangles(accel, job, strategy)
        }
    }

    impl Jobs for WatertightTriangle {
        fn run<A: Accelerator, C: Counters>(accel: &A, job: &Job<'_>, strategy: &Strategy) -> (Output, C) {
            run_triangles(accel, job, strategy)
        }
    }

    /// The tracer's structures over each primitive: non-generic, so compiled here.
    macro_rules! structure_over {
        ($($p:ty),*) => {$(
            impl Structure for BuiltAccel<$p> {
                fn run(&self, job: &Job<'_>, strategy: &Strategy) -> Output {
                    self.visit(Runs::<$p, NoCounters>::new(job, strategy)).0
                }
                fn run_counted(&self, job: &Job<'_>, strategy: &Strategy) -> (Output, WorkCounters) {
                    self.visit(Runs::<$p, WorkCounters>::new(job, strategy))
                }
                fn stats(&self) -> TreeStats {
                    BuiltAccel::stats(self)
                }
                fn simd_kernel(&self) -> Option<&'static str> {
                    self.kernel_name()
                }
            }
        )*};
    }

    structure_over!(Sphere, MollerTrumboreTriangle, WatertightTriangle);
}
