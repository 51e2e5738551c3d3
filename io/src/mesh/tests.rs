//! Cross-format tests: the real meshes, round trips, files on disk and
//! hostile input fed to every reader.

use super::*;
use glam::Vec3;
use isomorph_common::Aabb;
use proptest::prelude::*;

const ALL: [MeshFormat; 6] = [
    MeshFormat::Obj,
    MeshFormat::PlyAscii,
    MeshFormat::PlyBinaryLittleEndian,
    MeshFormat::PlyBinaryBigEndian,
    MeshFormat::StlAscii,
    MeshFormat::StlBinary,
];

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data").join(name)
}

fn bunny() -> TriMesh {
    read_mesh(data("bunny.ply")).unwrap()
}

fn tetrahedron() -> TriMesh {
    TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
    .unwrap()
}

fn to_bytes(mesh: &TriMesh, format: MeshFormat) -> Vec<u8> {
    let mut bytes = Vec::new();
    write_mesh_to(mesh, &mut bytes, format).unwrap();
    bytes
}

fn bits(points: &[Vec3]) -> Vec<[u32; 3]> {
    points.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

/// Bounding box from `mesh_stats.json` (f32 values printed as f64).
fn aabb(min: [f64; 3], max: [f64; 3]) -> Aabb {
    Aabb::new(Vec3::from_array(min.map(|v| v as f32)), Vec3::from_array(max.map(|v| v as f32)))
}

#[test]
fn bunny_matches_the_data_readme() {
    let ply = bunny();
    let obj = read_mesh(data("bunny.obj")).unwrap();
    for mesh in [&ply, &obj] {
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (1839, 3674));
        assert_eq!(
            mesh.bounds(),
            aabb(
                [-4.958475112915039, -0.003148999996483326, -3.729832887649536],
                [4.948850154876709, 9.65474796295166, 3.810638904571533]
            )
        );
        assert!(mesh.normals.is_none());
    }
    assert_eq!(bits(&ply.positions), bits(&obj.positions), "PLY and OBJ positions are bit-identical");
    assert_eq!(ply.triangles, obj.triangles);
}

#[test]
fn real_and_written_files_read_without_warnings() {
    for name in ["bunny.ply", "bunny.obj", "teapot.ply", "teapot.obj"] {
        let read = read_mesh_with_warnings(data(name)).unwrap();
        assert_eq!(read.warnings, vec![], "{name}");
        assert_eq!(read.mesh, read_mesh(data(name)).unwrap(), "{name}");
    }
    let mut mesh = bunny();
    mesh.compute_normals();
    for format in ALL {
        let read = read_mesh_from_with_warnings(&to_bytes(&mesh, format)[..], format).unwrap();
        assert_eq!(read.warnings, vec![], "{format}");
    }
}

#[test]
fn warnings_reach_the_path_reader() {
    let dir = std::env::temp_dir().join(format!("isomorph-io-warn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("dangling.obj");
    std::fs::write(&path, "v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1//1 2//1 3//1\r").unwrap();
    let read = read_mesh_with_warnings(&path).unwrap();
    assert_eq!(read.mesh.triangles, vec![[0, 1, 2]]);
    assert_eq!(read.warnings, vec![ReadWarning::ObjNormalsDropped { corners: 3, first_line: 4 }]);
    assert_eq!(read_mesh(&path).unwrap(), read.mesh);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn teapot_reads_in_both_formats() {
    let ply = read_mesh(data("teapot.ply")).unwrap();
    let obj = read_mesh(data("teapot.obj")).unwrap();
    assert_eq!((ply.positions.len(), ply.triangles.len()), (792, 992));
    assert_eq!(ply, obj);
    assert_eq!(ply.bounds(), aabb([-16.0703125, -7.875, -10.0], [16.0703125, 7.875, 10.0]));
}

/// Every triangle has the same three corner positions, bit for bit.
fn assert_same_corners(a: &TriMesh, b: &TriMesh, what: &str) {
    assert_eq!(a.triangles.len(), b.triangles.len(), "{what}");
    for t in 0..a.triangles.len() {
        assert_eq!(bits(&a.corners(t)), bits(&b.corners(t)), "{what}: triangle {t}");
    }
}

#[test]
fn every_format_round_trips_the_bunny() {
    let mesh = bunny();
    let mut with_normals = mesh.clone();
    with_normals.compute_normals();
    for format in ALL {
        let back = read_mesh_from(&to_bytes(&mesh, format)[..], format).unwrap();
        match format {
            MeshFormat::StlAscii | MeshFormat::StlBinary => {
                assert_eq!(back.positions.len(), 1839, "{format}: welding restores the vertex count");
                assert_same_corners(&back, &mesh, &format.to_string());
            }
            _ => {
                assert_eq!(bits(&back.positions), bits(&mesh.positions), "{format}");
                assert_eq!(back.triangles, mesh.triangles, "{format}");
                let back = read_mesh_from(&to_bytes(&with_normals, format)[..], format).unwrap();
                let normals = back.normals.unwrap_or_else(|| panic!("{format} keeps normals"));
                assert_eq!(bits(&normals), bits(with_normals.normals.as_ref().unwrap()), "{format}");
            }
        }
    }
}

#[test]
fn stl_welds_the_teapot_duplicates() {
    let teapot = read_mesh(data("teapot.ply")).unwrap();
    let back = read_stl(&to_bytes(&teapot, MeshFormat::StlBinary)[..]).unwrap();
    // 792 vertices of which 263 repeat a position (data README).
    assert_eq!(back.positions.len(), 529);
    assert_same_corners(&back, &teapot, "teapot");
}

#[test]
fn formats_from_paths() {
    let of = |p: &str| MeshFormat::from_path(Path::new(p));
    assert_eq!(of("a/b.OBJ"), Some(MeshFormat::Obj));
    assert_eq!(of("x.ply"), Some(MeshFormat::PlyBinaryLittleEndian));
    assert_eq!(of("x.Stl"), Some(MeshFormat::StlBinary));
    assert_eq!(of("x.off"), None);
    assert_eq!(of("ply"), None);
    for format in ALL {
        assert_eq!(
            of(&format!("m.{}", format.extension())).map(MeshFormat::extension),
            Some(format.extension())
        );
    }
}

#[test]
fn files_on_disk() {
    let dir = std::env::temp_dir().join(format!("isomorph-io-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = tetrahedron();
    for format in ALL {
        let path = dir.join(format!("tetra-{format:?}.{}", format.extension()));
        write_mesh(&mesh, &path, format).unwrap();
        let back = read_mesh(&path).unwrap();
        if format.extension() == "stl" {
            assert_same_corners(&back, &mesh, &format.to_string());
        } else {
            assert_eq!(back, mesh, "{format}");
        }
    }
    let unknown = dir.join("tetra.off");
    assert!(matches!(
        write_mesh(&mesh, dir.join("no/such/dir.obj"), MeshFormat::Obj),
        Err(MeshIoError::Io { path: Some(_), .. })
    ));
    assert!(matches!(read_mesh(&unknown), Err(MeshIoError::UnknownFormat { .. })));
    match read_mesh(dir.join("missing.ply")) {
        Err(e @ MeshIoError::Io { path: Some(_), .. }) => {
            assert!(e.to_string().contains("missing.ply"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn invalid_meshes_are_not_written() {
    let bad_index = TriMesh { positions: vec![Vec3::ZERO], triangles: vec![[0, 0, 1]], ..TriMesh::default() };
    let nan = TriMesh { positions: vec![Vec3::NAN], ..TriMesh::default() };
    for format in ALL {
        for mesh in [&bad_index, &nan] {
            let mut bytes = Vec::new();
            assert!(matches!(write_mesh_to(mesh, &mut bytes, format), Err(MeshIoError::Mesh(_))));
            assert!(bytes.is_empty());
        }
    }
}

#[test]
fn empty_mesh_round_trips() {
    for format in
        [MeshFormat::Obj, MeshFormat::PlyAscii, MeshFormat::PlyBinaryLittleEndian, MeshFormat::StlAscii]
    {
        let back = read_mesh_from(&to_bytes(&TriMesh::default(), format)[..], format).unwrap();
        assert_eq!(back, TriMesh::default(), "{format}");
    }
}

/// Whether a reader must fail on `bytes` cut to `len`: everything but OBJ
/// declares its size (OBJ may end after any complete line), except that the
/// last ASCII PLY line may lose its line break and ASCII STL may lose the
/// name after `endsolid`.
fn cut_must_fail(format: MeshFormat, bytes: &[u8], len: usize) -> bool {
    match format {
        MeshFormat::Obj => false,
        MeshFormat::PlyAscii => len + 1 < bytes.len(),
        MeshFormat::StlAscii => {
            let end = bytes.windows(8).rposition(|w| w == b"endsolid").unwrap();
            len < end + 8
        }
        _ => len < bytes.len(),
    }
}

fn check_cut(mesh: &TriMesh, format: MeshFormat, bytes: &[u8], len: usize) {
    match read_mesh_from(&bytes[..len], format) {
        Ok(back) => {
            assert!(
                !cut_must_fail(format, bytes, len),
                "{format} cut to {len} of {} bytes parsed",
                bytes.len()
            );
            back.validate().unwrap();
            assert!(
                back.positions.len() <= mesh.positions.len() && back.triangles.len() <= mesh.triangles.len()
            );
        }
        Err(MeshIoError::Io { .. }) => panic!("{format} cut to {len}: I/O error from memory"),
        Err(_) => {}
    }
}

#[test]
fn every_truncation_of_a_small_mesh_fails_cleanly() {
    let mut mesh = tetrahedron();
    mesh.compute_normals();
    for format in ALL {
        let bytes = to_bytes(&mesh, format);
        for len in 0..bytes.len() {
            check_cut(&mesh, format, &bytes, len);
        }
    }
}

#[test]
fn truncated_bunny_files_fail_cleanly() {
    let mesh = bunny();
    for format in ALL {
        let bytes = to_bytes(&mesh, format);
        // The whole header region, then a stride through the payload.
        for len in (0..400).chain((400..bytes.len()).step_by(997)) {
            check_cut(&mesh, format, &bytes, len);
        }
    }
}

/// Feeds `bytes` to every reader: no panic, and any mesh returned is valid.
fn read_everything(bytes: &[u8]) {
    for mesh in [read_obj(bytes), read_ply(bytes), read_stl(bytes)].into_iter().flatten() {
        mesh.validate().unwrap();
    }
}

/// Valid files of every format (tetrahedron with normals).
fn samples() -> Vec<Vec<u8>> {
    let mut mesh = tetrahedron();
    mesh.compute_normals();
    ALL.iter().map(|&f| to_bytes(&mesh, f)).collect()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x1507_0b1e),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        read_everything(&bytes);
    }

    #[test]
    fn binary_data_is_never_an_obj(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let control = bytes.iter().any(|&b| is_control(b));
        prop_assert!(!control || read_obj(&bytes[..]).is_err());
    }

    #[test]
    fn mutated_files_never_panic(
        sample in 0..6usize,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
    ) {
        let mut bytes = samples().swap_remove(sample);
        for (at, value) in edits {
            let at = at.index(bytes.len());
            bytes[at] = value;
        }
        read_everything(&bytes);
        read_everything(&bytes[..cut.index(bytes.len())]);
    }

    #[test]
    fn random_payloads_after_a_ply_header_never_panic(
        encoding in prop::sample::select(vec!["ascii", "binary_little_endian", "binary_big_endian"]),
        vertices in prop::sample::select(vec![0u64, 1, 3, 70, 4_000_000_000, u64::MAX]),
        faces in prop::sample::select(vec![0u64, 1, 5, 1_000_000_000_000]),
        list in prop::sample::select(vec!["uchar int", "char uint", "ushort short", "uint uchar", "int int"]),
        payload in proptest::collection::vec(any::<u8>(), 0..400),
    ) {
        let mut bytes = format!(
            "ply\nformat {encoding} 1.0\nelement vertex {vertices}\nproperty double x\nproperty float y\n\
             property int z\nelement face {faces}\nproperty list {list} vertex_indices\nend_header\n"
        )
        .into_bytes();
        bytes.extend_from_slice(&payload);
        read_everything(&bytes);
    }

    #[test]
    fn random_ascii_text_never_panics(
        text in "[ -~\n]{0,400}",
        prefix in prop::sample::select(vec!["", "solid x\n", "v 1 2 3\nf ", "ply\nformat ascii 1.0\n"]),
    ) {
        read_everything(format!("{prefix}{text}").as_bytes());
    }
}

/// The tetrahedron coloured by its positions, on the 256 PLY levels.
fn colored_tetrahedron() -> TriMesh {
    let colors: [[u8; 3]; 4] = [[255, 0, 0], [0, 128, 0], [0, 0, 7], [200, 100, 50]];
    tetrahedron().with_colors(colors.map(|c| Vec3::from_array(c.map(f32::from)) / 255.0).to_vec()).unwrap()
}

#[test]
fn colors_round_trip_through_ply_and_obj_and_are_dropped_by_stl() {
    let mesh = colored_tetrahedron();
    for format in ALL {
        let back = read_mesh_from(&to_bytes(&mesh, format)[..], format).unwrap();
        let expected = if matches!(format, MeshFormat::StlAscii | MeshFormat::StlBinary) {
            None
        } else {
            mesh.colors.clone()
        };
        assert_eq!(back.colors, expected, "{format}");
    }
    // Without colours nothing colour-like is written.
    for format in [MeshFormat::PlyAscii, MeshFormat::Obj] {
        let text = String::from_utf8(to_bytes(&tetrahedron(), format)).unwrap();
        assert!(!text.contains("red") && !text.contains("v 0 0 0 "), "{format}: {text}");
    }
}

#[test]
fn ply_colors_of_every_type_are_scaled_to_one() {
    let ply = |t: &str, values: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             property {t} red\nproperty {t} green\nproperty {t} blue\nproperty {t} alpha\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             0 0 0 {values}\n1 0 0 {values}\n0 1 0 {values}\n3 0 1 2\n"
        )
    };
    for (t, values, expected) in [
        ("uchar", "255 51 0 9", Vec3::new(1.0, 0.2, 0.0)),
        ("float", "0.25 0.5 1 0", Vec3::new(0.25, 0.5, 1.0)),
        ("double", "0.25 0.5 1 1", Vec3::new(0.25, 0.5, 1.0)),
        ("ushort", "65535 0 13107 0", Vec3::new(1.0, 0.0, 0.2)),
    ] {
        let mesh = read_mesh_from(ply(t, values).as_bytes(), MeshFormat::PlyAscii).unwrap();
        let colors = mesh.colors.expect(t);
        assert!(colors.iter().all(|c| (*c - expected).abs().max_element() < 1e-6), "{t}: {colors:?}");
    }
    let without_blue = ply("uchar", "1 2 3 4").replace("property uchar blue\n", "").replace(" 3 4", " 4");
    let mesh = read_mesh_from(without_blue.as_bytes(), MeshFormat::PlyAscii).unwrap();
    assert_eq!(mesh.colors, None, "red and green alone are no colour");
}

#[test]
fn obj_colors_are_kept_only_when_every_vertex_has_one() {
    let text = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n";
    let mesh = read_mesh_from(text.as_bytes(), MeshFormat::Obj).unwrap();
    assert_eq!(mesh.colors, Some(vec![Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, 0.5)]));
    let weighted = "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n";
    assert_eq!(read_mesh_from(weighted.as_bytes(), MeshFormat::Obj).unwrap().colors, None);
    let partial = "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n";
    let read = read_mesh_from_with_warnings(partial.as_bytes(), MeshFormat::Obj).unwrap();
    assert_eq!(read.mesh.colors, None);
    assert_eq!(
        read.warnings,
        vec![ReadWarning::ObjColorsDropped { uncolored: 1, vertices: 3, first_line: 2 }]
    );
    let nan = "v 0 0 0 1 0 0\nv 1 0 0 nan 0 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n";
    let err = read_mesh_from(nan.as_bytes(), MeshFormat::Obj).unwrap_err();
    assert!(matches!(err, MeshIoError::Mesh(MeshError::NonFiniteColor(1))), "{err}");
}

#[test]
fn colour_data_of_the_wrong_length_is_not_written() {
    let mut mesh = colored_tetrahedron();
    mesh.colors.as_mut().unwrap().pop();
    for format in ALL {
        let mut bytes = Vec::new();
        let err = write_mesh_to(&mesh, &mut bytes, format).unwrap_err();
        assert!(
            matches!(err, MeshIoError::Mesh(MeshError::ColorCount { colors: 3, vertices: 4 })),
            "{format}: {err}"
        );
        assert!(err.to_string().contains("colour data of the wrong length"), "{err}");
    }
}
