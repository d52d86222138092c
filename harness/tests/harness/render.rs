//! `harness render`: settings from the schema, the same image from every backend (of spheres and of triangles), and
//! bad settings refused with one line.

use std::collections::HashSet;
use std::path::Path;
use std::process::{Command, Output};

use crate::common::{harness, stderr, temp};

/// `render` takes every setting from the schema (`--set KEY=VALUE`, a config's defaults), through the run's backend
/// path (a peer renders the same image as our tree); a wrong key or value is one line, exit 2, nothing written.
#[test]
fn render_takes_schema_settings_and_refuses_bad_ones() {
    let dir = temp("render");
    let render = |sets: &[&str], out: &str| render_command(&[], sets, &dir.join(out)).output().unwrap();
    let hash = printed_hash;
    let base = ["objects=300", "width=48", "height=32"];
    let flat = render(&base, "flat.png");
    assert!(flat.status.success(), "{}", stderr(&flat));
    let out = String::from_utf8_lossy(&flat.stdout);
    assert!(out.contains("accel=flat-bvh") && out.contains("strategy=serial"), "schema defaults: {out}");
    let wide = render(&[&base[..], &["accel=wide-bvh", "node_width=4", "leaf_block=16"]].concat(), "wide.png");
    assert!(wide.status.success(), "{}", stderr(&wide));
    let obvhs = render(&[&base[..], &["accel=obvhs-bvh2"]].concat(), "obvhs.png");
    assert!(obvhs.status.success(), "{}", stderr(&obvhs));
    assert_eq!(hash(&flat), hash(&wide), "every backend renders the same image");
    assert_eq!(hash(&flat), hash(&obvhs));
    assert_eq!(hash(&flat).len(), 16);
    for (set, want) in [
        ("foo=1", "--set foo: unknown key (allowed: scene, objects,"),
        ("leaf_size=99", "--set leaf_size: 99 is out of range (allowed: integers 1..=16)"),
        ("accel=kd-tree", "--set accel: "),
        ("objects", "--set objects: expected KEY=VALUE"),
    ] {
        assert_refused(&render(&[set], "bad.png"), want, &dir.join("bad.png"), set);
    }
}

/// `render` draws triangle scenes, flat-shaded, with every backend that builds on triangles: our structures (both
/// triangle tests) and the peers draw the same image, and it is not all sky. A backend that cannot build the scene, a
/// mesh scene without its mesh and a data set not fetched are one line, exit 2, nothing written.
#[test]
fn render_draws_triangle_scenes_with_every_backend() {
    let dir = temp("render-triangles");
    let render = |sets: &[&str], out: &str| {
        render_command(&["--count"], sets, &dir.join(out)).env("BVHLAB_DATA", dir.join("no-data")).output().unwrap()
    };
    let hash = printed_hash;
    for (scene, count) in [("scene=tessellated-spheres", "4480 triangles"), ("scene=random-triangles", "20 triangles")]
    {
        let base = [scene, "objects=20", "width=48", "height=32"];
        let mut hashes = HashSet::new();
        for (i, sets) in [
            &["accel=list"][..],
            &["accel=bvh", "triangle_test=moller-trumbore"],
            &["accel=flat-bvh", "strategy=rayon-bands", "threads=2"],
            &["accel=wide-bvh", "node_width=4", "leaf_block=16", "triangle_test=moller-trumbore"],
            &["accel=wide-bvh"],
            &["accel=obvhs-bvh2"],
            &["accel=obvhs-cwbvh"],
        ]
        .iter()
        .enumerate()
        {
            let out = format!("t{i}.png");
            let o = render(&[&base[..], sets].concat(), &out);
            assert!(o.status.success(), "{scene} {sets:?}: {}", stderr(&o));
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(text.contains(count) && text.contains("triangle tests"), "{text}");
            let png = std::fs::read(dir.join(&out)).unwrap();
            assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{sets:?} wrote a PNG");
            hashes.insert(hash(&o));
        }
        assert_eq!(hashes.len(), 1, "{scene}: every structure and triangle test draws the same image: {hashes:?}");
        let sky = render(&[&base[..], &["accel=null"]].concat(), "sky.png");
        assert!(sky.status.success(), "{}", stderr(&sky));
        assert!(!hashes.contains(&hash(&sky)), "{scene}: the image is not all sky");
    }
    for (sets, want) in [
        (&["accel=tinybvh"][..], "--set accel=tinybvh: tinybvh traces triangles only"),
        (&["scene=mesh"], "--set scene=mesh needs --set mesh=NAME"),
        (&["scene=mesh", "mesh=bunny"], "harness fetch bunny"),
    ] {
        assert_refused(&render(sets, "bad.png"), want, &dir.join("bad.png"), &format!("{sets:?}"));
    }
}

/// `harness render ARGS --set S… --out OUT`.
fn render_command(args: &[&str], sets: &[&str], out: &Path) -> Command {
    let mut cmd = harness();
    cmd.arg("render").args(args);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd.args(["--out", out.to_str().unwrap()]);
    cmd
}

/// The 16 hex digits of the image hash `harness render` printed (empty when it printed none).
fn printed_hash(o: &Output) -> String {
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    text.lines().find_map(|l| l.split(" hash ").nth(1)).map(|h| h[..16].to_string()).unwrap_or_default()
}

/// Asserts that `o` (`what`) exited 2 with one line naming `want` and wrote nothing at `out`.
#[track_caller]
fn assert_refused(o: &Output, want: &str, out: &Path, what: &str) {
    assert_eq!(o.status.code(), Some(2), "{what}: {}", stderr(o));
    assert_eq!(stderr(o).trim_end().lines().count(), 1, "{what}: {}", stderr(o));
    assert!(stderr(o).contains(want), "{what}: expected {want:?} in {}", stderr(o));
    assert!(!out.exists(), "{what}: nothing written");
}
