//! The tree parameters a user chooses; serializable so that every recorded run names them.

use std::fmt;
use std::hash::{Hash, Hasher};
use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};

use super::sah::SahCosts;

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
    /// Binned SAH over object and spatial splits (SBVH), duplicating straddling references (see [`super::spatial`]).
    SpatialSah,
}

impl Split {
    /// Every rule, in the order tools list them.
    pub const ALL: [Split; 5] =
        [Split::CentroidMidpoint, Split::ObjectMedian, Split::BinnedSah, Split::SweepSah, Split::SpatialSah];

    /// True for the rules that build with the SAH cost model.
    pub fn is_sah(self) -> bool {
        matches!(self, Split::BinnedSah | Split::SweepSah | Split::SpatialSah)
    }

    /// True for the rules that bin with `sah_bins`.
    pub fn is_binned(self) -> bool {
        matches!(self, Split::BinnedSah | Split::SpatialSah)
    }

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Split::CentroidMidpoint => "centroid-midpoint",
            Split::ObjectMedian => "object-median",
            Split::BinnedSah => "binned-sah",
            Split::SweepSah => "sweep-sah",
            Split::SpatialSah => "spatial-sah",
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
    /// Largest number of spheres in a leaf, in [`BvhParams::LEAF_SIZES`].
    pub leaf_size: u32,
    /// The split rule.
    pub split: Split,
    /// Bins per axis for [`Split::BinnedSah`] and [`Split::SpatialSah`] (object and spatial bins), in
    /// [`BvhParams::SAH_BINS`].
    pub sah_bins: u32,
    /// The child visiting order.
    pub traversal: Traversal,
    /// Most rounds of the reinsertion pass run on the built tree (0: off), in [`BvhParams::REINSERTION_ROUNDS`].
    pub reinsertion: u32,
    /// The cost constants the SAH splits build with (ignored by the other splits).
    pub sah_costs: SahCosts,
    /// Overlap threshold of [`Split::SpatialSah`], in [`BvhParams::SPATIAL_ALPHAS`] (ignored by the other splits).
    pub spatial_alpha: SpatialAlpha,
}

/// [`Split::SpatialSah`]'s threshold: spatial splits are tried where the best object split's children overlap by
/// more than `alpha` times the root's surface area (Stich et al. 2009's α; 0: wherever they overlap, 1: never).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct SpatialAlpha(pub f32);

impl SpatialAlpha {
    /// The paper's recommended 1e-5.
    pub const DEFAULT: SpatialAlpha = SpatialAlpha(1e-5);
}

impl Default for SpatialAlpha {
    fn default() -> Self {
        Self::DEFAULT
    }
}

// Alphas are validated finite, so bitwise equality is equality.
impl Eq for SpatialAlpha {}

impl Hash for SpatialAlpha {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.0.to_bits().hash(state);
    }
}

impl Default for BvhParams {
    fn default() -> Self {
        Self {
            leaf_size: 4,
            split: Split::CentroidMidpoint,
            sah_bins: 16,
            traversal: Traversal::Fixed,
            reinsertion: 0,
            sah_costs: SahCosts::UNIT,
            spatial_alpha: SpatialAlpha::DEFAULT,
        }
    }
}

/// A parameter outside its allowed range.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParamError {
    /// The parameter's name.
    pub key: &'static str,
    /// The allowed values.
    pub allowed: String,
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
    /// Allowed `leaf_size` values.
    pub const LEAF_SIZES: RangeInclusive<u32> = 1..=16;
    /// Largest allowed `leaf_size`.
    pub const MAX_LEAF_SIZE: u32 = *Self::LEAF_SIZES.end();
    /// Allowed `sah_bins` values.
    pub const SAH_BINS: RangeInclusive<u32> = 2..=256;
    /// Allowed `reinsertion` values (most rounds; 0: off).
    pub const REINSERTION_ROUNDS: RangeInclusive<u32> = 0..=64;
    /// Allowed SAH cost constants.
    pub const SAH_COSTS: RangeInclusive<f32> = 1e-3..=1e3;
    /// Allowed `spatial_alpha` values.
    pub const SPATIAL_ALPHAS: RangeInclusive<f32> = 0.0..=1.0;

    /// Checks every range; builders refuse invalid parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        let check = |key, range: RangeInclusive<u32>, value: u32| {
            let allowed = format!("{}..={}", range.start(), range.end());
            if range.contains(&value) { Ok(()) } else { Err(ParamError { key, allowed, found: value.to_string() }) }
        };
        check("leaf_size", Self::LEAF_SIZES, self.leaf_size)?;
        check("sah_bins", Self::SAH_BINS, self.sah_bins)?;
        check("reinsertion", Self::REINSERTION_ROUNDS, self.reinsertion)?;
        for (key, cost) in
            [("sah_traversal_cost", self.sah_costs.traversal), ("sah_intersection_cost", self.sah_costs.intersection)]
        {
            if !(Self::SAH_COSTS.contains(&cost)) {
                let allowed = format!("{}..={}", Self::SAH_COSTS.start(), Self::SAH_COSTS.end());
                return Err(ParamError { key, allowed, found: cost.to_string() });
            }
        }
        let alpha = self.spatial_alpha.0;
        if !Self::SPATIAL_ALPHAS.contains(&alpha) {
            let allowed = format!("{}..={}", Self::SPATIAL_ALPHAS.start(), Self::SPATIAL_ALPHAS.end());
            return Err(ParamError { key: "spatial_alpha", allowed, found: alpha.to_string() });
        }
        Ok(())
    }
}
