//! `harness run` as a user runs it: bad configs refused before anything is written, the wide BVH's kernels, samples
//! of several series (`sample_ms`), a killed and resumed sweep, workers (`processes`), earlier runs kept, automatic
//! repetitions, claims, a missing Embree, and the quick paper and triangle-scene experiments end to end.

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use schema::{Named, PeerKind};
use tracer::accel::AccelKind;

use crate::common::{harness, names, stderr, temp};

/// Rows of a runs.csv as (config_id, repetition).
fn recorded(runs: &Path) -> Vec<(String, u32)> {
    let text = std::fs::read_to_string(runs).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[1].to_string(), f[3].parse().unwrap())
        })
        .collect()
}

/// The cells of `column` in a runs.csv, row by row (for columns without commas in their values).
fn column(runs: &Path, column: &str) -> Vec<String> {
    let text = std::fs::read_to_string(runs).unwrap();
    let mut lines = text.lines();
    let i = lines.next().unwrap().split(',').position(|h| h == column).unwrap();
    lines.map(|l| l.split(',').nth(i).unwrap().to_string()).collect()
}

/// Keeps the header and the first `rows` rows of a runs.csv (as if the sweep had been killed there).
fn keep_rows(runs: &Path, rows: usize) {
    let text = std::fs::read_to_string(runs).unwrap();
    let kept: Vec<&str> = text.lines().take(rows + 1).collect();
    std::fs::write(runs, kept.join("\n") + "\n").unwrap();
}

#[test]
fn bad_configs_exit_2_with_one_line_and_write_nothing() {
    let dir = temp("bad");
    std::fs::write(dir.join("present.csv"), "0,0,0,1\n").unwrap();
    let cases: &[(&str, &str, &str)] = &[
        ("unknown top key", "name = \"t\"\nfoo = 1\n[sweep]\n", "foo: unknown key (allowed: name,"),
        (
            "unknown sweep key",
            "name = \"t\"\n[sweep]\nobects = [1]\n",
            "sweep.obects: unknown key (allowed: scene, objects,",
        ),
        (
            "wrong type",
            "name = \"t\"\nrepetitions = \"five\"\n[sweep]\n",
            "repetitions: expected an integer in 1..=1000 or \"auto\", found \"five\"",
        ),
        (
            "auto key without auto",
            "name = \"t\"\nrepetitions = 5\nmin_repetitions = 3\n[sweep]\n",
            "min_repetitions: applies only with repetitions = \"auto\" (allowed there: min_repetitions, max_repetitions, target_ci_width)",
        ),
        (
            "auto max below min",
            "name = \"t\"\nrepetitions = \"auto\"\nmin_repetitions = 6\nmax_repetitions = 4\n[sweep]\n",
            "max_repetitions: 4 is below min_repetitions 6 (allowed: 6..=1000)",
        ),
        (
            "auto target out of range",
            "name = \"t\"\n[sweep]\n[quick]\nrepetitions = \"auto\"\ntarget_ci_width = 3\n",
            "quick.target_ci_width: 3 is out of range (allowed: 0.0001..=1)",
        ),
        (
            "empty sweep",
            "name = \"t\"\n[sweep]\nobjects = []\n",
            "sweep.objects: empty list (give at least one value; allowed: integers",
        ),
        (
            "unknown accelerator",
            "name = \"t\"\n[sweep]\naccel = [\"bvh\", \"bhv\"]\n",
            "sweep.accel[1]: unknown value \"bhv\" (allowed: list, bvh, flat-bvh, wide-bvh, obvhs-bvh2, obvhs-cwbvh, embree, embree-packets, tinybvh, null)",
        ),
        (
            "zero threads",
            "name = \"t\"\n[sweep]\nthreads = [0]\n",
            "sweep.threads[0]: 0 is out of range (allowed: integers 1..=4096 or all)",
        ),
        (
            "leaf size",
            "name = \"t\"\n[sweep]\nleaf_size = 17\n",
            "sweep.leaf_size[0]: 17 is out of range (allowed: integers 1..=16)",
        ),
        (
            "wide node width",
            "name = \"t\"\n[sweep]\naccel = \"wide-bvh\"\nnode_width = [4, 6]\n",
            "sweep.node_width[1]: 6 is not allowed (allowed: 4, 8)",
        ),
        (
            "wide kernel name",
            "name = \"t\"\n[sweep]\naccel = \"wide-bvh\"\nsimd_kernel = \"sse\"\n",
            "sweep.simd_kernel[0]: unknown value \"sse\" (allowed: auto, scalar, avx2, avx512)",
        ),
        ("missing sweep", "name = \"t\"\n", "missing [sweep] table"),
        (
            "unreadable sphere file",
            "name = \"t\"\n[sweep]\nscene = \"sphere-file\"\nsphere_file = \"absent.csv\"\n",
            "sweep.sphere_file: ",
        ),
        (
            "bad sphere file",
            "name = \"t\"\n[sweep]\nscene = \"sphere-file\"\nsphere_file = \"bad.csv\"\n",
            "bad.csv: line 1, column 4 (r): expected a positive number",
        ),
        (
            "unknown reference",
            "name = \"t\"\nreference = \"nope\"\n[sweep]\n[[series]]\nlabel = \"a\"\n",
            "reference: unknown series \"nope\" (allowed: a)",
        ),
        (
            "bad speedup metric",
            "name = \"t\"\nspeedup_metric = \"speed\"\n[sweep]\n",
            "speedup_metric: unknown metric \"speed\" (allowed: setup_s, scene_s,",
        ),
        (
            "bad plot metric",
            "name = \"t\"\n[sweep]\n[[plot]]\nfile = \"f\"\ny = \"speed\"\n",
            "plot[0].y: unknown metric \"speed\" (allowed: setup_s, scene_s, build_s, trace_s, overhead_s, encode_s, total_s,",
        ),
        (
            "trade-off plot against a setting",
            "name = \"t\"\n[sweep]\n[[plot]]\nfile = \"f\"\nkind = \"trade-off\"\nx = \"objects\"\n",
            "plot[0].x: unknown metric \"objects\" (allowed: setup_s, scene_s, build_s,",
        ),
        (
            "bad plot kind",
            "name = \"t\"\n[sweep]\n[[plot]]\nfile = \"f\"\nkind = \"scatter\"\n",
            "plot[0].kind: unknown value \"scatter\" (allowed: metric, speedup, efficiency, trade-off)",
        ),
        (
            "bad order",
            "name = \"t\"\norder = \"random\"\n[sweep]\n",
            "order: unknown value \"random\" (allowed: interleaved, sequential, shuffled)",
        ),
        ("invalid toml", "name = \"t\n", "line 1: invalid TOML"),
        (
            "bad mesh name",
            "name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = \"bunnny\"\nworkload = \"primary\"\n",
            "mesh: unknown data set \"bunnny\" (allowed: bunny,",
        ),
        (
            "missing mesh file",
            "name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = \"absent.obj\"\nworkload = \"primary\"\n",
            "-bad/absent.obj: no such mesh file (allowed: a data set name or an .obj/.ply path)",
        ),
        (
            // Refused at load for every backend alike (tinybvh used to stop mid-sweep on it).
            "mesh with a non-finite vertex",
            "name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = \"nan.obj\"\naccel = [\"flat-bvh\", \"tinybvh\"]\n",
            "-bad/nan.obj: vertex 1 is not finite (NaN, 0, 0) (allowed: finite x, y, z)",
        ),
        (
            "mesh scene without a mesh",
            "name = \"t\"\n[sweep]\nscene = \"mesh\"\nworkload = \"primary\"\n",
            "mesh: missing (scene \"mesh\" needs a data set name or an .obj/.ply path)",
        ),
        (
            "bad triangle test",
            "name = \"t\"\n[sweep]\nscene = \"tessellated-spheres\"\ntriangle_test = \"moller\"\n",
            "sweep.triangle_test[0]: unknown value \"moller\" (allowed: moller-trumbore, watertight)",
        ),
        (
            "bad view",
            "name = \"t\"\n[sweep]\nscene = \"random-triangles\"\nview = \"top\"\n",
            "sweep.view[0]: unknown value \"top\" (allowed: overview, street)",
        ),
        (
            "bad tinybvh layout",
            "name = \"t\"\n[sweep]\naccel = \"tinybvh\"\ntinybvh_layout = \"bvh2\"\n",
            "sweep.tinybvh_layout[0]: unknown value \"bvh2\" (allowed: bvh, bvh4-cpu, bvh8-cpu)",
        ),
    ];
    std::fs::write(dir.join("bad.csv"), "0,0,0,-1\n").unwrap();
    std::fs::write(dir.join("nan.obj"), "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    for (what, text, expected) in cases {
        let cfg = dir.join("bad.toml");
        std::fs::write(&cfg, text).unwrap();
        let out_dir = dir.join("out");
        for args in [
            vec!["run", cfg.to_str().unwrap(), "--out", out_dir.to_str().unwrap()],
            vec!["validate", cfg.to_str().unwrap()],
        ] {
            let o = harness().args(&args).output().unwrap();
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{what}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{what}: one line: {err}");
            assert!(err.contains("bad.toml"), "{what}: names the file: {err}");
            assert!(err.contains(expected), "{what}: expected {expected:?} in {err}");
            assert!(!out_dir.exists(), "{what}: nothing written");
        }
    }
    // A data set that is not fetched: one line naming the fetch command, nothing written.
    let cfg = dir.join("unfetched.toml");
    std::fs::write(&cfg, "name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = \"teapot\"\nworkload = \"primary\"\n")
        .unwrap();
    let out_dir = dir.join("out");
    let o = harness()
        .env("BVHLAB_DATA", dir.join("empty-cache"))
        .args(["run", cfg.to_str().unwrap(), "--out", out_dir.to_str().unwrap()])
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!((o.status.code(), err.trim_end().lines().count()), (Some(2), 1), "{err}");
    assert!(err.contains("unfetched.toml: mesh: ") && err.contains("harness fetch teapot"), "{err}");
    assert!(!out_dir.exists(), "nothing written");
    let o = harness().args(["run", dir.join("missing.toml").to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.toml: cannot read"), "{}", stderr(&o));
    let o = harness().args(["run", "--shard", "3/2", "x.toml"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "clap errors exit 2 too");
}

/// A mesh without a triangle (an empty OBJ, a PLY of zero faces) is refused like other bad input by `run`,
/// `validate` and `render`: one line naming the file, exit 2, nothing written. A mesh with degenerate triangles
/// runs, and its load summary counts them.
#[test]
fn a_mesh_without_triangles_is_refused_and_degenerate_ones_are_counted() {
    let dir = temp("empty-mesh");
    std::fs::write(dir.join("empty.obj"), "").unwrap();
    let no_faces = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    std::fs::write(dir.join("no-faces.ply"), no_faces).unwrap();
    let out_dir = dir.join("out");
    for mesh in ["empty.obj", "no-faces.ply"] {
        let path = dir.join(mesh);
        let cfg = dir.join("empty.toml");
        let text =
            format!("name = \"t\"\n[sweep]\nscene = \"mesh\"\nmesh = \"{}\"\nworkload = \"primary\"\n", path.display());
        std::fs::write(&cfg, text).unwrap();
        let png = dir.join("out.png");
        let set_mesh = format!("mesh={}", path.display());
        for args in [
            vec!["run", cfg.to_str().unwrap(), "--out", out_dir.to_str().unwrap()],
            vec!["validate", cfg.to_str().unwrap()],
            vec!["render", "--set", "scene=mesh", "--set", &set_mesh, "--out", png.to_str().unwrap()],
        ] {
            let o = harness().args(&args).output().unwrap();
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{mesh} {}: {err}", args[0]);
            assert_eq!(err.trim_end().lines().count(), 1, "{mesh} {}: one line: {err}", args[0]);
            let line = format!("{}: no triangles (allowed: a mesh of at least one triangle", path.display());
            assert!(err.contains(&line), "{mesh} {}: expected {line:?} in {err}", args[0]);
            assert!(!out_dir.exists() && !png.exists(), "{mesh} {}: nothing written", args[0]);
        }
    }
    // Two triangles, one of zero area (its corners on a line): counted where the mesh's load is summarized.
    let obj = dir.join("degenerate.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n").unwrap();
    let cfg = dir.join("degenerate.toml");
    let text = format!(
        "name = \"t\"\nrepetitions = 1\n[sweep]\nscene = \"mesh\"\nmesh = \"{}\"\nworkload = \"primary\"\n\
         width = 8\nheight = 8\n",
        obj.display()
    );
    std::fs::write(&cfg, text).unwrap();
    let summary = format!("{}: 2 triangles (1 degenerate), fingerprint ", obj.display());
    let o = harness().args(["validate", cfg.to_str().unwrap()]).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains(&format!("mesh           {summary}")), "{out}");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains(&format!("mesh {summary}")), "{}", stderr(&o));
    let o = harness()
        .args(["render", "--set", "scene=mesh", "--set", &format!("mesh={}", obj.display())])
        .args(["--set", "width=8", "--set", "height=8", "--out", dir.join("d.png").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("scene        2 triangles (1 degenerate), fingerprint"));
}

/// The wide BVH through a whole run: validated exact against brute force, with the kernel that ran recorded
/// (`scalar` when asked, `auto` as the best this CPU has); a kernel this CPU lacks is refused before anything runs.
#[test]
fn wide_bvh_runs_validated_and_records_its_kernel() {
    use tracer::accel::wide::Kernel;
    let dir = temp("wide");
    let cfg = dir.join("wide.toml");
    let text = "name = \"w\"\nsample_ms = 0\nprocesses = 1\nrepetitions = 1\nwarmups = 0\n[sweep]\nobjects = 300\nwidth = 40\nheight = 30\n\
                strategy = \"serial\"\nworkload = [\"primary\", \"shadow\"]\naccel = \"wide-bvh\"\nnode_width = [4, 8]\n\
                simd_kernel = [\"scalar\", \"auto\"]\nchild_order = \"octant\"\nleaf_block = 4\n";
    std::fs::write(&cfg, text).unwrap();
    let out = dir.join("out");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = schema::row::read_rows(&std::fs::read_to_string(out.join("runs.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 2 * 2 * 2, "2 workloads x 2 widths x 2 kernels");
    for r in &rows {
        assert_eq!((r.validation, r.validated_against.as_str()), (schema::ValidationStatus::Exact, "list"), "{r:?}");
        let want = if r.simd_kernel == Some(Kernel::Scalar) { Kernel::Scalar } else { Kernel::Auto.resolve_for(4) };
        assert_eq!(r.simd_kernel_used, want.name(), "{:?}", r.simd_kernel);
        assert_eq!(r.child_order.map(|o| o.name()), Some("octant"));
    }
    // Every kernel answers alike: the same answer hash and counters for both kernels of one width and workload.
    for a in &rows {
        for b in rows.iter().filter(|b| b.node_width == a.node_width && b.workload == a.workload) {
            assert_eq!(
                (&a.image_hash, a.nodes_per_ray, a.prim_tests_per_ray),
                (&b.image_hash, b.nodes_per_ray, b.prim_tests_per_ray)
            );
        }
    }

    // A kernel this CPU lacks is skipped with a note (a config runs on every machine kind); where it has every
    // kernel, nothing is skipped.
    let cfg = dir.join("avx512.toml");
    std::fs::write(&cfg, text.replace("[\"scalar\", \"auto\"]", "[\"auto\", \"avx512\"]")).unwrap();
    let out = dir.join("out512");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let kernels = column(&out.join("runs.csv"), "simd_kernel");
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    if Kernel::Avx512.is_available() {
        assert!(kernels.iter().any(|k| k == "avx512"), "{kernels:?}");
        assert!(!report.contains("so they were skipped"), "{report}");
    } else {
        assert!(kernels.iter().all(|k| k == "auto"), "{kernels:?}");
        let note = "simd_kernel avx512: this CPU lacks it";
        assert!(report.contains("cannot run here, so they were skipped") && report.contains(note), "{report}");
        let o = harness().args(["validate", cfg.to_str().unwrap()]).output().unwrap();
        assert!(String::from_utf8_lossy(&o.stdout).contains(note));
    }
}

#[test]
fn a_packet_not_allowed_or_the_old_packet_size_is_one_line_exit_2_and_nothing_written() {
    let dir = temp("packet");
    let cfg = dir.join("packet.toml");
    let (wide, embree) = (AccelKind::WideBvh.name(), PeerKind::EmbreePackets.name());
    let base = "name = \"t\"\n[sweep]\nworkload = \"primary\"\n";
    let cases = [
        (
            format!("{base}accel = \"{wide}\"\npacket = \"masked-4\"\n"),
            "packet.toml: sweep.packet[0]: unknown value \"masked-4\" (allowed: single, masked-8, masked-16, tile-8x8)",
        ),
        // Refused while reading the config, before Embree is looked for, so this holds with or without it.
        (
            format!("{base}[[series]]\nlabel = \"e\"\naccel = \"{embree}\"\nembree_packet = [8, 1]\n"),
            "packet.toml: series[0].embree_packet[1]: 1 is not allowed (allowed: 8, 16)",
        ),
        (
            format!("{base}[[series]]\nlabel = \"w\"\naccel = \"{wide}\"\npacket_size = 64\n"),
            "packet.toml: series[0].packet_size: replaced by packet (allowed: single, masked-8, masked-16, tile-8x8) \
             and embree_packet (allowed: 8, 16)",
        ),
    ];
    let out = dir.join("out");
    for (text, expected) in cases {
        std::fs::write(&cfg, text).unwrap();
        for args in [
            vec!["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()],
            vec!["validate", cfg.to_str().unwrap()],
        ] {
            let o = harness().args(&args).output().unwrap();
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{err}");
            assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
            assert!(err.contains(expected), "expected {expected:?} in {err}");
            assert!(!out.exists(), "nothing written");
        }
    }
}

#[test]
fn with_sample_ms_the_series_of_one_point_are_sampled_together() {
    let dir = temp("together");
    let cfg = dir.join("together.toml");
    let text = |order: &str| {
        format!(
            "name = \"together\"\nprocesses = 1\nrepetitions = 2\nwarmups = 1\nsample_ms = 5\norder = \"{order}\"\n[sweep]\n\
             objects = [300, 400]\nwidth = 32\nheight = 24\nworkload = \"primary\"\n\
             [[series]]\nlabel = \"a\"\n[[series]]\nlabel = \"b\"\n"
        )
    };
    for (order, configs) in [("interleaved", "2"), ("sequential", "1")] {
        std::fs::write(&cfg, text(order)).unwrap();
        let out = dir.join(order);
        let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let text = std::fs::read_to_string(out.join("runs.csv")).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let rows: Vec<Vec<&str>> = text.lines().skip(1).map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), 8, "2 series x 2 object counts x 2 repetitions");
        let passes = |row: &Vec<&str>| row[column("trace_passes")].parse::<u32>().unwrap();
        for row in &rows {
            assert_eq!(row[column("sample_configs")], configs, "{order}: {row:?}");
            assert!(passes(row) >= 1, "{order}: {row:?}");
        }
        // A pass of 768 rays over a few hundred spheres takes well under a millisecond: 5 ms take several.
        assert!(rows.iter().any(|row| passes(row) > 1), "{order}: samples of several passes");
    }
}

#[test]
fn a_killed_sweep_resumes_without_losing_or_duplicating_rows() {
    let (list, ..) = names();
    let dir = temp("resume");
    let cfg = dir.join("resume.toml");
    // 3 object counts x 2 seeds x 4 repetitions = 24 rows of a few tens of milliseconds each.
    std::fs::write(&cfg, format!("name = \"resume\"\nsample_ms = 0\nprocesses = 1\nrepetitions = 4\nwarmups = 1\n[sweep]\naccel = \"{list}\"\nobjects = [400, 500, 600]\nseed = [1, 2]\nwidth = 96\nheight = 64\n")).unwrap();
    let out = dir.join("out");
    let runs = out.join("runs.csv");
    let mut child = harness()
        .args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while std::fs::read_to_string(&runs).map_or(0, |t| t.lines().count()) < 4
        && start.elapsed() < Duration::from_secs(120)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = recorded(&runs);
    assert!(before.len() >= 3, "rows were flushed as runs finished");
    assert!(before.len() < 24, "the kill came before the end ({} rows); make the runs longer", before.len());

    let o =
        harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let after = recorded(&runs);
    assert_eq!(after.len(), 24, "no row lost");
    assert_eq!(after.iter().collect::<HashSet<_>>().len(), 24, "no row duplicated");
    assert_eq!(after[..before.len()], before[..], "earlier rows kept as they were");
    assert!(out.join("REPORT.md").exists());

    // Resuming a complete sweep runs nothing more.
    let o =
        harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]).output().unwrap();
    assert!(o.status.success());
    assert_eq!(recorded(&runs).len(), 24);

    // Resuming rows timed on other pages is refused (`huge_pages` is not part of a point's key), and nothing is
    // written.
    let mut rows = schema::row::read_rows(&std::fs::read_to_string(&runs).unwrap()).unwrap();
    rows.iter_mut().for_each(|row| row.huge_pages = "always".into());
    let on_huge_pages =
        schema::row::header() + "\n" + &rows.iter().map(|row| schema::row::csv_line(row).unwrap()).collect::<String>();
    std::fs::write(&runs, &on_huge_pages).unwrap();
    let o =
        harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("huge_pages") && stderr(&o).lines().count() == 1, "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&runs).unwrap(), on_huge_pages, "nothing written");

    // Resuming with another config is refused.
    std::fs::write(&cfg, "name = \"resume\"\nrepetitions = 5\n[sweep]\nobjects = [400]\n").unwrap();
    let o =
        harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// With `processes = 3` each configuration's six runs fall into three blocks of two, each timed in a worker of its
/// own: every row names the process that timed it, runs 0–1, 2–3 and 4–5 share one each, no two configurations
/// share one.
#[test]
fn with_processes_each_configuration_is_timed_in_blocks_by_workers_of_its_own() {
    let dir = temp("processes");
    let cfg = dir.join("processes.toml");
    std::fs::write(
        &cfg,
        "name = \"processes\"\nwarmups = 0\nsample_ms = 0\nrepetitions = 6\nprocesses = 3\n[sweep]\nobjects = [10, 20]\nwidth = 32\nheight = 16\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let runs = out.join("runs.csv");
    let (configs, reps, ids) = (column(&runs, "config_id"), column(&runs, "repetition"), column(&runs, "process_id"));
    assert_eq!(ids.len(), 12);
    let mut by_config: HashMap<&str, HashMap<u32, &str>> = HashMap::new();
    for ((config, rep), id) in configs.iter().zip(&reps).zip(&ids) {
        assert_ne!(id, "0", "a timed row names its process");
        assert_ne!(id.parse::<u32>().unwrap(), std::process::id());
        by_config.entry(config).or_default().insert(rep.parse().unwrap(), id);
    }
    assert_eq!(by_config.len(), 2);
    let mut all = HashSet::new();
    for turns in by_config.values() {
        for r in [0, 2, 4] {
            assert_eq!(turns[&r], turns[&(r + 1)], "runs {r} and {} in one process: {turns:?}", r + 1);
        }
        let own: HashSet<&str> = (0..6).map(|r| turns[&r]).collect();
        assert_eq!(own.len(), 3, "three processes: {turns:?}");
        all.extend(own);
    }
    assert_eq!(all.len(), 6, "no process shared between configurations");
}

/// The series of a point sampled together (`sample_ms`, interleaved) with `processes`: each round starts a fresh worker
/// per series (their warm-ups side by side), and every timed row comes from a process of its own that took turns.
#[test]
fn with_processes_the_series_of_a_round_start_their_workers_together() {
    let dir = temp("processes-series");
    let cfg = dir.join("series.toml");
    std::fs::write(
        &cfg,
        "name = \"series\"\nwarmups = 0\nrepetitions = 3\nprocesses = 3\nsample_ms = 5\n[sweep]\nobjects = 10\nwidth = 32\nheight = 16\n\
         [[series]]\nlabel = \"a\"\n[[series]]\nlabel = \"b\"\naccel = \"bvh\"\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let runs = out.join("runs.csv");
    let (ids, takers) = (column(&runs, "process_id"), column(&runs, "sample_configs"));
    assert_eq!(ids.len(), 6);
    assert!(takers.iter().all(|n| n == "2"), "both series take turns in every round: {takers:?}");
    assert_eq!(ids.iter().collect::<HashSet<_>>().len(), 6, "one process per series and round: {ids:?}");
}

/// Runs into a folder that holds rows never lose them: each earlier run moves into `previous/` (older ones into
/// `previous-1`, …), `check` compares against it out of the box, `--force` replaces, `--resume --force` is refused.
#[test]
fn runs_into_one_folder_keep_every_earlier_run() {
    let dir = temp("keep");
    let cfg = dir.join("keep.toml");
    std::fs::write(&cfg, "name = \"keep\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 2\n[sweep]\nobjects = [10, 20]\nwidth = 32\nheight = 16\n")
        .unwrap();
    let out = dir.join("out");
    let run = || harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    let timestamps = |runs: &Path| column(runs, "timestamp");
    let o = run();
    assert!(o.status.success(), "{}", stderr(&o));
    let first = timestamps(&out.join("runs.csv"));
    assert_eq!(first.len(), 4);
    let o = run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("moved to"), "says where the earlier rows went: {}", stderr(&o));
    assert_eq!(timestamps(&out.join("previous/runs.csv")), first, "the first run's rows kept whole");
    assert!(out.join("previous/REPORT.md").is_file() && out.join("previous/experiment.toml").is_file());
    let second = timestamps(&out.join("runs.csv"));
    assert_eq!(second.len(), 4);
    let o = run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(timestamps(&out.join("previous-1/runs.csv")), first, "the oldest run moved on to previous-1");
    assert_eq!(timestamps(&out.join("previous/runs.csv")), second);
    assert!(!out.join("previous/previous").exists(), "earlier runs are not nested");

    let o = harness()
        .args([
            "check",
            out.to_str().unwrap(),
            "--baseline",
            out.join("previous").to_str().unwrap(),
            "--timings-for-information",
        ])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "check against previous/: {}{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(&o)
    );

    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--force"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("previous-2").exists(), "--force replaces without moving aside");
    let before = std::fs::read_to_string(out.join("runs.csv")).unwrap();
    let o = harness()
        .args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap(), "--resume", "--force"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(stderr(&o).lines().count(), 1, "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(out.join("runs.csv")).unwrap(), before, "nothing written");
}

#[test]
fn auto_repetitions_stop_when_the_interval_is_narrow_and_at_the_maximum_otherwise() {
    let (_, flat, ..) = names();
    let dir = temp("auto");
    let cfg = dir.join("auto.toml");
    let run = |extra: &str, resume: bool| {
        let text = format!(
            "name = \"auto\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = \"auto\"\nmin_repetitions = 6\nmax_repetitions = 8\n{extra}\n[sweep]\n\
             accel = \"{flat}\"\nobjects = [50, 60]\nwidth = 32\nheight = 24\nworkload = \"primary\"\n"
        );
        std::fs::write(&cfg, text).unwrap();
        let out = dir.join("out");
        let mut args = vec!["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()];
        if resume {
            args.push("--resume");
        }
        let o = harness().args(&args).output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };

    // A counter is the same in every repetition: its interval has width 0 from the second on, so every
    // configuration stops at the minimum.
    let out = run("speedup_metric = \"nodes_per_ray\"", false);
    let runs = out.join("runs.csv");
    assert_eq!(recorded(&runs).len(), 2 * 6, "2 configurations x min_repetitions");
    assert!(column(&runs, "repetition_rule").iter().all(|r| r == "auto 6..8 width 0.02 nodes_per_ray"));
    assert_eq!(column(&runs, "interval_width"), [vec![""; 2], vec!["0.0"; 10]].concat());
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(report.contains("2 of 2 configurations got there, 0 stopped at 8"), "{report}");
    // Killed after its first row: the resumed sweep records the rest and no more.
    keep_rows(&runs, 1);
    run("speedup_metric = \"nodes_per_ray\"", true);
    assert_eq!(recorded(&runs).len(), 12);

    // A target no timing meets: every configuration runs to the maximum, and a resumed sweep counts the rows it
    // already has.
    let out = run("target_ci_width = 0.0001", false);
    let runs = out.join("runs.csv");
    assert_eq!(recorded(&runs).len(), 2 * 8, "2 configurations x max_repetitions");
    let widths = column(&runs, "interval_width");
    assert!(widths[10..].iter().all(|w| w.parse::<f64>().unwrap() > 0.0001), "{widths:?}");
    keep_rows(&runs, 5);
    let before = recorded(&runs);
    run("target_ci_width = 0.0001", true);
    let after = recorded(&runs);
    assert_eq!(after.len(), 16, "no row lost or added: {after:?}");
    assert_eq!(after[..5], before[..]);
    assert_eq!(after.iter().collect::<HashSet<_>>().len(), 16, "no row duplicated");
}

#[test]
fn quick_paper_experiment_end_to_end() {
    let dir = temp("paper");
    let out = dir.join("paper");
    let o =
        harness().args(["run", "experiments/paper.toml", "--quick", "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = recorded(&out.join("runs.csv"));
    assert_eq!(rows.len(), 6 * 4 * 3, "6 series x 4 object counts x 1 seed x 3 repetitions");
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    for must in ["time-vs-objects", "speedup-vs-objects", "flat BVH is within 10%", "serial·list"] {
        assert!(report.contains(must), "REPORT.md lacks {must:?}");
    }
    for f in
        ["runs.parquet", "summary.csv", "summary.parquet", "figures/time-vs-objects.svg", "figures/time-vs-objects.png"]
    {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Every row's image hash is the same for every series at the same scene: all structures and strategies agree.
    let text = std::fs::read_to_string(out.join("runs.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let mut by_scene = std::collections::HashMap::new();
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        let prev = by_scene
            .entry((f[col("objects")].to_string(), f[col("seed")].to_string()))
            .or_insert(f[col("image_hash")].to_string());
        assert_eq!(*prev, f[col("image_hash")], "all series render the same image");
    }
    // The report can be rebuilt from the rows alone.
    std::fs::remove_file(out.join("REPORT.md")).unwrap();
    let o = harness().args(["report", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("REPORT.md").exists());
}

#[test]
fn check_claims_exits_1_when_a_claim_fails() {
    let (list, flat, ..) = names();
    let dir = temp("claims");
    let cfg = dir.join("claims.toml");
    std::fs::write(
        &cfg,
        format!("name = \"claims\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 6\n[sweep]\nobjects = 300\nwidth = 48\nheight = 32\nworkload = \"primary\"\n\
         [[series]]\nlabel = \"brute\"\naccel = \"{list}\"\n[[series]]\nlabel = \"tree\"\naccel = \"{flat}\"\n\
         [[claim]]\ntext = \"the list is 1000x faster than the BVH\"\nkind = \"faster\"\nseries = \"brute\"\nthan = \"tree\"\nfactor = 1000\n"),
    )
    .unwrap();
    let out = dir.join("out");
    let run = |extra: &[&str]| {
        harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).args(extra).output().unwrap()
    };
    let o = run(&[]);
    assert!(o.status.success(), "without --check-claims a failed claim is reported, not fatal: {}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("claim FAILS"));
    let o = run(&["--check-claims"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

#[test]
fn a_claim_at_all_cores_keeps_its_serial_side() {
    let dir = temp("claim-serial");
    let cfg = dir.join("threads.toml");
    std::fs::write(
        &cfg,
        "name = \"t\"\nwarmups = 0\nsample_ms = 0\nprocesses = 1\nrepetitions = 6\n[sweep]\nobjects = 200\nwidth = 48\nheight = 32\nworkload = \"primary\"\n\
         threads = [1, 2]\n[[series]]\nlabel = \"serial\"\nstrategy = \"serial\"\n[[series]]\nlabel = \"rayon\"\n\
         strategy = \"rayon-bands\"\n[[claim]]\ntext = \"rayon on all cores is not 100x slower\"\nkind = \"faster\"\n\
         series = \"rayon\"\nthan = \"serial\"\nfactor = 0.01\nwhere = { threads = \"all\" }\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = harness().args(["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(printed.contains("claim holds") && printed.contains("rayon on all cores"), "{printed}");
}

#[test]
fn a_missing_embree_is_reported_skipped_or_refused() {
    let (_, flat, embree, _) = names();
    let dir = temp("noembree");
    let cfg = dir.join("peers.toml");
    std::fs::write(
        &cfg,
        format!(
            "name = \"noembree\"\nrepetitions = 1\nwarmups = 0\nsample_ms = 0\nprocesses = 1\n[sweep]\nobjects = 100\nwidth = 32\nheight = 24\nworkload = \"primary\"\n\
         [[series]]\nlabel = \"ours\"\naccel = \"{flat}\"\n[[series]]\nlabel = \"embree\"\naccel = \"{embree}\"\n"
        ),
    )
    .unwrap();
    let without =
        |args: &[&str]| harness().env("EMBREE_LIB", dir.join("no-such-libembree4.so")).args(args).output().unwrap();
    let o = without(&["list"]);
    let listed = String::from_utf8_lossy(&o.stdout);
    assert!(
        listed.contains("embree, embree-packets: unavailable") && listed.contains("pip install embreex==4.4.0.post1"),
        "{listed}"
    );
    let out = dir.join("out");
    let o = without(&["run", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = recorded(&out.join("runs.csv"));
    assert_eq!(rows.len(), 1, "only the flat BVH ran");
    let report = std::fs::read_to_string(out.join("REPORT.md")).unwrap();
    assert!(
        report.contains("These series cannot run here, so they were skipped: embree. Embree 4 not found"),
        "{report}"
    );
    let refused = dir.join("refused");
    let o = without(&["run", cfg.to_str().unwrap(), "--out", refused.to_str().unwrap(), "--require-all"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(stderr(&o).trim_end().lines().count(), 1);
    assert!(stderr(&o).contains("peers.toml: accel embree: Embree 4 not found") && !refused.exists());
}

/// `experiments/triangle-scenes.toml --quick`: procedural triangle scenes, every backend this machine has (Embree's
/// single rays and packets, obvhs, tinybvh, ours with both triangle tests), every ray kind, each validated exact.
#[test]
fn quick_triangle_scenes_experiment_validates_every_configuration() {
    let dir = temp("meshes");
    let out = dir.join("out");
    let o = harness()
        .args(["run", "--quick", "experiments/triangle-scenes.toml", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let rows = schema::row::read_rows(&std::fs::read_to_string(out.join("runs.csv")).unwrap()).unwrap();
    assert!(rows.len() >= 2 * 2 * 4 * 5, "{}", rows.len());
    for r in &rows {
        assert_eq!((r.validation, r.mismatches), (schema::ValidationStatus::Exact, 0), "{r:?}");
        assert!(r.scene.is_triangles() && r.rays > 0, "{r:?}");
    }
    let scenes: std::collections::HashSet<_> = rows.iter().map(|r| r.scene_fingerprint.clone()).collect();
    assert_eq!(scenes.len(), 2, "one fingerprint per scene");
}
