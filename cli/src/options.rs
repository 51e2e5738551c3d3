//! The method options of `isomorph morph` and `isomorph compare`, grouped
//! by method in `--help`, with the libraries' defaults; each applies to its
//! method's settings, and giving an option of another method is an error.

use anyhow::{Context, bail};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, ValueEnum};
use isomorph_blobtree::MorphSpec;
use isomorph_cli::methods::{Method, Settings};
use isomorph_common::glam::{Affine3A, Mat4, Vec3};
use isomorph_levelset::{Align, LevelSetSettings, SolverKind};
use isomorph_rbf::{Kernel, RbfSettings};
use isomorph_tspline::{Speed, TsplineSettings};
use isomorph_warp::{WarpMorphSettings, WarpSpec};
use std::path::{Path, PathBuf};

/// Method options (each belongs to one method).
#[derive(Debug, Clone, Args)]
pub struct MethodArgs {
    /// Alignment of the source onto the target before evolving: `auto`
    /// (moments), `none`, or a JSON map file as `isomorph align` prints it.
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", value_parser = parse_align, default_value = "none")]
    pub align: AlignArg,
    /// The level-set solver.
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", value_enum, default_value_t = SolverArg::Sparse)]
    pub solver: SolverArg,
    /// Weight of a mean-curvature term that smooths the surface away from
    /// the target (off when not given).
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", value_parser = parse_weight)]
    pub curvature: Option<f32>,
    /// Most evolution iterations.
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", default_value_t = LevelSetSettings::default().max_iterations)]
    pub max_iterations: usize,

    /// Surface points per shape (each a boundary and a normal constraint).
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", default_value_t = RbfSettings::default().points)]
    pub points: usize,
    /// Separation of the shapes along the fourth axis (world units).
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", default_value_t = RbfSettings::default().separation)]
    pub separation: f32,
    /// The radial kernel.
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", value_enum, default_value_t = KernelArg::from(RbfSettings::default().kernel))]
    pub kernel: KernelArg,

    /// How the source is carried onto the target: `identity` (a plain
    /// cross-dissolve) or `align` (moment alignment as a B-spline warp);
    /// `--landmark` pairs replace both.
    #[arg(long, help_heading = "Volume warp (True)", value_enum, default_value_t = WarpSpecArg::Align)]
    pub warp_spec: WarpSpecArg,
    /// A correspondence `X,Y,Z:X,Y,Z` (source point : target point, world
    /// units); repeat for several. The volume warp carries the source by
    /// them; the RBF method warps both shapes half-way by them (at least 4,
    /// not all on one plane).
    #[arg(long = "landmark", help_heading = "Volume warp (True)", value_parser = parse_pair, allow_hyphen_values = true)]
    pub landmarks: Vec<(Vec3, Vec3)>,
    /// Voxels between B-spline control points.
    #[arg(long, help_heading = "Volume warp (True)", default_value_t = WarpMorphSettings::default().control_spacing)]
    pub control_spacing: u32,

    /// The evolution speed.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", value_enum, default_value_t = SpeedArg::Robust)]
    pub speed: SpeedArg,
    /// Largest number of surface samples per octree cell.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().tmesh.max_samples_per_cell)]
    pub nt: usize,
    /// Maximum octree depth (1–7).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().tmesh.max_depth)]
    pub depth: u32,
    /// Morph step size h (units of the [−1, 1]³ domain; automatic when not
    /// given).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub step: Option<f64>,
    /// Empty margin around the shapes in the [−1, 1]³ domain, as a fraction
    /// of their half size.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().margin)]
    pub margin: f64,
    /// The paper's final refinement of the initial fit: split the cells
    /// where the fitted surface is farther than this from the source (units
    /// of the [−1, 1]³ domain) and refit (off when not given).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub refine: Option<f64>,
    /// At most this many refinement rounds (with `--refine`).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = 3)]
    pub refine_rounds: usize,

    /// The animator's links, speed curves and trajectories (a RON or JSON
    /// morph spec); the built-in spec of a built-in pair, or automatic
    /// correspondence, without it.
    #[arg(long, help_heading = "BlobTree (Galin et al.)")]
    pub links: Option<PathBuf>,
}

/// Which options belong to which method (by their argument ids).
const OWNERS: [(&str, &[Method]); 18] = [
    ("align", &[Method::LevelSet]),
    ("solver", &[Method::LevelSet]),
    ("curvature", &[Method::LevelSet]),
    ("max_iterations", &[Method::LevelSet]),
    ("points", &[Method::Rbf]),
    ("separation", &[Method::Rbf]),
    ("kernel", &[Method::Rbf]),
    ("warp_spec", &[Method::Warp]),
    ("landmarks", &[Method::Warp, Method::Rbf]),
    ("control_spacing", &[Method::Warp]),
    ("speed", &[Method::Tspline]),
    ("nt", &[Method::Tspline]),
    ("depth", &[Method::Tspline]),
    ("step", &[Method::Tspline]),
    ("margin", &[Method::Tspline]),
    ("refine", &[Method::Tspline]),
    ("refine_rounds", &[Method::Tspline]),
    ("links", &[Method::Blobtree]),
];

/// The options given on the command line that belong to no method in
/// `methods` (as `--name (method)`).
pub fn foreign_options(matches: &ArgMatches, methods: &[Method]) -> Vec<String> {
    OWNERS
        .iter()
        .filter(|(id, owners)| {
            !owners.iter().any(|o| methods.contains(o))
                && matches.value_source(id) == Some(ValueSource::CommandLine)
        })
        .map(|(id, owners)| {
            let names: Vec<&str> = owners.iter().map(|o| o.name()).collect();
            format!("--{} ({})", id.replace('_', "-"), names.join(", "))
        })
        .collect()
}

/// Refuses options of other methods than `methods`.
///
/// # Errors
/// Names the options and their methods.
pub fn refuse_foreign(matches: &ArgMatches, methods: &[Method]) -> anyhow::Result<()> {
    let foreign = foreign_options(matches, methods);
    if !foreign.is_empty() {
        let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
        bail!("{} do(es) not apply to {}", foreign.join(", "), names.join(", "));
    }
    Ok(())
}

impl MethodArgs {
    /// `settings` with these options applied (source and target name the
    /// inputs, for the BlobTree demo specs).
    ///
    /// # Errors
    /// An unreadable alignment map or links file.
    pub fn apply(&self, mut settings: Settings, source: &str, target: &str) -> anyhow::Result<Settings> {
        let l = &mut settings.level_set;
        l.align = match &self.align {
            AlignArg::None => Align::None,
            AlignArg::Auto => Align::Auto,
            AlignArg::File(path) => Align::Map(read_map(path)?),
        };
        l.solver = match self.solver {
            SolverArg::Sparse => SolverKind::SparseField,
            SolverArg::Dense => SolverKind::Dense,
        };
        l.curvature = self.curvature;
        l.max_iterations = self.max_iterations;

        let r = &mut settings.rbf;
        r.points = self.points;
        r.separation = self.separation;
        r.kernel = self.kernel.into();
        settings.rbf_correspondences.clone_from(&self.landmarks);

        let w = &mut settings.warp;
        w.spec = match self.warp_spec {
            _ if !self.landmarks.is_empty() => WarpSpec::Landmarks(self.landmarks.clone()),
            WarpSpecArg::Identity => WarpSpec::Identity,
            WarpSpecArg::Align => WarpSpec::Align,
        };
        w.control_spacing = self.control_spacing;

        let t = &mut settings.tspline;
        t.tmesh.max_samples_per_cell = self.nt;
        t.tmesh.max_depth = self.depth;
        t.evolve.step = self.step;
        t.margin = self.margin;
        t.evolve.speed = match self.speed {
            SpeedArg::Paper => Speed::Paper,
            SpeedArg::Distance => Speed::Distance,
            SpeedArg::Robust => TsplineSettings::default().evolve.speed,
        };
        t.fit.refinement = self
            .refine
            .map(|tolerance| isomorph_tspline::Refinement { tolerance, max_rounds: self.refine_rounds });

        settings.blobtree.spec = match &self.links {
            Some(path) => {
                MorphSpec::load(path).with_context(|| format!("invalid links file {}", path.display()))?
            }
            None => isomorph_blobtree::scenes::demo_spec(source, target).unwrap_or_default(),
        };
        Ok(settings)
    }
}

/// `--align`.
#[derive(Debug, Clone, PartialEq)]
pub enum AlignArg {
    /// Moment alignment.
    Auto,
    /// The shapes where they are.
    None,
    /// A map file.
    File(PathBuf),
}

/// Parses `--align`: `auto`, `none` or the path of a JSON map.
fn parse_align(s: &str) -> Result<AlignArg, String> {
    match s {
        "auto" => Ok(AlignArg::Auto),
        "none" => Ok(AlignArg::None),
        path if path.ends_with(".json") => Ok(AlignArg::File(PathBuf::from(path))),
        other => Err(format!("'{other}' is not auto, none or a .json file")),
    }
}

/// Accepts a finite weight in `[0, 100]`.
fn parse_weight(s: &str) -> Result<f32, String> {
    let w: f32 = s.parse().map_err(|e| format!("{e}"))?;
    if (0.0..=100.0).contains(&w) { Ok(w) } else { Err(format!("{w} is not in [0, 100]")) }
}

/// Parses `A,B,C:D,E,F` into two vectors.
pub fn parse_pair(s: &str) -> Result<(Vec3, Vec3), String> {
    let (a, b) = s.split_once(':').ok_or_else(|| format!("'{s}' is not of the form A,B,C:D,E,F"))?;
    let vec = |t: &str| -> Result<Vec3, String> {
        let v: Vec<f32> = t
            .split(',')
            .map(|x| x.trim().parse::<f32>().map_err(|e| format!("'{x}': {e}")))
            .collect::<Result<_, _>>()?;
        match v[..] {
            [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
            _ => Err(format!("'{t}' is not three finite numbers")),
        }
    };
    Ok((vec(a)?, vec(b)?))
}

/// Reads an affine map written by `isomorph align` (its `matrix` entry).
///
/// # Errors
/// Unreadable files, a missing or malformed `matrix`, a last row other than
/// `0 0 0 1`, non-finite entries or a singular map.
pub fn read_map(path: &Path) -> anyhow::Result<Affine3A> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let rows: [[f32; 4]; 4] = serde_json::from_value(json["matrix"].clone())
        .with_context(|| format!("{}: expected \"matrix\": 4 rows of 4 numbers", path.display()))?;
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        bail!("{}: the matrix's last row must be 0 0 0 1 (an affine map)", path.display());
    }
    let map = Affine3A::from_mat4(Mat4::from_cols_array_2d(&rows).transpose());
    if !map.is_finite() || map.matrix3.determinant().abs() < 1e-12 {
        bail!("{}: the map is not finite and invertible", path.display());
    }
    Ok(map)
}

/// The level-set solvers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// Whitaker's sparse field (fast; cost ∝ surface).
    Sparse,
    /// Up-wind scheme over the whole grid (the slow reference).
    Dense,
}

/// The radial kernels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KernelArg {
    /// `r² log r` (the paper's; better conditioned, less bloated in-betweens).
    Tps,
    /// `r³`.
    R3,
}

impl From<KernelArg> for Kernel {
    fn from(k: KernelArg) -> Self {
        match k {
            KernelArg::Tps => Kernel::ThinPlate,
            KernelArg::R3 => Kernel::Cubic,
        }
    }
}

impl From<Kernel> for KernelArg {
    fn from(k: Kernel) -> Self {
        match k {
            Kernel::Cubic => KernelArg::R3,
            _ => KernelArg::Tps,
        }
    }
}

/// The warp's correspondences.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WarpSpecArg {
    /// No warp: a cross-dissolve of the densities.
    Identity,
    /// Moment alignment as a B-spline warp.
    Align,
}

/// The T-spline evolution speeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpeedArg {
    /// The paper's curvature-regularized speed (eq. 8).
    Paper,
    /// The plain distance speed of the paper's Fig. 2.
    Distance,
    /// The distance speed bounded near the target (the library default).
    Robust,
}
