use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geometry::Ray;

/// A pinhole camera and the image it takes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// The point at the image center.
    pub look_at: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_degrees: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// The same camera taking an image of another size.
    pub fn with_resolution(self, width: u32, height: u32) -> Self {
        Self { width, height, ..self }
    }

    /// Precomputes the image plane for ray generation.
    pub fn rays(&self) -> CameraRays {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let half_h = (self.vfov_degrees.to_radians() * 0.5).tan();
        let half_w = half_h * self.width as f32 / self.height.max(1) as f32;
        CameraRays {
            origin: self.position,
            top_left: forward - right * half_w + up * half_h,
            dx: right * (2.0 * half_w / self.width.max(1) as f32),
            dy: -up * (2.0 * half_h / self.height.max(1) as f32),
        }
    }
}

/// A camera's image plane, ready to make one ray per pixel.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    origin: Vec3,
    top_left: Vec3,
    dx: Vec3,
    dy: Vec3,
}

impl CameraRays {
    /// The unit-direction ray through the center of pixel `(x, y)`, row 0 at the top.
    #[inline]
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        let d = self.top_left + self.dx * (x as f32 + 0.5) + self.dy * (y as f32 + 0.5);
        Ray::new(self.origin, d.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn center_pixel_looks_at_target() {
        let cam = Camera {
            position: Vec3::ZERO,
            look_at: Vec3::new(0.0, 0.0, -5.0),
            up: Vec3::Y,
            vfov_degrees: 60.0,
            width: 101,
            height: 51,
        };
        let r = cam.rays().ray(50, 25);
        assert!((r.dir - -Vec3::Z).length() < 1e-6);
        let top = cam.rays().ray(50, 0);
        assert!(top.dir.y > 0.0, "row 0 is the top of the image");
    }
}
