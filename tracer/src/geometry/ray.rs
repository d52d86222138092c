use glam::Vec3;

/// A ray segment: points `origin + t * dir` for `t_min < t < t_max`; `dir` need not be unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (hits report `t` in units of this vector's length).
    pub dir: Vec3,
    /// Hits at or before this parameter are ignored.
    pub t_min: f32,
    /// Hits at or beyond this parameter are ignored.
    pub t_max: f32,
}

impl Ray {
    /// An unbounded ray starting at `origin`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// A ray that ignores hits at or beyond `t_max` (shadow rays toward a light).
    pub fn segment(origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self { origin, dir, t_min: 0.0, t_max }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}
