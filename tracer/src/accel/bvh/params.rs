//! The tree parameters a user chooses; serializable so that every recorded run names them.

use std::fmt;

use serde::{Deserialize, Serialize};

/// How a node's spheres are divided between its two children.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Split {
    /// The paper's rule: the middle of the centroid bounds' longest axis.
    CentroidMidpoint,
    /// Half of the spheres on each side, ordered by centroid on the longest axis.
    ObjectMedian,
    /// Surface area heuristic over `sah_bins` equal bins per axis.
    BinnedSah,
    /// Surface area heuristic over every sorted split position on every axis.
    SweepSah,
}

impl Split {
    /// Every rule, in the order tools list them.
    pub const ALL: [Split; 4] = [Split::CentroidMidpoint, Split::ObjectMedian, Split::BinnedSah, Split::SweepSah];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Split::CentroidMidpoint => "centroid-midpoint",
            Split::ObjectMedian => "object-median",
            Split::BinnedSah => "binned-sah",
            Split::SweepSah => "sweep-sah",
        }
    }
}

/// The order in which a traversal visits the two children of a node it enters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Traversal {
    /// Always left, then right (the paper's).
    Fixed,
    /// The child the ray enters first, then the other.
    FrontToBack,
}

impl Traversal {
    /// Both orders.
    pub const ALL: [Traversal; 2] = [Traversal::Fixed, Traversal::FrontToBack];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Traversal::Fixed => "fixed",
            Traversal::FrontToBack => "front-to-back",
        }
    }
}

/// Parameters of a BVH; the default is the paper's tree (leaf size 4, centroid midpoint, fixed order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BvhParams {
    /// Largest number of spheres in a leaf, `1..=16`.
    pub max_leaf_size: u32,
    /// The split rule.
    pub split: Split,
    /// Bins per axis for [`Split::BinnedSah`], `2..=256`.
    pub sah_bins: u32,
    /// The child visiting order.
    pub traversal: Traversal,
}

impl Default for BvhParams {
    fn default() -> Self {
        Self { max_leaf_size: 4, split: Split::CentroidMidpoint, sah_bins: 16, traversal: Traversal::Fixed }
    }
}

/// A parameter outside its allowed range.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParamError {
    /// The parameter's name.
    pub key: &'static str,
    /// The allowed values.
    pub allowed: &'static str,
    /// The value given.
    pub found: String,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {} is out of range (allowed: {})", self.key, self.found, self.allowed)
    }
}

impl std::error::Error for ParamError {}

impl BvhParams {
    /// Largest allowed `max_leaf_size`.
    pub const MAX_LEAF_SIZE: u32 = 16;

    /// Checks every range; builders assume valid parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(1..=Self::MAX_LEAF_SIZE).contains(&self.max_leaf_size) {
            return Err(ParamError { key: "max_leaf_size", allowed: "1..=16", found: self.max_leaf_size.to_string() });
        }
        if !(2..=256).contains(&self.sah_bins) {
            return Err(ParamError { key: "sah_bins", allowed: "2..=256", found: self.sah_bins.to_string() });
        }
        Ok(())
    }
}
