//! Embree against brute force, over spheres and triangle meshes: single rays, occlusion and 8- and 16-wide
//! packets, plus the loader's error.

use std::path::PathBuf;

use schema::{EmbreeQuality, Named};
use tracer::Vec3;
use tracer::accel::{Accelerator, Hit};
use tracer::agreement::ExactPrimitive;
use tracer::agreement::Strictness;
use tracer::counters::NoCounters;
use tracer::geometry::Ray;
use tracer::scene::mesh::Mesh;
use tracer::testing::{Comparison, Reference, TestMesh, TestScene, scenes, test_meshes};

use super::library::SearchInputs;
use super::*;
use crate::peers::testing::{embree_device, triangle_reference};

/// The last test scene with `n` spheres (clustered spheres, seed 2).
fn scene_of(n: usize) -> TestScene {
    scenes().into_iter().rfind(|s| s.spheres.len() == n).unwrap()
}

#[test]
fn single_rays_agree_with_brute_force() {
    let Some(device) = embree_device("single_rays_agree_with_brute_force") else { return };
    for TestScene { label, spheres, rays } in scenes() {
        let scene = EmbreeSpheres::build(&device, &spheres, EmbreeQuality::Medium).expect("build");
        assert!(scene.input_bytes() >= SpherePoints::bytes(&spheres), "{label}: {}", scene.input_bytes());
        assert!(spheres.is_empty() || scene.stats().bytes > 0, "{label}: {:?}", scene.stats());
        Reference::new(&spheres, &rays).assert_agrees(&format!("embree {label}"), &scene, Strictness::Arbitrated);
    }
}

#[test]
fn every_build_quality_agrees() {
    let Some(device) = embree_device("every_build_quality_agrees") else { return };
    let TestScene { label, spheres, rays } = scene_of(2000);
    let reference = Reference::new(&spheres, &rays);
    for &quality in EmbreeQuality::ALL {
        let scene = EmbreeSpheres::build(&device, &spheres, quality).expect("build");
        reference.assert_agrees(&format!("embree {} {label}", quality.name()), &scene, Strictness::Arbitrated);
    }
}

#[test]
fn packets_agree_with_brute_force() {
    let Some(device) = embree_device("packets_agree_with_brute_force") else { return };
    for TestScene { label, spheres, rays } in scenes() {
        let scene = EmbreeSpheres::build(&device, &spheres, EmbreeQuality::Medium).expect("build");
        let reference = Reference::new(&spheres, &rays);
        let start = |what: &str| reference.compare(what, Strictness::Arbitrated);
        check_packets(start, &label, &rays, |chunk| scene.intersect16(chunk));
        check_packets(start, &label, &rays, |chunk| scene.intersect8(chunk));
    }
}

/// `query` (an `intersectN`) in full packets of N, then the same rays in partial packets of 7 (lanes 7..N
/// inactive), against brute force (`start` begins a comparison with it).
fn check_packets<'r, 'a: 'r, const N: usize, X: ExactPrimitive + 'r>(
    start: impl Fn(&str) -> Comparison<'r, 'a, X>,
    label: &str,
    rays: &[Ray],
    query: impl Fn(&[Ray]) -> [Option<Hit>; N],
) {
    for width in [N, 7] {
        let mut comparison = start(&format!("embree intersect{N} in packets of {width} {label}"));
        for (c, chunk) in rays.chunks(width).enumerate() {
            let got = query(chunk);
            for (lane, &hit) in got[..chunk.len()].iter().enumerate() {
                comparison.closest(c * width + lane, hit);
            }
            assert!(
                got[chunk.len()..].iter().all(Option::is_none),
                "{label}: inactive lanes of intersect{N} must report no hit"
            );
        }
        comparison.finish();
    }
}

/// Every test mesh at every build quality: closest hit and occlusion, one ray at a time and in a batch, agree
/// with f64 brute force (edge ties tolerated and counted), and hits name a triangle hit at that distance.
#[test]
fn triangles_agree_with_brute_force() {
    let Some(device) = embree_device("triangles_agree_with_brute_force") else { return };
    for TestMesh { label, mesh, rays } in test_meshes() {
        let reference = triangle_reference(&mesh, &rays);
        for &quality in EmbreeQuality::ALL {
            let scene = EmbreeTriangles::build(&device, &mesh, quality).expect("build");
            assert!(scene.input_bytes() >= Triangles::bytes(&mesh), "{label}: {}", scene.input_bytes());
            assert!(mesh.indices.is_empty() || scene.stats().bytes > 0, "{label}: {:?}", scene.stats());
            let what = format!("embree triangles {} {label}", quality.name());
            let tally = reference.assert_agrees(&what, &scene, Strictness::Arbitrated);
            eprintln!(
                "embree triangles {} {label}: {} answers, {} edge ties",
                quality.name(),
                tally.answers,
                tally.tolerated
            );
        }
    }
}

/// Embree's builder's trees (`rtcBuildBVH`, binned and with spatial splits), copied out and collapsed into our wide
/// BVH, give brute force's hits; every triangle is in some leaf, and only spatial splits name one twice.
#[test]
fn embree_trees_under_our_kernel_agree_with_brute_force() {
    use tracer::accel::WideBvh;
    use tracer::accel::bvh::BvhParams;
    use tracer::accel::bvh::tree::BuiltTree;
    use tracer::accel::wide::WideParams;
    use tracer::geometry::{MollerTrumboreTriangle, TrianglePrimitive};

    let Some(device) = embree_device("embree_trees_under_our_kernel_agree_with_brute_force") else { return };
    let mut meshes: Vec<(String, Mesh, Vec<Ray>)> =
        test_meshes().into_iter().map(|m| (m.label, m.mesh, m.rays)).collect();
    let g = grid(64);
    meshes.push(("grid 64".into(), g.clone(), tracer::testing::mesh_ray_mix(&g, 7, 2_000)));
    for (label, mesh, rays) in meshes {
        if mesh.indices.is_empty() {
            assert!(tree::build(&device, &mesh, tree::TreeQuality::Medium).is_err(), "{label}: no triangles");
            continue;
        }
        let reference = triangle_reference(&mesh, &rays);
        for quality in [tree::TreeQuality::Medium, tree::TreeQuality::High] {
            let what = format!("embree tree {quality:?} {label}");
            let (nodes, order) = tree::build(&device, &mesh, quality).expect(&what);
            eprintln!("{what}: {} refs of {} tris, {} nodes", order.len(), mesh.indices.len(), nodes.len());
            let mut named = vec![0u32; mesh.indices.len()];
            order.iter().for_each(|&id| named[id as usize] += 1);
            assert!(named.iter().all(|&k| k >= 1), "{what}: a triangle in no leaf");
            if quality == tree::TreeQuality::Medium {
                assert_eq!(order.len(), mesh.indices.len(), "{what}: references without spatial splits");
            }
            let prims = MollerTrumboreTriangle::all(mesh.triangles());
            let built = BuiltTree::from_external(&nodes, &order, &prims).expect(&what);
            let wide = WideBvh::try_from_tree(&built, &BvhParams::default(), &WideParams::default()).expect(&what);
            reference.assert_agrees(&what, &wide, Strictness::Arbitrated);
        }
    }
}

/// A `side` × `side` grid of unit quads, two triangles each, its heights a fixed bumpy function (not flat, so
/// the boxes are not degenerate).
fn grid(side: u32) -> Mesh {
    let v = |x: u32, y: u32| Vec3::new(x as f32, y as f32, ((x * 7 + y * 13) % 5) as f32 * 0.25);
    let positions = (0..=side).flat_map(|y| (0..=side).map(move |x| v(x, y))).collect();
    let at = |x: u32, y: u32| y * (side + 1) + x;
    let indices = (0..side)
        .flat_map(|y| {
            (0..side).flat_map(move |x| {
                [[at(x, y), at(x + 1, y), at(x, y + 1)], [at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)]]
            })
        })
        .collect();
    Mesh { positions, indices }
}

/// The tree bytes are what the memory monitor saw the commit allocate (net of frees): more than nothing, growing
/// with the triangles, at least one 256-byte BVH8 node per 8 triangles, not the input's bytes (Embree's own copies
/// of the input, allocated before the commit, are at least those bytes and counted apart); releasing the scene
/// gives back everything the build took.
#[test]
fn tree_bytes_are_what_the_commit_allocates() {
    let Some(device) = embree_device("tree_bytes_are_what_the_commit_allocates") else { return };
    for &quality in EmbreeQuality::ALL {
        let mut last = 0;
        for side in [16, 64, 256] {
            let mesh = grid(side);
            let tris = mesh.indices.len();
            let before = device.inner.memory_bytes();
            let scene = EmbreeTriangles::build(&device, &mesh, quality).expect("build");
            let (bytes, input) = (scene.stats().bytes, scene.input_bytes());
            let what = format!("{} {tris} triangles: {bytes} tree bytes, {input} input bytes", quality.name());
            eprintln!("embree {what} ({:.1} tree bytes a triangle)", bytes as f64 / tris as f64);
            assert!(bytes > last, "{what}: not more than {last} for fewer triangles");
            assert!(bytes >= 256 * tris / 8, "{what}: less than one BVH8 node per 8 triangles");
            assert!(input >= Triangles::bytes(&mesh), "{what}: less than the input's {}", Triangles::bytes(&mesh));
            assert_ne!(bytes, Triangles::bytes(&mesh), "{what}: the input's bytes");
            assert_eq!(
                device.inner.memory_bytes() as usize,
                before as usize + input + bytes,
                "{what}: the device holds more than the scene's input and tree"
            );
            drop(scene);
            assert_eq!(device.inner.memory_bytes(), before, "{what}: not all given back on release");
            last = bytes;
        }
    }
}

#[test]
fn triangle_packets_agree_with_brute_force() {
    let Some(device) = embree_device("triangle_packets_agree_with_brute_force") else { return };
    for TestMesh { label, mesh, rays } in test_meshes() {
        let scene = EmbreeTriangles::build(&device, &mesh, EmbreeQuality::Medium).expect("build");
        let reference = triangle_reference(&mesh, &rays);
        let start = |what: &str| reference.compare(what, Strictness::Arbitrated);
        check_packets(start, &label, &rays, |chunk| scene.intersect16(chunk));
        check_packets(start, &label, &rays, |chunk| scene.intersect8(chunk));
    }
}

#[test]
fn a_triangle_indexing_past_the_vertices_is_an_error() {
    let Some(device) = embree_device("a_triangle_indexing_past_the_vertices_is_an_error") else { return };
    let mut mesh = tracer::scene::random_triangles(10, 1);
    mesh.indices[7][2] = 30;
    let err = EmbreeTriangles::build(&device, &mesh, EmbreeQuality::Medium).expect_err("index 30 of 30 vertices");
    assert!(matches!(err, device::EmbreeError::Input(_)), "{err}");
    assert!(err.to_string().contains("triangle 7"), "{err}");
}

#[test]
fn concurrent_queries_match_serial_ones() {
    let Some(device) = embree_device("concurrent_queries_match_serial_ones") else { return };
    let TestScene { spheres, rays, .. } = scene_of(2000);
    let scene = EmbreeSpheres::build(&device, &spheres, EmbreeQuality::Medium).expect("build");
    let serial: Vec<_> = rays.iter().map(|r| scene.intersect(r, &mut NoCounters)).collect();
    std::thread::scope(|s| {
        for part in 0..4 {
            let (scene, rays, serial) = (&scene, &rays, &serial);
            s.spawn(move || {
                for i in (part..rays.len()).step_by(4) {
                    assert_eq!(scene.intersect(&rays[i], &mut NoCounters), serial[i]);
                }
            });
        }
    });
}

#[test]
fn device_reports_version_and_isa() {
    let Some(device) = embree_device("device_reports_version_and_isa") else { return };
    let info = device.info();
    assert!(info.version.starts_with("4."), "{info:?}");
    assert!([4, 8, 16].contains(&info.native_packet), "{info:?}");
    assert_eq!(info.config, "threads=2");
    let status = crate::peers::embree_status().expect("status");
    assert_eq!(status.version, info.version);
}

#[test]
fn bad_isa_is_an_error_not_a_crash() {
    let Some(_) = embree_device("bad_isa_is_an_error_not_a_crash") else { return };
    let config = EmbreeConfig { isa: Some("no-such-isa".into()), ..EmbreeConfig::default() };
    // Embree either rejects the value or ignores it; it must not abort the process.
    if let Err(e) = EmbreeDevice::new(&config) {
        assert!(e.to_string().contains("Embree error"), "{e}");
    }
}

#[test]
fn explicit_bogus_path_gives_one_line_with_the_install_hint() {
    let inputs = SearchInputs { explicit: Some(PathBuf::from("/nonexistent")), ..SearchInputs::default() };
    let err = EmbreeLibrary::load(&inputs).expect_err("/nonexistent must not load");
    let msg = err.to_string();
    assert!(!msg.contains('\n'), "one line: {msg}");
    assert!(msg.contains("python3 -m pip install embreex==4.4.0.post1"), "{msg}");
    assert!(msg.contains("EMBREE_LIB=/nonexistent"), "{msg}");
    assert_eq!(err.tried.len(), 1, "an explicit path is the only candidate: {err:?}");
}

#[test]
fn site_dirs_without_the_wheel_are_listed_as_tried() {
    let dir = std::env::temp_dir().join(format!("bvhlab-no-embree-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("embreex.libs")).unwrap();
    let inputs = SearchInputs { site_dirs: vec![dir.clone()], ..SearchInputs::default() };
    let err = EmbreeLibrary::load(&inputs).expect_err("an empty embreex.libs must not load");
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(err.to_string().contains("embreex.libs/libembree4*.so*: none"), "{err}");
}

#[test]
fn camera_hits_match_exactly_without_excuses() {
    let Some(device) = embree_device("camera_hits_match_exactly_without_excuses") else { return };
    use tracer::accel::{BvhParams, FlatBvh};
    use tracer::executor::Strategy;
    use tracer::render::trace_primary;
    for kind in tracer::scene::SceneKind::ALL {
        for n in [2_000, 50_000] {
            let scene = kind.generate(n, 7);
            let camera = scene.camera.with_resolution(256, 192);
            let ours = FlatBvh::build(&scene.spheres, &BvhParams::default());
            let embree = EmbreeSpheres::build(&device, &scene.spheres, EmbreeQuality::Medium).expect("build");
            let (want, _) = trace_primary::<_, NoCounters>(&camera, &ours, &Strategy::SERIAL);
            let (got, _) = trace_primary::<_, NoCounters>(&camera, &embree, &Strategy::SERIAL);
            assert_eq!(got.hit_count(), want.hit_count(), "{} n={n}", kind.name());
            let differ =
                want.hits.iter().zip(&got.hits).filter(|(w, g)| (w.prim == u32::MAX) != (g.prim == u32::MAX)).count();
            assert_eq!(differ, 0, "{} n={n}: pixels whose hit/miss differ", kind.name());
        }
    }
}

/// Every instruction set this CPU runs, pinned: the native packet width it reports, and sphere and triangle
/// scenes agreeing with brute force.
#[test]
fn pinned_isa_sets_the_native_packet_width() {
    let Some(_) = embree_device("pinned_isa_sets_the_native_packet_width") else { return };
    let TestScene { spheres, rays, .. } = scene_of(50);
    let reference = Reference::new(&spheres, &rays);
    let mesh = test_meshes().swap_remove(0);
    let mesh_reference = triangle_reference(&mesh.mesh, &mesh.rays);
    let on_cpu = [
        true,
        true,
        is_x86_feature_detected!("avx"),
        is_x86_feature_detected!("avx2"),
        is_x86_feature_detected!("avx512f"),
    ];
    for ((isa, width), on_cpu) in
        [("sse2", 4), ("sse4.2", 4), ("avx", 8), ("avx2", 8), ("avx512", 16)].into_iter().zip(on_cpu)
    {
        if !on_cpu {
            continue;
        }
        let device =
            EmbreeDevice::new(&EmbreeConfig { threads: Some(1), isa: Some(isa.into()), ..EmbreeConfig::default() })
                .expect(isa);
        assert_eq!(device.info().native_packet, width, "isa={isa}: {:?}", device.info());
        let scene = EmbreeSpheres::build(&device, &spheres, EmbreeQuality::Medium).expect(isa);
        reference.assert_agrees(&format!("embree isa={isa}"), &scene, Strictness::Arbitrated);
        let triangles = EmbreeTriangles::build(&device, &mesh.mesh, EmbreeQuality::Medium).expect(isa);
        let what = format!("embree triangles isa={isa} {}", mesh.label);
        mesh_reference.assert_agrees(&what, &triangles, Strictness::Arbitrated);
    }
}

/// Runs `f` with the stack shifted by `PAD` bytes, so that locals land at other addresses modulo 64.
#[inline(never)]
fn with_stack_shifted<const PAD: usize>(f: &mut dyn FnMut()) {
    let pad = [0u8; PAD];
    std::hint::black_box(&pad);
    f();
    std::hint::black_box(&pad);
}

/// Prepares packet calls at four stack offsets (frames differ by 16 bytes, so a mask or packet aligned to less
/// than 64 bytes lands misaligned in at least one of them): on any machine, a type with too little alignment
/// makes `pointers` panic here instead of crashing only where Embree's AVX-512 kernels load it.
#[test]
fn packet_masks_and_rays_are_aligned_wherever_the_stack_puts_them() {
    let rays = vec![Ray::new(tracer::Vec3::ZERO, tracer::Vec3::Z); 16];
    let mut check = || {
        let mut call8 = super::scene::PacketCall::<8, abi::RTCRayHit8>::new(&rays[..5]);
        let (valid, packet) = call8.pointers();
        assert!((valid as usize).is_multiple_of(32) && (packet as usize).is_multiple_of(32));
        let mut call16 = super::scene::PacketCall::<16, abi::RTCRayHit16>::new(&rays);
        let (valid, packet) = call16.pointers();
        assert!((valid as usize).is_multiple_of(64) && (packet as usize).is_multiple_of(64));
    };
    with_stack_shifted::<1>(&mut check);
    with_stack_shifted::<17>(&mut check);
    with_stack_shifted::<33>(&mut check);
    with_stack_shifted::<49>(&mut check);
    // The shifts really move locals: a 4-byte aligned array (what the mask used to be) lands at other offsets.
    let mut offsets = std::collections::BTreeSet::new();
    let mut record = || {
        let plain = [0i32; 16];
        offsets.insert(std::hint::black_box(plain.as_ptr()) as usize % 64);
    };
    with_stack_shifted::<1>(&mut record);
    with_stack_shifted::<17>(&mut record);
    with_stack_shifted::<33>(&mut record);
    with_stack_shifted::<49>(&mut record);
    assert!(offsets.len() > 1 && offsets.iter().any(|&o| o != 0), "the stack shifts moved nothing: {offsets:?}");
}

#[test]
fn the_alignment_check_rejects_a_misaligned_pointer() {
    let storage = abi::ValidMask16([0; 16]);
    let base = std::ptr::from_ref(&storage).cast::<u8>();
    assert_eq!(abi::aligned(base, 64, "a mask"), base);
    for offset in [4, 8, 16, 32] {
        let shifted = base.wrapping_add(offset);
        let result = std::panic::catch_unwind(|| abi::aligned(shifted, 64, "a mask"));
        assert!(result.is_err(), "address {shifted:p} (offset {offset}) passed a 64-byte alignment check");
    }
    let ray_hit = std::ptr::from_ref(&abi::RTCRayHit::default()).cast::<u8>();
    assert!(std::panic::catch_unwind(|| abi::aligned(ray_hit.wrapping_add(8), 16, "RTCRayHit")).is_err());
}
