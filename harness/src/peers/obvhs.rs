//! obvhs 0.4 as a peer: its BVH2 and compressed wide BVH8 (CWBVH), over our spheres or over a triangle mesh.
//!
//! Both trees are generic over the primitive their leaves test ([`ObvhsLeaf`]):
//! - [`Sphere`] (the default; `build`): obvhs builds from the spheres' boxes ([`Sphere::bounds`]) and the leaves
//!   call our own [`Sphere::intersect`], so hit distances are bit-identical to the tracer's;
//! - [`RtTriangle`] (`build_mesh`, e.g. `ObvhsBvh2<RtTriangle>`): obvhs's own triangle path, built by
//!   `build_*_from_tris` (which splits large triangles' boxes under the slow presets) and tested by obvhs's own
//!   ray-triangle test (`RtTriangle::intersect`, a Möller–Trumbore variant over precomputed edges and normal).
//!   obvhs's node boxes are not padded, so its traversal may cull a hit its triangle test reports right on an
//!   edge or vertex: an edge tie, which brute force tolerates.
//!
//! Primitives are stored in obvhs's primitive order, so leaves read them directly; `primitive_indices` maps a
//! hit back to the scene's sphere or triangle index.

use std::time::Duration;

use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb as ObvhsAabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
pub use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle as ObvhsTriangle;
use schema::ObvhsQuality;
use tracer::Vec3;
use tracer::accel::bvh::sah;
use tracer::accel::{Accelerator, Hit, TreeStats};
use tracer::counters::Counters;
use tracer::geometry::{Ray, Sphere};
use tracer::scene::mesh::Mesh;

/// A primitive obvhs's trees hold in their leaves: the ray test the leaves run.
pub trait ObvhsLeaf: Copy + Send + Sync {
    /// Distance of the hit of `ray` (as obvhs passes it, `r`: its `tmax` shrinks to the nearest hit so far), or
    /// infinity for a miss.
    fn hit(&self, ray: &Ray, r: &ObvhsRay) -> f32;
}

impl ObvhsLeaf for Sphere {
    /// Our own test on our ray, up to obvhs's current `tmax`.
    #[inline(always)]
    fn hit(&self, ray: &Ray, r: &ObvhsRay) -> f32 {
        self.intersect(ray, r.tmax).unwrap_or(f32::INFINITY)
    }
}

impl ObvhsLeaf for RtTriangle {
    /// obvhs's own test on obvhs's ray (hits with `t` in `[tmin, tmax]`; the traversal keeps those below `tmax`).
    #[inline(always)]
    fn hit(&self, _ray: &Ray, r: &ObvhsRay) -> f32 {
        self.intersect(r)
    }
}

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

/// A mesh's triangles as obvhs's triangles, in index order.
fn obvhs_triangles(mesh: &Mesh) -> Vec<ObvhsTriangle> {
    mesh.triangles().map(|t| ObvhsTriangle { v0: t.p[0].into(), v1: t.p[1].into(), v2: t.p[2].into() }).collect()
}

/// `source`'s primitives in obvhs's primitive order, as leaf primitives.
fn reordered<S: Copy, P>(source: &[S], primitive_indices: &[u32], leaf: impl Fn(S) -> P) -> Vec<P> {
    primitive_indices.iter().map(|&i| leaf(source[i as usize])).collect()
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

/// obvhs's binary BVH (PLOC build, reinsertion, leaf collapse) over spheres or [`RtTriangle`]s, traversed by
/// `Bvh2::ray_traverse`.
#[derive(Clone)]
pub struct ObvhsBvh2<P = Sphere> {
    bvh: Bvh2,
    /// Primitives in obvhs's primitive order.
    prims: Vec<P>,
}

impl<P> std::fmt::Debug for ObvhsBvh2<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ObvhsBvh2").field("nodes", &self.bvh.nodes.len()).field("prims", &self.prims.len()).finish()
    }
}

impl ObvhsBvh2 {
    /// Builds the tree over `spheres`' boxes with one of obvhs's presets (parallel where obvhs parallelizes).
    pub fn build(spheres: &[Sphere], quality: ObvhsQuality) -> Self {
        if spheres.is_empty() {
            return Self { bvh: Bvh2::default(), prims: Vec::new() };
        }
        let bvh = obvhs::bvh2::builder::build_bvh2(&boxes(spheres), preset(quality), &mut Duration::default());
        let prims = reordered(spheres, &bvh.primitive_indices, std::convert::identity);
        Self { bvh, prims }
    }
}

impl ObvhsBvh2<RtTriangle> {
    /// Builds the tree over `mesh`'s triangles with obvhs's triangle builder and one of its presets.
    pub fn build_mesh(mesh: &Mesh, quality: ObvhsQuality) -> Self {
        let triangles = obvhs_triangles(mesh);
        if triangles.is_empty() {
            return Self { bvh: Bvh2::default(), prims: Vec::new() };
        }
        let bvh = obvhs::bvh2::builder::build_bvh2_from_tris(&triangles, preset(quality), &mut Duration::default());
        let prims = reordered(&triangles, &bvh.primitive_indices, |t| RtTriangle::from(&t));
        Self { bvh, prims }
    }
}

impl<P: ObvhsLeaf> Accelerator for ObvhsBvh2<P> {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(obvhs_ray(ray), &mut hit, |r, id| {
            counters.prim_test();
            // `id` is a primitive slot of this tree: it indexes the reordered primitives directly.
            self.prims[id].hit(ray, r)
        });
        found.then(|| Hit { t: hit.t, prim: self.bvh.primitive_indices[hit.primitive_id as usize] })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        !self.bvh.ray_traverse_miss(obvhs_ray(ray), |r, id| {
            counters.prim_test();
            self.prims[id].hit(ray, r)
        })
    }

    /// Nodes, leaves, depth and SAH (the tracer's cost model) from a walk of the tree.
    fn stats(&self) -> TreeStats {
        let nodes = &self.bvh.nodes;
        let bytes = size_of_val(nodes.as_slice())
            + size_of_val(self.bvh.primitive_indices.as_slice())
            + size_of_val(self.prims.as_slice());
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

/// obvhs's compressed wide BVH8 (80-byte quantized nodes, up to 3 primitives a leaf) over spheres or
/// [`RtTriangle`]s, traversed by `CwBvh::ray_traverse`.
#[derive(Clone)]
pub struct ObvhsCwbvh<P = Sphere> {
    /// `None` for an empty scene (obvhs's traversal expects a root node).
    bvh: Option<CwBvh>,
    /// Primitives in obvhs's primitive order.
    prims: Vec<P>,
}

impl<P> std::fmt::Debug for ObvhsCwbvh<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let nodes = self.bvh.as_ref().map_or(0, |b| b.nodes.len());
        f.debug_struct("ObvhsCwbvh").field("nodes", &nodes).field("prims", &self.prims.len()).finish()
    }
}

impl ObvhsCwbvh {
    /// Builds the tree over `spheres`' boxes with one of obvhs's presets (parallel where obvhs parallelizes).
    pub fn build(spheres: &[Sphere], quality: ObvhsQuality) -> Self {
        if spheres.is_empty() {
            return Self { bvh: None, prims: Vec::new() };
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh(&boxes(spheres), preset(quality), &mut Duration::default());
        let prims = reordered(spheres, &bvh.primitive_indices, std::convert::identity);
        Self { bvh: Some(bvh), prims }
    }
}

impl ObvhsCwbvh<RtTriangle> {
    /// Builds the tree over `mesh`'s triangles with obvhs's triangle builder and one of its presets.
    pub fn build_mesh(mesh: &Mesh, quality: ObvhsQuality) -> Self {
        let triangles = obvhs_triangles(mesh);
        if triangles.is_empty() {
            return Self { bvh: None, prims: Vec::new() };
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&triangles, preset(quality), &mut Duration::default());
        let prims = reordered(&triangles, &bvh.primitive_indices, |t| RtTriangle::from(&t));
        Self { bvh: Some(bvh), prims }
    }
}

impl<P: ObvhsLeaf> Accelerator for ObvhsCwbvh<P> {
    #[inline]
    fn intersect<C: Counters>(&self, ray: &Ray, counters: &mut C) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(obvhs_ray(ray), &mut hit, |r, id| {
            counters.prim_test();
            self.prims[id].hit(ray, r)
        });
        found.then(|| Hit { t: hit.t, prim: bvh.primitive_indices[hit.primitive_id as usize] })
    }

    #[inline]
    fn occluded<C: Counters>(&self, ray: &Ray, counters: &mut C) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        !bvh.ray_traverse_miss(obvhs_ray(ray), |r, id| {
            counters.prim_test();
            self.prims[id].hit(ray, r)
        })
    }

    /// Wide nodes, leaves (child slots holding primitives) and depth; `sah_cost` is 0 (the binary cost model
    /// does not apply to 8-wide nodes).
    fn stats(&self) -> TreeStats {
        let Some(bvh) = &self.bvh else { return TreeStats { nodes: 0, leaves: 0, depth: 0, bytes: 0, sah_cost: 0.0 } };
        let bytes = size_of_val(bvh.nodes.as_slice())
            + size_of_val(bvh.primitive_indices.as_slice())
            + size_of_val(self.prims.as_slice());
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
    use tracer::counters::NoCounters;
    use tracer::testing::{Reference, TestMesh, scenes, test_meshes};

    use crate::peers::testing::triangle_reference;

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

    /// Every test mesh, built at three presets (the slowest splits triangle boxes): closest hit and occlusion
    /// agree with f64 brute force (edge ties tolerated and counted), hits name a triangle hit at that distance,
    /// and a hit's `t` is, bit for bit, obvhs's own `Triangle::intersect` of the triangle it names (the leaves run
    /// obvhs's test). Answers that differ from obvhs's test over every triangle (brute force) are counted: the
    /// traversal's box tests may cull a hit right on an edge or vertex (node boxes are not padded).
    fn triangles_agree_with_brute_force<A: Accelerator>(name: &str, build: impl Fn(&Mesh, ObvhsQuality) -> A) {
        let (mut answers, mut ties, mut culled) = (0, 0, 0);
        for TestMesh { label, mesh, rays } in test_meshes() {
            let reference = triangle_reference(&mesh, &rays);
            let triangles = obvhs_triangles(&mesh);
            let own: Vec<Option<f32>> = rays.iter().map(|ray| obvhs_closest(&triangles, ray)).collect();
            for quality in [ObvhsQuality::Fastest, ObvhsQuality::Medium, ObvhsQuality::VerySlow] {
                let what = format!("{name} triangles {} {label}", quality.name());
                let accel = build(&mesh, quality);
                let tally = reference.assert_agrees(&what, &accel, Strictness::Arbitrated);
                (answers, ties) = (answers + tally.answers, ties + tally.tolerated);
                for (i, (ray, own)) in rays.iter().zip(&own).enumerate() {
                    let hit = accel.intersect(ray, &mut NoCounters);
                    if let Some(h) = hit {
                        let t = triangles[h.prim as usize].intersect(&obvhs_ray(ray));
                        assert_eq!(h.t.to_bits(), t.to_bits(), "{what}: ray {i} {ray:?}: {h:?} vs obvhs's test {t}");
                    }
                    culled += (hit.map(|h| h.t.to_bits()) != own.map(f32::to_bits)) as usize;
                    culled += (accel.occluded(ray, &mut NoCounters) != own.is_some()) as usize;
                }
                if !mesh.indices.is_empty() {
                    let st = accel.stats();
                    assert!(st.nodes > 0 && st.leaves > 0 && st.bytes > mesh.indices.len() * 48, "{what}: {st:?}");
                }
            }
        }
        eprintln!("{name} triangles: {answers} answers, {ties} edge ties; {culled} differ from obvhs's brute force");
    }

    /// obvhs's own triangle test over every triangle: the closest `t` below `tmax` (what its traversal keeps).
    fn obvhs_closest(triangles: &[ObvhsTriangle], ray: &Ray) -> Option<f32> {
        let r = obvhs_ray(ray);
        let t = triangles.iter().map(|t| t.intersect(&r)).fold(f32::INFINITY, f32::min);
        (t < r.tmax).then_some(t)
    }

    #[test]
    fn triangle_bvh2_agrees_with_brute_force() {
        triangles_agree_with_brute_force(PeerKind::ObvhsBvh2.name(), ObvhsBvh2::build_mesh);
    }

    #[test]
    fn triangle_cwbvh_agrees_with_brute_force() {
        triangles_agree_with_brute_force(PeerKind::ObvhsCwbvh.name(), ObvhsCwbvh::build_mesh);
    }

    #[test]
    fn quality_names_are_the_serde_names() {
        for &q in ObvhsQuality::ALL {
            let toml = toml::to_string(&std::collections::BTreeMap::from([("quality", q)])).unwrap();
            assert_eq!(toml.trim(), format!("quality = \"{}\"", q.name()));
        }
    }
}
