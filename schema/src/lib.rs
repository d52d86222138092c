//! The vocabulary every stage shares: each experiment setting (an *axis*) and each recorded column is
//! declared once, in [`columns`], with its key, Rust type, allowed values or range, default, unit, and
//! the backends it applies to. Config parsing, planning, normalization, configuration ids, the row
//! struct written by the harness and read by the report, the report's column types and `report/ROWS.md`
//! all follow from that declaration; strings exist only at the edges (TOML, CSV, command line).
//!
//! - [`names`]: the kebab-case names of the tracer's and the peers' enums, and the [`Named`] trait;
//! - [`value`]: how one setting value is parsed from a config and written to a row ([`AxisType`]);
//! - [`columns`]: the declaration itself: [`Settings`], [`Axis`], [`AxisValue`] and [`Row`];
//! - [`row`]: columns as metadata, cells, configuration ids and the CSV row log format;
//! - [`rows_md`]: `report/ROWS.md`, generated from the declaration;
//! - [`config_md`]: `docs/configuration.md`, the configuration reference, generated from it too.

#[macro_use]
mod declare;
pub mod applicability;
pub mod columns;
pub mod config_md;
pub mod names;
pub mod row;
pub mod rows_md;
pub mod value;

pub use columns::{Axis, AxisValue, Row, Settings, column};
pub use names::MeshSource;
pub use names::{
    Accel, EmbreeIsa, EmbreePacket, EmbreeQuality, LeafBlock, Named, NodeWidth, ObvhsQuality, Packet, PeerKind,
    SahBlock, SceneName, Threads, TinyBvhLayout, TinyBvhQuality, TreeBuilder, ValidationStatus, Workload, WrongSide,
};
pub use row::{Cell, Column, Kind, Role};
pub use value::{AxisType, Raw};
