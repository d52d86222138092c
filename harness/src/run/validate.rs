//! Validation before timing, planned → validated or rejected: a configuration's scene made, its ray sets taken from
//! the [`RayBank`], one counted pass ([`counted`]), and its answers judged against the reference's
//! ([`super::reference`]); what it found is counted into its rows. Validation passes (`exact`) when no answer
//! mismatches.

use std::sync::Arc;

use schema::{ValidationStatus, WrongSide};
use tracer::counters::WorkCounters;
use tracer::rays::RaySet;

use super::rays::RayBank;
use super::reference::Judgement;
use super::scenes::make_scene;
use super::trial::counted;
use crate::error::Error;
use crate::plan::{Configuration, Plan};

/// What validating one configuration found: the counted pass's counters and output hash, and the judgement of its
/// answers against the reference's (no reference and no judgement for a backend that gives no answers).
#[derive(Clone, Debug)]
pub struct Findings {
    pub status: ValidationStatus,
    pub counters: WorkCounters,
    pub output_hash: u64,
    pub reference: &'static str,
    /// Mismatches, tolerated disagreements by kind, the reference's own check and whose answers were wrong.
    pub judged: Judgement,
    pub rays: usize,
    /// The scene's primitives (spheres or triangles) as traced.
    pub primitives: u64,
}

/// A planned configuration after validation: cleared for timing, or rejected (recorded once, never timed).
#[derive(Clone, Debug)]
pub enum Validation {
    /// Its answers agree with the reference's (`exact`), or its backend gives none to check (`unchecked`); `rays` is
    /// the ray set its timed runs trace (`None` for the render workload).
    Validated { findings: Findings, rays: Option<Arc<RaySet>> },
    /// Its answers disagree with the reference's beyond f64 brute force's tolerance.
    Rejected(Findings),
}

impl Findings {
    /// Why a configuration (`what`) was rejected, in one line.
    pub fn failure(&self, what: &str) -> String {
        format!(
            "VALIDATION FAILED: {what}: {} of {} rays disagree with {} beyond f64 brute force's tolerance ({} grazing, \
             {} ties, {} leaks tolerated); f64 shows the {} answers wrong; this configuration is not timed",
            self.judged.mismatches,
            self.rays,
            self.reference,
            self.judged.grazing,
            self.judged.ties,
            self.judged.leaks,
            match self.judged.wrong_side {
                WrongSide::Both => "backend's and the reference's",
                WrongSide::Reference => "reference's",
                WrongSide::Backend | WrongSide::Neither => "backend's",
            }
        )
    }
}

/// Validates configuration `c` before its first timed run: its scene made once, one counted pass over its
/// workload (its counters and output hash), and its answers to its validation ray set judged against the
/// reference's (a backend that gives no answers is recorded `unchecked`). A validated configuration carries the
/// ray set its timed runs trace.
pub fn validate(plan: &Plan, c: &Configuration, bank: &mut RayBank) -> Result<Validation, Error> {
    let (settings, file) = (&c.settings, plan.scene_file());
    let scene = make_scene(settings, file);
    let (rays, reference) = bank.validation(settings, file, &scene);
    let answer_rays = reference.as_ref().map(|r| &*r.set);
    let (counters, output_hash, answers) = counted(settings, &scene, rays.as_deref(), answer_rays)?;
    let Some((reference, answers)) = reference.zip(answers) else {
        let (judged, status) = (Judgement::default(), ValidationStatus::Unchecked);
        let primitives = scene.primitives() as u64;
        let findings = Findings { status, counters, output_hash, reference: "-", judged, rays: 0, primitives };
        return Ok(Validation::Validated { findings, rays });
    };
    let judged = reference.judge(&answers);
    let exact = judged.mismatches == 0;
    let status = if exact { ValidationStatus::Exact } else { ValidationStatus::Failed };
    let (rays_judged, primitives) = (reference.set.rays.len(), scene.primitives() as u64);
    let findings =
        Findings { status, counters, output_hash, reference: reference.name, judged, rays: rays_judged, primitives };
    Ok(if exact { Validation::Validated { findings, rays } } else { Validation::Rejected(findings) })
}
