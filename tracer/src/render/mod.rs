//! Rendering: full Whitted shading ([`render`]) and the closest-hit primary-ray kernel ([`trace_primary`]).

mod image;
mod primary;
mod shade;

pub use image::Image;
pub use primary::{PrimaryHits, trace_primary};
pub use shade::{RenderSettings, render};
