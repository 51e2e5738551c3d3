//! The method options of `isomorph morph` and `isomorph compare`, grouped
//! by method in `--help`, with the libraries' defaults; each applies to its
//! method's settings, and giving an option of another method is an error.

use anyhow::{Context, bail};
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, ValueEnum};
use isomorph_blobtree::MorphSpec;
use isomorph_cli::methods::{LandmarkWarp, Method, Settings, landmark_warp};
use isomorph_cli::parse::{parse_pair, read_map};
use isomorph_common::Landmarks;
use isomorph_common::alignment::AlignMode;
use isomorph_common::glam::Vec3;
use isomorph_io::compare::error_chain;
use isomorph_levelset::{Align, LevelSetSettings, SolverKind};
use isomorph_rbf::{Kernel, RbfSettings};
use isomorph_tspline::{Align as TsplineAlign, Speed, TsplineSettings};
use isomorph_warp::{WarpMorphSettings, WarpSpec, WorldMap};
use std::path::PathBuf;
use std::sync::Arc;

/// Method options (each belongs to one method).
#[derive(Debug, Clone, Args)]
pub struct MethodArgs {
    /// Alignment of the source onto the target before evolving: `auto`
    /// (moments), `none`, or a JSON map file as `isomorph align` prints it.
    /// Also for the T-spline method, whose frames undo it gradually (eq. 11).
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
    /// Which warp carries the target's distance through the landmarks
    /// (`--landmarks`/`--landmark`): Breen & Whitaker's generalized warp
    /// `W` (§6.2), frames placed by `(1 − α) x + α W(x)`.
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", value_enum, default_value_t = LandmarkWarp::Rbf)]
    pub landmark_warp: LandmarkWarp,
    /// A B-spline map as `isomorph warp` writes it (`map.json`) used as the
    /// generalized warp `W` from source to target space (§6.2).
    #[arg(long, help_heading = "Level set (Breen & Whitaker)")]
    pub warp_map: Option<PathBuf>,
    /// Largest share (0–1) of the target's inside that may lie in parts the
    /// source does not overlap: the morph goes on without them and warns up
    /// to it, and is refused above it.
    #[arg(long, help_heading = "Level set (Breen & Whitaker)", default_value_t = LevelSetSettings::default().max_unreached_share)]
    pub max_unreached: f32,

    /// Surface points per shape (each a boundary and a normal constraint).
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", default_value_t = RbfSettings::default().points)]
    pub points: usize,
    /// Separation of the shapes along the fourth axis (world units).
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", default_value_t = RbfSettings::default().separation)]
    pub separation: f32,
    /// The radial kernel.
    #[arg(long, help_heading = "RBF (Turk & O'Brien)", value_enum, default_value_t = KernelArg::from(RbfSettings::default().kernel))]
    pub kernel: KernelArg,
    /// An influence shape (§7; repeat for a second): the morph runs from the
    /// source to the target through one implicit of all the shapes, pulled
    /// towards this one (a built-in shape, a mesh or a volume, read as the
    /// inputs are).
    #[arg(long, help_heading = "RBF (Turk & O'Brien)")]
    pub influence: Vec<String>,
    /// Fit to this tolerance through greedily chosen centres (FastRBF)
    /// instead of interpolating every constraint: relative to the normal
    /// constraints' value, 0.001–1 (a residual ε moves the surface by about
    /// ε × the normal offset); allows up to 250000 --points. Points sampled
    /// at a mesh's own resolution need nearly all of them below ~0.1.
    #[arg(long, help_heading = "RBF (Turk & O'Brien)")]
    pub tolerance: Option<f64>,

    /// How the source is carried onto the target: `identity` (a plain
    /// cross-dissolve) or `align` (moment alignment as a B-spline warp);
    /// `--landmark` pairs replace both.
    #[arg(long, help_heading = "Volume warp (True)", value_enum, default_value_t = WarpSpecArg::Align)]
    pub warp_spec: WarpSpecArg,
    /// A correspondence `X,Y,Z:X,Y,Z` (source point : target point, world
    /// units); repeat for several. The volume warp carries the source by
    /// them; the RBF method warps both shapes half-way by them; the level
    /// set evolves towards the target seen through the warp they define
    /// (at least 4, not all on one plane).
    #[arg(long, help_heading = "Volume warp (True)", value_parser = parse_pair, allow_hyphen_values = true)]
    pub landmark: Vec<(Vec3, Vec3)>,
    /// A landmarks file: a JSON list of `{"source": [x, y, z], "target":
    /// [x, y, z]}` pairs (world units), used as `--landmark` pairs are.
    #[arg(long, help_heading = "Volume warp (True)")]
    pub landmarks: Option<PathBuf>,
    /// Voxels between B-spline control points.
    #[arg(long, help_heading = "Volume warp (True)", default_value_t = WarpMorphSettings::default().control_spacing)]
    pub control_spacing: u32,

    /// The evolution speed.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", value_enum, default_value_t = SpeedArg::Robust)]
    pub speed: SpeedArg,
    /// Curvature weight β of the robust speed (`--speed robust`), in finest
    /// T-mesh cells: v = clamp(d_B, ±0.2) + β h (1 − λ) κ (0 to 10; higher
    /// smooths the in-between shapes more and slows growth into thin target
    /// parts) [default: the library's, 1].
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", value_parser = parse_beta_cells)]
    pub beta_cells: Option<f64>,
    /// Largest number of surface samples per octree cell.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().tmesh.max_samples_per_cell)]
    pub nt: usize,
    /// Maximum octree depth (1–7).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().tmesh.max_depth, value_parser = clap::value_parser!(u32).range(1..=i64::from(isomorph_tspline::MAX_DEPTH)))]
    pub depth: u32,
    /// Minimum octree depth: every cell is split at least this deep (0 to
    /// --depth) [default: 2, or --depth when that is lower].
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub min_depth: Option<u32>,
    /// Spacing of the surface samples that drive the octree (units of the
    /// [−1, 1]³ domain, 1e-4 to 2).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().tmesh.sample_spacing)]
    pub sample_spacing: f64,
    /// Most evolution steps (0 keeps the initial fit).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().evolve.max_steps)]
    pub max_steps: usize,
    /// Stop the evolution as stalled when its error has not dropped by 1 %
    /// over this many steps (at least 1; the paper's speed on a depth-5
    /// T-mesh needs about 40, e.g. Example 1: `--speed paper --depth 5 --nt
    /// 60 --stall-steps 40`).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().evolve.stall_steps)]
    pub stall_steps: usize,
    /// Weight of the distance-field constraint |∇f| = 1 (0 to 1e6; lower
    /// lets narrow features open).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().evolve.distance_weight)]
    pub distance_weight: f64,
    /// Weight of the far-field rows ḟ = 0 in octree leaves without a zero
    /// and out of the front's reach, against the velocity rows' total of 1
    /// (0 to 1e6; 0 turns them off; they stop new pieces of surface from
    /// appearing away from the front).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().evolve.far_field_weight)]
    pub far_field_weight: f64,
    /// Hold the cells that a step would lift through zero away from the
    /// front (0 to 1; 0 turns it off): finest cells farther than h / F from
    /// the front where the step moves f towards zero by more than F |f| get
    /// far-field rows ḟ = 0 and the step is solved again, so that no new
    /// piece of surface is born there.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = TsplineSettings::default().evolve.hold_fraction)]
    pub hold_fraction: f64,
    /// Leave out the projection frames (§4.3) at both ends: the sequence
    /// then starts and ends on the fitted level sets, not on the inputs.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub no_projection_frames: bool,
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
    /// At most this many refinement rounds (with `--refine` or
    /// `--refine-target`).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = 3)]
    pub refine_rounds: usize,
    /// The final refinement of the target's approximation after the
    /// evolution (§3.2): fit the target on the T-mesh, split the cells
    /// where it is farther than this from the target (units of the
    /// [−1, 1]³ domain), refit, and end the level sets on it (off when not
    /// given).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub refine_target: Option<f64>,
    /// Adapt the T-mesh to the target before the evolution: fit the
    /// target on it, split the cells (up to --depth) where that fit misses
    /// the target by more than this (units of the [−1, 1]³ domain) and
    /// refit, at most --refine-rounds times; gives thin target parts (a
    /// handle thinner than a cell) the coefficients to grow into (off when
    /// not given).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)")]
    pub adapt_target: Option<f64>,
    /// How level-set frames become triangle meshes: marching cubes at
    /// --resolution, or the paper's marching triangulation (Hartmann 1998;
    /// near-equilateral triangles of --mesh-edge, seeded from a lattice of
    /// --resolution nodes).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", value_enum, default_value_t = MesherArg::MarchingCubes)]
    pub mesher: MesherArg,
    /// Edge length of the marching triangulation's triangles (units of the
    /// [−1, 1]³ domain, 1e-4 to 1).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = 0.02)]
    pub mesh_edge: f64,
    /// Where each evolution step's zero-set samples come from (paper
    /// §3.3): the vertices of marching cubes on the finest cells (fast), or
    /// the paper's uniformly spaced points of a marching triangulation
    /// (Hartmann 1998) with edges of --sample-edge finest cells.
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", value_enum, default_value_t = SamplerArg::MarchingCubes)]
    pub sampler: SamplerArg,
    /// Spacing of the marching-triangulation samples, in finest T-mesh
    /// cells (0.05 to 4; with --sampler marching-triangulation).
    #[arg(long, help_heading = "T-spline (Yang & Jüttler)", default_value_t = 0.5)]
    pub sample_edge: f64,

    /// The animator's links, speed curves and trajectories (a RON or JSON
    /// morph spec); the built-in spec of a built-in pair, or automatic
    /// correspondence, without it. With --via: the spec of the last pair
    /// (the last --via shape → the target), whose `levels` may give links
    /// for the Bézier morph's de Casteljau levels above the first. Format:
    /// the isomorph-blobtree crate docs, "Scene files"; examples in
    /// blobtree/scenes/.
    #[arg(long, help_heading = "BlobTree (Galin et al.)")]
    pub links: Option<PathBuf>,

    /// A control (key) shape between the source and the target (a BlobTree
    /// scene file or a built-in scene); repeat for several, in order. The
    /// generic trees of each pair of consecutive shapes are combined as
    /// --via-mode says. Each pair uses its --via-links or --links spec if
    /// given, else its built-in spec (a built-in pair) or automatic
    /// correspondence.
    #[arg(long, help_heading = "BlobTree (Galin et al.)")]
    pub via: Vec<String>,

    /// The links spec (as --links) of the pair arriving at each --via shape:
    /// the first is the source → first --via shape's, the second the first
    /// → second --via shape's, and so on; give none or one per --via
    /// (--links stays the last --via shape → target's). Node paths `a` name
    /// nodes of the pair's first shape, `b` of its second.
    #[arg(long, value_name = "FILE", help_heading = "BlobTree (Galin et al.)")]
    pub via_links: Vec<PathBuf>,

    /// How the --via shapes are used: `bezier` (the paper's Bézier-like
    /// morph: de Casteljau's combination of the pairwise generic trees; the
    /// --via shapes are control shapes, approached but in general not
    /// reached) or `chain` (the pairwise morphs one after the other: the
    /// morph is each key shape at evenly spaced times; with two, the source
    /// at 0, the keys at 1/3 and 2/3, the target at 1).
    #[arg(long, help_heading = "BlobTree (Galin et al.)", value_enum, default_value_t = ViaModeArg::Bezier)]
    pub via_mode: ViaModeArg,

    /// Also write each frame's BlobTree C(t) as a scene file
    /// (OUT/frame_000.ron, ...; the paper's genericity): it loads back into
    /// the same field, to polygonize with `isomorph blob` or morph further.
    #[arg(long, help_heading = "BlobTree (Galin et al.)")]
    pub scenes: bool,
}

/// Which options belong to which method (by their argument ids).
const OWNERS: &[(&str, &[Method])] = &[
    ("align", &[Method::LevelSet, Method::Tspline]),
    ("solver", &[Method::LevelSet]),
    ("curvature", &[Method::LevelSet]),
    ("max_iterations", &[Method::LevelSet]),
    ("max_unreached", &[Method::LevelSet]),
    ("landmark_warp", &[Method::LevelSet]),
    ("warp_map", &[Method::LevelSet]),
    ("points", &[Method::Rbf]),
    ("separation", &[Method::Rbf]),
    ("kernel", &[Method::Rbf]),
    ("tolerance", &[Method::Rbf]),
    ("influence", &[Method::Rbf]),
    ("warp_spec", &[Method::Warp]),
    ("landmark", &[Method::Warp, Method::Rbf, Method::LevelSet]),
    ("landmarks", &[Method::Warp, Method::Rbf, Method::LevelSet]),
    ("control_spacing", &[Method::Warp]),
    ("speed", &[Method::Tspline]),
    ("beta_cells", &[Method::Tspline]),
    ("nt", &[Method::Tspline]),
    ("depth", &[Method::Tspline]),
    ("min_depth", &[Method::Tspline]),
    ("sample_spacing", &[Method::Tspline]),
    ("max_steps", &[Method::Tspline]),
    ("stall_steps", &[Method::Tspline]),
    ("distance_weight", &[Method::Tspline]),
    ("far_field_weight", &[Method::Tspline]),
    ("hold_fraction", &[Method::Tspline]),
    ("no_projection_frames", &[Method::Tspline]),
    ("step", &[Method::Tspline]),
    ("margin", &[Method::Tspline]),
    ("refine", &[Method::Tspline]),
    ("refine_rounds", &[Method::Tspline]),
    ("refine_target", &[Method::Tspline]),
    ("adapt_target", &[Method::Tspline]),
    ("mesher", &[Method::Tspline]),
    ("mesh_edge", &[Method::Tspline]),
    ("sampler", &[Method::Tspline]),
    ("sample_edge", &[Method::Tspline]),
    ("links", &[Method::Blobtree]),
    ("via", &[Method::Blobtree]),
    ("via_mode", &[Method::Blobtree]),
    ("via_links", &[Method::Blobtree]),
    ("scenes", &[Method::Blobtree]),
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
    /// An unreadable alignment map, landmarks or links file; landmarks
    /// together with `--align`.
    pub fn apply(&self, mut settings: Settings, source: &str, target: &str) -> anyhow::Result<Settings> {
        let landmarks = self.landmark_pairs()?;
        let l = &mut settings.level_set;
        l.align = match (&self.align, &landmarks, &self.warp_map) {
            (AlignArg::None, None, None) => Align::None,
            (AlignArg::Auto, None, None) => Align::Auto,
            (AlignArg::File(path), None, None) => Align::Map(read_map(path)?),
            (AlignArg::None, Some(landmarks), None) => Align::Warp(
                landmark_warp(landmarks, self.landmark_warp, self.control_spacing)
                    .map_err(|e| anyhow::anyhow!(error_chain(&e)))
                    .context("cannot fit a warp through the landmarks")?,
            ),
            (AlignArg::None, None, Some(path)) => {
                let map =
                    WorldMap::load(path).with_context(|| format!("invalid warp map {}", path.display()))?;
                Align::Warp(Arc::new(move |x| map.apply(x)))
            }
            (_, _, Some(_)) => {
                bail!("--warp-map places the source on the target: give it without --align or landmarks")
            }
            (_, Some(_), None) => {
                bail!("--align and landmarks both place the source on the target: give one")
            }
        };
        l.solver = match self.solver {
            SolverArg::Sparse => SolverKind::SparseField,
            SolverArg::Dense => SolverKind::Dense,
        };
        l.curvature = self.curvature;
        l.max_iterations = self.max_iterations;
        l.max_unreached_share = self.max_unreached;

        let r = &mut settings.rbf;
        r.points = self.points;
        r.separation = self.separation;
        r.kernel = self.kernel.into();
        r.tolerance = self.tolerance;
        let pairs = landmarks.as_ref().map(|l| l.pairs().to_vec()).unwrap_or_default();
        settings.rbf_correspondences.clone_from(&pairs);

        let w = &mut settings.warp;
        w.spec = match self.warp_spec {
            _ if !pairs.is_empty() => WarpSpec::Landmarks(pairs),
            WarpSpecArg::Identity => WarpSpec::Identity,
            WarpSpecArg::Align => WarpSpec::Align,
        };
        w.control_spacing = self.control_spacing;

        let t = &mut settings.tspline;
        t.tmesh.max_samples_per_cell = self.nt;
        t.tmesh.max_depth = self.depth;
        t.tmesh.min_depth = self.min_depth.unwrap_or(t.tmesh.min_depth.min(self.depth));
        t.tmesh.sample_spacing = self.sample_spacing;
        t.evolve.max_steps = self.max_steps;
        t.evolve.stall_steps = self.stall_steps;
        t.evolve.distance_weight = self.distance_weight;
        t.evolve.far_field_weight = self.far_field_weight;
        t.evolve.hold_fraction = self.hold_fraction;
        t.projection_frames = !self.no_projection_frames;
        t.align = match &self.align {
            AlignArg::None => TsplineAlign::None,
            AlignArg::Auto => TsplineAlign::Moments(AlignMode::Affine),
            AlignArg::File(path) => TsplineAlign::Map(read_map(path)?),
        };
        t.evolve.step = self.step;
        t.margin = self.margin;
        t.evolve.speed = match (self.speed, self.beta_cells) {
            (SpeedArg::Robust, beta) => Speed::robust(beta.unwrap_or(Speed::ROBUST_BETA_CELLS)),
            (_, Some(_)) => bail!("--beta-cells is the robust speed's: give it with --speed robust"),
            (SpeedArg::Paper, None) => Speed::Paper,
            (SpeedArg::Distance, None) => Speed::Distance,
        };
        t.fit.refinement = self
            .refine
            .map(|tolerance| isomorph_tspline::Refinement { tolerance, max_rounds: self.refine_rounds });
        t.target_refinement = self
            .refine_target
            .map(|tolerance| isomorph_tspline::Refinement { tolerance, max_rounds: self.refine_rounds });
        t.target_adaptation = self
            .adapt_target
            .map(|tolerance| isomorph_tspline::Refinement { tolerance, max_rounds: self.refine_rounds });
        t.mesher = match self.mesher {
            MesherArg::MarchingCubes => isomorph_tspline::Mesher::MarchingCubes,
            MesherArg::MarchingTriangulation => {
                isomorph_tspline::Mesher::MarchingTriangulation { edge: self.mesh_edge }
            }
        };

        t.evolve.sampler = match self.sampler {
            SamplerArg::MarchingCubes => isomorph_tspline::Sampler::MarchingCubes,
            SamplerArg::MarchingTriangulation => {
                isomorph_tspline::Sampler::MarchingTriangulation { edge_cells: self.sample_edge }
            }
        };

        let load_links = |path: &PathBuf| {
            MorphSpec::load(path).with_context(|| format!("invalid links file {}", path.display()))
        };
        settings.blobtree.spec = match &self.links {
            Some(path) => load_links(path)?,
            None => {
                let last = self.via.last().map_or(source, String::as_str);
                isomorph_blobtree::scenes::demo_spec(last, target).unwrap_or_default()
            }
        };
        settings.blobtree.via_mode = match self.via_mode {
            ViaModeArg::Bezier => isomorph_blobtree::ViaMode::Bezier,
            ViaModeArg::Chain => isomorph_blobtree::ViaMode::Chain,
        };
        if !self.via_links.is_empty() && self.via_links.len() != self.via.len() {
            bail!(
                "give one --via-links per --via shape, in order (the spec of the pair arriving at it), or none: got \
                 {} --via and {} --via-links",
                self.via.len(),
                self.via_links.len()
            );
        }
        let mut from = source;
        settings.blobtree.via = Vec::with_capacity(self.via.len());
        for (k, name) in self.via.iter().enumerate() {
            let shape = isomorph_blobtree::scenes::load(name).with_context(|| format!("--via {name}"))?;
            let spec = match self.via_links.get(k) {
                Some(path) => load_links(path).with_context(|| format!("--via-links for {from} → {name}"))?,
                None => isomorph_blobtree::scenes::demo_spec(from, name).unwrap_or_default(),
            };
            settings.blobtree.via.push(isomorph_blobtree::KeyShape { shape, spec });
            from = name;
        }
        Ok(settings)
    }
}

impl MethodArgs {
    /// Whether landmark pairs are given (`--landmark` or `--landmarks`).
    pub fn has_landmarks(&self) -> bool {
        !self.landmark.is_empty() || self.landmarks.is_some()
    }

    /// The `--landmark` pairs and those of the `--landmarks` file,
    /// validated together; `None` when neither is given.
    ///
    /// # Errors
    /// An unreadable file or an invalid set ([`Landmarks::new`]).
    fn landmark_pairs(&self) -> anyhow::Result<Option<Landmarks>> {
        let mut pairs = self.landmark.clone();
        if let Some(path) = &self.landmarks {
            pairs.extend_from_slice(Landmarks::load(path)?.pairs());
        }
        if pairs.is_empty() {
            return Ok(None);
        }
        Ok(Some(Landmarks::new(&pairs).context("invalid landmarks")?))
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

/// Accepts a finite robust-speed curvature weight in `[0, 10]` finest cells.
fn parse_beta_cells(s: &str) -> Result<f64, String> {
    let b: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if (0.0..=Speed::MAX_BETA_CELLS).contains(&b) {
        Ok(b)
    } else {
        Err(format!("{b} is not in [0, {}] finest cells", Speed::MAX_BETA_CELLS))
    }
}

/// How a BlobTree morph uses its `--via` shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ViaModeArg {
    /// The paper's Bézier-like morph: control shapes, approached.
    Bezier,
    /// The pairwise morphs one after the other: key shapes, passed through.
    Chain,
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

/// The T-spline method's frame meshers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MesherArg {
    /// Marching cubes at --resolution.
    MarchingCubes,
    /// Hartmann's marching triangulation with --mesh-edge (the paper's).
    MarchingTriangulation,
}

/// Where the T-spline evolution's zero-set samples come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SamplerArg {
    /// Marching-cubes vertices on the finest cells.
    MarchingCubes,
    /// Hartmann's marching triangulation with --sample-edge (the paper's).
    MarchingTriangulation,
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
