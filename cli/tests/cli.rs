//! End-to-end tests of the `isomorph` binary.

mod common;

use common::{assert_ok, isomorph, morph, read_json, scratch, stderr};
use std::path::Path;

fn bunny() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/bunny.ply").to_string_lossy().into_owned()
}

#[test]
fn demo_writes_frames_sheet_and_report() {
    let out = scratch("demo");
    let o = isomorph(&["demo", "--res", "32", "--frames", "4", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "demo failed: {}", stderr(&o));
    let dir = out.join("baseline_mug_to_chain");
    for f in ["frame_000.ply", "frame_003.ply", "contact_sheet.png", "report.json"] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    let report: serde_json::Value = read_json(dir.join("report.json"));
    assert_eq!(report["method"], "baseline");
    assert_eq!(report["resolution"], 32);
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 4);
    for key in ["t", "vertices", "triangles", "components", "voids", "genus", "area", "volume", "seconds"] {
        assert!(frames[0].get(key).is_some(), "frame key {key} missing");
    }
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        for key in ["mean", "hausdorff", "mean_voxels", "hausdorff_voxels"] {
            assert!(e[key].as_f64().is_some(), "endpoint {end}.{key} missing");
        }
        // The baseline reproduces its inputs at t = 0 and 1 up to sampling.
        assert!(e["mean_voxels"].as_f64().unwrap() < 0.5, "{end}: {e}");
    }
    // The level-set ball → C stays one piece and ends on the C.
    let level_set: serde_json::Value = read_json(out.join("level_set_ball_to_c/report.json"));
    assert_eq!(level_set["method"], "level-set");
    for f in level_set["frames"].as_array().unwrap() {
        assert_eq!(f["components"], 1, "{f}");
    }
    assert!(level_set["endpoints"]["target"]["mean_voxels"].as_f64().unwrap() < 0.5);
    assert!(out.join("level_set_mug_to_chain/contact_sheet.png").is_file());
    // Colour through the morph: the painted bunny's and torus's colours.
    let painted = out.join("level_set_colour_bunny_to_torus");
    for f in ["frame_000.ply", "frame_003.ply"] {
        let frame = isomorph_io::mesh::read_mesh(painted.join(f)).unwrap();
        assert!(frame.colors.is_some(), "{f} has no colours");
    }
    // The rook becomes the queen in one piece (its built-in links and speeds).
    let blob: serde_json::Value = read_json(out.join("blobtree_rook_to_queen/report.json"));
    for f in blob["frames"].as_array().unwrap() {
        assert_eq!(f["components"], 1, "{f}");
    }
    // RBF and T-spline: sphere → torus, genus 0 → 1, ends on the inputs.
    for dir in ["rbf_sphere_to_torus", "tspline_sphere_to_torus"] {
        let r: serde_json::Value = read_json(out.join(dir).join("report.json"));
        let frames = r["frames"].as_array().unwrap();
        assert_eq!(
            (&frames[0]["genus"], &frames[frames.len() - 1]["genus"]),
            (&serde_json::json!(0), &serde_json::json!(1)),
            "{dir}: {r}"
        );
        for end in ["source", "target"] {
            assert!(r["endpoints"][end]["mean_voxels"].as_f64().unwrap() < 0.5, "{dir} {end}: {r}");
        }
    }
    // Yang & Jüttler's Example 2: the sphere becomes the genus-3 holed cube.
    let holed: serde_json::Value = read_json(out.join("tspline_sphere_to_holed_cube/report.json"));
    let frames = holed["frames"].as_array().unwrap();
    assert_eq!(frames[0]["genus"], 0, "{holed}");
    assert_eq!(frames[frames.len() - 1]["genus"], 3, "{holed}");
    // One outer shell in every frame; a cavity where the holes open from
    // inside is reported as a void, not as another piece (issue 17).
    for f in frames {
        let (components, voids) = (f["components"].as_u64().unwrap(), f["voids"].as_u64().unwrap());
        assert_eq!(components - voids, 1, "{f}");
    }
    for f in ["frame_000.png", "contact_sheet.png", "spacetime.ply"] {
        assert!(out.join("rbf_x_to_o").join(f).is_file(), "missing rbf_x_to_o/{f}");
    }
    // The warped bunny: the ear tip was dragged up by 2.5 units.
    let ear = out.join("warp_bunny_ear");
    assert!(ear.join("before_after.png").is_file());
    let top = |f: &str| isomorph_io::mesh::read_mesh(ear.join(f)).unwrap().bounds().max.y;
    assert!(top("warped.obj") > top("source.obj") + 2.0, "{} vs {}", top("warped.obj"), top("source.obj"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn info_prints_bunny_metrics_as_json() {
    let o = isomorph(&["info", &bunny(), "--json"]);
    assert_ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["vertices"], 1839);
    assert_eq!(v["triangles"], 3674);
    assert_eq!(v["components"], 1);
    assert_eq!(v["euler"], 2);
    assert_eq!(v["genus"], 0);
    assert_eq!(v["boundary_edges"], 0);
    assert_eq!(v["nonmanifold_edges"], 0);
    assert!((v["area"].as_f64().unwrap() - 218.68927).abs() < 1e-3);
    assert!((v["volume"].as_f64().unwrap() - 194.28837).abs() < 1e-3);
}

#[test]
fn morph_of_a_mesh_into_a_builtin_shape() {
    let out = scratch("morph");
    let o = morph(
        "baseline",
        &bunny(),
        "sphere",
        &["--res", "24", "--frames", "3", "--format", "obj", "--out", out.to_str().unwrap()],
    );
    assert_ok(&o);
    assert!(out.join("frame_002.obj").is_file());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_input_is_one_clear_line_and_nonzero_exit() {
    let o = isomorph(&["morph", "--source", "no-such-shape", "--target", "sphere"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.starts_with("error: "), "{err}");
    assert!(err.contains("no-such-shape") && err.contains("sphere"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");

    let garbage = scratch("garbage.ply");
    std::fs::write(&garbage, b"ply\nformat ascii 1.0\nelement vertex 99999999999\nend_header\n1 2").unwrap();
    let o = isomorph(&["info", garbage.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).starts_with("error: "));
    let _ = std::fs::remove_file(&garbage);

    let o = isomorph(&["morph", "--source", "sphere", "--target", "torus", "--res", "2"]);
    assert!(!o.status.success(), "resolution below the minimum is rejected");

    let o = morph("tspline", "sphere", "torus", &["--refine", "0"]);
    assert!(!o.status.success(), "a zero refinement tolerance is rejected");
    assert!(stderr(&o).contains("tolerance"));

    // Options of another method are refused, naming them; the level set's
    // curvature is a weight in [0, 100].
    let tspline = ["morph", "--method", "tspline", "--source", "sphere", "--target", "torus"];
    let o = isomorph(&[&tspline[..], &["--curvature", "2"]].concat());
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--curvature (level-set)") && err.contains("tspline"), "{err}");
    let o = morph("level-set", "sphere", "torus", &["--curvature", "sometimes"]);
    assert!(!o.status.success());
    let o = morph("level-set", "sphere", "torus", &["--points", "10"]);
    assert!(stderr(&o).contains("--points (rbf)"), "{}", stderr(&o));
}

/// Splits `.npy` bytes into the header text and the f32 values.
fn read_npy(path: &Path) -> (String, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0, "data is 64-byte aligned");
    let header = String::from_utf8(bytes[10..10 + len].to_vec()).unwrap();
    let values =
        bytes[10 + len..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    (header, values)
}

#[test]
fn sdf_writes_npy_and_sidecar() {
    let out = scratch("sdf");
    std::fs::create_dir_all(&out).unwrap();
    let npy = out.join("sphere.npy");
    let o = isomorph(&["sdf", "sphere", "--res", "24", "--pad", "0.1", "--out", npy.to_str().unwrap()]);
    assert_ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("24 x 24 x 24 nodes"));
    let meta: serde_json::Value = read_json(out.join("sphere.json"));
    assert_eq!(meta["sign"], "positive inside");
    assert_eq!(meta["axis_order"], "zyx");
    assert_eq!(meta["dims"], serde_json::json!([24, 24, 24]));
    let h = meta["spacing"].as_f64().unwrap() as f32;
    let origin: Vec<f32> =
        meta["origin"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect();
    // The sphere of radius 0.3 padded by 10 % per side.
    assert!((h - 0.72 / 23.0).abs() < 1e-6 && (origin[0] + 0.36).abs() < 1e-6, "{meta}");
    let (header, values) = read_npy(&npy);
    assert!(header.contains("'descr': '<f4'") && header.contains("'shape': (24, 24, 24)"), "{header}");
    assert_eq!(values.len(), 24 * 24 * 24);
    // x fastest: value number i + 24 (j + 24 k) is node (i, j, k).
    for (n, v) in values.iter().enumerate() {
        let (i, j, k) = (n % 24, (n / 24) % 24, n / 576);
        let p = [i, j, k].map(|c| c as f32 * h);
        let r = (0..3).map(|a| (origin[a] + p[a]).powi(2)).sum::<f32>().sqrt();
        assert!((v - (0.3 - r)).abs() < 1e-5, "node ({i}, {j}, {k}): {v} vs {}", 0.3 - r);
    }

    // A mesh keeps its own coordinates; the box is its bounds padded 10 %.
    let npy = out.join("bunny.npy");
    let o = isomorph(&["sdf", &bunny(), "--res", "16", "--out", npy.to_str().unwrap()]);
    assert_ok(&o);
    let meta: serde_json::Value = read_json(out.join("bunny.json"));
    let dims: Vec<u64> = meta["dims"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).collect();
    assert_eq!(dims[0], 16, "x is the bunny's longest side");
    let (header, values) = read_npy(&npy);
    assert!(header.contains(&format!("'shape': ({}, {}, 16)", dims[2], dims[1])), "{header}");
    assert!(values[0] < -1.0, "the box corner is outside");
    assert!(values.iter().any(|&v| v > 1.0), "the bunny has an inside");
    let _ = std::fs::remove_dir_all(&out);
}

/// Runs `isomorph align ARGS`, expecting success, and parses its JSON.
fn align_json(args: &[&str]) -> serde_json::Value {
    let o = isomorph(&[&["align"], args].concat());
    assert_ok(&o);
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A JSON array of numbers as f32.
fn floats(v: &serde_json::Value) -> Vec<f32> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect()
}

#[test]
fn align_puts_a_moved_mesh_back() {
    use isomorph_common::glam::{Affine3A, Mat4, Quat, Vec3};
    use isomorph_common::mesh::distance::surface_distance;
    use isomorph_io::mesh::{MeshFormat, read_mesh, write_mesh};
    let out = scratch("align");
    std::fs::create_dir_all(&out).unwrap();
    let bunny_mesh = read_mesh(bunny()).unwrap();
    let motion = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.5),
        Quat::from_euler(isomorph_common::glam::EulerRot::XYZ, 0.4, -1.1, 2.5),
        Vec3::new(3.0, -2.0, 1.0),
    );
    let moved = out.join("moved.ply");
    write_mesh(&bunny_mesh.transformed(&motion), &moved, MeshFormat::PlyBinaryLittleEndian).unwrap();
    let back = out.join("back.obj");
    let v = align_json(&[
        moved.to_str().unwrap(),
        &bunny(),
        "--mode",
        "similarity",
        "--out",
        back.to_str().unwrap(),
    ]);
    assert_eq!(v["mode"], "similarity");
    // The printed map undoes the motion.
    let matrix = Mat4::from_cols_array_2d(&std::array::from_fn(|c| {
        std::array::from_fn(|r| floats(&v["matrix"][r])[c])
    }));
    assert!((matrix * Mat4::from(motion)).abs_diff_eq(Mat4::IDENTITY, 1e-4), "{matrix}");
    assert!(floats(&v["scale"]).iter().all(|s| (s - 2.0).abs() < 1e-4), "{}", v["scale"]);
    let q = Quat::from_slice(&floats(&v["rotation"]));
    let undo = motion.to_scale_rotation_translation().1.inverse();
    assert!(q.is_normalized(), "{q}");
    assert!(q.abs_diff_eq(undo, 1e-4) || q.abs_diff_eq(-undo, 1e-4), "{q} vs {undo}");
    // The written mesh lies on the original bunny.
    let d = surface_distance(&read_mesh(&back).unwrap(), &bunny_mesh, 2000).unwrap();
    assert!(d.hausdorff < 1e-3, "{d:?}");

    // A built-in source is polygonized; a rigid map has unit scale.
    let mesh = out.join("ball.ply");
    let v =
        align_json(&["ball", "c-shape", "--mode", "rigid", "--res", "24", "--out", mesh.to_str().unwrap()]);
    assert_eq!(v["scale"], serde_json::json!([1.0, 1.0, 1.0]));
    assert!((Quat::from_slice(&floats(&v["rotation"])).length() - 1.0).abs() < 1e-6);
    assert!(!read_mesh(&mesh).unwrap().is_empty());

    // An open mesh is measured by its winding-number inside, as the morphs
    // see it, with the morphs' warning.
    let teapot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/teapot.ply");
    let o = isomorph(&["align", teapot.to_str().unwrap(), "sphere", "--out", mesh.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(o.status.success() && err.starts_with("warning: ") && err.contains("winding number"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(floats(&v["scale"]).iter().all(|s| s.is_finite() && *s > 0.0), "{}", v["scale"]);
    assert!(!read_mesh(&mesh).unwrap().is_empty());
    // Errors: an unknown extension.
    let o = isomorph(&["align", "sphere", "torus", "--out", out.join("x.vtk").to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains(".ply, .obj or .stl"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn warp_drags_a_sphere_point_and_writes_volume_meshes_and_png() {
    use isomorph_io::mesh::read_mesh;
    let out = scratch("warp");
    // The sphere's (radius 0.3) +x pole pulled outward by 0.15.
    let o = isomorph(&[
        "warp",
        "sphere",
        "--res",
        "32",
        "--csize",
        "7",
        "--drag",
        "0.3,0,0:0.15,0,0",
        "--frames",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "warp failed: {}", stderr(&o));
    for f in ["warped.npy", "warped.json", "source.obj", "warped.obj", "before_after.png"] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    // A shape's distance field is warped as an f32 density, not quantized
    // to bytes: most ramp values are no multiple of 1/255.
    let (_, values) = read_npy(&out.join("warped.npy"));
    let ramp: Vec<f32> = values.into_iter().filter(|v| *v > 0.0 && *v < 1.0).collect();
    let off_grid = ramp.iter().filter(|v| ((*v * 255.0) - (*v * 255.0).round()).abs() > 1e-3).count();
    assert!(off_grid * 2 > ramp.len(), "{off_grid} of {} ramp values are off the u8 levels", ramp.len());
    // The animation from the identity: frame 0 is the sphere, the last the warp.
    let report: serde_json::Value = read_json(out.join("frames/report.json"));
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    let volume = |i: usize| frames[i]["volume"].as_f64().unwrap();
    assert!(volume(2) > volume(0) * 1.02 && volume(1) > volume(0), "volumes {frames:?}");
    let before = read_mesh(out.join("source.obj")).unwrap().bounds();
    let after = read_mesh(out.join("warped.obj")).unwrap().bounds();
    assert!(after.max.x > before.max.x + 0.1, "pole moved from {} to {}", before.max.x, after.max.x);
    assert!((after.min.x - before.min.x).abs() < 0.02, "far side stays: {} vs {}", before.min.x, after.min.x);
    // A malformed drag is one clear error line.
    let o = isomorph(&["warp", "sphere", "--drag", "1,2:3,4,5", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("three finite numbers"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn level_set_morph_takes_an_align_file_and_prints_its_report() {
    let out = scratch("align-file");
    std::fs::create_dir_all(&out).unwrap();
    let map = out.join("map.json");
    let v = align_json(&["mug", "chain", "--res", "32", "--out", out.join("aligned.ply").to_str().unwrap()]);
    std::fs::write(&map, v.to_string()).unwrap();
    let frames = out.join("frames");
    let (map_arg, frames_arg) = (map.to_str().unwrap(), frames.to_str().unwrap());
    let morph =
        ["morph", "--method", "level-set", "--source", "mug", "--target", "chain", "--align", map_arg];
    let o =
        isomorph(&[&morph[..], &["--res", "32", "--frames", "3", "--report", "--out", frames_arg]].concat());
    assert_ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is the JSON report");
    assert_eq!(report["method"], "level-set");
    assert_eq!(report["frames"].as_array().unwrap().len(), 3);
    let morph_report = &report["morph"];
    assert_eq!(morph_report["details"]["placement"], "affine", "{morph_report}");
    assert_eq!(morph_report["converged"], true, "{morph_report}");
    assert!(morph_report["iterations"].as_u64().unwrap() > 0);
    // The aligned mug ends on the chain, placed in the chain's space.
    let target = &report["endpoints"]["target"];
    assert!(target["mean_voxels"].as_f64().unwrap() < 0.5, "{target}");
    // A map file that is not affine is refused with one clear line.
    std::fs::write(&map, r#"{"matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[1,0,0,1]]}"#).unwrap();
    let o = isomorph(&[&morph[..], &["--out", frames_arg]].concat());
    assert!(!o.status.success());
    assert!(stderr(&o).contains("last row"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn warp_and_morph_take_npy_and_raw_volumes() {
    use isomorph_io::mesh::read_mesh;
    let out = scratch("warp-volumes");
    std::fs::create_dir_all(&out).unwrap();
    // An f32 distance volume with its sidecar, written by `isomorph sdf`.
    let npy = out.join("sphere.npy");
    let o = isomorph(&["sdf", "sphere", "--res", "32", "--pad", "0.2", "--out", npy.to_str().unwrap()]);
    assert_ok(&o);
    let warped = out.join("from-npy");
    let o = isomorph(&[
        "warp",
        npy.to_str().unwrap(),
        "--csize",
        "7",
        "--drag",
        "0.3,0,0:0.12,0,0",
        "--out",
        warped.to_str().unwrap(),
    ]);
    assert_ok(&o);
    let before = read_mesh(warped.join("source.obj")).unwrap().bounds();
    let after = read_mesh(warped.join("warped.obj")).unwrap().bounds();
    // The volume keeps its world placement from the sidecar.
    assert!((before.max.x - 0.3).abs() < 0.03, "source pole at {}", before.max.x);
    assert!(after.max.x > before.max.x + 0.08, "pole moved from {} to {}", before.max.x, after.max.x);
    // A u8 density cube in a headerless .raw file, in voxel units.
    let n = 24u32;
    let bytes: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let c = [i % n, (i / n) % n, i / (n * n)];
            if c.iter().all(|&v| (6..18).contains(&v)) { 255 } else { 0 }
        })
        .collect();
    let raw = out.join("cube.raw");
    std::fs::write(&raw, &bytes).unwrap();
    let moved = out.join("from-raw");
    let args = ["warp", raw.to_str().unwrap(), "--move", "3,3,3:0,0,2", "--out", moved.to_str().unwrap()];
    let o = isomorph(&[&args[..], &["--raw-dims", "24,24,24"]].concat());
    assert_ok(&o);
    assert!(moved.join("warped.npy").is_file() && moved.join("before_after.png").is_file());
    // Without dimensions, or with the wrong ones, one clear error line.
    let o = isomorph(&args);
    assert!(!o.status.success() && stderr(&o).contains("--raw-dims"));
    let o = isomorph(&[&args[..], &["--raw-dims", "24,24,23"]].concat());
    assert!(!o.status.success() && stderr(&o).contains("bytes"));
    // `morph` takes both volumes: the density cube (fitted like a mesh,
    // its level kept) into the distance-volume sphere.
    let morphed = out.join("morph");
    let args = ["morph", "--method", "level-set", "--source", raw.to_str().unwrap(), "--target"];
    let args = [&args[..], &[npy.to_str().unwrap(), "--res", "32", "--frames", "3", "--out"]].concat();
    let args = [&args[..], &[morphed.to_str().unwrap()]].concat();
    let o = isomorph(&[&args[..], &["--raw-dims", "24,24,24"]].concat());
    assert_ok(&o);
    let report: serde_json::Value = read_json(morphed.join("report.json"));
    assert_eq!(report["morph"]["converged"], true, "{report}");
    assert!(report["endpoints"]["target"]["mean_voxels"].as_f64().unwrap() < 0.5, "{report}");
    let o = isomorph(&args);
    assert!(!o.status.success() && stderr(&o).contains("--raw-dims"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn blob_polygonizes_a_scene_and_morph_takes_blobtrees() {
    let out = scratch("blob");
    std::fs::create_dir_all(&out).unwrap();
    let scene = out.join("capsule.ron");
    std::fs::write(
        &scene,
        r#"(root: (kind: "segment", vertices: [(-0.5, 0, 0), (0.5, 0, 0)], radius: 0.6))"#,
    )
    .unwrap();
    let o = isomorph(&[
        "blob",
        scene.to_str().unwrap(),
        "--res",
        "32",
        "--out",
        out.join("one").to_str().unwrap(),
    ]);
    assert_ok(&o);
    let mesh = isomorph_io::mesh::read_mesh(out.join("one/surface.ply")).unwrap();
    assert_eq!((mesh.connected_components(), mesh.genus()), (1, Some(0)));
    assert!(out.join("one/preview.png").is_file());
    // The capsule into the built-in rook, automatic correspondence.
    let frames = out.join("morph");
    let o = morph(
        "blobtree",
        scene.to_str().unwrap(),
        "rook",
        &["--res", "32", "--frames", "3", "--report", "--out", frames.to_str().unwrap()],
    );
    assert_ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["method"], "blobtree");
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        assert!(e["mean_voxels"].as_f64().unwrap() < 0.5, "{end}: {e}");
    }
    // The queen as a key shape (chain: reached at t = 0.5) and, by default,
    // as a Bézier control shape (approached, not reached).
    let queen = isomorph_blobtree::scenes::queen().mesh(32).unwrap();
    for mode in [&["--via-mode", "chain"][..], &[]] {
        let out = frames.to_str().unwrap();
        let args: [&[&str]; 2] = [
            &["--via", "queen", "--res", "32", "--frames", "3", "--no-preview", "--report", "--out", out],
            mode,
        ];
        let o = morph("blobtree", "rook", "bear", &args.concat());
        assert_ok(&o);
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(report["morph"]["details"]["key shapes"], 3, "{report}");
        let middle = isomorph_io::mesh::read_mesh(frames.join("frame_001.ply")).unwrap();
        let reached = (middle.signed_volume() - queen.signed_volume()).abs() < 0.15 * queen.signed_volume();
        let chain = !mode.is_empty();
        assert_eq!(
            report["morph"]["details"]["via mode"],
            if chain { "chain" } else { "bezier" },
            "{report}"
        );
        assert_eq!(
            reached,
            chain,
            "queen volume {} at t = 0.5: {}",
            queen.signed_volume(),
            middle.signed_volume()
        );
        if chain {
            assert_eq!(middle.genus(), queen.genus());
        }
    }
    let o = isomorph(&[
        "morph",
        "--method",
        "level-set",
        "--source",
        "sphere",
        "--via",
        "torus",
        "--target",
        "ball",
    ]);
    assert!(!o.status.success() && stderr(&o).contains("--via"));
    // Any built-in scene or links spec is dumped as the shipped file (RON) or as JSON.
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../blobtree/scenes");
    let o = isomorph(&["blob", "--dump", "rook"]);
    assert_ok(&o);
    let rook = std::fs::read_to_string(shipped.join("rook.ron")).unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim_end(), rook.trim_end());
    let o = isomorph(&["blob", "--dump", "queen", "--format", "json"]);
    let queen = isomorph_blobtree::BlobTree::from_json(&String::from_utf8_lossy(&o.stdout)).unwrap();
    assert_eq!(queen.root(), isomorph_blobtree::scenes::queen().root());
    let o = isomorph(&["blob", "--dump", "rook_queen"]);
    let links = std::fs::read_to_string(shipped.join("rook_queen.links.ron")).unwrap();
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim_end(), links.trim_end());
    let o = isomorph(&["blob", "--help"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("Scene files"));
    // A scene with a negative radius is one error line naming the node.
    std::fs::write(&scene, r#"(root: (kind: "point", vertices: [(0, 0, 0)], radius: -1.0))"#).unwrap();
    let o = isomorph(&["blob", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("radius") && err.lines().count() == 1, "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn contours_and_rbf_morph_run_and_refuse_bad_input() {
    let out = scratch("contours");
    let o = isomorph(&["contours", "x", "o", "--frames", "3", "--res", "32", "--out", out.to_str().unwrap()]);
    assert_ok(&o);
    for f in ["frame_000.png", "frame_002.png", "contact_sheet.png", "spacetime.ply", "spacetime.png"] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let o = isomorph(&["contours", "x", "no-such.png", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("no-such.png"));
    // The paper's comparison row: the distance blend writes the same
    // frames and sheet (it has no space-time surface).
    let blend = out.join("baseline");
    let args = ["contours", "x", "o", "--frames", "3", "--res", "32", "--method", "baseline", "--out"];
    let o = isomorph(&[&args[..], &[blend.to_str().unwrap()]].concat());
    assert_ok(&o);
    assert!(blend.join("frame_001.png").is_file() && !blend.join("spacetime.ply").exists());
    // RBF morph with a mesh: the bunny into the sphere, the report says rbf.
    let frames = out.join("morph");
    let o = morph(
        "rbf",
        "bunny",
        "sphere",
        &["--points", "150", "--res", "24", "--frames", "2", "--report", "--out", frames.to_str().unwrap()],
    );
    assert_ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["method"], "rbf");
    assert_eq!(report["frames"][1]["components"], 1);
    let _ = std::fs::remove_dir_all(&out);
}

/// `--landmark` pairs reach the RBF method (the paper's warped
/// transformation) as well as the volume warp, and no other method.
#[test]
fn landmarks_warp_the_rbf_transformation() {
    let out = scratch("rbf-landmarks");
    let mut args: Vec<String> = [
        "morph", "--method", "rbf", "--source", "sphere", "--target", "torus", "--frames", "3", "--res", "32",
    ]
    .map(String::from)
    .to_vec();
    for k in 0..4 {
        let a = k as f32 * std::f32::consts::FRAC_PI_2;
        let (c, s) = (a.cos(), a.sin());
        for z in [-1.0f32, 1.0] {
            let n = (1.0f32 + z * z).sqrt();
            let (p, q) = ([0.3 * c / n, 0.3 * s / n, 0.3 * z / n], [0.3 * c, 0.3 * s, 0.12 * z]);
            args.push(format!("--landmark={},{},{}:{},{},{}", p[0], p[1], p[2], q[0], q[1], q[2]));
        }
    }
    let run = |extra: &[&str]| {
        let all: Vec<&str> = args.iter().map(String::as_str).chain(extra.iter().copied()).collect();
        isomorph(&all)
    };
    let o = run(&["--out", out.to_str().unwrap()]);
    assert_ok(&o);
    let report: serde_json::Value = read_json(out.join("report.json"));
    assert_eq!(report["method"], "rbf-warp");
    assert_eq!(report["morph"]["details"]["correspondences"], 8);
    let o = morph("tspline", "sphere", "torus", &["--landmark", "0,0,0:0,0,0"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--landmark (warp, rbf, level-set)"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn reconstruct_takes_a_slices_file_and_a_folder_of_pngs() {
    use isomorph_io::mesh::read_mesh;
    use isomorph_io::render::Image;
    let out = scratch("reconstruct");
    std::fs::create_dir_all(&out).unwrap();
    // Circles of a sphere of radius 0.3 at unevenly spaced heights, and one
    // vertical great circle crossing them (§6.1).
    let circle = |r: f32, n: usize| -> Vec<[f32; 2]> {
        (0..n)
            .map(|i| i as f32 * std::f32::consts::TAU / n as f32)
            .map(|a| [r * a.cos(), r * a.sin()])
            .collect()
    };
    let mut slices: Vec<serde_json::Value> = [-0.25f32, -0.1, 0.0, 0.05, 0.2]
        .iter()
        .map(|&z| serde_json::json!({ "z": z, "polylines": [circle((0.09 - z * z).sqrt(), 24)] }))
        .collect();
    slices.push(serde_json::json!({ "origin": [0, 0, 0], "u": [1, 0, 0], "v": [0, 0, 1], "polylines": [circle(0.3, 32)] }));
    let file = out.join("sphere.json");
    std::fs::write(&file, serde_json::json!({ "slices": slices }).to_string()).unwrap();
    let surface = out.join("from-json");
    let o =
        isomorph(&["reconstruct", file.to_str().unwrap(), "--res", "48", "--out", surface.to_str().unwrap()]);
    assert_ok(&o);
    let mesh = read_mesh(surface.join("surface.ply")).unwrap();
    assert_eq!((mesh.connected_components(), mesh.genus()), (1, Some(0)));
    let size = mesh.bounds().size();
    assert!((size.x - 0.6).abs() < 0.05 && (size.z - 0.6).abs() < 0.08, "box {size}");

    // A folder of PNG slices: discs growing then shrinking, a lens.
    let pngs = out.join("pngs");
    std::fs::create_dir_all(&pngs).unwrap();
    for (k, r) in [6.0f32, 11.0, 13.0, 11.0, 6.0].into_iter().enumerate() {
        let mut image = Image::new(32, 32, [0, 0, 0]);
        for (x, y) in (0..32).flat_map(|x| (0..32).map(move |y| (x, y))) {
            if (x as f32 - 15.5).hypot(y as f32 - 15.5) < r {
                image.set(x, y, [255, 255, 255]);
            }
        }
        image.write_png(pngs.join(format!("slice_{k}.png"))).unwrap();
    }
    let lens = out.join("from-pngs");
    let o =
        isomorph(&["reconstruct", pngs.to_str().unwrap(), "--res", "40", "--out", lens.to_str().unwrap()]);
    assert_ok(&o);
    let mesh = read_mesh(lens.join("surface.ply")).unwrap();
    assert_eq!((mesh.connected_components(), mesh.genus()), (1, Some(0)));

    // A slice with two planes is one error line naming the slice.
    std::fs::write(&file, r#"{"slices": [{"z": 0, "origin": [0, 0, 0], "polylines": []}]}"#).unwrap();
    let o = isomorph(&["reconstruct", file.to_str().unwrap(), "--out", surface.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("slice 0") && err.contains("either `z`"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn usd_format_writes_one_stage_with_a_sample_per_frame() {
    let out = scratch("usd");
    let args = ["morph", "--method", "baseline", "--source", "sphere", "--target", "torus", "--res", "24"];
    let o = isomorph(
        &[&args[..], &["--frames", "3", "--format", "usd", "--no-preview", "--out", out.to_str().unwrap()]]
            .concat(),
    );
    assert_ok(&o);
    assert!(!out.join("frame_000.ply").exists() && !out.join("preview.gif").exists());
    let text = std::fs::read_to_string(out.join("morph.usda")).unwrap();
    assert!(text.starts_with("#usda 1.0") && text.contains("endTimeCode = 2"), "{}", &text[..300]);
    let report: serde_json::Value = read_json(out.join("report.json"));
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames[2]["file"], "morph.usda@2");
    // Each frame's vertex count is its sample's point count.
    let points = &text[text.find("point3f[] points.timeSamples").unwrap()..];
    for (i, frame) in frames.iter().enumerate() {
        let line = points.lines().find(|l| l.trim_start().starts_with(&format!("{i}: ["))).unwrap();
        assert_eq!(line.matches('(').count() as u64, frame["vertices"].as_u64().unwrap(), "frame {i}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn rbf_tolerance_fits_many_points_through_fewer_centres() {
    let out = scratch("rbf-greedy");
    let args = [
        "morph", "--method", "rbf", "--source", "sphere", "--target", "torus", "--res", "32", "--frames", "3",
    ];
    let greedy = ["--points", "1500", "--tolerance", "0.05", "--no-preview", "--out", out.to_str().unwrap()];
    let o = isomorph(&[&args[..], &greedy[..]].concat());
    assert_ok(&o);
    let report: serde_json::Value = read_json(out.join("report.json"));
    let morph = &report["morph"];
    assert_eq!(morph["outcome"], "converged", "{morph}");
    let centres = morph["details"]["constraints"].as_u64().unwrap();
    assert!(centres < 6000 && morph["details"]["input_constraints"] == 6000, "{morph}");
    assert!(morph["residual"]["value"].as_f64().unwrap() <= 0.05, "{morph}");
    // Without a tolerance, 25001 points are over the exact fit's limit.
    let o = isomorph(&[&args[..], &["--points", "25001", "--out", out.to_str().unwrap()]].concat());
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("points"), "{err}");
    let o = isomorph(&[&args[..], &["--tolerance", "0", "--out", out.to_str().unwrap()]].concat());
    assert!(!o.status.success() && stderr(&o).contains("tolerance"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn rbf_influence_shapes_from_the_command_line() {
    let out = scratch("rbf_influence");
    let dir = out.to_str().unwrap();
    let run = |extra: &[&str]| {
        let base = ["morph", "--source", "sphere", "--target", "torus", "--res", "24", "--frames", "3"];
        isomorph(&[&base[..], extra, &["--no-preview", "--report", "--out", dir][..]].concat())
    };
    let o = run(&["--method", "rbf", "--points", "100", "--influence", "cube"]);
    assert_ok(&o);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["morph"]["method"], "rbf-influence", "{report}");
    assert_eq!(report["morph"]["details"]["shapes"], 3, "{report}");
    for end in ["source", "target"] {
        let e = &report["endpoints"][end];
        assert!(e["mean_voxels"].as_f64().unwrap() < 0.5, "{end}: {e}");
    }
    let o = run(&[
        "--method",
        "rbf",
        "--points",
        "50",
        "--influence",
        "cube",
        "--influence",
        "ball",
        "--influence",
        "mug",
    ]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("one or two influence shapes"), "{err}");
    let o = run(&["--method", "level-set", "--influence", "cube"]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("--influence (rbf)"), "{err}");
}
