//! One setting value: parsed from a config, written to and read from a row.

use std::fmt::Debug;

use crate::names::{EmbreePacket, LeafBlock, MeshSource, Named, NodeWidth, SahBlock, Threads};
use crate::row::{Cell, Kind};

/// A config value as TOML (or the command line) gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Raw<'a> {
    /// An integer.
    Int(i64),
    /// A float.
    Float(f64),
    /// A string.
    Str(&'a str),
}

impl Raw<'_> {
    /// What kind of value this is, in words.
    pub fn what(&self) -> String {
        match self {
            Raw::Int(i) => format!("the number {i}"),
            Raw::Float(x) => format!("the number {x}"),
            Raw::Str(s) => format!("{s:?}"),
        }
    }
}

/// The Rust type of a setting.
pub trait AxisType: Clone + PartialEq + Debug + Send + Sync + 'static {
    /// The column's type in rows and frames.
    const KIND: Kind;
    /// Parses one config value; the declaration's range is checked by the caller.
    fn parse(raw: Raw<'_>) -> Result<Self, String>;
    /// What a config may give, in words: names, or the kind of number within `range` (e.g. `1..=16`).
    fn allowed(range: &str) -> String;
    /// The value as a row cell.
    fn cell(&self) -> Cell;
    /// Reads a row's text (the inverse of [`AxisType::cell`]).
    fn from_text(text: &str) -> Result<Self, String>;
    /// The value as a number, for range checks (`None` for names).
    fn number(&self) -> Option<f64> {
        None
    }
    /// Every value, for types with a finite set of names (`None` for numbers).
    fn choices() -> Option<Vec<Self>> {
        None
    }
    /// The cell written where the setting does not apply.
    fn not_applicable_cell() -> Cell {
        match Self::KIND {
            Kind::Text => Cell::Text("-".into()),
            Kind::Int => Cell::Int(0),
            Kind::Float => Cell::Float(0.0),
            Kind::Bool => Cell::Bool(false),
        }
    }
}

impl<T: Named> AxisType for T {
    const KIND: Kind = Kind::Text;
    fn parse(raw: Raw<'_>) -> Result<Self, String> {
        match raw {
            Raw::Str(s) => T::from_name(s).ok_or_else(|| format!("unknown value {s:?}")),
            other => Err(format!("expected a name, found {}", other.what())),
        }
    }
    fn allowed(_: &str) -> String {
        T::names()
    }
    fn cell(&self) -> Cell {
        Cell::Text(self.name().to_string())
    }
    fn from_text(text: &str) -> Result<Self, String> {
        T::from_name(text).ok_or_else(|| format!("unknown value {text:?} (allowed: {})", T::names()))
    }
    fn choices() -> Option<Vec<Self>> {
        Some(T::ALL.to_vec())
    }
}

macro_rules! integer_axis_type {
    ($($t:ty),*) => {$(
        impl AxisType for $t {
            const KIND: Kind = Kind::Int;
            fn parse(raw: Raw<'_>) -> Result<Self, String> {
                match raw {
                    Raw::Int(i) => <$t>::try_from(i).map_err(|_| format!("{i} is out of range")),
                    other => Err(format!("expected an integer, found {}", other.what())),
                }
            }
            fn allowed(range: &str) -> String {
                format!("integers {range}")
            }
            fn cell(&self) -> Cell {
                Cell::Int(*self as i64)
            }
            fn from_text(text: &str) -> Result<Self, String> {
                text.parse().map_err(|_| format!("expected an integer, found {text:?}"))
            }
            fn number(&self) -> Option<f64> {
                Some(*self as f64)
            }
        }
    )*};
}

integer_axis_type!(u32, u64);

macro_rules! int_choice_axis_type {
    ($($t:ident),*) => {$(
        impl AxisType for $t {
            const KIND: Kind = Kind::Int;
            fn parse(raw: Raw<'_>) -> Result<Self, String> {
                match raw {
                    Raw::Int(i) => u32::try_from(i).ok().and_then($t::new).ok_or_else(|| format!("{i} is not allowed")),
                    other => Err(format!("expected an integer, found {}", other.what())),
                }
            }
            fn allowed(_: &str) -> String {
                $t::VALUES.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
            }
            fn cell(&self) -> Cell {
                Cell::Int(i64::from(self.0))
            }
            fn from_text(text: &str) -> Result<Self, String> {
                text.parse().ok().and_then($t::new).ok_or_else(|| format!("expected one of {}, found {text:?}", Self::allowed("")))
            }
            fn number(&self) -> Option<f64> {
                Some(f64::from(self.0))
            }
            fn choices() -> Option<Vec<Self>> {
                Some($t::VALUES.iter().map(|&n| $t(n)).collect())
            }
        }
    )*};
}

int_choice_axis_type!(NodeWidth, LeafBlock, SahBlock, EmbreePacket);

impl AxisType for f32 {
    const KIND: Kind = Kind::Float;
    fn parse(raw: Raw<'_>) -> Result<Self, String> {
        match raw {
            Raw::Int(i) => Ok(i as f32),
            Raw::Float(x) if x.is_finite() => Ok(x as f32),
            other => Err(format!("expected a finite number, found {}", other.what())),
        }
    }
    fn allowed(range: &str) -> String {
        format!("numbers {range}")
    }
    fn cell(&self) -> Cell {
        // Through the shortest decimal of the f32, so that 0.1 is written `0.1`, not 0.10000000149…
        Cell::Float(self.to_string().parse().expect("an f32 prints as a number"))
    }
    fn from_text(text: &str) -> Result<Self, String> {
        text.parse().map_err(|_| format!("expected a number, found {text:?}"))
    }
    fn number(&self) -> Option<f64> {
        Some(f64::from(*self))
    }
}

impl AxisType for Threads {
    const KIND: Kind = Kind::Int;
    fn parse(raw: Raw<'_>) -> Result<Self, String> {
        match raw {
            Raw::Str(Threads::ALL_WORD) => Ok(Threads::All),
            other => u32::parse(other).map(Threads::Count),
        }
    }
    fn allowed(range: &str) -> String {
        format!("integers {range} or {}", Threads::ALL_WORD)
    }
    fn cell(&self) -> Cell {
        match self {
            Threads::All => Cell::Text(Threads::ALL_WORD.into()),
            Threads::Count(n) => Cell::Int(i64::from(*n)),
        }
    }
    fn from_text(text: &str) -> Result<Self, String> {
        if text == Threads::ALL_WORD { Ok(Threads::All) } else { u32::from_text(text).map(Threads::Count) }
    }
    fn number(&self) -> Option<f64> {
        match self {
            Threads::All => None,
            Threads::Count(n) => Some(f64::from(*n)),
        }
    }
}

impl AxisType for MeshSource {
    const KIND: Kind = Kind::Text;
    fn parse(raw: Raw<'_>) -> Result<Self, String> {
        match raw {
            Raw::Str(s) if !s.is_empty() && s != "-" && !s.contains([',', '"', '\n']) => Ok(MeshSource(s.to_string())),
            other => Err(format!("expected a data set name or a mesh path, found {}", other.what())),
        }
    }
    fn allowed(_: &str) -> String {
        "a data set name (harness fetch --list), an .obj/.ply path, or MODEL*N (N copies)".into()
    }
    fn cell(&self) -> Cell {
        Cell::Text(self.0.clone())
    }
    fn from_text(text: &str) -> Result<Self, String> {
        Self::parse(Raw::Str(text))
    }
}

/// A setting that only applies to some configurations: `None` where it does not (written `-`, or `0` for
/// numbers, so `0` is never a valid value of such a numeric setting).
impl<T: AxisType> AxisType for Option<T> {
    const KIND: Kind = T::KIND;
    fn parse(raw: Raw<'_>) -> Result<Self, String> {
        T::parse(raw).map(Some)
    }
    fn allowed(range: &str) -> String {
        T::allowed(range)
    }
    fn cell(&self) -> Cell {
        self.as_ref().map_or_else(T::not_applicable_cell, T::cell)
    }
    fn from_text(text: &str) -> Result<Self, String> {
        if text.is_empty() || T::not_applicable_cell().to_string() == text {
            Ok(None)
        } else {
            T::from_text(text).map(Some)
        }
    }
    fn number(&self) -> Option<f64> {
        self.as_ref().and_then(T::number)
    }
    fn choices() -> Option<Vec<Self>> {
        T::choices().map(|all| all.into_iter().map(Some).collect())
    }
}

/// `#[serde(with = "as_text")]`: a setting serialized as its row text, so JSON and CSV spell it alike.
pub mod as_text {
    use serde::{Deserialize, Deserializer, Serializer};

    use super::AxisType;

    /// Writes the row text.
    pub fn serialize<T: AxisType, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(&value.cell())
    }

    /// Reads the row text.
    pub fn deserialize<'de, T: AxisType, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
        let text = String::deserialize(d)?;
        T::from_text(&text).map_err(serde::de::Error::custom)
    }
}
