//! `isomorph._native`: the Python binding of the isomorph morph contract.
//!
//! It binds the contract, not each crate's internals: inputs become
//! [`Solid`]s (names and paths through the CLI's registry,
//! [`isomorph_cli::methods::load_input`]; NumPy meshes and volumes
//! directly), every method is built by [`isomorph_cli::methods::build`] as a
//! boxed [`Morph`], frames are exported by
//! [`isomorph_io::export::export_sequence`] and methods compared by
//! [`isomorph_io::compare::compare`], exactly as the `isomorph` command line
//! tool does. The Python package `isomorph` (`python/isomorph/`) re-exports
//! this module and adds `Volume` and the exception classes.
//!
//! Long operations run on a worker thread while the calling thread waits
//! without the GIL, polling Python's signal handlers every 50 ms: Ctrl-C
//! cancels the work through the contract's [`CancelToken`] and raises
//! `KeyboardInterrupt`; a `timeout` cancels it the same way and raises
//! `isomorph.Cancelled`.

use isomorph_blobtree::MorphSpec;
use isomorph_cli::methods::{LandmarkWarp, Method, Settings, build, landmark_warp, load_input};
use isomorph_cli::parse::read_map;
use isomorph_common::glam::{Affine3A, UVec3, Vec3};
use isomorph_common::{
    Aabb, BoxedError, BoxedMorph, CancelToken, Control, DynField, Field3, Grid3, Landmarks, MorphError,
    MorphFailure, Solid, TriMesh, lattice_for_box,
};
use isomorph_io::compare::{Candidate, Comparison, compare as compare_methods, error_chain};
use isomorph_io::export::{ExportError, ExportSettings, export_sequence, reference_surfaces};
use isomorph_io::inputs::LoadOptions;
use isomorph_io::mesh::MeshFormat;
use isomorph_levelset::{Align, SolverKind};
use isomorph_rbf::Kernel;
use isomorph_tspline::{Refinement, Sampler, Speed, TsplineSettings};
use isomorph_warp::WarpSpec;
use numpy::{
    PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::{Duration, Instant};

/// How often the waiting thread checks for Ctrl-C and the timeout.
const POLL: Duration = Duration::from_millis(50);

/// Frame resolution when neither the call nor the morph gives one (the
/// CLI's default).
const DEFAULT_FRAME_RESOLUTION: u32 = 64;

// ---------------------------------------------------------------- errors

/// Which Python exception an error becomes (classes of `isomorph._errors`).
#[derive(Debug, Clone, Copy)]
enum Kind {
    /// `isomorph.MorphError`: the method or an IO operation failed.
    Morph,
    /// `isomorph.InputError` (a `MorphError` and a `ValueError`): an input
    /// cannot be read or used.
    Input,
    /// `isomorph.SettingError` (a `MorphError` and a `ValueError`): a bad
    /// setting name or value.
    Setting,
    /// `isomorph.Cancelled` (a `MorphError`): cancelled by a timeout.
    Cancelled,
}

fn error(py: Python<'_>, kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    let class = match kind {
        Kind::Morph => "MorphError",
        Kind::Input => "InputError",
        Kind::Setting => "SettingError",
        Kind::Cancelled => "Cancelled",
    };
    match py.import("isomorph._errors").and_then(|m| m.getattr(class)) {
        Ok(class) => match class.call1((message.clone(),)) {
            Ok(instance) => PyErr::from_value(instance),
            Err(e) => e,
        },
        Err(_) => PyRuntimeError::new_err(message),
    }
}

fn setting_error(py: Python<'_>, name: &str, message: impl std::fmt::Display) -> PyErr {
    error(py, Kind::Setting, format!("setting '{name}': {message}"))
}

/// The exception kind of a shared morph error.
fn kind_of(shared: Option<&MorphError>) -> Kind {
    match shared {
        Some(MorphError::Cancelled) => Kind::Cancelled,
        Some(MorphError::BadSetting { .. } | MorphError::InvalidTime(_)) => Kind::Setting,
        Some(
            MorphError::InvalidInput(_)
            | MorphError::NonFinite { .. }
            | MorphError::EmptyShape { .. }
            | MorphError::InsideOut { .. }
            | MorphError::NoOverlap { .. }
            | MorphError::UnsupportedInput { .. }
            | MorphError::Mesh(_),
        ) => Kind::Input,
        _ => Kind::Morph,
    }
}

/// A shared morph error as an exception kind and message.
fn shared_kind(e: MorphError) -> (Kind, String) {
    (kind_of(Some(&e)), error_chain(&e))
}

fn morph_error(py: Python<'_>, e: &BoxedError) -> PyErr {
    error(py, kind_of(e.shared()), error_chain(e))
}

// ---------------------------------------------------------------- work

/// Runs `work` on a worker thread while this thread waits without the GIL,
/// checking Python's signal handlers and the timeout every [`POLL`]: an
/// exception from a signal handler (Ctrl-C's `KeyboardInterrupt`) or the
/// timeout cancels `token`; the work then ends early (the contract's
/// cancellation) and the signal's exception is raised. A timeout returns
/// the work's own result (a `Cancelled` error when it stopped in time).
fn run_blocking<T, F>(py: Python<'_>, token: &CancelToken, timeout: Option<f64>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> T + Send + 'static,
{
    let (tx, rx) = channel::<()>();
    let handle = std::thread::Builder::new()
        .name("isomorph".into())
        .spawn(move || {
            let result = work();
            let _ = tx.send(());
            result
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a worker thread: {e}")))?;
    let start = Instant::now();
    let limit = timeout.map(Duration::from_secs_f64);
    let mut interrupt = None;
    let mut rx = rx;
    loop {
        // The receiver is Send but not Sync: it moves into the GIL-free wait and back.
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match received {
            Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
            Err(RecvTimeoutError::Timeout) => {}
        }
        if interrupt.is_none() {
            if let Err(e) = py.check_signals() {
                token.cancel();
                interrupt = Some(e);
            } else if limit.is_some_and(|l| start.elapsed() >= l) {
                token.cancel();
            }
        }
    }
    let result = py
        .detach(|| handle.join())
        .map_err(|_| PyRuntimeError::new_err("the isomorph worker thread panicked"))?;
    match interrupt {
        Some(e) => Err(e),
        None => Ok(result),
    }
}

fn check_timeout(py: Python<'_>, timeout: Option<f64>) -> PyResult<()> {
    match timeout {
        Some(t) if !(t.is_finite() && t >= 0.0) => {
            Err(setting_error(py, "timeout", format!("expected a number of seconds >= 0, got {t}")))
        }
        _ => Ok(()),
    }
}

/// A control with `threads` (all cores when `None`) and a fresh token.
fn control_with(py: Python<'_>, threads: Option<usize>) -> PyResult<Control> {
    match threads {
        None => Ok(Control::new()),
        Some(0) => Err(setting_error(py, "threads", "expected at least 1 thread, got 0")),
        Some(n) => Control::new().with_threads(n).map_err(|e| setting_error(py, "threads", e)),
    }
}

fn fresh(control: &Control) -> (Control, CancelToken) {
    let token = CancelToken::new();
    (control.clone().with_cancel(token.clone()), token)
}

// ---------------------------------------------------------------- inputs

/// An input as given: a name or path (loaded per method, as the CLI does),
/// or a solid made from arrays.
#[derive(Clone)]
enum Input {
    Spec(String),
    Solid(Solid, String),
}

impl Input {
    fn name(&self) -> &str {
        match self {
            Input::Spec(s) => s,
            Input::Solid(_, name) => name,
        }
    }

    fn load(&self, method: Method, options: &LoadOptions) -> Result<Solid, (Kind, String)> {
        match self {
            Input::Solid(solid, _) => Ok(solid.clone()),
            Input::Spec(spec) => load_input(method, spec, options)
                .map_err(|e| (Kind::Input, format!("input {spec}: {}", error_chain(&e)))),
        }
    }
}

fn attr<'py>(obj: &Bound<'py, PyAny>, name: &str) -> Option<Bound<'py, PyAny>> {
    if let Ok(dict) = obj.cast::<PyDict>() {
        dict.get_item(name).ok().flatten()
    } else if obj.hasattr(name).unwrap_or(false) {
        obj.getattr(name).ok()
    } else {
        None
    }
}

fn contiguous<'py>(obj: &Bound<'py, PyAny>, dtype: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    let kwargs = PyDict::new(obj.py());
    kwargs.set_item("dtype", dtype)?;
    np.getattr("ascontiguousarray")?.call((obj,), Some(&kwargs))
}

fn mesh_from(py: Python<'_>, vertices: &Bound<'_, PyAny>, faces: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let bad = |m: String| error(py, Kind::Input, m);
    let v = contiguous(vertices, "float32").map_err(|e| bad(format!("vertices: {e}")))?;
    let v: PyReadonlyArray2<'_, f32> =
        v.extract().map_err(|_| bad("vertices must be a 2D array of shape (n, 3)".into()))?;
    let f = contiguous(faces, "int64").map_err(|e| bad(format!("faces: {e}")))?;
    let f: PyReadonlyArray2<'_, i64> =
        f.extract().map_err(|_| bad("faces must be a 2D integer array of shape (m, 3)".into()))?;
    if v.shape()[1] != 3 || f.shape()[1] != 3 {
        return Err(bad(format!(
            "vertices must have shape (n, 3) and faces (m, 3), got {:?} and {:?}",
            v.shape(),
            f.shape()
        )));
    }
    let vs = v.as_slice()?;
    let fs = f.as_slice()?;
    let n = v.shape()[0];
    let positions: Vec<Vec3> = vs.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let mut triangles = Vec::with_capacity(f.shape()[0]);
    for (t, tri) in fs.chunks_exact(3).enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i < 0 || i as usize >= n) {
            return Err(bad(format!("face {t} has vertex index {i}, outside 0..{n}")));
        }
        triangles.push([tri[0] as u32, tri[1] as u32, tri[2] as u32]);
    }
    TriMesh::new(positions, triangles).map_err(|e| bad(format!("invalid mesh: {}", error_chain(&e))))
}

fn volume_from(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<Solid> {
    let bad = |m: String| error(py, Kind::Input, m);
    let values = attr(obj, "values").ok_or_else(|| bad("a volume needs 'values'".into()))?;
    let values = contiguous(&values, "float32").map_err(|e| bad(format!("volume values: {e}")))?;
    let values: PyReadonlyArray3<'_, f32> =
        values.extract().map_err(|_| bad("volume values must be a 3D array indexed [k, j, i]".into()))?;
    let origin = attr(obj, "origin").ok_or_else(|| bad("a volume needs 'origin'".into()))?;
    let origin: [f32; 3] = match contiguous(&origin, "float32")?.extract::<PyReadonlyArray1<'_, f32>>() {
        Ok(a) if a.len() == 3 => {
            let s = a.as_slice()?;
            [s[0], s[1], s[2]]
        }
        _ => return Err(bad("volume origin must be three numbers (x, y, z)".into())),
    };
    let spacing: f32 = attr(obj, "spacing")
        .ok_or_else(|| bad("a volume needs 'spacing'".into()))?
        .extract()
        .map_err(|_| bad("volume spacing must be a number".into()))?;
    let iso: Option<f32> = match attr(obj, "iso") {
        Some(v) if !v.is_none() => Some(v.extract().map_err(|_| bad("volume iso must be a number".into()))?),
        _ => None,
    };
    let shape = values.shape();
    let dims = UVec3::new(shape[2] as u32, shape[1] as u32, shape[0] as u32);
    let data = values.as_slice()?.to_vec();
    let grid = Grid3::from_vec(dims, Vec3::from(origin), spacing, data)
        .map_err(|e| bad(format!("invalid volume: {}", error_chain(&e))))?;
    match iso {
        Some(iso) => Solid::level_volume(&grid, iso),
        None => Solid::volume(grid),
    }
    .map_err(|e| bad(format!("invalid volume: {}", error_chain(&e))))
}

/// A Python input as an [`Input`] (see the `morph` docs for the forms).
fn input_from(py: Python<'_>, obj: &Bound<'_, PyAny>, side: &str) -> PyResult<Input> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(Input::Spec(s));
    }
    if obj.hasattr("__fspath__")? {
        let path: PathBuf = obj.extract()?;
        return Ok(Input::Spec(path.to_string_lossy().into_owned()));
    }
    let mesh = |m: TriMesh| -> PyResult<Input> {
        let name = format!("mesh ({} vertices, {} triangles)", m.positions.len(), m.triangles.len());
        let solid =
            Solid::mesh(m).map_err(|e| error(py, Kind::Input, format!("{side}: {}", error_chain(&e))))?;
        Ok(Input::Solid(solid, name))
    };
    if let Ok(t) = obj.cast::<PyTuple>()
        && t.len() == 2
    {
        return mesh(mesh_from(py, &t.get_item(0)?, &t.get_item(1)?)?);
    }
    if let Ok(l) = obj.cast::<PyList>()
        && l.len() == 2
    {
        return mesh(mesh_from(py, &l.get_item(0)?, &l.get_item(1)?)?);
    }
    if let (Some(v), Some(f)) = (attr(obj, "vertices"), attr(obj, "faces")) {
        return mesh(mesh_from(py, &v, &f)?);
    }
    if attr(obj, "values").is_some() {
        let solid = volume_from(py, obj)?;
        let dims = solid.bounds();
        return Ok(Input::Solid(
            solid,
            format!("volume {:?}..{:?}", dims.min.to_array(), dims.max.to_array()),
        ));
    }
    Err(PyTypeError::new_err(format!(
        "{side}: expected a shape name or file path (str), a mesh as (vertices, faces) or an object with \
         .vertices and .faces, or a volume (isomorph.Volume, or a dict / object with values, origin, \
         spacing), got {}",
        obj.get_type().name()?
    )))
}

// ---------------------------------------------------------------- settings

/// Spacing of the T-spline evolution's marching-triangulation samples
/// (`sampler="marching-triangulation"`), in finest T-mesh cells.
const DEFAULT_SAMPLE_EDGE: f64 = 0.5;

/// Every keyword setting and the methods it belongs to.
const SETTINGS: &[(&str, &[Method])] = &[
    ("resolution", &Method::ALL),
    ("padding", &[Method::Baseline, Method::LevelSet, Method::Warp]),
    ("align", &[Method::LevelSet]),
    ("solver", &[Method::LevelSet]),
    ("curvature", &[Method::LevelSet]),
    ("max_iterations", &[Method::LevelSet]),
    ("points", &[Method::Rbf]),
    ("separation", &[Method::Rbf]),
    ("kernel", &[Method::Rbf]),
    ("normal_offset", &[Method::Rbf]),
    ("surface_resolution", &[Method::Rbf, Method::Tspline]),
    ("landmarks", &[Method::Rbf, Method::Warp, Method::LevelSet]),
    ("warp_spec", &[Method::Warp]),
    ("control_spacing", &[Method::Warp]),
    ("depth", &[Method::Tspline]),
    ("nt", &[Method::Tspline]),
    ("step", &[Method::Tspline]),
    ("margin", &[Method::Tspline]),
    ("speed", &[Method::Tspline]),
    ("beta_cells", &[Method::Tspline]),
    ("max_steps", &[Method::Tspline]),
    ("refine", &[Method::Tspline]),
    ("refine_rounds", &[Method::Tspline]),
    ("projection_frames", &[Method::Tspline]),
    ("sampler", &[Method::Tspline]),
    ("sample_edge", &[Method::Tspline]),
    ("stall_steps", &[Method::Tspline]),
    ("far_field_weight", &[Method::Tspline]),
    ("hold_fraction", &[Method::Tspline]),
    ("links", &[Method::Blobtree]),
];

fn method_from(py: Python<'_>, name: &str) -> PyResult<Method> {
    Method::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        setting_error(py, "method", format!("unknown method '{name}' (expected one of {})", names.join(", ")))
    })
}

fn names(methods: &[Method]) -> String {
    methods.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ")
}

fn number<'py, T: FromPyObjectOwned<'py> + PartialOrd + std::fmt::Display + Copy>(
    name: &str,
    value: &Bound<'py, PyAny>,
    what: &str,
    range: (T, T),
) -> PyResult<T> {
    let py = value.py();
    if value.is_instance_of::<pyo3::types::PyBool>() {
        return Err(setting_error(py, name, format!("expected {what}, got a bool")));
    }
    let v: T = value.extract().map_err(|_| {
        let shown = value.repr().map(|r| r.to_string()).unwrap_or_default();
        setting_error(py, name, format!("expected {what}, got {shown}"))
    })?;
    if !(v >= range.0 && v <= range.1) {
        return Err(setting_error(
            py,
            name,
            format!("{v} is out of range: expected {} to {}", range.0, range.1),
        ));
    }
    Ok(v)
}

fn choice(name: &str, value: &Bound<'_, PyAny>, choices: &[&str]) -> PyResult<String> {
    let py = value.py();
    let expected = || {
        format!("expected one of {}", choices.iter().map(|c| format!("'{c}'")).collect::<Vec<_>>().join(", "))
    };
    let s: String = value.extract().map_err(|_| setting_error(py, name, expected()))?;
    if choices.contains(&s.as_str()) {
        Ok(s)
    } else {
        Err(setting_error(py, name, format!("'{s}' is not valid: {}", expected())))
    }
}

fn optional<'py, T>(
    value: &Bound<'py, PyAny>,
    f: impl FnOnce(&Bound<'py, PyAny>) -> PyResult<T>,
) -> PyResult<Option<T>> {
    if value.is_none() { Ok(None) } else { f(value).map(Some) }
}

/// Applies the keyword `settings` to `settings` for `methods`; a setting
/// that belongs to none of them, or an unknown one, is a `SettingError`.
fn apply_settings(
    py: Python<'_>,
    kwargs: Option<&Bound<'_, PyDict>>,
    methods: &[Method],
    resolution: Option<u32>,
    names_pair: (&str, &str),
) -> PyResult<Settings> {
    let mut s = Settings::default();
    if let Some(res) = resolution {
        s = s.with_resolution(res);
    }
    s.blobtree.spec = isomorph_blobtree::scenes::demo_spec(names_pair.0, names_pair.1).unwrap_or_default();
    let Some(kwargs) = kwargs else { return Ok(s) };
    let mut refine = None;
    let mut refine_rounds = 3usize;
    let mut triangulation_samples = false;
    let mut sample_edge = DEFAULT_SAMPLE_EDGE;
    let mut beta_cells = None;
    for (key, value) in kwargs.iter() {
        let name: String = key.extract()?;
        let Some((_, owners)) = SETTINGS.iter().find(|(n, _)| *n == name) else {
            let known: Vec<&str> = SETTINGS.iter().map(|(n, _)| *n).collect();
            return Err(setting_error(
                py,
                &name,
                format!("unknown setting (settings are: {})", known.join(", ")),
            ));
        };
        if !owners.iter().any(|o| methods.contains(o)) {
            return Err(setting_error(
                py,
                &name,
                format!("applies to {}, not to {}", names(owners), names(methods)),
            ));
        }
        let v = &value;
        match name.as_str() {
            "resolution" => s = s.with_resolution(number(&name, v, "an integer", (8u32, 1024))?),
            "padding" => {
                let p = number(&name, v, "a number", (0.0f32, 10.0))?;
                s.baseline.padding = p;
                s.level_set.padding = p;
                s.warp.padding = p;
            }
            "align" => {
                s.level_set.align = match v.extract::<String>() {
                    Ok(a) if a == "none" => Align::None,
                    Ok(a) if a == "auto" => Align::Auto,
                    Ok(a) if a.ends_with(".json") => Align::Map(
                        read_map(std::path::Path::new(&a))
                            .map_err(|e| setting_error(py, &name, format!("{e:#}")))?,
                    ),
                    _ => {
                        return Err(setting_error(
                            py,
                            &name,
                            "expected 'none', 'auto' or the path of a .json map as `isomorph align` writes it",
                        ));
                    }
                }
            }
            "solver" => {
                s.level_set.solver = match choice(&name, v, &["sparse", "dense"])?.as_str() {
                    "dense" => SolverKind::Dense,
                    _ => SolverKind::SparseField,
                }
            }
            "curvature" => {
                s.level_set.curvature = optional(v, |v| number(&name, v, "a number", (0.0f32, 100.0)))?
            }
            "max_iterations" => {
                s.level_set.max_iterations = number(&name, v, "an integer", (1usize, 10_000_000))?
            }
            "points" => s.rbf.points = number(&name, v, "an integer", (1usize, 1_000_000))?,
            "separation" => s.rbf.separation = number(&name, v, "a number", (f32::MIN_POSITIVE, 1e6))?,
            "kernel" => {
                s.rbf.kernel = match choice(&name, v, &["tps", "r3"])?.as_str() {
                    "r3" => Kernel::Cubic,
                    _ => Kernel::ThinPlate,
                }
            }
            "normal_offset" => s.rbf.normal_offset = number(&name, v, "a number", (0.0f32, 1e6))?,
            "surface_resolution" => {
                let r = number(&name, v, "an integer", (8u32, 1024))?;
                if methods.contains(&Method::Rbf) {
                    s.rbf.surface_resolution = r;
                }
                s.tspline.surface_resolution = r;
            }
            "landmarks" => {
                let pairs: Vec<([f32; 3], [f32; 3])> = v.extract().map_err(|_| {
                    setting_error(py, &name, "expected a list of ((x, y, z), (x, y, z)) source/target pairs")
                })?;
                let pairs: Vec<(Vec3, Vec3)> = pairs.into_iter().map(|(a, b)| (a.into(), b.into())).collect();
                if !pairs.is_empty() {
                    s.warp.spec = WarpSpec::Landmarks(pairs.clone());
                    if methods.contains(&Method::LevelSet) {
                        // Breen & Whitaker §6.2: the level set evolves towards
                        // the target seen through the RBF warp of the pairs.
                        let warp = Landmarks::new(&pairs).map_err(|e| setting_error(py, &name, e)).and_then(
                            |l| {
                                landmark_warp(&l, LandmarkWarp::Rbf, s.warp.control_spacing)
                                    .map_err(|e| setting_error(py, &name, error_chain(&e)))
                            },
                        )?;
                        s.level_set.align = Align::Warp(warp);
                    }
                }
                s.rbf_correspondences = pairs;
            }
            "warp_spec" => {
                if !matches!(s.warp.spec, WarpSpec::Landmarks(_)) {
                    s.warp.spec = match choice(&name, v, &["identity", "align"])?.as_str() {
                        "identity" => WarpSpec::Identity,
                        _ => WarpSpec::Align,
                    };
                }
            }
            "control_spacing" => s.warp.control_spacing = number(&name, v, "an integer", (1u32, 1024))?,
            "depth" => s.tspline.tmesh.max_depth = number(&name, v, "an integer", (1u32, 7))?,
            "nt" => {
                s.tspline.tmesh.max_samples_per_cell = number(&name, v, "an integer", (1usize, 1_000_000))?
            }
            "step" => {
                s.tspline.evolve.step =
                    optional(v, |v| number(&name, v, "a number", (f64::MIN_POSITIVE, 1e3)))?
            }
            "margin" => s.tspline.margin = number(&name, v, "a number", (0.0f64, 10.0))?,
            "speed" => {
                s.tspline.evolve.speed = match choice(&name, v, &["paper", "distance", "robust"])?.as_str() {
                    "paper" => Speed::Paper,
                    "distance" => Speed::Distance,
                    _ => TsplineSettings::default().evolve.speed,
                }
            }
            "beta_cells" => beta_cells = Some(number(&name, v, "a number", (0.0f64, Speed::MAX_BETA_CELLS))?),
            "max_steps" => s.tspline.evolve.max_steps = number(&name, v, "an integer", (1usize, 10_000_000))?,
            "refine" => refine = optional(v, |v| number(&name, v, "a number", (f64::MIN_POSITIVE, 1e3)))?,
            "refine_rounds" => refine_rounds = number(&name, v, "an integer", (1usize, 1000))?,
            "projection_frames" => {
                s.tspline.projection_frames =
                    v.extract().map_err(|_| setting_error(py, &name, "expected True or False"))?
            }
            "sampler" => {
                triangulation_samples = choice(&name, v, &["marching-cubes", "marching-triangulation"])?
                    == "marching-triangulation"
            }
            "sample_edge" => sample_edge = number(&name, v, "a number", (0.05f64, 4.0))?,
            "stall_steps" => {
                s.tspline.evolve.stall_steps = number(&name, v, "an integer", (1usize, 1_000_000_000))?
            }
            "far_field_weight" => {
                s.tspline.evolve.far_field_weight = number(&name, v, "a number", (0.0f64, 1e6))?
            }
            "hold_fraction" => s.tspline.evolve.hold_fraction = number(&name, v, "a number", (0.0f64, 1.0))?,
            "links" => {
                let path: PathBuf =
                    v.extract().map_err(|_| setting_error(py, &name, "expected a file path"))?;
                s.blobtree.spec = MorphSpec::load(&path).map_err(|e| {
                    setting_error(py, &name, format!("{}: {}", path.display(), error_chain(&e)))
                })?;
            }
            other => unreachable!("setting {other} is listed but not applied"),
        }
    }
    s.tspline.fit.refinement = refine.map(|tolerance| Refinement { tolerance, max_rounds: refine_rounds });
    if let Some(beta) = beta_cells {
        if !matches!(s.tspline.evolve.speed, Speed::Robust { .. }) {
            return Err(setting_error(
                py,
                "beta_cells",
                "is the robust speed's: give it with speed='robust'",
            ));
        }
        s.tspline.evolve.speed = Speed::robust(beta);
    }
    if triangulation_samples {
        s.tspline.evolve.sampler = Sampler::MarchingTriangulation { edge_cells: sample_edge };
    }
    Ok(s)
}

/// The default value of setting `name` as Python sees it.
fn default_of<'py>(py: Python<'py>, name: &str, s: &Settings, method: Method) -> PyResult<Bound<'py, PyAny>> {
    Ok(match name {
        "resolution" => match method {
            Method::Baseline => s.baseline.resolution.into_pyobject(py)?.into_any(),
            Method::LevelSet => s.level_set.resolution.into_pyobject(py)?.into_any(),
            Method::Warp => s.warp.resolution.into_pyobject(py)?.into_any(),
            _ => py.None().into_bound(py),
        },
        "padding" => match method {
            Method::Baseline => s.baseline.padding.into_pyobject(py)?.into_any(),
            Method::LevelSet => s.level_set.padding.into_pyobject(py)?.into_any(),
            _ => s.warp.padding.into_pyobject(py)?.into_any(),
        },
        "align" => "none".into_pyobject(py)?.into_any(),
        "solver" => "sparse".into_pyobject(py)?.into_any(),
        "curvature" => s.level_set.curvature.into_pyobject(py)?.into_any(),
        "max_iterations" => s.level_set.max_iterations.into_pyobject(py)?.into_any(),
        "points" => s.rbf.points.into_pyobject(py)?.into_any(),
        "separation" => s.rbf.separation.into_pyobject(py)?.into_any(),
        "kernel" => match s.rbf.kernel {
            Kernel::Cubic => "r3",
            _ => "tps",
        }
        .into_pyobject(py)?
        .into_any(),
        "normal_offset" => s.rbf.normal_offset.into_pyobject(py)?.into_any(),
        "surface_resolution" => match method {
            Method::Rbf => s.rbf.surface_resolution.into_pyobject(py)?.into_any(),
            _ => s.tspline.surface_resolution.into_pyobject(py)?.into_any(),
        },
        "landmarks" => PyList::empty(py).into_any(),
        "warp_spec" => "align".into_pyobject(py)?.into_any(),
        "control_spacing" => s.warp.control_spacing.into_pyobject(py)?.into_any(),
        "depth" => s.tspline.tmesh.max_depth.into_pyobject(py)?.into_any(),
        "nt" => s.tspline.tmesh.max_samples_per_cell.into_pyobject(py)?.into_any(),
        "step" => s.tspline.evolve.step.into_pyobject(py)?.into_any(),
        "margin" => s.tspline.margin.into_pyobject(py)?.into_any(),
        "speed" => "robust".into_pyobject(py)?.into_any(),
        "beta_cells" => match s.tspline.evolve.speed {
            Speed::Robust { beta_cells, .. } => beta_cells.into_pyobject(py)?.into_any(),
            _ => py.None().into_bound(py),
        },
        "max_steps" => s.tspline.evolve.max_steps.into_pyobject(py)?.into_any(),
        "refine" => py.None().into_bound(py),
        "refine_rounds" => 3usize.into_pyobject(py)?.into_any(),
        "projection_frames" => {
            pyo3::types::PyBool::new(py, s.tspline.projection_frames).to_owned().into_any()
        }
        "sampler" => "marching-cubes".into_pyobject(py)?.into_any(),
        "sample_edge" => DEFAULT_SAMPLE_EDGE.into_pyobject(py)?.into_any(),
        "stall_steps" => s.tspline.evolve.stall_steps.into_pyobject(py)?.into_any(),
        "far_field_weight" => s.tspline.evolve.far_field_weight.into_pyobject(py)?.into_any(),
        "hold_fraction" => s.tspline.evolve.hold_fraction.into_pyobject(py)?.into_any(),
        "links" => py.None().into_bound(py),
        _ => py.None().into_bound(py),
    })
}

/// defaults(method)
/// --
///
/// The keyword settings of `method` and their defaults (the Rust
/// libraries' `Default`s; `None` where the library chooses by itself, e.g.
/// the T-spline step, or where a setting is off by default).
#[pyfunction]
fn defaults<'py>(py: Python<'py>, method: &str) -> PyResult<Bound<'py, PyDict>> {
    let m = method_from(py, method)?;
    let s = Settings::default();
    let out = PyDict::new(py);
    for (name, owners) in SETTINGS {
        if owners.contains(&m) {
            out.set_item(*name, default_of(py, name, &s, m)?)?;
        }
    }
    Ok(out)
}

/// methods()
/// --
///
/// The names of the morph methods, in the order of the comparison tables.
#[pyfunction]
fn methods() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}

// ---------------------------------------------------------------- morph

fn json_to_py<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

fn load_options(fit: bool, iso: Option<f32>) -> LoadOptions {
    LoadOptions { fit, iso, raw: None }
}

/// The frame file format and whether the sequence is one USD stage
/// instead (`"usd"`: `morph.usda`, no frame files).
fn mesh_format(py: Python<'_>, format: &str) -> PyResult<(MeshFormat, bool)> {
    Ok(match format {
        "ply" => (MeshFormat::PlyBinaryLittleEndian, false),
        "obj" => (MeshFormat::Obj, false),
        "stl" => (MeshFormat::StlBinary, false),
        "usd" => (MeshFormat::PlyBinaryLittleEndian, true),
        other => {
            return Err(setting_error(
                py,
                "format",
                format!("'{other}' is not valid: expected 'ply', 'obj', 'stl' or 'usd'"),
            ));
        }
    })
}

fn check_resolution(py: Python<'_>, name: &str, res: u32) -> PyResult<u32> {
    if (2..=2048).contains(&res) {
        Ok(res)
    } else {
        Err(setting_error(py, name, format!("{res} is out of range: expected 2 to 2048")))
    }
}

/// A frame's field placed in the world, minus its iso value.
struct Placed<'a> {
    field: &'a DynField,
    inverse: Affine3A,
    iso: f32,
}

impl Field3 for Placed<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.field.value(self.inverse.transform_point3(p)) - self.iso
    }

    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        let mapped: Vec<Vec3> = points.iter().map(|&p| self.inverse.transform_point3(p)).collect();
        self.field.values(&mapped, out);
        for v in out.iter_mut() {
            *v -= self.iso;
        }
    }
}

/// A morph from a source to a target: frames as meshes and volumes, its
/// report, and the exporter. Made by `isomorph.morph`.
#[pyclass(module = "isomorph", name = "Morph", frozen)]
struct PyMorph {
    morph: Arc<BoxedMorph>,
    control: Control,
    inputs: (Solid, Solid),
    names: (String, String),
    resolution: Option<u32>,
}

impl PyMorph {
    fn frame_res(&self, py: Python<'_>, resolution: Option<u32>) -> PyResult<u32> {
        check_resolution(py, "resolution", resolution.or(self.resolution).unwrap_or(DEFAULT_FRAME_RESOLUTION))
    }
}

#[pymethods]
impl PyMorph {
    /// The method's name (`"level-set"`, ...).
    #[getter]
    fn method(&self) -> &'static str {
        self.morph.method()
    }

    /// The method's report (`MorphReport` as a dict: outcome, converged,
    /// iterations, residual, rcond, stages, stored_bytes, peak_bytes,
    /// warnings, details), as `report.json` holds it under `"morph"`.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, self.morph.report())
    }

    /// A box in world space containing every frame mesh: `((xmin, ymin,
    /// zmin), (xmax, ymax, zmax))`.
    #[getter]
    fn world_bounds(&self) -> ((f32, f32, f32), (f32, f32, f32)) {
        let b = self.morph.world_bounds();
        ((b.min.x, b.min.y, b.min.z), (b.max.x, b.max.y, b.max.z))
    }

    /// The source and target as given (names, paths or a short description
    /// of array inputs).
    #[getter]
    fn inputs(&self) -> (String, String) {
        self.names.clone()
    }

    /// frame_mesh(t, resolution=None)
    /// --
    ///
    /// The frame at `t` in [0, 1] as a world-space, outward triangle mesh:
    /// `(vertices float32[n, 3], faces int64[m, 3])`. `resolution` is the
    /// number of nodes along the longest edge of the morph's bounds (default:
    /// the morph's `resolution`, else 64); grid methods (baseline, level
    /// set, warp) polygonize their own lattice whatever it is.
    #[pyo3(signature = (t, resolution = None))]
    fn frame_mesh<'py>(
        &self,
        py: Python<'py>,
        t: f32,
        resolution: Option<u32>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let res = self.frame_res(py, resolution)?;
        let morph = self.morph.clone();
        let control = self.control.clone();
        let mesh = py.detach(move || control.install(|| morph.frame_mesh(t, res)));
        let mesh = mesh.map_err(|e| morph_error(py, &e))?;
        mesh_arrays(py, mesh)
    }

    /// frame_volume(t, resolution=None)
    /// --
    ///
    /// The frame at `t` sampled on a world-space grid, as an
    /// `isomorph.Volume`: `values` float32 indexed `[k, j, i]` (z, y, x; x
    /// varies fastest, like the `.npy` volumes), the node `(i, j, k)` at
    /// `origin + spacing * (i, j, k)`; values are the frame's field minus
    /// its iso value: positive inside, zero on the surface (signed
    /// distances for the distance-based methods, other scales otherwise).
    /// The grid covers `world_bounds` grown by 5 % of its longest edge per
    /// side, with `resolution` nodes along the longest edge (default: the
    /// morph's `resolution`, else 64).
    #[pyo3(signature = (t, resolution = None))]
    fn frame_volume<'py>(
        &self,
        py: Python<'py>,
        t: f32,
        resolution: Option<u32>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let res = self.frame_res(py, resolution)?;
        let morph = self.morph.clone();
        let control = self.control.clone();
        let grid = py.detach(move || -> Result<Grid3<f32>, BoxedError> {
            control.install(|| {
                let frame = morph.frame(t)?;
                let b = morph.world_bounds();
                let margin = Vec3::splat(0.05 * b.size().max_element());
                let bounds = Aabb { min: b.min - margin, max: b.max + margin };
                let (dims, origin, spacing) = lattice_for_box(&bounds, res).map_err(MorphError::from)?;
                let placed =
                    Placed { field: &frame.field, inverse: frame.transform.inverse(), iso: frame.iso };
                Ok(Grid3::sample(&placed, dims, origin, spacing).map_err(MorphError::from)?)
            })
        });
        let grid = grid.map_err(|e| morph_error(py, &e))?;
        let (dims, origin, spacing) = (grid.dims(), grid.origin(), grid.spacing());
        let values = PyArray1::from_vec(py, grid.into_data()).reshape([
            dims.z as usize,
            dims.y as usize,
            dims.x as usize,
        ])?;
        py.import("isomorph")?.getattr("Volume")?.call1((values, origin.to_array(), spacing))
    }

    /// export(dir, frames=9, resolution=None, format="ply", timeout=None)
    /// --
    ///
    /// Writes what `isomorph morph --out DIR` writes: `frame_NNN.ply` (or
    /// `.obj`, `.stl`), `contact_sheet.png` and `report.json` (frames at
    /// `t = i / (frames - 1)`, endpoint distances to the inputs), and
    /// returns `report.json`'s contents as a dict.
    #[pyo3(signature = (dir, frames = 9, resolution = None, format = "ply", timeout = None))]
    fn export<'py>(
        &self,
        py: Python<'py>,
        dir: PathBuf,
        frames: usize,
        resolution: Option<u32>,
        format: &str,
        timeout: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let res = self.frame_res(py, resolution)?;
        let (format, usd) = mesh_format(py, format)?;
        check_timeout(py, timeout)?;
        if !(2..=1000).contains(&frames) {
            return Err(setting_error(py, "frames", format!("{frames} is out of range: expected 2 to 1000")));
        }
        let (control, token) = fresh(&self.control);
        let morph = self.morph.clone();
        let inputs = self.inputs.clone();
        let result = run_blocking(py, &token, timeout, move || -> Result<_, (Kind, String)> {
            let (source, target) =
                reference_surfaces(&inputs.0, &inputs.1, res, &control).map_err(shared_kind)?;
            let settings = ExportSettings {
                frames,
                resolution: res,
                out_dir: dir,
                format,
                frame_files: !usd,
                usd,
                source_reference: Some(source),
                target_reference: Some(target),
                ..ExportSettings::default()
            };
            export_sequence(&**morph, &settings, &control).map_err(|e| match e {
                ExportError::Cancelled(c) => shared_kind(c),
                other => (Kind::Morph, error_chain(&other)),
            })
        })?;
        let exported = result.map_err(|(k, m)| error(py, k, m))?;
        json_to_py(py, &exported.report)
    }

    fn __repr__(&self) -> String {
        let r = self.morph.report();
        format!(
            "<isomorph.Morph {} {} -> {}: {:?} in {:.2} s>",
            self.morph.method(),
            self.names.0,
            self.names.1,
            r.outcome,
            r.total_seconds()
        )
    }
}

fn mesh_arrays<'py>(py: Python<'py>, mesh: TriMesh) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let (n, m) = (mesh.positions.len(), mesh.triangles.len());
    let mut v = Vec::with_capacity(3 * n);
    for p in &mesh.positions {
        v.extend_from_slice(&p.to_array());
    }
    let mut f = Vec::with_capacity(3 * m);
    for t in &mesh.triangles {
        f.extend(t.iter().map(|&i| i64::from(i)));
    }
    let vertices = PyArray1::from_vec(py, v).reshape([n, 3])?.into_any();
    let faces = PyArray1::from_vec(py, f).reshape([m, 3])?.into_any();
    Ok((vertices, faces))
}

/// morph(source, target, method="level-set", resolution=None, threads=None, fit=True, iso=None, timeout=None, **settings)
/// --
///
/// Builds the morph of `source` into `target` with `method` (see
/// `isomorph.methods()`); see the package docs for inputs and settings.
#[pyfunction]
#[pyo3(signature = (source, target, method = "level-set", resolution = None, threads = None, fit = true, iso = None, timeout = None, **settings))]
#[allow(clippy::too_many_arguments)]
fn morph(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    target: &Bound<'_, PyAny>,
    method: &str,
    resolution: Option<u32>,
    threads: Option<usize>,
    fit: bool,
    iso: Option<f32>,
    timeout: Option<f64>,
    settings: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyMorph> {
    let method = method_from(py, method)?;
    if let Some(r) = resolution
        && !(8..=1024).contains(&r)
    {
        return Err(setting_error(py, "resolution", format!("{r} is out of range: expected 8 to 1024")));
    }
    check_timeout(py, timeout)?;
    let source = input_from(py, source, "source")?;
    let target = input_from(py, target, "target")?;
    let names = (source.name().to_string(), target.name().to_string());
    let settings = apply_settings(py, settings, &[method], resolution, (&names.0, &names.1))?;
    let control = control_with(py, threads)?;
    let options = load_options(fit, iso);
    let (s, t) = (
        source.load(method, &options).map_err(|(k, m)| error(py, k, m))?,
        target.load(method, &options).map_err(|(k, m)| error(py, k, m))?,
    );
    let (run_control, token) = fresh(&control);
    let inputs = (s.clone(), t.clone());
    let built = run_blocking(py, &token, timeout, move || build(method, &s, &t, &settings, &run_control))?;
    let morph = built.map_err(|e| morph_error(py, &e))?;
    Ok(PyMorph { morph: Arc::new(morph), control, inputs, names, resolution })
}

/// compare(source, target, methods=None, resolution=None, frames=9, out=None, threads=None, fit=True, iso=None, format="ply", timeout=None, **settings)
/// --
///
/// Runs `methods` (default: all) on one pair as `isomorph compare` does and
/// returns the comparison table as a list of dicts (one per method).
#[pyfunction]
#[pyo3(signature = (source, target, methods = None, resolution = None, frames = 9, out = None, threads = None, fit = true, iso = None, format = "ply", timeout = None, **settings))]
#[allow(clippy::too_many_arguments)]
fn compare<'py>(
    py: Python<'py>,
    source: &Bound<'py, PyAny>,
    target: &Bound<'py, PyAny>,
    methods: Option<Vec<String>>,
    resolution: Option<u32>,
    frames: usize,
    out: Option<PathBuf>,
    threads: Option<usize>,
    fit: bool,
    iso: Option<f32>,
    format: &str,
    timeout: Option<f64>,
    settings: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let list: Vec<Method> = match methods {
        None => Method::ALL.to_vec(),
        Some(names) => {
            let mut list = Vec::new();
            for n in names {
                let m = method_from(py, &n)?;
                if !list.contains(&m) {
                    list.push(m);
                }
            }
            list
        }
    };
    if list.is_empty() {
        return Err(setting_error(py, "methods", "expected at least one method"));
    }
    if let Some(r) = resolution
        && !(8..=1024).contains(&r)
    {
        return Err(setting_error(py, "resolution", format!("{r} is out of range: expected 8 to 1024")));
    }
    if !(2..=1000).contains(&frames) {
        return Err(setting_error(py, "frames", format!("{frames} is out of range: expected 2 to 1000")));
    }
    check_timeout(py, timeout)?;
    let (format, usd) = mesh_format(py, format)?;
    let source = input_from(py, source, "source")?;
    let target = input_from(py, target, "target")?;
    let names = (source.name().to_string(), target.name().to_string());
    let settings = apply_settings(py, settings, &list, resolution, (&names.0, &names.1))?;
    let control = control_with(py, threads)?;
    let (control, token) = fresh(&control);
    let options = load_options(fit, iso);
    let res = resolution.unwrap_or(DEFAULT_FRAME_RESOLUTION);
    let (temporary, dir) = match out {
        Some(dir) => (false, dir),
        None => (
            true,
            std::env::temp_dir().join(format!(
                "isomorph-compare-{}-{}",
                std::process::id(),
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos())
            )),
        ),
    };
    let out_dir = dir.clone();
    let result = run_blocking(py, &token, timeout, move || -> Result<Comparison, (Kind, String)> {
        // The shared references: the inputs as the non-BlobTree methods read them.
        let shared = match (source.load(Method::Baseline, &options), target.load(Method::Baseline, &options))
        {
            (Ok(s), Ok(t)) => (s, t),
            _ => (source.load(Method::Blobtree, &options)?, target.load(Method::Blobtree, &options)?),
        };
        let (src_ref, tgt_ref) =
            reference_surfaces(&shared.0, &shared.1, res, &control).map_err(shared_kind)?;
        let export = ExportSettings {
            frames,
            resolution: res,
            out_dir,
            format,
            frame_files: !usd,
            usd,
            source_reference: Some(src_ref),
            target_reference: Some(tgt_ref),
            ..ExportSettings::default()
        };
        let mut candidates = Vec::new();
        for method in list {
            let name = method.name().to_string();
            let inputs = match (source.load(method, &options), target.load(method, &options)) {
                (Ok(s), Ok(t)) => (s, t),
                (Err((_, e)), _) | (_, Err((_, e))) => {
                    candidates.push(Candidate { name, build: Err(e), references: None });
                    continue;
                }
            };
            let references = if method == Method::Blobtree {
                Some(reference_surfaces(&inputs.0, &inputs.1, res, &control).map_err(shared_kind)?)
            } else {
                None
            };
            let settings = settings.clone();
            candidates.push(Candidate {
                name,
                build: Ok(Box::new(move |control: &Control| {
                    build(method, &inputs.0, &inputs.1, &settings, control)
                })),
                references,
            });
        }
        compare_methods(source.name(), target.name(), candidates, &export, &control).map_err(|e| match e {
            isomorph_io::compare::CompareError::Cancelled => (Kind::Cancelled, "cancelled".to_string()),
            other => (Kind::Morph, error_chain(&other)),
        })
    });
    if temporary {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let comparison = result?.map_err(|(k, m)| error(py, k, m))?;
    json_to_py(py, &comparison.rows)
}

/// The isomorph morph contract from Python (see the `isomorph` package).
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMorph>()?;
    m.add_function(wrap_pyfunction!(morph, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
