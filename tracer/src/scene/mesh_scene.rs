//! Triangle scenes: a mesh, a camera from one of its named [`View`]s, and one point light above it.
//!
//! Views are computed from the mesh and its up axis only, so they work on any mesh: `overview` looks at the center
//! of the box from outside it (above, in front and to one side), far enough that the whole box is in frame.
//! `street` (meant for the city data sets) stands at eye height on open ground and looks along the longest free
//! line of sight: see [`View::Street`]. The light sits above the box, off center, at twice its height plus its
//! diagonal.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::camera::Camera;
use super::mesh::Mesh;
use crate::accel::{Accelerator, BvhParams, FlatBvh, Traversal};
use crate::counters::NoCounters;
use crate::fingerprint::Fnv64;
use crate::geometry::{Aabb, Ray, TrianglePrimitive, WatertightTriangle};

/// A named camera view of a triangle scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    /// From outside, the whole model in frame.
    Overview,
    /// At eye height (0.2% of the box's diagonal) on open ground — a surface with nothing above it and nothing
    /// below it down to the box's floor, so not a roof and not inside a closed model — at one of 32 × 32 points of
    /// the middle 60% of the box's footprint, looking level along one of 16 directions: the point and direction
    /// whose line of sight runs longest before it meets the model (a line that leaves the model is not counted).
    /// Without such ground (a closed model such as the bunny) it stands outside the box at 5% of its height above
    /// its floor, on the overview's side, and looks at the box's center.
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

    /// The camera of this view of `mesh`, whose up direction is the unit axis `up`.
    pub fn camera(self, mesh: &Mesh, up: Vec3) -> Camera {
        let bounds = mesh.bounds();
        let (c, e) = (bounds.center(), bounds.extent());
        let diagonal = e.length().max(f32::MIN_POSITIVE);
        // Two horizontal axes: the next axes after `up` (x → y, z; y → z, x; z → x, y).
        let (ahead, side) = horizontal(up);
        let camera =
            |position, look_at, vfov_degrees| Camera { position, look_at, up, vfov_degrees, width: 640, height: 480 };
        match self {
            View::Overview => {
                let out = (ahead * 1.0 + side * 0.6 + up * 0.5).normalize();
                camera(c + out * (1.1 * diagonal), c, 45.0)
            }
            View::Street => match street(mesh, bounds, up) {
                Some((position, toward)) => camera(position, position + toward * diagonal, 60.0),
                None => {
                    let height = up.dot(e).abs();
                    let out = (ahead * 1.0 + side * 0.6).normalize();
                    let low = c - up * (0.45 * height);
                    camera(low + out * (1.1 * diagonal), c, 60.0)
                }
            },
        }
    }
}

/// Points per horizontal axis where the street view may stand.
const STREET_GRID: u32 = 32;

/// The street view's eye and level direction (see [`View::Street`]); `None` where the model has no open ground.
fn street(mesh: &Mesh, bounds: Aabb, up: Vec3) -> Option<(Vec3, Vec3)> {
    let (c, e) = (bounds.center(), bounds.extent());
    let eye = 0.002 * e.length();
    let (ahead, side) = horizontal(up);
    // Sixteen level directions from integer steps (no trigonometry, so the same on every machine).
    let steps = [(1.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0)];
    let directions: Vec<Vec3> = (0..4)
        .flat_map(|quarter| {
            steps.map(|(a, b): (f32, f32)| {
                let (a, b) = match quarter {
                    0 => (a, b),
                    1 => (-b, a),
                    2 => (-a, -b),
                    _ => (b, -a),
                };
                (ahead * a + side * b).normalize()
            })
        })
        .collect();
    let triangles = WatertightTriangle::all(mesh.triangles());
    let bvh = FlatBvh::build(&triangles, &BvhParams { traversal: Traversal::FrontToBack, ..BvhParams::default() });
    let hit = |ray: Ray| bvh.intersect(&ray, &mut NoCounters).map(|h| h.t);
    let top = c + up * (0.5 * up.dot(e).abs() + eye);
    let (span_ahead, span_side) = (ahead.dot(e).abs(), side.dot(e).abs());
    let mut best: Option<(f32, Vec3, Vec3)> = None;
    for i in 0..STREET_GRID {
        for j in 0..STREET_GRID {
            let at = |k: u32| 0.6 * ((k as f32 + 0.5) / STREET_GRID as f32 - 0.5);
            let from = top + ahead * (at(i) * span_ahead) + side * (at(j) * span_side);
            let Some(t) = hit(Ray::new(from, -up)) else { continue };
            let ground = from - up * t;
            let below = Ray { t_min: 1e-4 * ground.abs().max_element().max(1.0), ..Ray::new(ground, -up) };
            if hit(below).is_some() {
                continue; // a roof, or the top of a closed model
            }
            let position = ground + up * eye;
            let sights: Vec<Option<f32>> = directions.iter().map(|&d| hit(Ray::new(position, d))).collect();
            if sights.iter().flatten().any(|&t| t < 2.0 * eye) {
                continue; // against a wall
            }
            for (&d, &sight) in directions.iter().zip(&sights) {
                if let Some(t) = sight
                    && best.is_none_or(|(longest, _, _)| t > longest)
                {
                    best = Some((t, position, d));
                }
            }
        }
    }
    best.map(|(_, position, toward)| (position, toward))
}

/// Two horizontal unit axes for the unit axis `up`.
pub(super) fn horizontal(up: Vec3) -> (Vec3, Vec3) {
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
        let camera = view.camera(&mesh, up);
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
    use crate::geometry::Primitive;
    use crate::scene::{SceneKind, random_triangles, tessellate};

    #[test]
    fn the_overview_is_outside_the_model_and_the_light_is_above_it() {
        let mesh = random_triangles(200, 3);
        let b = mesh.bounds();
        for up in [Vec3::Y, Vec3::Z] {
            let s = MeshScene::new(mesh.clone(), View::Overview, up);
            assert!(!b.contains(s.camera.position), "overview is outside");
            assert!(up.dot(s.light) > up.dot(b.max), "the light is above");
        }
        assert_ne!(
            MeshScene::new(mesh.clone(), View::Overview, Vec3::Y).fingerprint(),
            MeshScene::new(mesh, View::Street, Vec3::Y).fingerprint()
        );
    }

    /// A city with `up` as its up axis: a ground square of side 100 at height 0 and 4 × 4 blocks (walls and roof,
    /// no floor, 8 to 20 high) of side 14 with streets of 11 between them; returns the mesh and the blocks' footprints
    /// in (ahead, side) coordinates.
    fn city(up: Vec3) -> (Mesh, Vec<[f32; 4]>) {
        let (ahead, side) = horizontal(up);
        let at = |a: f32, b: f32, h: f32| ahead * a + side * b + up * h;
        let mut mesh = Mesh::default();
        let mut quad = |corners: [Vec3; 4]| {
            let n = mesh.positions.len() as u32;
            mesh.positions.extend(corners);
            mesh.indices.extend([[n, n + 1, n + 2], [n, n + 2, n + 3]]);
        };
        quad([at(-50.0, -50.0, 0.0), at(50.0, -50.0, 0.0), at(50.0, 50.0, 0.0), at(-50.0, 50.0, 0.0)]);
        let mut blocks = vec![];
        for i in 0..4 {
            for j in 0..4 {
                let (a0, b0) = (-44.5 + 25.0 * i as f32, -44.5 + 25.0 * j as f32);
                let (a1, b1, h) = (a0 + 14.0, b0 + 14.0, 8.0 + ((i * 4 + j) % 5) as f32 * 3.0);
                let c = [(a0, b0), (a1, b0), (a1, b1), (a0, b1)];
                for k in 0..4 {
                    let ((pa, pb), (qa, qb)) = (c[k], c[(k + 1) % 4]);
                    quad([at(pa, pb, 0.0), at(qa, qb, 0.0), at(qa, qb, h), at(pa, pb, h)]);
                }
                quad(c.map(|(a, b)| at(a, b, h)));
                blocks.push([a0, a1, b0, b1]);
            }
        }
        (mesh, blocks)
    }

    #[test]
    fn the_street_view_stands_at_eye_height_in_a_street_and_looks_along_it() {
        for up in [Vec3::Y, Vec3::Z] {
            let (mesh, blocks) = city(up);
            let b = mesh.bounds();
            let cam = View::Street.camera(&mesh, up);
            let (ahead, side) = horizontal(up);
            let p = cam.position;
            assert!(b.contains(p), "inside the city's box: {p}");
            let eye = up.dot(p);
            assert!((eye - 0.002 * b.extent().length()).abs() < 1e-4, "at eye height above the ground: {eye}");
            let (a, s) = (ahead.dot(p), side.dot(p));
            let inside = |&[a0, a1, b0, b1]: &[f32; 4]| a > a0 && a < a1 && s > b0 && s < b1;
            assert!(!blocks.iter().any(inside), "in a street, not in a block: {p}");
            let toward = cam.look_at - p;
            assert!(toward.dot(up).abs() < 1e-3 * toward.length(), "looking level");
            let (rays, tris) = (cam.with_resolution(33, 33).rays(), WatertightTriangle::all(mesh.triangles()));
            let center = rays.ray(16, 16);
            let sight = tris.iter().filter_map(|t| t.intersect(&center, f32::INFINITY)).fold(f32::INFINITY, f32::min);
            assert!(sight.is_finite() && sight > 25.0, "down a street to a block or the ground's edge: {sight}");
        }
    }

    #[test]
    fn a_closed_model_is_seen_from_outside_at_its_floor() {
        let spheres = SceneKind::RandomSpheres.generate(5, 2).spheres;
        let mesh = tessellate(&spheres, 16);
        let b = mesh.bounds();
        for up in [Vec3::Y, Vec3::Z] {
            let cam = View::Street.camera(&mesh, up);
            assert!(!b.contains(cam.position), "outside: no open ground");
            assert!(up.dot(cam.position) < up.dot(b.center()), "low");
            assert_eq!(cam.look_at, b.center());
        }
    }
}
