//! Work counters, chosen by type: [`NoCounters`] compiles to nothing, [`WorkCounters`] counts.
//!
//! Every traversal and renderer is generic over `C: Counters`; with `NoCounters` each hook is an
//! empty inlined function on a zero-sized type, so a timing build contains no counting code at all.

use std::ops::AddAssign;

use serde::{Deserialize, Serialize};

/// Hooks a traversal calls as it works; implementations decide whether anything is counted.
pub trait Counters: Default + Send {
    /// True for implementations that record anything.
    const ENABLED: bool;
    /// One ray handed to an accelerator.
    fn ray(&mut self);
    /// One tree node taken for processing.
    fn node_visit(&mut self);
    /// `n` ray-box tests.
    fn box_tests(&mut self, n: u32);
    /// One ray-primitive test.
    fn prim_test(&mut self);
    /// Adds another band's counts into this one.
    fn merge(&mut self, other: Self);
}

/// Counts nothing and costs nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoCounters;

impl Counters for NoCounters {
    const ENABLED: bool = false;
    #[inline(always)]
    fn ray(&mut self) {}
    #[inline(always)]
    fn node_visit(&mut self) {}
    #[inline(always)]
    fn box_tests(&mut self, _: u32) {}
    #[inline(always)]
    fn prim_test(&mut self) {}
    #[inline(always)]
    fn merge(&mut self, _: Self) {}
}

/// Totals of the work done: rays, nodes visited, ray-box tests and ray-primitive tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct WorkCounters {
    /// Rays handed to the accelerator.
    pub rays: u64,
    /// Tree nodes taken for processing (the root counts even when the ray misses it).
    pub nodes_visited: u64,
    /// Ray-box slab tests.
    pub box_tests: u64,
    /// Ray-sphere tests.
    pub prim_tests: u64,
}

impl WorkCounters {
    /// Per-ray averages `(nodes, box tests, primitive tests)`; zeros when no ray was traced.
    pub fn per_ray(&self) -> (f64, f64, f64) {
        if self.rays == 0 {
            return (0.0, 0.0, 0.0);
        }
        let r = self.rays as f64;
        (self.nodes_visited as f64 / r, self.box_tests as f64 / r, self.prim_tests as f64 / r)
    }
}

impl AddAssign for WorkCounters {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nodes_visited += o.nodes_visited;
        self.box_tests += o.box_tests;
        self.prim_tests += o.prim_tests;
    }
}

impl Counters for WorkCounters {
    const ENABLED: bool = true;
    #[inline(always)]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline(always)]
    fn node_visit(&mut self) {
        self.nodes_visited += 1;
    }
    #[inline(always)]
    fn box_tests(&mut self, n: u32) {
        self.box_tests += n as u64;
    }
    #[inline(always)]
    fn prim_test(&mut self) {
        self.prim_tests += 1;
    }
    fn merge(&mut self, other: Self) {
        *self += other;
    }
}
