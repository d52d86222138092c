//! The sweep axes: every setting a configuration can vary, its config key (= row column) and its values.

use std::fmt;

use tracer::accel::{AccelKind, Split, Traversal};
use tracer::executor::StrategyKind;
use tracer::rays::RayKind;
use tracer::scene::SceneKind;

use crate::peers::{EmbreeQuality, ObvhsQuality, PeerKind};

/// One setting of a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Axis {
    Scene,
    Objects,
    Seed,
    Accel,
    Split,
    LeafSize,
    SahBins,
    Traversal,
    Strategy,
    Threads,
    Width,
    Height,
    MaxDepth,
    Workload,
    ObvhsBuild,
    EmbreeBuild,
    EmbreeIsa,
}

/// A value on an axis: a number or one of the axis's names.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Value {
    Int(u64),
    Name(&'static str),
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Int(v) => write!(f, "{v}"),
            Value::Name(n) => f.write_str(n),
        }
    }
}

/// What a run computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Workload {
    /// Full Whitted shading and PNG encoding.
    Render,
    /// One fixed ray set (primary, shadow or diffuse rays), the same for every backend.
    Rays(RayKind),
}

impl Workload {
    pub const ALL: [Workload; 4] =
        [Workload::Render, Workload::Rays(RayKind::Primary), Workload::Rays(RayKind::Shadow), Workload::Rays(RayKind::Diffuse)];
    pub fn name(self) -> &'static str {
        match self {
            Workload::Render => "render",
            Workload::Rays(k) => k.name(),
        }
    }
}

/// Instruction sets a config may pin for Embree (`default` lets Embree choose).
pub const EMBREE_ISAS: [&str; 6] = ["default", "sse2", "sse4.2", "avx", "avx2", "avx512"];

/// Every accelerator name: the tracer's structures, then the peers.
pub fn accel_names() -> Vec<&'static str> {
    let mut v = names(&AccelKind::ALL, AccelKind::name);
    v.extend(PeerKind::ALL.iter().map(|p| p.name()));
    v
}

/// The scene names a config may use: the generators and `sphere-file`.
pub const SPHERE_FILE: &str = "sphere-file";

fn names<T: Copy>(all: &[T], name: fn(T) -> &'static str) -> Vec<&'static str> {
    all.iter().map(|&t| name(t)).collect()
}

impl Axis {
    /// Every axis, in row-column order.
    pub const ALL: [Axis; 17] = [
        Axis::Scene,
        Axis::Objects,
        Axis::Seed,
        Axis::Accel,
        Axis::Split,
        Axis::LeafSize,
        Axis::SahBins,
        Axis::Traversal,
        Axis::Strategy,
        Axis::Threads,
        Axis::Width,
        Axis::Height,
        Axis::MaxDepth,
        Axis::Workload,
        Axis::ObvhsBuild,
        Axis::EmbreeBuild,
        Axis::EmbreeIsa,
    ];

    /// The config key and row column.
    pub fn key(self) -> &'static str {
        match self {
            Axis::Scene => "scene",
            Axis::Objects => "objects",
            Axis::Seed => "seed",
            Axis::Accel => "accel",
            Axis::Split => "split",
            Axis::LeafSize => "leaf_size",
            Axis::SahBins => "sah_bins",
            Axis::Traversal => "traversal",
            Axis::Strategy => "strategy",
            Axis::Threads => "threads",
            Axis::Width => "width",
            Axis::Height => "height",
            Axis::MaxDepth => "max_depth",
            Axis::Workload => "workload",
            Axis::ObvhsBuild => "obvhs_build",
            Axis::EmbreeBuild => "embree_build",
            Axis::EmbreeIsa => "embree_isa",
        }
    }

    /// The axis with config key `key`.
    pub fn from_key(key: &str) -> Option<Axis> {
        Axis::ALL.into_iter().find(|a| a.key() == key)
    }

    /// The names this axis accepts (empty for numeric axes).
    pub fn names(self) -> Vec<&'static str> {
        match self {
            Axis::Scene => {
                let mut v = names(&SceneKind::ALL, SceneKind::name);
                v.push(SPHERE_FILE);
                v
            }
            Axis::Accel => accel_names(),
            Axis::Split => names(&Split::ALL, Split::name),
            Axis::Traversal => names(&Traversal::ALL, Traversal::name),
            Axis::Strategy => names(&StrategyKind::ALL, StrategyKind::name),
            Axis::Workload => names(&Workload::ALL, Workload::name),
            Axis::Threads => vec!["all"],
            Axis::ObvhsBuild => names(&ObvhsQuality::ALL, ObvhsQuality::name),
            Axis::EmbreeBuild => names(&EmbreeQuality::ALL, EmbreeQuality::name),
            Axis::EmbreeIsa => EMBREE_ISAS.to_vec(),
            _ => vec![],
        }
    }

    /// Allowed integer range, for numeric axes.
    pub fn range(self) -> Option<(u64, u64)> {
        match self {
            Axis::Objects => Some((0, 10_000_000)),
            Axis::Seed => Some((0, i64::MAX as u64)),
            Axis::LeafSize => Some((1, 16)),
            Axis::SahBins => Some((2, 256)),
            Axis::Threads => Some((1, 4096)),
            Axis::Width | Axis::Height => Some((1, 16384)),
            Axis::MaxDepth => Some((0, 64)),
            _ => None,
        }
    }

    /// What the axis accepts, in words, for error messages.
    pub fn allowed(self) -> String {
        let names = self.names().join(", ");
        match self.range() {
            Some((lo, hi)) if names.is_empty() => format!("integers {lo}..={hi}"),
            Some((lo, hi)) => format!("integers {lo}..={hi} or {names}"),
            None => names,
        }
    }

    /// Parses one TOML value for this axis; the error says what is allowed.
    pub fn parse(self, v: &toml::Value) -> Result<Value, String> {
        let bad = |what: String| Err(format!("{what} (allowed: {})", self.allowed()));
        match v {
            toml::Value::Integer(i) => match self.range() {
                Some((lo, hi)) if *i >= 0 && (lo..=hi).contains(&(*i as u64)) => Ok(Value::Int(*i as u64)),
                Some(_) => bad(format!("{i} is out of range")),
                None => bad(format!("expected a name, found the number {i}")),
            },
            toml::Value::String(s) => match self.names().into_iter().find(|n| n == s) {
                Some(n) => Ok(Value::Name(n)),
                None => bad(format!("unknown value {s:?}")),
            },
            other => bad(format!("expected a string or integer, found a {}", other.type_str())),
        }
    }

    /// The value a sweep uses when it does not name this axis.
    pub fn default_value(self) -> Value {
        match self {
            Axis::Scene => Value::Name(SceneKind::RandomSpheres.name()),
            Axis::Objects => Value::Int(1000),
            Axis::Seed => Value::Int(1),
            Axis::Accel => Value::Name(AccelKind::FlatBvh.name()),
            Axis::Split => Value::Name(Split::CentroidMidpoint.name()),
            Axis::LeafSize => Value::Int(4),
            Axis::SahBins => Value::Int(16),
            Axis::Traversal => Value::Name(Traversal::Fixed.name()),
            Axis::Strategy => Value::Name(StrategyKind::Serial.name()),
            Axis::Threads => Value::Name("all"),
            Axis::Width => Value::Int(320),
            Axis::Height => Value::Int(240),
            Axis::MaxDepth => Value::Int(3),
            Axis::Workload => Value::Name(Workload::Render.name()),
            Axis::ObvhsBuild => Value::Name(ObvhsQuality::default().name()),
            Axis::EmbreeBuild => Value::Name(EmbreeQuality::default().name()),
            Axis::EmbreeIsa => Value::Name(EMBREE_ISAS[0]),
        }
    }
}

/// Keys of all axes, for "allowed keys" messages.
pub fn axis_keys() -> String {
    Axis::ALL.map(Axis::key).join(", ")
}
