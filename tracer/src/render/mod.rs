//! Rendering: full Whitted shading of sphere scenes ([`render`]), flat shading of triangle scenes
//! ([`render_mesh`]) and the closest-hit primary-ray kernel ([`trace_primary`]).

mod image;
mod mesh;
mod primary;
mod shade;

pub use image::Image;
pub use mesh::render_mesh;
pub use primary::{PrimaryHits, trace_primary};
pub use shade::{RenderSettings, render};
