//! Loaders on small procedural files, the registry, the cache's errors: nothing here needs fetched data.

use std::path::{Path, PathBuf};

use super::registry::DataSet;
use super::{cache, fetch, load_path};

/// A fresh temporary folder for one test.
fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("bvhlab-meshes-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const TETRA: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const TETRA_FACES: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// A PLY tetrahedron (with an extra vertex property and an int index list), ASCII or binary little-endian.
fn tetra_ply(binary: bool) -> Vec<u8> {
    let format = if binary { "binary_little_endian" } else { "ascii" };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for p in TETRA {
        if binary {
            p.iter().for_each(|c| out.extend(c.to_le_bytes()));
            out.push(7);
        } else {
            out.extend(format!("{} {} {} 7\n", p[0], p[1], p[2]).bytes());
        }
    }
    for f in TETRA_FACES {
        if binary {
            out.push(3);
            f.iter().for_each(|&i| out.extend((i as i32).to_le_bytes()));
        } else {
            out.extend(format!("3 {} {} {}\n", f[0], f[1], f[2]).bytes());
        }
    }
    out
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn obj_cube_of_quads_triangulates_to_twelve() {
    let dir = temp("obj");
    let mut obj = String::from("# cube\no cube\n");
    for i in 0..8 {
        obj += &format!("v {} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
    }
    obj += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
    let mesh = load_path(&write(&dir, "cube.obj", obj.as_bytes())).unwrap();
    assert_eq!((mesh.positions.len(), mesh.triangle_count()), (8, 12));
    assert_eq!(mesh.bounds().extent(), tracer::Vec3::ONE);
    assert_eq!(mesh.indices[1], [0, 2, 3], "a quad fans from its first corner");
}

#[test]
fn ascii_and_binary_ply_load_the_same_tetrahedron() {
    let dir = temp("ply");
    let a = load_path(&write(&dir, "a.ply", &tetra_ply(false))).unwrap();
    let b = load_path(&write(&dir, "b.ply", &tetra_ply(true))).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.indices, TETRA_FACES.to_vec());
    assert_eq!(a.positions[3], tracer::Vec3::Z);
}

#[test]
fn ply_polygons_fan_and_folders_merge_in_name_order() {
    let dir = temp("ply-folder");
    let quad = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list uchar uint vertex_index\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    write(&dir, "b.ply", quad.as_bytes());
    write(&dir, "a.ply", &tetra_ply(true));
    write(&dir, "notes.txt", b"not a mesh");
    let mesh = load_path(&dir).unwrap();
    assert_eq!(mesh.triangle_count(), 6);
    assert_eq!(&mesh.indices[4..], &[[4, 5, 6], [4, 6, 7]]);
    assert_eq!(mesh.fingerprint(), load_path(&dir).unwrap().fingerprint());
}

/// A one-triangle PLY whose third index is past its three vertices.
const RANGE_PLY: &[u8] =
    b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
    element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n";

#[test]
fn loader_errors_are_one_line_naming_the_file() {
    let dir = temp("bad");
    let cases = [
        ("range.ply", RANGE_PLY.to_vec(), "indexes vertices [0, 1, 9]"),
        (
            "novert.ply",
            b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n".to_vec(),
            "x, y, z",
        ),
        ("garbage.ply", b"hello".to_vec(), "not a readable PLY"),
        ("range.obj", b"v 0 0 0\nf 1 2 3\n".to_vec(), "range.obj"),
        ("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(), "vertex 1 is not finite (NaN, 0, 0)"),
        ("inf.obj", b"v 0 0 0\nv 0 -inf 0\nv 0 1 0\nf 1 2 3\n".to_vec(), "vertex 1 is not finite (0, -inf, 0)"),
        ("mesh.stl", b"solid".to_vec(), "allowed: an .obj or .ply"),
    ];
    for (name, bytes, says) in cases {
        let e = load_path(&write(&dir, name, &bytes)).unwrap_err();
        let line = e.to_string();
        assert!(line.contains(name) && line.contains(says) && !line.contains('\n'), "{name}: {line}");
        assert_eq!(e.exit_code(), 2, "{name}");
    }
}

/// An empty OBJ, one of vertices only, a PLY of zero faces, a folder of such: no triangles, refused in one line.
#[test]
fn a_mesh_without_triangles_is_refused() {
    let dir = temp("empty");
    let no_faces = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
        element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    std::fs::create_dir_all(dir.join("folder")).unwrap();
    write(&dir.join("folder"), "a.ply", no_faces);
    let paths = [
        write(&dir, "empty.obj", b""),
        write(&dir, "points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        write(&dir, "no-faces.ply", no_faces),
        dir.join("folder"),
    ];
    for path in paths {
        let e = load_path(&path).unwrap_err();
        let line = e.to_string();
        let says = format!("{}: no triangles (allowed: a mesh of at least one triangle", path.display());
        assert!(line.starts_with(&says) && !line.contains('\n') && e.exit_code() == 2, "{line}");
    }
}

/// Zero-area triangles (a repeated corner, three corners on a line) count as degenerate; a tiny one does not.
#[test]
fn degenerate_triangles_are_counted() {
    let dir = temp("degenerate");
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 1e-20 0 0\nv 0 1e-20 0\n\
               f 1 2 3\nf 1 2 4\nf 1 1 3\nf 1 5 6\n";
    let mesh = load_path(&write(&dir, "d.obj", obj.as_bytes())).unwrap();
    assert_eq!((mesh.triangle_count(), super::degenerate(&mesh)), (4, 2));
    let tetra = load_path(&write(&dir, "t.ply", &tetra_ply(false))).unwrap();
    assert_eq!(super::degenerate(&tetra), 0);
}

#[test]
fn js_arrays_load_positions_and_cells() {
    let dir = temp("js");
    let js = "exports.positions=[[0,0,0],[1,0,0],[0,1.5,0]];\nexports.cells=[[0,1,2]];\n";
    let mesh = super::js::load(&write(&dir, "index.js", js.as_bytes())).unwrap();
    assert_eq!((mesh.triangle_count(), mesh.positions[2].y), (1, 1.5));
    let e = super::js::load(&write(&dir, "bad.js", b"exports.positions=[[0,0]];")).unwrap_err().to_string();
    assert!(e.contains("bad.js") && e.contains("positions"), "{e}");
}

#[test]
fn an_unfetched_data_set_names_the_command_that_fetches_it() {
    let root = temp("unfetched");
    let e = cache::load(&root, DataSet::named("bunny").unwrap()).unwrap_err();
    assert!(e.to_string().contains("run `harness fetch bunny`"), "{e}");
    assert_eq!(e.exit_code(), 2);
}

#[test]
fn an_archive_with_another_sha256_is_refused() {
    let root = temp("sha");
    let set = DataSet::named("teapot").unwrap();
    std::fs::create_dir_all(root.join(set.name)).unwrap();
    let fake = write(&root.join(set.name), set.archive, b"not the teapot");
    let e = fetch::fetch(&root, set).unwrap_err();
    let line = e.to_string();
    assert!(line.contains(&fake.display().to_string()) && line.contains(set.sha256), "{line}");
    assert_eq!(e.exit_code(), 2);
    assert!(!root.join(set.name).join(cache::MANIFEST).exists());
}

#[test]
#[ignore = "downloads glmark2-data with apt-get (needs the Debian archive)"]
fn fetches_the_bunny_for_real() {
    let root = temp("real");
    let set = DataSet::named("bunny").unwrap();
    let m = fetch::fetch(&root, set).unwrap();
    assert_eq!(m.triangles, 69_666);
    assert_eq!(cache::load(&root, set).unwrap().triangle_count(), 69_666);
}

#[test]
fn model_star_n_is_n_copies_and_a_bad_count_is_refused() {
    let dir = temp("tiled");
    let one = write(&dir, "t.ply", &tetra_ply(true)).display().to_string();
    let nine = super::load_source(&format!("{one}*9")).unwrap();
    assert_eq!(nine.triangle_count(), 9 * super::load_source(&one).unwrap().triangle_count());
    assert_eq!(super::up_axis("munich*64"), tracer::Vec3::Z);
    assert_eq!(super::triangles("munich*64"), Some(64 * 38_936));
    assert_eq!(super::triangles(&format!("{one}*9")), None);
    for bad in ["*0", "*1025", "*99999999999"] {
        let e = super::load_source(&format!("{one}{bad}")).unwrap_err().to_string();
        assert!(e.contains("allowed: MODEL*N with N from 1 to 1024") && !e.contains('\n'), "{e}");
    }
}
