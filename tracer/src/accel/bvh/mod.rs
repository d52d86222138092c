//! Bounding volume hierarchies: one builder, two layouts, one generic traversal.
//!
//! - [`params`]: what a user chooses (leaf size, split rule, traversal order).
//! - [`tree`]: what every builder produces (a [`tree::BuiltTree`] of [`tree::FlatNode`]s) and the depth bound.
//! - [`builder`]: the shared top-down builder; [`split`] holds one file per split rule, [`sah`] the cost model;
//!   [`spatial`]: the builder of [`Split::SpatialSah`] (object and spatial splits, references duplicated).
//! - [`reinsertion`]: the optional post-build pass that moves subtrees to lower the tree's SAH cost.
//! - [`traverse`]: closest-hit/any-hit traversal, generic over tree layout, child order, counters and leaves,
//!   and the one dispatch from a tree's [`Traversal`] to the child order compiled for it.
//! - [`Bvh`] (pointer tree, the paper's) and [`FlatBvh`] (one array) are the layouts.

pub mod builder;
pub mod flat;
pub mod params;
pub mod pointer;
pub mod reinsertion;
pub mod sah;
pub mod spatial;
pub mod split;
pub mod stats;
pub mod traverse;
pub mod tree;

pub use flat::FlatBvh;
pub use params::{BvhParams, ParamError, SpatialAlpha, Split, Traversal};
pub use pointer::Bvh;
pub use sah::{CostModel, SahCosts};
pub use stats::TreeStats;
