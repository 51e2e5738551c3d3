//! Replays every saved fuzz input (`fuzz/corpus/<target>/*`) through its
//! target's function in `isomorph_tests::fuzzing`, on the stable toolchain:
//! no panic, no abort, each input within a time bound and the whole replay
//! within a memory bound. `fuzz/findings/` (known failures, not yet fixed) is
//! not replayed. See `fuzz/README.md`.

use isomorph_tests::fuzzing::{self, TARGETS};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The slowest any single saved input may be, in this (debug) build.
const TIME_PER_INPUT: Duration = Duration::from_secs(10);

/// Peak resident memory of the whole replay (all targets, in parallel).
const PEAK_RSS_MB: u64 = 2048;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz")
}

fn inputs(target: &str) -> Vec<PathBuf> {
    files_in(&fuzz_dir().join("corpus").join(target))
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a corpus entry").path())
        .filter(|path| path.is_file())
        .collect();
    files.sort();
    files
}

/// Peak resident set size of this process in MiB (Linux; `None` elsewhere).
fn peak_rss_mb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024)
}

/// Runs one input through its target, within [`TIME_PER_INPUT`].
fn check(target: &str, path: &Path) {
    let data = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let start = Instant::now();
    assert!(fuzzing::run(target, &data), "unknown target {target}");
    let took = start.elapsed();
    assert!(took < TIME_PER_INPUT, "{target}: {} took {took:?}", path.display());
}

fn replay(target: &str) {
    let files = inputs(target);
    assert!(!files.is_empty(), "fuzz/corpus/{target}/ holds no inputs");
    for path in &files {
        check(target, path);
    }
    if let Some(mb) = peak_rss_mb() {
        assert!(mb < PEAK_RSS_MB, "{target}: peak RSS {mb} MiB after replaying {} inputs", files.len());
    }
}

#[test]
fn obj() {
    replay("obj");
}

#[test]
fn ply() {
    replay("ply");
}

#[test]
fn stl() {
    replay("stl");
}

#[test]
fn npy() {
    replay("npy");
}

#[test]
fn png() {
    replay("png");
}

#[test]
fn scene() {
    replay("scene");
}

#[test]
fn links() {
    replay("links");
}

#[test]
fn align_map() {
    replay("align_map");
}

#[test]
fn landmark() {
    replay("landmark");
}

/// Replays `fuzz/findings/<target>/*` (known failures: panics, or time and
/// memory beyond the bounds above) through the same checks; fails until the
/// readers are fixed, then the files move into `fuzz/corpus/`.
#[test]
#[ignore = "known failures of the readers, see fuzz/README.md"]
fn findings() {
    let mut failing = Vec::new();
    for target in TARGETS {
        let dir = fuzz_dir().join("findings").join(target);
        if dir.is_dir() {
            for path in files_in(&dir) {
                let run = std::panic::catch_unwind(|| check(target, &path));
                if run.is_err() {
                    failing.push(format!("{target}/{}", path.file_name().unwrap_or_default().display()));
                }
            }
        }
    }
    assert!(failing.is_empty(), "still failing: {failing:#?}");
}

/// Every fuzz target has a function, a replay above and a corpus, and the
/// other way round.
#[test]
fn targets_match_the_fuzz_folder() {
    let mut on_disk: Vec<String> = std::fs::read_dir(fuzz_dir().join("fuzz_targets"))
        .expect("fuzz/fuzz_targets")
        .map(|e| e.expect("an entry").path())
        .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_owned))
        .collect();
    on_disk.sort();
    let mut known: Vec<String> = TARGETS.iter().map(|s| s.to_string()).collect();
    known.sort();
    assert_eq!(on_disk, known);
    let manifest = std::fs::read_to_string(fuzz_dir().join("Cargo.toml")).expect("fuzz/Cargo.toml");
    for target in TARGETS {
        assert!(
            manifest.contains(&format!("name = \"{target}\"")),
            "{target} is not a [[bin]] of fuzz/Cargo.toml"
        );
        assert!(fuzz_dir().join("corpus").join(target).is_dir(), "no fuzz/corpus/{target}/");
    }
}

/// Writes the hand-made seed inputs into `fuzz/corpus/` (run once before
/// fuzzing a new target: `cargo test -p isomorph-tests --test fuzz_corpus --
/// --ignored write_seeds`; the fuzzer and `cargo fuzz cmin` take it from
/// there).
#[test]
#[ignore = "writes into fuzz/corpus/"]
fn write_seeds() {
    use isomorph_common::{Aabb, Grid3, Shape, TriMesh};
    use isomorph_io::mesh::{MeshFormat, write_mesh_to};

    let write = |target: &str, name: &str, bytes: &[u8]| {
        let dir = fuzz_dir().join("corpus").join(target);
        std::fs::create_dir_all(&dir).expect("corpus folder");
        std::fs::write(dir.join(format!("seed-{name}")), bytes).expect("seed file");
    };
    let tetra = TriMesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        normals: None,
        colors: None,
    };
    let mesh_bytes = |format| {
        let mut out = Vec::new();
        write_mesh_to(&tetra, &mut out, format).expect("write the tetrahedron");
        out
    };
    write("obj", "tetra.obj", &mesh_bytes(MeshFormat::Obj));
    write(
        "obj",
        "quad-normals-negative.obj",
        b"# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1//1 2//1 3//1 4//1\nf -4/1/1 -2/1/1 -1/1/1\n",
    );
    write("ply", "tetra-ascii.ply", &mesh_bytes(MeshFormat::PlyAscii));
    write("ply", "tetra-le.ply", &mesh_bytes(MeshFormat::PlyBinaryLittleEndian));
    write("ply", "tetra-be.ply", &mesh_bytes(MeshFormat::PlyBinaryBigEndian));
    write("stl", "tetra-ascii.stl", &mesh_bytes(MeshFormat::StlAscii));
    write("stl", "tetra-binary.stl", &mesh_bytes(MeshFormat::StlBinary));

    // npy: the sidecar JSON followed by the array (see `fuzzing::npy`).
    let grid = Grid3::sample_box(&Shape::sphere(0.3), &Aabb::cube(0.5), 3).expect("a small grid");
    let mut array = Vec::new();
    isomorph_io::npy::write_npy(&grid, &mut array).expect("write the npy");
    let sidecar = serde_json_text(&isomorph_io::npy::NpyMetadata::of(&grid));
    write("npy", "sphere3.npy", &array);
    write("npy", "sphere3-with-sidecar", &[sidecar.as_bytes(), &array].concat());
    let header = |descr: &str, fortran: &str, shape: &str| {
        let dict = format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}\n");
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        b.extend_from_slice(dict.as_bytes());
        b
    };
    write(
        "npy",
        "u1-fortran.npy",
        &[header("|u1", "True", "(2, 2, 2)"), vec![0, 255, 0, 255, 0, 255, 0, 255]].concat(),
    );
    write(
        "npy",
        "f8-big.npy",
        &[
            header(">f8", "False", "(1, 1, 2)"),
            1.0f64.to_be_bytes().to_vec(),
            (-1.0f64).to_be_bytes().to_vec(),
        ]
        .concat(),
    );

    // png: gray 8-bit, gray 16-bit, RGBA, palette.
    let png_bytes = |color: png::ColorType,
                     depth: png::BitDepth,
                     w: u32,
                     h: u32,
                     data: &[u8],
                     palette: Option<Vec<u8>>| {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, w, h);
        encoder.set_color(color);
        encoder.set_depth(depth);
        if let Some(p) = palette {
            encoder.set_palette(p);
        }
        let mut writer = encoder.write_header().expect("png header");
        writer.write_image_data(data).expect("png data");
        writer.finish().expect("png end");
        out
    };
    write(
        "png",
        "gray8.png",
        &png_bytes(png::ColorType::Grayscale, png::BitDepth::Eight, 3, 2, &[0, 128, 255, 255, 128, 0], None),
    );
    write(
        "png",
        "gray16.png",
        &png_bytes(png::ColorType::Grayscale, png::BitDepth::Sixteen, 2, 1, &[0, 0, 255, 255], None),
    );
    write(
        "png",
        "rgba.png",
        &png_bytes(png::ColorType::Rgba, png::BitDepth::Eight, 1, 2, &[255, 0, 0, 255, 0, 0, 255, 128], None),
    );
    write(
        "png",
        "palette2.png",
        &png_bytes(
            png::ColorType::Indexed,
            png::BitDepth::Two,
            4,
            1,
            &[0b0001_1011],
            Some(vec![0, 0, 0, 255, 255, 255, 9, 9, 9, 90, 90, 90]),
        ),
    );
    write(
        "png",
        "gray1.png",
        &png_bytes(png::ColorType::Grayscale, png::BitDepth::One, 9, 1, &[0b1010_1010, 0b1000_0000], None),
    );

    // Scenes: the smaller built-ins in both formats.
    for (name, tree) in [
        ("sphere", isomorph_blobtree::scenes::sphere()),
        ("rounded_cube", isomorph_blobtree::scenes::rounded_cube()),
        ("pierced_sphere", isomorph_blobtree::scenes::pierced_sphere()),
        ("propeller", isomorph_blobtree::scenes::propeller()),
    ] {
        write("scene", &format!("{name}.ron"), tree.to_ron().expect("ron").as_bytes());
        write("scene", &format!("{name}.json"), tree.to_json().expect("json").as_bytes());
    }

    // Links: the rook → queen spec in both formats, and a hand-written one.
    let (_, _, spec) = isomorph_blobtree::scenes::demo("rook_queen").expect("the rook_queen demo");
    write("links", "rook_queen.json", serde_json_text(&spec).as_bytes());
    write("links", "rook_queen.ron", ron_text(&spec).as_bytes());
    write(
        "links",
        "hand.ron",
        b"(links: [(a: [0], b: [1, 0])], heuristic: NearestCentre, speeds: [(a: [], b: [], speed: (start: 0.2, end: 0.8))])",
    );

    // Alignment maps as `isomorph align` prints them (the matrix is read).
    write(
        "align_map",
        "scale-translate.json",
        br#"{"mode": "affine", "matrix": [[2, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, -1], [0, 0, 0, 1]], "translation": [0.5, 0, -1], "rotation": [0, 0, 0, 1], "scale": [2, 1, 1], "output": "aligned.ply"}"#,
    );
    write(
        "align_map",
        "rotation.json",
        br#"{"matrix": [[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}"#,
    );
    write(
        "align_map",
        "singular.json",
        br#"{"matrix": [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}"#,
    );

    write("landmark", "pair", b"0.1,0.2,0.3:-0.1,0,1e-3");
    write("landmark", "spaces", b" 1 , 2 ,3 : 4,5 , 6 ");
}

fn serde_json_text<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_string_pretty(value).expect("serialize to JSON")
}

fn ron_text<T: serde::Serialize>(value: &T) -> String {
    ron::ser::to_string_pretty(value, ron::ser::PrettyConfig::default()).expect("serialize to RON")
}
