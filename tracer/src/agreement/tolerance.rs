//! The distance tolerance: how far apart two hits of one ray may lie and still agree.

use crate::geometry::Ray;

/// Relative tolerance on hit distances.
pub const T_TOLERANCE: f32 = 1e-4;

/// Floor of the distance tolerance, in ulps of the ray origin's largest coordinate.
pub const ORIGIN_ULPS: f32 = 8.0;

/// Largest accepted `|t - t_reference|` for a hit at `t` along `ray`: [`T_TOLERANCE`] relative, with a floor of
/// [`ORIGIN_ULPS`] ulps of the origin's magnitude (in units of the direction's length) for hits right at the
/// origin, where both distances are rounding noise of the coordinates.
pub fn t_tolerance(ray: &Ray, t: f32) -> f32 {
    let floor = ORIGIN_ULPS * f32::EPSILON * ray.origin.abs().max_element().max(1.0) / ray.dir.length();
    (T_TOLERANCE * t.abs()).max(floor)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn hits_near_the_origin_get_an_ulp_floor() {
        let far = Ray::new(Vec3::new(14.0, 3.0, -13.0), Vec3::Y);
        assert!(t_tolerance(&far, 2.7e-4) > 3.6e-8, "the Embree bounce case seen in peers.toml");
        assert!(t_tolerance(&far, 2.7e-4) < 1e-4);
        assert_eq!(t_tolerance(&Ray::new(Vec3::ZERO, Vec3::Y), 100.0), 1e-2);
    }
}
