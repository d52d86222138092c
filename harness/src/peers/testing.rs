//! Test helpers for the peers: the Embree device, and brute force over triangle meshes. The test scenes, ray
//! mixes and agreement check against brute force for spheres are the tracer's own, shared with its tests:
//! `tracer::testing` (the `testing` feature); meshes use the same check, [`tracer::agreement::check`].

use std::io::Write;

use tracer::Vec3;
use tracer::accel::{Accelerator, Hit};
use tracer::agreement::{Answer, BruteForce64, ExactPrimitive, Outcome, Strictness, check, t_tolerance};
use tracer::counters::NoCounters;
use tracer::geometry::{Aabb, Ray, Triangle, TriangleTest};
use tracer::render::PrimaryHits;
use tracer::rng::SplitMix64;
use tracer::scene::mesh::Mesh;
use tracer::scene::{SceneKind, random_triangles, tessellate};
use tracer::testing::{Comparison, sphere_ray_mix};

use super::embree::{EmbreeConfig, EmbreeDevice, EmbreeLibrary};

/// The Embree device for a test, or `None` (after saying so) when Embree is missing and not required.
/// With `BVHLAB_REQUIRE_EMBREE=1` a missing Embree fails the test.
pub fn embree_device(test: &str) -> Option<EmbreeDevice> {
    let required = std::env::var("BVHLAB_REQUIRE_EMBREE").is_ok_and(|v| v == "1");
    match EmbreeLibrary::shared() {
        Ok(_) => Some(
            EmbreeDevice::new(&EmbreeConfig { threads: Some(2), ..EmbreeConfig::default() }).expect("Embree device"),
        ),
        Err(e) if required => panic!("{test}: BVHLAB_REQUIRE_EMBREE=1 but {e}"),
        Err(e) => {
            // Straight to stderr, past libtest's output capture, so the skip is always visible.
            let _ = writeln!(std::io::stderr(), "{test}: skipped: {e}");
            None
        }
    }
}

/// A triangle mesh with its ray mix, named for failure messages.
#[derive(Clone, Debug)]
pub struct TestMesh {
    /// What the mesh is, e.g. `"tessellated 40 spheres ×8"`.
    pub label: String,
    /// The mesh.
    pub mesh: Mesh,
    /// [`mesh_ray_mix`] of it (plus the spheres' [`sphere_ray_mix`] for tessellated spheres).
    pub rays: Vec<Ray>,
}

/// The procedural test meshes: random spheres tessellated coarsely and finely (closed meshes: shared edges and
/// vertices), random triangles (3000, seed 5), one triangle and an empty mesh, each with its rays.
pub fn test_meshes() -> Vec<TestMesh> {
    let tessellated = |n: usize, segments: u32, seed: u64| {
        let spheres = SceneKind::RandomSpheres.generate(n, seed).spheres;
        let mesh = tessellate(&spheres, segments);
        let mut rays = mesh_ray_mix(&mesh, seed ^ 0x5eed, 2_100);
        rays.extend(sphere_ray_mix(&spheres, seed ^ 0xface, 700));
        TestMesh { label: format!("tessellated {n} spheres ×{segments} seed={seed}"), mesh, rays }
    };
    let plain = |label: &str, mesh: Mesh, count: usize| {
        let rays = mesh_ray_mix(&mesh, 11, count);
        TestMesh { label: label.to_owned(), mesh, rays }
    };
    // Tilted, so that its box has volume and random points lie off its plane.
    let one = Mesh {
        positions: vec![Vec3::new(-1.0, -1.0, 0.3), Vec3::new(1.0, -0.8, -0.2), Vec3::new(0.1, 1.0, 0.5)],
        indices: vec![[0, 1, 2]],
    };
    vec![
        tessellated(40, 8, 3),
        tessellated(6, 32, 4),
        plain("random triangles n=3000 seed=5", random_triangles(3_000, 5), 2_800),
        plain("one triangle", one, 700),
        plain("empty mesh", Mesh::default(), 70),
    ]
}

/// `count` rays at `mesh`, cycling through seven families (ray `i` is of family `i % 7`); points are drawn from
/// the mesh's box grown by half its extent per side:
///
/// 0. random lines through the box;
/// 1. from a random point through a random vertex (shared by several triangles in a closed mesh);
/// 2. from a random point through a random point of a random edge;
/// 3. from a random point through a random interior point of a random triangle;
/// 4. finite segments between two random points (`t_max` is the segment's length);
/// 5. non-unit directions through an interior point, 0.1 to 3 times the distance long;
/// 6. leaving a surface like a bounce: from an interior point moved off the plane by `1e-4` of its magnitude,
///    in a random direction.
///
/// With no triangles every ray is a random line around the origin.
pub fn mesh_ray_mix(mesh: &Mesh, seed: u64, count: usize) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    let bounds = if mesh.positions.is_empty() { Aabb { min: -Vec3::ONE, max: Vec3::ONE } } else { mesh.bounds() };
    let (lo, hi) = (bounds.min - bounds.extent() * 0.5, bounds.max + bounds.extent() * 0.5);
    let unit = |rng: &mut SplitMix64| loop {
        let v = Vec3::new(rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32, rng.range(-1.0, 1.0) as f32);
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    };
    let point = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(lo.x as f64, hi.x as f64) as f32,
            rng.range(lo.y as f64, hi.y as f64) as f32,
            rng.range(lo.z as f64, hi.z as f64) as f32,
        )
    };
    let interior = |rng: &mut SplitMix64, t: &Triangle| {
        let (mut b1, mut b2) = (rng.next_f64() as f32, rng.next_f64() as f32);
        if b1 + b2 > 1.0 {
            (b1, b2) = (1.0 - b1, 1.0 - b2);
        }
        t.p[0] + (t.p[1] - t.p[0]) * b1 + (t.p[2] - t.p[0]) * b2
    };
    let n = mesh.triangle_count() as u64;
    (0..count)
        .map(|i| {
            let family = if n == 0 { 0 } else { i % 7 };
            let tri = if n == 0 {
                Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)
            } else {
                mesh.triangle(rng.below(n) as usize)
            };
            let through = |rng: &mut SplitMix64, aim: Vec3| {
                let origin = point(rng);
                Ray::new(origin, (aim - origin).normalize_or(Vec3::X))
            };
            match family {
                0 => Ray::new(point(&mut rng), unit(&mut rng)),
                1 => {
                    let aim = tri.p[rng.below(3) as usize];
                    through(&mut rng, aim)
                }
                2 => {
                    let e = rng.below(3) as usize;
                    let aim = tri.p[e].lerp(tri.p[(e + 1) % 3], rng.next_f64() as f32);
                    through(&mut rng, aim)
                }
                3 => {
                    let aim = interior(&mut rng, &tri);
                    through(&mut rng, aim)
                }
                4 => {
                    let (a, b) = (point(&mut rng), point(&mut rng));
                    let length = (b - a).length().max(1e-3);
                    Ray::segment(a, (b - a) / length, length)
                }
                5 => {
                    let aim = interior(&mut rng, &tri);
                    let origin = point(&mut rng);
                    Ray::new(origin, (aim - origin) * rng.range(0.1, 3.0) as f32)
                }
                _ => {
                    let p = interior(&mut rng, &tri);
                    let normal = (tri.p[1] - tri.p[0]).cross(tri.p[2] - tri.p[0]).normalize_or(Vec3::Y);
                    let side = if rng.below(2) == 0 { 1.0 } else { -1.0 };
                    let n = normal * side;
                    let origin = p + n * (1e-4 * p.abs().max_element().max(1.0));
                    Ray::new(origin, (n + unit(&mut rng)).normalize_or(n))
                }
            }
        })
        .collect()
}

/// f32 brute force's answers (the watertight test) to a ray set over a mesh's triangles, compared with an
/// accelerator's by [`tracer::agreement::check`] under [`Strictness::Arbitrated`], f64 brute force arbitrating.
#[derive(Clone, Debug)]
pub struct TriangleReference<'a> {
    triangles: Vec<Triangle>,
    rays: &'a [Ray],
    closest: Vec<Option<Hit>>,
    occluded: Vec<bool>,
    brute: BruteForce64<Triangle>,
}

impl<'a> TriangleReference<'a> {
    /// Traces `rays` through every triangle of `mesh` with the watertight test.
    pub fn new(mesh: &Mesh, rays: &'a [Ray]) -> Self {
        let triangles: Vec<Triangle> = mesh.triangles().collect();
        let closest: Vec<Option<Hit>> = rays
            .iter()
            .map(|ray| {
                let hits = triangles.iter().enumerate().filter_map(|(prim, t)| {
                    t.intersect(TriangleTest::Watertight, ray, ray.t_max).map(|h| Hit { t: h.t, prim: prim as u32 })
                });
                hits.min_by(|a, b| a.t.total_cmp(&b.t))
            })
            .collect();
        let occluded = closest.iter().map(Option::is_some).collect();
        let brute = BruteForce64::new(&triangles);
        Self { triangles, rays, closest, occluded, brute }
    }

    /// Starts comparing answers to these rays; `what` names the backend in the failure message.
    pub fn compare(&self, what: &str) -> TriangleComparison<'_, 'a> {
        TriangleComparison { reference: self, what: what.to_owned(), answers: 0, ties: Vec::new(), bad: Vec::new() }
    }

    /// Panics unless `accel` answers every ray acceptably (closest hit and occlusion, one ray at a time and as
    /// one batch); returns the tally of the single-ray answers.
    #[track_caller]
    pub fn assert_agrees<A: Accelerator>(&self, what: &str, accel: &A) -> Tally {
        let mut single = self.compare(what);
        for (i, ray) in self.rays.iter().enumerate() {
            single.closest(i, accel.intersect(ray, &mut NoCounters));
            single.occluded(i, accel.occluded(ray, &mut NoCounters));
        }
        let tally = single.finish();
        let mut batch = self.compare(&format!("{what} (batch)"));
        let mut hits = vec![PrimaryHits::MISS; self.rays.len()];
        accel.intersect_batch(self.rays, &mut hits, &mut NoCounters);
        let mut occluded = vec![false; self.rays.len()];
        accel.occluded_batch(self.rays, &mut occluded, &mut NoCounters);
        for (i, (hit, occluded)) in hits.into_iter().zip(occluded).enumerate() {
            batch.check(i, Answer::closest(hit));
            batch.occluded(i, occluded);
        }
        batch.finish();
        tally
    }
}

/// What a finished comparison counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Answers compared.
    pub answers: usize,
    /// Disagreements f64 tolerated (edge ties).
    pub ties: usize,
}

/// Answers being compared with a [`TriangleReference`], one at a time; [`TriangleComparison::finish`] fails if
/// any is wrong. Besides [`tracer::agreement::check`], a hit must name a triangle f64 allows at its `t`.
#[must_use = "call `finish` to fail on disagreements"]
#[derive(Debug)]
pub struct TriangleComparison<'r, 'a> {
    reference: &'r TriangleReference<'a>,
    what: String,
    answers: usize,
    ties: Vec<String>,
    bad: Vec<String>,
}

impl TriangleComparison<'_, '_> {
    /// Compares `got` with brute force's closest hit of ray `i`.
    pub fn closest(&mut self, i: usize, got: Option<Hit>) {
        self.check(i, Answer::Closest(got));
    }

    /// Compares `got` with brute force's occlusion of ray `i`.
    pub fn occluded(&mut self, i: usize, got: bool) {
        self.check(i, Answer::Occluded(got));
    }

    fn check(&mut self, i: usize, got: Answer) {
        let (reference, ray) = (self.reference, &self.reference.rays[i]);
        self.answers += 1;
        let want = match got {
            Answer::Closest(_) => Answer::Closest(reference.closest[i]),
            Answer::Occluded(_) => Answer::Occluded(reference.occluded[i]),
        };
        let text = format!("ray {i} {ray:?}: {got:?} vs brute force {want:?}");
        match check(&reference.brute, ray, &want, &got, Strictness::Arbitrated) {
            Outcome::Agree => {}
            Outcome::Tolerated(why) => self.ties.push(format!("{text} ({why:?})")),
            Outcome::Mismatch(side) => self.bad.push(format!("{text} (wrong: {side:?})")),
        }
        if let Answer::Closest(Some(hit)) = got {
            let named = reference.triangles.get(hit.prim as usize).map(|t| t.exact(ray).outcomes);
            if !named.is_some_and(|o| o.may_report(hit.t as f64, t_tolerance(ray, hit.t) as f64)) {
                self.bad.push(format!("{text} (triangle {} cannot be hit at t = {})", hit.prim, hit.t));
            }
        }
    }

    /// Prints the tolerated disagreements and panics with the others (the first 8 shown), if any.
    #[track_caller]
    pub fn finish(self) -> Tally {
        let Self { what, answers, ties, bad, reference } = self;
        if !ties.is_empty() {
            eprintln!("{what}: {} edge tie(s) f64 tolerates:\n  {}", ties.len(), ties.join("\n  "));
        }
        assert!(
            bad.is_empty(),
            "{what}: {} wrong answer(s) over {} rays (Arbitrated):\n{}",
            bad.len(),
            reference.rays.len(),
            bad[..bad.len().min(8)].join("\n")
        );
        Tally { answers, ties: ties.len() }
    }
}

/// A comparison packet answers are fed to, lane by lane: the tracer's for spheres, [`TriangleComparison`] for
/// meshes.
pub trait ClosestComparison {
    /// Compares the closest hit `got` of ray `i`.
    fn closest(&mut self, i: usize, got: Option<Hit>);
    /// Fails on disagreements.
    fn finish(self);
}

impl ClosestComparison for Comparison<'_, '_> {
    fn closest(&mut self, i: usize, got: Option<Hit>) {
        Comparison::closest(self, i, got);
    }
    #[track_caller]
    fn finish(self) {
        Comparison::finish(self);
    }
}

impl ClosestComparison for TriangleComparison<'_, '_> {
    fn closest(&mut self, i: usize, got: Option<Hit>) {
        TriangleComparison::closest(self, i, got);
    }
    #[track_caller]
    fn finish(self) {
        TriangleComparison::finish(self);
    }
}
