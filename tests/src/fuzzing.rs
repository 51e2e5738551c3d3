//! One function per fuzz target (`fuzz/fuzz_targets/<name>.rs` calls
//! `fuzzing::<name>`): each feeds arbitrary bytes to a reader of hostile
//! input and ignores whether it accepts them; it must not panic, abort, hang
//! or allocate without bound. `tests/tests/fuzz_corpus.rs` replays every
//! saved input of `fuzz/corpus/<name>/` through the same function on stable
//! Rust, so CI checks the corpus without nightly.
//!
//! Readers that take a path only ([`npy`] with its sidecar, [`align_map`])
//! get the bytes through scratch files of their own per thread, removed
//! after each input.

use isomorph_blobtree::{BlobTree, GenericTree, MorphSpec};
use isomorph_io::mesh::{MeshFormat, read_mesh_from};
use std::path::PathBuf;
use std::sync::OnceLock;

/// Largest grid any reader may allocate while fuzzing (the default, 8 GiB,
/// is above the fuzzer's RSS limit, so a wrong size would read as an OOM
/// rather than as the [`isomorph_common::GridError::TooLarge`] it should be).
const MEMORY_LIMIT: usize = 256 << 20;

/// The name of every target, as in `fuzz/fuzz_targets/` and `fuzz/corpus/`.
pub const TARGETS: [&str; 9] = ["obj", "ply", "stl", "npy", "png", "scene", "links", "align_map", "landmark"];

/// Runs target `name` on `data`; `false` for an unknown name.
pub fn run(name: &str, data: &[u8]) -> bool {
    match name {
        "obj" => obj(data),
        "ply" => ply(data),
        "stl" => stl(data),
        "npy" => npy(data),
        "png" => png(data),
        "scene" => scene(data),
        "links" => links(data),
        "align_map" => align_map(data),
        "landmark" => landmark(data),
        _ => return false,
    }
    true
}

fn limit_memory() {
    isomorph_common::set_memory_limit(MEMORY_LIMIT);
}

/// A scratch file of this process and thread in the temporary folder:
/// `isomorph-fuzz-<process>-<thread><suffix>` (the caller removes it).
fn scratch(suffix: &str) -> PathBuf {
    let thread = format!("{:?}", std::thread::current().id());
    let thread: String = thread.chars().filter(char::is_ascii_digit).collect();
    std::env::temp_dir().join(format!("isomorph-fuzz-{}-{thread}{suffix}", std::process::id()))
}

/// OBJ through [`read_mesh_from`] (`isomorph_io::mesh::obj::read_obj`).
pub fn obj(data: &[u8]) {
    limit_memory();
    let _ = read_mesh_from(data, MeshFormat::Obj);
}

/// PLY (ASCII or binary, detected from the header) through [`read_mesh_from`].
pub fn ply(data: &[u8]) {
    limit_memory();
    let _ = read_mesh_from(data, MeshFormat::PlyBinaryLittleEndian);
}

/// STL (ASCII or binary, detected from the content) through [`read_mesh_from`].
pub fn stl(data: &[u8]) {
    limit_memory();
    let _ = read_mesh_from(data, MeshFormat::StlBinary);
}

/// A `.npy` volume and its JSON sidecar through
/// [`isomorph_io::npy::load_npy`]: the input is the sidecar text followed by
/// the array, split at the first `\x93NUMPY` magic (no magic: all sidecar,
/// empty array; an empty sidecar part: no sidecar file). The array alone also
/// goes through the in-memory [`isomorph_io::npy::read_npy`].
pub fn npy(data: &[u8]) {
    limit_memory();
    let magic = b"\x93NUMPY";
    let split = data.windows(magic.len()).position(|w| w == magic).unwrap_or(data.len());
    let (sidecar, array) = data.split_at(split);
    let _ = isomorph_io::npy::read_npy(array, glam::Vec3::ZERO, 1.0, std::path::Path::new("fuzz.npy"));
    let npy = scratch(".npy");
    let json = isomorph_io::npy::sidecar_path(&npy);
    std::fs::write(&npy, array).expect("write the scratch .npy");
    if !sidecar.is_empty() {
        std::fs::write(&json, sidecar).expect("write the scratch sidecar");
    }
    let _ = isomorph_io::npy::load_npy(&npy);
    let _ = std::fs::remove_file(&npy);
    let _ = std::fs::remove_file(&json);
}

/// A grayscale contour image through [`isomorph_io::png_gray::decode_png_gray`].
pub fn png(data: &[u8]) {
    limit_memory();
    let _ = isomorph_io::png_gray::decode_png_gray(std::io::Cursor::new(data));
}

/// A BlobTree scene through [`BlobTree::from_ron`] and [`BlobTree::from_json`]
/// (both, on the same text); an accepted scene is written back to RON and
/// JSON and its potential evaluated at the origin.
pub fn scene(data: &[u8]) {
    limit_memory();
    let Ok(text) = std::str::from_utf8(data) else { return };
    for tree in [BlobTree::from_ron(text), BlobTree::from_json(text)].into_iter().flatten() {
        let _ = tree.to_ron();
        let _ = tree.to_json();
        let _ = tree.potential(glam::Vec3::ZERO);
    }
}

/// The built-in pair the links are applied to (`rook` → `queen`: nested
/// unions, so node paths of several depths exist).
fn link_pair() -> &'static (BlobTree, BlobTree) {
    static PAIR: OnceLock<(BlobTree, BlobTree)> = OnceLock::new();
    PAIR.get_or_init(|| (isomorph_blobtree::scenes::rook(), isomorph_blobtree::scenes::queen()))
}

/// A `--links` spec through [`MorphSpec::from_ron`] and
/// [`MorphSpec::from_json`]; an accepted spec builds the generic tree of the
/// `rook` → `queen` morph ([`GenericTree::new`]) and its tree at `t = 0.5`.
pub fn links(data: &[u8]) {
    limit_memory();
    let Ok(text) = std::str::from_utf8(data) else { return };
    let (a, b) = link_pair();
    for spec in [MorphSpec::from_ron(text), MorphSpec::from_json(text)].into_iter().flatten() {
        if let Ok(generic) = GenericTree::new(a, b, &spec) {
            let _ = generic.at(0.5);
        }
    }
}

/// An alignment map (`--align map.json`, as `isomorph align` prints it)
/// through the command line's `read_map` (a file path only, so the bytes go
/// through a scratch file).
pub fn align_map(data: &[u8]) {
    limit_memory();
    let path = scratch("-map.json");
    std::fs::write(&path, data).expect("write the scratch map");
    let _ = isomorph_cli::parse::read_map(&path);
    let _ = std::fs::remove_file(&path);
}

/// A `--landmark` / `--drag` / `--move` pair `A,B,C:D,E,F` through the
/// command line's `parse_pair`.
pub fn landmark(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let _ = isomorph_cli::parse::parse_pair(text);
}
