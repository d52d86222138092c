//! obvhs 0.4 as a peer: its BVH2 and compressed wide BVH8 (CWBVH) built over our spheres' boxes.
//!
//! obvhs builds from boxes only ([`Sphere::bounds`]); leaves call our own [`Sphere::intersect`], so hit
//! distances are bit-identical to the tracer's. Spheres are stored in obvhs's primitive order, so leaves read
//! them directly; `primitive_indices` maps a hit back to the scene's sphere index.

use std::time::Duration;

use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb as ObvhsAabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use schema::ObvhsQuality;
use tracer::Vec3;
use tracer::accel::bvh::sah;
use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};

/// The build parameters of an obvhs preset (`BvhBuildParams::*_build()`; `pre_split` only applies to triangles).
pub fn preset(quality: ObvhsQuality) -> BvhBuildParams {
    match quality {
        ObvhsQuality::Fastest => BvhBuildParams::fastest_build(),
        ObvhsQuality::VeryFast => BvhBuildParams::very_fast_build(),
        ObvhsQuality::Fast => BvhBuildParams::fast_build(),
        ObvhsQuality::Medium => BvhBuildParams::medium_build(),
        ObvhsQuality::Slow => BvhBuildParams::slow_build(),
        ObvhsQuality::VerySlow => BvhBuildParams::very_slow_build(),
    }
}

/// The boxes obvhs builds over, one per sphere in scene order.
fn boxes(spheres: &[Sphere]) -> Vec<ObvhsAabb> {
    spheres
        .iter()
        .map(|s| {
            let b = s.bounds();
            ObvhsAabb::new(b.min.into(), b.max.into())
        })
        .collect()
}

/// Spheres in obvhs's primitive order.
fn reordered(spheres: &[Sphere], primitive_indices: &[u32]) -> Vec<Sphere> {
    primitive_indices.iter().map(|&i| spheres[i as usize]).collect()
}

/// Our ray in obvhs's form (obvhs computes its own guarded reciprocal direction).
///
/// `-0.0` direction components become `+0.0` (the same ray): obvhs 0.4 inverts `-0.0` to `-1/EPSILON` but its
/// CWBVH node test takes the octant from `direction < 0.0` (false for `-0.0`), and with the two signs disagreeing
/// every node test misses.
#[inline(always)]
fn obvhs_ray(ray: &Ray) -> ObvhsRay {
    ObvhsRay::new(ray.origin.into(), (ray.dir + Vec3::ZERO).into(), ray.t_min, ray.t_max)
}

/// Surface area of an obvhs box (0 for an empty or inverted one).
fn area(min: Vec3, max: Vec3) -> f64 {
    let e = (max - min).max(Vec3::ZERO);
    2.0 * (e.x as f64 * e.y as f64 + e.y as f64 * e.z as f64 + e.z as f64 * e.x as f64)
}

/// obvhs's binary BVH (PLOC build, reinsertion, leaf collapse), traversed by `Bvh2::ray_traverse`.
#[derive(Clone)]
pub struct ObvhsBvh2 {
    bvh: Bvh2,
    /// Spheres in obvhs's primitive order.
    spheres: Vec<Sphere>,
}

impl std::fmt::Debug for ObvhsBvh2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObvhsBvh2").field("nodes", &self.bvh.nodes.len()).field("spheres", &self.spheres.len()).finish()
    }
}

impl ObvhsBvh2 {
    /// Builds the tree with one of obvhs's presets (parallel where obvhs parallelizes).
    pub fn build(spheres: &[Sphere], quality: ObvhsQuality) -> Self {
        if spheres.is_empty() {
            return Self { bvh: Bvh2::default(), spheres: Vec::new() };
        }
        let mut build_time = Duration::ZERO;
        let bvh = obvhs::bvh2::builder::build_bvh2(&boxes(spheres), preset(quality), &mut build_time);
        let spheres = reordered(spheres, &bvh.primitive_indices);
        Self { bvh, spheres }
    }
}

impl Accelerator for ObvhsBvh2 {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(obvhs_ray(ray), &mut hit, |r, id| {
            counters.prim_test();
            // `id` is a primitive slot of this tree: it indexes the reordered spheres directly.
            self.spheres[id].intersect(ray, r.tmax).unwrap_or(f32::INFINITY)
        });
        found.then(|| Hit { t: hit.t, prim: self.bvh.primitive_indices[hit.primitive_id as usize] })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        !self.bvh.ray_traverse_miss(obvhs_ray(ray), |r, id| {
            counters.prim_test();
            self.spheres[id].intersect(ray, r.tmax).unwrap_or(f32::INFINITY)
        })
    }

    /// Nodes, leaves, depth and SAH (the tracer's cost model) from a walk of the tree.
    fn stats(&self) -> TreeStats {
        let nodes = &self.bvh.nodes;
        let bytes = size_of_val(nodes.as_slice())
            + size_of_val(self.bvh.primitive_indices.as_slice())
            + size_of_val(self.spheres.as_slice());
        let mut s = TreeStats { nodes: 0, leaves: 0, depth: 0, bytes, sah_cost: 0.0 };
        if nodes.is_empty() {
            return s;
        }
        let node_area = |n: &Bvh2Node| area(n.aabb.min.into(), n.aabb.max.into());
        let root_area = node_area(&nodes[0]);
        let root_area = if root_area > 0.0 { root_area } else { 1.0 };
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &nodes[i];
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            let a = node_area(n) / root_area;
            if n.is_leaf() {
                s.leaves += 1;
                s.sah_cost += sah::leaf_cost(n.prim_count as usize) as f64 * a;
            } else {
                s.sah_cost += sah::TRAVERSAL_COST as f64 * a;
                stack.push((n.first_index as usize, depth + 1));
                stack.push((n.first_index as usize + 1, depth + 1));
            }
        }
        s
    }
}

/// obvhs's compressed wide BVH8 (80-byte quantized nodes, up to 3 spheres a leaf), traversed by `CwBvh::ray_traverse`.
#[derive(Clone, Debug)]
pub struct ObvhsCwbvh {
    /// `None` for an empty scene (obvhs's traversal expects a root node).
    bvh: Option<CwBvh>,
    /// Spheres in obvhs's primitive order.
    spheres: Vec<Sphere>,
}

impl ObvhsCwbvh {
    /// Builds the tree with one of obvhs's presets (parallel where obvhs parallelizes).
    pub fn build(spheres: &[Sphere], quality: ObvhsQuality) -> Self {
        if spheres.is_empty() {
            return Self { bvh: None, spheres: Vec::new() };
        }
        let mut build_time = Duration::ZERO;
        let bvh = obvhs::cwbvh::builder::build_cwbvh(&boxes(spheres), preset(quality), &mut build_time);
        let spheres = reordered(spheres, &bvh.primitive_indices);
        Self { bvh: Some(bvh), spheres }
    }
}

impl Accelerator for ObvhsCwbvh {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(obvhs_ray(ray), &mut hit, |r, id| {
            counters.prim_test();
            self.spheres[id].intersect(ray, r.tmax).unwrap_or(f32::INFINITY)
        });
        found.then(|| Hit { t: hit.t, prim: bvh.primitive_indices[hit.primitive_id as usize] })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        !bvh.ray_traverse_miss(obvhs_ray(ray), |r, id| {
            counters.prim_test();
            self.spheres[id].intersect(ray, r.tmax).unwrap_or(f32::INFINITY)
        })
    }

    /// Wide nodes, leaves (child slots holding spheres) and depth; `sah_cost` is 0 (the binary cost model
    /// does not apply to 8-wide nodes).
    fn stats(&self) -> TreeStats {
        let Some(bvh) = &self.bvh else { return TreeStats { nodes: 0, leaves: 0, depth: 0, bytes: 0, sah_cost: 0.0 } };
        let bytes = size_of_val(bvh.nodes.as_slice())
            + size_of_val(bvh.primitive_indices.as_slice())
            + size_of_val(self.spheres.as_slice());
        let mut s = TreeStats { nodes: 0, leaves: 0, depth: 0, bytes, sah_cost: 0.0 };
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            let n: &CwBvhNode = &bvh.nodes[i];
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            for meta in n.child_meta {
                if meta == 0 {
                    continue;
                }
                let slot = (meta & 0b1_1111) as u32;
                if slot >= 24 {
                    // Inner child: its index is the base plus the inner children in lower slots.
                    let below = (n.imask as u32 & !(u32::MAX << (slot - 24))).count_ones();
                    stack.push((n.child_base_idx as usize + below as usize, depth + 1));
                } else {
                    s.leaves += 1;
                    s.depth = s.depth.max(depth + 1);
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use schema::{Named, PeerKind};
    use tracer::agreement::Strictness;
    use tracer::testing::{Reference, scenes};

    /// Every test scene, built at three presets: leaves call our own `Sphere::intersect`, so hit distances must
    /// be bit-identical to brute force's.
    fn agrees_with_brute_force<A: Accelerator>(name: &str, build: impl Fn(&[Sphere], ObvhsQuality) -> A) {
        for scene in scenes() {
            let reference = Reference::new(&scene.spheres, &scene.rays);
            for quality in [ObvhsQuality::Fastest, ObvhsQuality::Medium, ObvhsQuality::VerySlow] {
                let accel = build(&scene.spheres, quality);
                reference.assert_agrees(
                    &format!("{name} {} {}", quality.name(), scene.label),
                    &accel,
                    Strictness::Identical,
                );
            }
        }
    }

    #[test]
    fn bvh2_agrees_with_brute_force() {
        agrees_with_brute_force(PeerKind::ObvhsBvh2.name(), ObvhsBvh2::build);
    }

    #[test]
    fn cwbvh_agrees_with_brute_force() {
        agrees_with_brute_force(PeerKind::ObvhsCwbvh.name(), ObvhsCwbvh::build);
    }

    #[test]
    fn hits_map_back_to_scene_indices_and_stats_are_sane() {
        let spheres: Vec<Sphere> = tracer::scene::SceneKind::RandomSpheres.generate(500, 3).spheres;
        let bvh2 = ObvhsBvh2::build(&spheres, ObvhsQuality::Medium);
        let cw = ObvhsCwbvh::build(&spheres, ObvhsQuality::Medium);
        for (i, s) in spheres.iter().enumerate().step_by(7) {
            // A ray from outside straight at the center: the first sphere hit must be a real one at that t.
            let origin = s.center + Vec3::new(0.0, 0.0, 100.0);
            let ray = Ray::new(origin, (s.center - origin).normalize());
            for hit in [
                bvh2.intersect(&ray, &mut tracer::counters::NoCounters),
                cw.intersect(&ray, &mut tracer::counters::NoCounters),
            ] {
                let hit = hit.unwrap_or_else(|| panic!("ray at sphere {i} missed"));
                assert_eq!(spheres[hit.prim as usize].intersect(&ray, f32::INFINITY), Some(hit.t));
            }
        }
        for st in [bvh2.stats(), cw.stats()] {
            assert!(st.nodes > 0 && st.leaves > 0 && st.depth > 0 && st.bytes > spheres.len() * 16, "{st:?}");
        }
        assert!(bvh2.stats().sah_cost > 0.0);
    }

    #[test]
    fn quality_names_are_the_serde_names() {
        for &q in ObvhsQuality::ALL {
            let toml = toml::to_string(&std::collections::BTreeMap::from([("quality", q)])).unwrap();
            assert_eq!(toml.trim(), format!("quality = \"{}\"", q.name()));
        }
    }
}
