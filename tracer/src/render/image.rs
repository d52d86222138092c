use std::io::Write;

use crate::fingerprint::Fnv64;

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major.
    pub pixels: Vec<[u8; 3]>,
}

impl Image {
    /// Stable FNV-1a hash of the size and pixel bytes (not of the PNG, whose compression may change).
    pub fn hash(&self) -> u64 {
        let mut h = Fnv64::default();
        h.u32(self.width).u32(self.height);
        for p in &self.pixels {
            h.bytes(p);
        }
        h.finish()
    }

    /// Encodes the image as PNG into `w`.
    pub fn write_png<W: Write>(&self, w: W) -> Result<(), png::EncodingError> {
        let mut encoder = png::Encoder::new(w, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(self.pixels.as_flattened())?;
        writer.finish()
    }
}
