//! Triangle scenes: a mesh, a camera from one of its named [`View`]s, and one point light above it.
//!
//! Views are computed from the mesh's bounds and its up axis only, so they work on any mesh: `overview` looks at
//! the center of the box from outside it (above, in front and to one side), far enough that the whole box is in
//! frame; `street` stands low inside the box (at 5% of its height above its floor, at its center) and looks along
//! the ground (meant for the city data sets). The light sits above the box, off center, at twice its height plus
//! its diagonal.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::camera::Camera;
use super::mesh::Mesh;
use crate::fingerprint::Fnv64;
use crate::geometry::Aabb;

/// A named camera view of a triangle scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    /// From outside, the whole model in frame.
    Overview,
    /// Low inside the model's box, looking along the ground (for cities).
    Street,
}

impl View {
    /// Every view.
    pub const ALL: [View; 2] = [View::Overview, View::Street];

    /// The kebab-case name used in configs.
    pub fn name(self) -> &'static str {
        match self {
            View::Overview => "overview",
            View::Street => "street",
        }
    }

    /// The camera of this view of a model with `bounds` whose up direction is the unit axis `up`.
    pub fn camera(self, bounds: Aabb, up: Vec3) -> Camera {
        let (c, e) = (bounds.center(), bounds.extent());
        let diagonal = e.length().max(f32::MIN_POSITIVE);
        // Two horizontal axes: the next axes after `up` (x → y, z; y → z, x; z → x, y).
        let (ahead, side) = horizontal(up);
        match self {
            View::Overview => {
                let out = (ahead * 1.0 + side * 0.6 + up * 0.5).normalize();
                Camera {
                    position: c + out * (1.1 * diagonal),
                    look_at: c,
                    up,
                    vfov_degrees: 45.0,
                    width: 640,
                    height: 480,
                }
            }
            View::Street => {
                let height = up.dot(e).abs();
                let floor = c - up * (0.5 * height);
                let position = floor + up * (0.05 * height);
                Camera {
                    position,
                    look_at: position - ahead * diagonal,
                    up,
                    vfov_degrees: 60.0,
                    width: 640,
                    height: 480,
                }
            }
        }
    }
}

/// Two horizontal unit axes for the unit axis `up`.
fn horizontal(up: Vec3) -> (Vec3, Vec3) {
    let a = Vec3::new(up.z, up.x, up.y);
    let b = Vec3::new(up.y, up.z, up.x);
    (a, b)
}

/// A triangle mesh with its camera and light.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshScene {
    /// The triangles.
    pub mesh: Mesh,
    /// The camera of the chosen view.
    pub camera: Camera,
    /// The one point light (shadow rays go to it).
    pub light: Vec3,
}

impl MeshScene {
    /// `mesh` seen from `view`, `up` its unit up axis.
    pub fn new(mesh: Mesh, view: View, up: Vec3) -> Self {
        let bounds = mesh.bounds();
        let camera = view.camera(bounds, up);
        let (ahead, side) = horizontal(up);
        let d = bounds.extent().length();
        let light =
            bounds.center() + up * (2.0 * up.dot(bounds.extent()).abs() + d) + ahead * (0.25 * d) + side * (0.15 * d);
        MeshScene { mesh, camera, light }
    }

    /// Stable hash of the mesh, camera and light.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv64::default();
        h.bytes(&self.mesh.fingerprint().to_le_bytes());
        let c = &self.camera;
        for v in [c.position, c.look_at, c.up, self.light] {
            h.f32(v.x).f32(v.y).f32(v.z);
        }
        h.f32(c.vfov_degrees).u32(c.width).u32(c.height);
        h.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::random_triangles;

    #[test]
    fn views_look_at_the_model_and_the_light_is_above_it() {
        let mesh = random_triangles(200, 3);
        let b = mesh.bounds();
        for up in [Vec3::Y, Vec3::Z] {
            let s = MeshScene::new(mesh.clone(), View::Overview, up);
            assert!(!b.contains(s.camera.position), "overview is outside");
            assert!(up.dot(s.light) > up.dot(b.max), "the light is above");
            let street = View::Street.camera(b, up);
            assert!(b.contains(street.position), "street is inside");
            assert!((street.look_at - street.position).dot(up).abs() < 1e-3, "and looks along the ground");
        }
        assert_ne!(
            MeshScene::new(mesh.clone(), View::Overview, Vec3::Y).fingerprint(),
            MeshScene::new(mesh, View::Street, Vec3::Y).fingerprint()
        );
    }
}
