//! `report::check` on synthetic rows: seeded noise around fixed medians, deterministic counters.

use std::collections::BTreeMap;
use std::path::PathBuf;

use report::check::{self, CheckOptions, SpeedupVerdict};
use report::spec::ReportSpec;
use tracer::rng::SplitMix64;

const HEADER: &str = "experiment,config_id,series,repetition,scene,objects,seed,accel,split,leaf_size,sah_bins,traversal,strategy,threads,width,height,max_depth,workload,scene_s,build_s,trace_s,encode_s,total_s,rays,mrays_per_s,nodes_per_ray,box_tests_per_ray,prim_tests_per_ray,tree_nodes,tree_leaves,tree_depth,tree_bytes,sah_cost,image_hash,scene_fingerprint,git_commit,git_dirty,rustc,cpu_model,logical_cores,load_avg_1m,timestamp,harness_version";

/// (label, accel, split, leaf_size, sah_bins, traversal); "list" is the reference.
const SERIES: [(&str, &str, &str, u32, u32, &str); 3] = [
    ("list", "list", "-", 0, 0, "-"),
    ("bvh", "bvh", "sah", 4, 16, "front-to-back"),
    ("flat", "flat-bvh", "sah", 4, 16, "front-to-back"),
];
const OBJECTS: [u64; 2] = [100, 1000];
const SEEDS: [u64; 2] = [1, 2];
const REPETITIONS: u32 = 10;
/// Relative standard deviation of the timing noise.
const NOISE: f64 = 0.05;

/// What differs between generated runs.
struct Gen<'a> {
    experiment: &'a str,
    /// Seeds the timing noise.
    noise_seed: u64,
    /// `trace_s` of this series is multiplied by the factor.
    slowdown: Option<(&'a str, f64)>,
    /// `nodes_per_ray` of (series, objects, seed) is replaced.
    nodes_per_ray: Option<(&'a str, u64, u64, f64)>,
    /// Object counts generated.
    objects: &'a [u64],
}

impl Default for Gen<'_> {
    fn default() -> Self {
        Gen { experiment: "synthetic", noise_seed: 1, slowdown: None, nodes_per_ray: None, objects: &OBJECTS }
    }
}

fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xCBF2_9CE4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01B3))
}

/// The runs.csv text: 3 series × object counts × 2 seeds × 10 repetitions, all serial (threads 1).
fn runs_csv(g: &Gen) -> String {
    let mut rng = SplitMix64::new(g.noise_seed);
    let mut out = format!("{HEADER}\n");
    for (label, accel, split, leaf, bins, traversal) in SERIES {
        for &objects in g.objects {
            for seed in SEEDS {
                let id = format!("{:016x}", fnv(&format!("{label}|{objects}|{seed}")));
                let base = match accel {
                    "list" => objects as f64 * 1e-4,
                    "bvh" => (objects as f64).log2() * 1e-3,
                    _ => (objects as f64).log2() * 0.8e-3,
                };
                let factor = g.slowdown.filter(|(s, _)| *s == label).map_or(1.0, |(_, f)| f);
                let base_nodes = if accel == "list" { 0.0 } else { (objects as f64).log2() * 2.5 };
                let mut nodes = base_nodes;
                if let Some((s, o, sd, v)) = g.nodes_per_ray {
                    if (s, o, sd) == (label, objects, seed) {
                        nodes = v;
                    }
                }
                let tree_nodes = if accel == "list" { 0 } else { objects / 2 };
                for rep in 0..REPETITIONS {
                    let trace = base * factor * (1.0 + NOISE * rng.normal());
                    let build = if accel == "list" { 0.0 } else { objects as f64 * 1e-6 };
                    let rays = 3072;
                    out.push_str(&format!(
                        "{},{id},{label},{rep},random-spheres,{objects},{seed},{accel},{split},{leaf},{bins},{traversal},serial,1,64,48,0,primary,\
                         0.0,{build},{trace},0.0,{total},{rays},{mrays},{nodes},{boxes},{prims},{tree_nodes},{leaves},{depth},{bytes},{sah},\
                         {hash:016x},{fp:016x},0123456789012345678901234567890123456789,false,rustc 1.91.0 (f8297e351 2025-10-28),\"Test CPU, 2 cores\",2,0.5,2025-11-22T03:00:00Z,0.1.0\n",
                        g.experiment,
                        total = build + trace,
                        mrays = rays as f64 / trace / 1e6,
                        boxes = base_nodes * 2.0,
                        prims = if accel == "list" { objects as f64 } else { 3.5 },
                        leaves = tree_nodes / 2,
                        depth = if accel == "list" { 0 } else { 12 },
                        bytes = tree_nodes * 32,
                        sah = if accel == "list" { objects as f64 } else { 20.5 },
                        hash = fnv(&format!("{objects}|{seed}|image")),
                        fp = fnv(&format!("{objects}|{seed}|scene")),
                    ));
                }
            }
        }
    }
    out
}

/// A fresh directory under the system temp dir holding `runs` as runs.csv (none when `runs` is None).
fn run_dir(name: &str, runs: Option<&str>) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bvhlab-check-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(runs) = runs {
        std::fs::write(dir.join("runs.csv"), runs).unwrap();
    }
    dir
}

fn spec() -> ReportSpec {
    let fixed: Vec<String> =
        ["accel", "split", "leaf_size", "sah_bins", "traversal", "strategy", "threads"].map(String::from).to_vec();
    ReportSpec {
        name: "synthetic".into(),
        reference: Some("list".into()),
        series: SERIES.iter().map(|s| s.0.to_string()).collect(),
        series_fixed: SERIES.iter().map(|s| (s.0.to_string(), fixed.clone())).collect::<BTreeMap<_, _>>(),
        ..ReportSpec::default()
    }
}

/// Compares `new` (as the run) against `old` (as the baseline).
fn compare(name: &str, new: &Gen, old: &Gen, options: &CheckOptions) -> Result<check::CheckOutcome, report::Error> {
    let run = run_dir(&format!("{name}-run"), Some(&runs_csv(new)));
    let baseline = run_dir(&format!("{name}-baseline"), Some(&runs_csv(old)));
    let outcome = check::compare(&run, &baseline, &spec(), options);
    let _ = std::fs::remove_dir_all(run);
    let _ = std::fs::remove_dir_all(baseline);
    outcome
}

#[test]
fn injected_slowdown_is_flagged() {
    let old = Gen { noise_seed: 11, ..Gen::default() };
    let new = Gen { noise_seed: 12, slowdown: Some(("bvh", 1.3)), ..Gen::default() };
    let outcome = compare("slow", &new, &old, &CheckOptions::default()).unwrap();
    println!("{}", outcome.markdown());
    assert!(outcome.failed);
    assert!(outcome.counter_changes.is_empty() && outcome.missing.is_empty(), "{outcome:?}");
    assert_eq!(outcome.common, 12);
    // Two series besides the reference, two object counts each (seeds pooled).
    assert_eq!(outcome.speedups.len(), 4, "{:?}", outcome.speedups);
    for s in &outcome.speedups {
        assert!(s.gating, "{s:?}");
        assert!(s.point.starts_with("objects ") && s.point.contains("threads 1"), "{s:?}");
        assert!(s.lo <= s.ratio && s.ratio <= s.hi, "{s:?}");
        if s.series == "bvh" {
            assert_eq!(s.verdict, SpeedupVerdict::Regressed, "{s:?}");
            assert!((s.ratio - 1.0 / 1.3).abs() < 0.05, "{s:?}");
            assert!(s.hi < 1.0, "{s:?}");
        } else {
            assert_eq!(s.series, "flat");
            assert_eq!(s.verdict, SpeedupVerdict::Unchanged, "{s:?}");
        }
    }
    // The same regression outside the gate (threads 2 gate) is reported but does not fail.
    let options = CheckOptions { gate_threads: 2, ..CheckOptions::default() };
    let ungated = compare("slow-ungated", &new, &old, &options).unwrap();
    assert!(!ungated.failed, "{ungated:?}");
    assert!(ungated.speedups.iter().all(|s| !s.gating));
    assert_eq!(ungated.speedups.iter().filter(|s| s.verdict == SpeedupVerdict::Regressed).count(), 2);
    // A slowdown below the minimum effect is not a regression even when significant.
    let slight = Gen { noise_seed: 12, slowdown: Some(("bvh", 1.05)), ..Gen::default() };
    let small = compare("slight", &slight, &old, &CheckOptions::default()).unwrap();
    assert!(!small.failed, "{:?}", small.speedups);
    // A faster series is an improvement and passes.
    let faster = Gen { noise_seed: 12, slowdown: Some(("flat", 1.0 / 1.5)), ..Gen::default() };
    let improved = compare("faster", &faster, &old, &CheckOptions::default()).unwrap();
    assert!(!improved.failed);
    assert!(improved.speedups.iter().filter(|s| s.series == "flat").all(|s| s.verdict == SpeedupVerdict::Improved));
}

#[test]
fn same_distribution_is_rarely_flagged() {
    let trials = 100;
    let mut flagged = 0;
    let mut significant = 0;
    for t in 0..trials {
        let old = Gen { noise_seed: 1000 + 2 * t, ..Gen::default() };
        let new = Gen { noise_seed: 1001 + 2 * t, ..Gen::default() };
        let outcome = compare(&format!("null-{t}"), &new, &old, &CheckOptions::default()).unwrap();
        assert!(outcome.counter_changes.is_empty() && outcome.missing.is_empty());
        assert_eq!(outcome.speedups.len(), 4);
        flagged += outcome.failed as usize;
        significant += outcome.speedups.iter().any(|s| s.hi < 1.0 || s.lo > 1.0) as usize;
    }
    println!("false alarms: {flagged} of {trials} trials flagged; {significant} trials had some interval excluding 1");
    assert!(flagged <= 5, "{flagged} of {trials} same-distribution trials flagged");
}

#[test]
fn changed_counter_is_flagged_unless_accepted() {
    let old = Gen { noise_seed: 21, ..Gen::default() };
    let new = Gen { noise_seed: 22, nodes_per_ray: Some(("bvh", 1000, 2, 99.5)), ..Gen::default() };
    let outcome = compare("counter", &new, &old, &CheckOptions::default()).unwrap();
    assert!(outcome.failed);
    assert_eq!(outcome.counter_changes.len(), 1, "{:?}", outcome.counter_changes);
    let change = &outcome.counter_changes[0];
    assert_eq!((change.series.as_str(), change.column.as_str()), ("bvh", "nodes_per_ray"));
    assert_eq!(change.old.parse::<f64>().unwrap(), 1000f64.log2() * 2.5);
    assert_eq!(change.new, "99.5");
    assert_eq!(change.settings, "random-spheres objects 1000 seed 2");
    assert_eq!(change.config_id, format!("{:016x}", fnv("bvh|1000|2")));
    assert!(outcome.speedups.iter().all(|s| s.verdict != SpeedupVerdict::Regressed));
    let md = outcome.markdown();
    assert!(md.contains("FAIL") && md.contains("nodes_per_ray") && md.contains("→ 99.5"), "{md}");

    let accept = CheckOptions { accept_counter_changes: true, ..CheckOptions::default() };
    let accepted = compare("counter-accepted", &new, &old, &accept).unwrap();
    assert!(!accepted.failed);
    assert_eq!(accepted.counter_changes, outcome.counter_changes);
    assert!(accepted.markdown().contains("PASS"));

    // A configuration on one side only is listed and fails the check unless accepted.
    let fewer = Gen { noise_seed: 23, objects: &[100], ..Gen::default() };
    let partial = compare("missing", &fewer, &old, &CheckOptions::default()).unwrap();
    assert!(partial.failed);
    assert_eq!(partial.missing.len(), 6, "{:?}", partial.missing);
    assert!(partial.missing.iter().all(|m| m.starts_with("only in baseline") && m.contains("objects 1000")));
    assert_eq!(partial.speedups.len(), 2);
    assert!(!compare("missing-accepted", &fewer, &old, &accept).unwrap().failed);
}

#[test]
fn mismatches_are_one_line_errors_naming_the_file() {
    let old = Gen::default();
    let other = Gen { experiment: "other", ..Gen::default() };
    let err = compare("experiments", &other, &old, &CheckOptions::default()).unwrap_err().to_string();
    assert!(err.contains("experiments do not match: run is other, baseline is synthetic"), "{err}");
    assert!(err.contains("runs.csv") && !err.contains('\n'), "{err}");

    let big = Gen { objects: &[10_000], ..Gen::default() };
    let err = compare("disjoint", &big, &old, &CheckOptions::default()).unwrap_err().to_string();
    assert!(err.contains("no configuration in common") && err.contains("runs.csv") && !err.contains('\n'), "{err}");

    let empty = run_dir("no-runs", None);
    let baseline = run_dir("no-runs-baseline", Some(&runs_csv(&old)));
    for (run, base) in [(&empty, &baseline), (&baseline, &empty)] {
        let err = check::compare(run, base, &spec(), &CheckOptions::default()).unwrap_err().to_string();
        let missing = empty.join("runs.csv");
        assert!(err.contains(&missing.display().to_string()) && !err.contains('\n'), "{err}");
    }
    let _ = std::fs::remove_dir_all(empty);
    let _ = std::fs::remove_dir_all(baseline);
}

#[test]
fn without_reference_only_counters_are_compared() {
    let old = Gen { noise_seed: 31, ..Gen::default() };
    let new = Gen { noise_seed: 32, slowdown: Some(("bvh", 1.3)), ..Gen::default() };
    let run = run_dir("noref-run", Some(&runs_csv(&new)));
    let baseline = run_dir("noref-baseline", Some(&runs_csv(&old)));
    let spec = ReportSpec { reference: None, ..spec() };
    let outcome = check::compare(&run, &baseline, &spec, &CheckOptions::default()).unwrap();
    assert!(outcome.speedups.is_empty() && !outcome.failed, "{outcome:?}");
    assert!(outcome.markdown().contains("counters: all 12 configurations identical"));
    let _ = std::fs::remove_dir_all(run);
    let _ = std::fs::remove_dir_all(baseline);
}

#[test]
fn markdown_and_json_list_every_measure() {
    let old = Gen { noise_seed: 41, ..Gen::default() };
    let new = Gen {
        noise_seed: 42,
        slowdown: Some(("bvh", 1.3)),
        nodes_per_ray: Some(("flat", 100, 1, 7.25)),
        ..Gen::default()
    };
    let outcome = compare("output", &new, &old, &CheckOptions::default()).unwrap();
    let md = outcome.markdown();
    println!("{md}");
    assert!(md.contains("FAIL") && md.contains("**regressed**") && md.contains("bvh at objects"), "{md}");
    // Regressions come first in the speedup table.
    let rows: Vec<&str> = md.lines().filter(|l| l.contains("| objects ")).collect();
    assert_eq!(rows.len(), 4, "{md}");
    assert!(
        rows[0].starts_with("| bvh |") && rows[0].contains("**regressed**") && rows[0].ends_with("| yes |"),
        "{md}"
    );
    assert!(rows[1].starts_with("| bvh |") && rows[3].starts_with("| flat |") && rows[3].contains("unchanged"), "{md}");

    let json = outcome.to_json();
    println!("{json}");
    let value = Json::parse(&json).unwrap_or_else(|e| panic!("invalid JSON ({e}):\n{json}"));
    assert_eq!(value.get("failed"), Some(&Json::Bool(true)));
    let Some(Json::Array(speedups)) = value.get("speedups") else { panic!("{json}") };
    assert_eq!(speedups.len(), outcome.speedups.len());
    for (s, c) in speedups.iter().zip(&outcome.speedups) {
        for measure in ["old", "new", "ratio"] {
            let m = s.get(measure).unwrap_or_else(|| panic!("{measure} in {json}"));
            for key in ["value", "lower", "upper"] {
                assert!(matches!(m.get(key), Some(Json::Number(_))), "{measure}.{key} in {json}");
            }
        }
        assert_eq!(s.get("ratio").unwrap().get("lower"), Some(&Json::Number(c.lo)));
        assert_eq!(s.get("verdict"), Some(&Json::String(c.verdict.word().into())));
        assert_eq!(s.get("gating"), Some(&Json::Bool(c.gating)));
    }
    let Some(Json::Array(changes)) = value.get("counter_changes") else { panic!("{json}") };
    assert_eq!(changes.len(), 1);
    assert_eq!(changes[0].get("new"), Some(&Json::String("7.25".into())));
    assert_eq!(value.get("missing"), Some(&Json::Array(vec![])));
}

/// A minimal strict JSON parser, enough to check the document's structure.
#[derive(Debug, PartialEq)]
enum Json {
    Null,
    Bool(bool),
    Number(f64),
    String(String),
    Array(Vec<Json>),
    Object(Vec<(String, Json)>),
}

impl Json {
    fn parse(text: &str) -> Result<Json, String> {
        let mut p = Parser { s: text.as_bytes(), i: 0 };
        let v = p.value()?;
        p.ws();
        if p.i != p.s.len() {
            return Err(format!("trailing text at {}", p.i));
        }
        Ok(v)
    }

    fn get(&self, key: &str) -> Option<&Json> {
        match self {
            Json::Object(fields) => fields.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn ws(&mut self) {
        while self.i < self.s.len() && b" \t\r\n".contains(&self.s[self.i]) {
            self.i += 1;
        }
    }

    fn eat(&mut self, lit: &str) -> bool {
        let ok = self.s[self.i..].starts_with(lit.as_bytes());
        if ok {
            self.i += lit.len();
        }
        ok
    }

    fn value(&mut self) -> Result<Json, String> {
        self.ws();
        let at = self.i;
        match self.s.get(self.i) {
            Some(b'{') => {
                self.i += 1;
                let mut fields = Vec::new();
                self.ws();
                if self.eat("}") {
                    return Ok(Json::Object(fields));
                }
                loop {
                    self.ws();
                    let Json::String(key) = self.value()? else { return Err(format!("unquoted key at {at}")) };
                    self.ws();
                    if !self.eat(":") {
                        return Err(format!("expected : at {}", self.i));
                    }
                    fields.push((key, self.value()?));
                    self.ws();
                    if self.eat("}") {
                        return Ok(Json::Object(fields));
                    }
                    if !self.eat(",") {
                        return Err(format!("expected , or }} at {}", self.i));
                    }
                }
            }
            Some(b'[') => {
                self.i += 1;
                let mut items = Vec::new();
                self.ws();
                if self.eat("]") {
                    return Ok(Json::Array(items));
                }
                loop {
                    items.push(self.value()?);
                    self.ws();
                    if self.eat("]") {
                        return Ok(Json::Array(items));
                    }
                    if !self.eat(",") {
                        return Err(format!("expected , or ] at {}", self.i));
                    }
                }
            }
            Some(b'"') => {
                self.i += 1;
                let mut out = String::new();
                loop {
                    let rest = std::str::from_utf8(&self.s[self.i..]).map_err(|e| e.to_string())?;
                    let c = rest.chars().next().ok_or("unterminated string")?;
                    self.i += c.len_utf8();
                    match c {
                        '"' => return Ok(Json::String(out)),
                        '\\' => {
                            let e = *self.s.get(self.i).ok_or("bad escape")?;
                            self.i += 1;
                            match e {
                                b'"' => out.push('"'),
                                b'\\' => out.push('\\'),
                                b'/' => out.push('/'),
                                b'n' => out.push('\n'),
                                b'r' => out.push('\r'),
                                b't' => out.push('\t'),
                                b'b' => out.push('\u{8}'),
                                b'f' => out.push('\u{c}'),
                                b'u' => {
                                    let hex =
                                        std::str::from_utf8(&self.s[self.i..self.i + 4]).map_err(|e| e.to_string())?;
                                    let code = u32::from_str_radix(hex, 16).map_err(|e| e.to_string())?;
                                    out.push(char::from_u32(code).ok_or("bad \\u")?);
                                    self.i += 4;
                                }
                                _ => return Err(format!("bad escape at {}", self.i)),
                            }
                        }
                        c if (c as u32) < 0x20 => return Err(format!("control character in string at {}", self.i)),
                        c => out.push(c),
                    }
                }
            }
            Some(_) if self.eat("true") => Ok(Json::Bool(true)),
            Some(_) if self.eat("false") => Ok(Json::Bool(false)),
            Some(_) if self.eat("null") => Ok(Json::Null),
            Some(b'-' | b'0'..=b'9') => {
                while self.i < self.s.len() && b"+-0123456789.eE".contains(&self.s[self.i]) {
                    self.i += 1;
                }
                let text = std::str::from_utf8(&self.s[at..self.i]).unwrap();
                let leading_zero = text.trim_start_matches('-').starts_with('0')
                    && text.trim_start_matches('-').get(1..2).is_some_and(|d| d.chars().all(|c| c.is_ascii_digit()));
                if leading_zero || text.ends_with('.') {
                    return Err(format!("bad number {text}"));
                }
                text.parse().map(Json::Number).map_err(|_| format!("bad number {text}"))
            }
            _ => Err(format!("unexpected input at {at}")),
        }
    }
}
