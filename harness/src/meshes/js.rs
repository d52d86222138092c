//! The npm mesh packages' JavaScript modules: `exports.positions=[[x,y,z],…]` and `exports.cells=[[a,b,c],…]`.

use std::path::Path;

use serde::de::DeserializeOwned;
use tracer::Vec3;
use tracer::scene::mesh::Mesh;

use crate::error::Error;

/// The mesh of the JS module `path`, from its `positions` and `cells` arrays.
pub fn load(path: &Path) -> Result<Mesh, Error> {
    let text =
        std::fs::read_to_string(path).map_err(|e| Error::Input(format!("{}: cannot read: {e}", path.display())))?;
    let positions: Vec<[f32; 3]> = array(&text, "positions", path)?;
    let indices = array(&text, "cells", path)?;
    super::checked(Mesh { positions: positions.into_iter().map(Vec3::from).collect(), indices }, path)
}

/// The JSON array assigned to `exports.NAME` in `text`.
fn array<T: DeserializeOwned>(text: &str, name: &str, path: &Path) -> Result<Vec<T>, Error> {
    let bad = |what: String| {
        Error::Input(format!(
            "{}: {what} (allowed: `exports.{name}=[[…, …, …], …]` of three numbers each)",
            path.display()
        ))
    };
    let key = format!("exports.{name}=");
    let start = text.find(&key).ok_or_else(|| bad(format!("no `exports.{name}=`")))? + key.len();
    let mut values = serde_json::Deserializer::from_str(&text[start..]).into_iter::<Vec<T>>();
    match values.next() {
        Some(Ok(v)) => Ok(v),
        Some(Err(e)) => Err(bad(format!("`{name}` is not an array of triples: {e}"))),
        None => Err(bad(format!("`exports.{name}=` has no value"))),
    }
}
