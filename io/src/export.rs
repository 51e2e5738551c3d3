//! The generic sequence exporter: polygonize frames of any [`Morph`], write
//! the meshes, a PNG contact sheet and `report.json`.
//!
//! # `report.json`
//! Stable keys (all distances in world units unless suffixed `_voxels`; a
//! voxel is the longest edge of the morph's world bounds over
//! `resolution − 1`):
//!
//! ```json
//! {
//!   "method": "baseline", "resolution": 64, "voxel_size": 0.0159,
//!   "export_seconds": 0.41,
//!   "frames": [ { "t": 0.0, "file": "frame_000.ply", "vertices": 1234, "triangles": 2464,
//!                 "components": 1, "genus": 0, "area": 0.9, "volume": 0.1, "seconds": 0.02,
//!                 "step_from_previous": null } ],
//!   "endpoints": { "source": { "mean": 0.001, "hausdorff": 0.004,
//!                              "mean_voxels": 0.06, "hausdorff_voxels": 0.25 },
//!                  "target": { ... } },
//!   "largest_step": 0.03, "largest_step_voxels": 1.9,
//!   "morph": { "method": "baseline", "outcome": "direct", "converged": true, "stages": [ ... ], ... },
//!   "warnings": [ "1 in-between frame(s) have no surface (t = 0.5): ..." ]
//! }
//! ```
//! `genus` is `null` for frames that are not closed 2-manifolds; an endpoint is
//! `null` when no reference mesh was given. An endpoint distance is
//! two-sided: samples of the frame measured against the input's surface,
//! and samples of the reference mesh (the input's surface) measured against
//! the frame; with [`ExportSettings::source_solid`] (`target_solid`) the
//! first side uses the input's exact distance where it has one (meshes,
//! analytic shapes) rather than the distance to the reference mesh, and the
//! samples of a polygonized analytic shape are moved onto its true surface
//! ([`Solid::nearest_surface_point`]). `step_from_previous` is the
//! Hausdorff distance from the frame before (how far the surface jumped);
//! `largest_step` the largest of them. `morph` is the method's
//! [`MorphReport`].
//!
//! # Colour
//! With [`ExportSettings::colors`], every frame carries per-vertex colours
//! (Breen & Whitaker Fig. 13): a vertex `p` of the frame at `t` is taken
//! back to where the morph places the same field point in the frames at 0
//! and 1 ([`Morph::ends_of`]: `W(0) · W(t)⁻¹ p` and `W(1) · W(t)⁻¹ p` for a
//! placement `W` = [`Morph::world_transform`], the identity for methods that
//! do not place their frames; the inverse of Breen's `T(x, α)` for a level
//! set placed by a warp), and gets `(1 − t) · source colour at the surface
//! point closest to the first + t · target colour at the one closest to the
//! second` ([`ColorLookup`]), sRGB components blended linearly. At `t = 0` a
//! vertex thus gets exactly the source's colour at its closest source
//! point, at `t = 1` the target's. Frame files (PLY `uchar red green blue`,
//! OBJ `v x y z r g b`), `morph.usda` (per-vertex `displayColor`), the
//! contact sheet and `preview.gif` then show them. Without it nothing about
//! the output changes.

use crate::mesh::{MeshFormat, write_mesh};
use crate::render::{Camera, Image, RenderSettings, contact_sheet, render, write_gif};
use crate::usd::{UsdSettings, write_usda};
use isomorph_common::glam::Vec3;
use isomorph_common::mesh::color::ColorLookup;
use isomorph_common::mesh::distance::{IndexedSurface, SurfaceDistance, surface_samples};
use isomorph_common::mesh::winding::WindingNumber;
use isomorph_common::{Aabb, Control, Morph, MorphError, Solid, TriMesh};
use isomorph_common::{BoxedError, MorphReport};
use rayon::prelude::*;
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

/// An endpoint frame farther than this (Hausdorff, voxels) from its input
/// is reported in [`Report::warnings`], with the place where the two are
/// farthest apart when that is farther than this too: a part of the input
/// outside the frame (one the grid may be too coarse to form, and the finer
/// resolution to try) or inside its solid (a hollow it fills, an open
/// input's inner sheet), or frame surface outside the input (a bulge or a
/// piece the input does not have) or inside it (a hollow or a dent).
pub const ENDPOINT_WARNING_VOXELS: f32 = 3.0;

/// The USD stage of the whole sequence ([`ExportSettings::usd`]).
pub const USD_FILE: &str = "morph.usda";

/// Hundredths of a second per frame of `preview.gif`.
pub const PREVIEW_DELAY: u16 = 12;

/// What to export and how.
#[derive(Debug, Clone)]
pub struct ExportSettings {
    /// Number of frames, at `t = i / (frames − 1)` (at least 2).
    pub frames: usize,
    /// Nodes along the longest edge of the morph's bounds.
    pub resolution: u32,
    /// Output folder (created if missing).
    pub out_dir: PathBuf,
    /// Mesh file format of the frames.
    pub format: MeshFormat,
    /// Write each frame as `frame_NNN.<ext>` (default true).
    pub frame_files: bool,
    /// Write the whole sequence as one USD stage, `morph.usda` (a mesh with
    /// a time sample per frame, see [`crate::usd`]).
    pub usd: bool,
    /// Write `contact_sheet.png`.
    pub contact_sheet: bool,
    /// Write `preview.gif`: the contact sheet's renders as a loop, forward
    /// and back.
    pub preview: bool,
    /// Frames per row of the contact sheet.
    pub sheet_columns: u32,
    /// Preview settings of each contact-sheet tile (camera fitted to all frames when `None`).
    pub render: RenderSettings,
    /// The source surface, to measure how well frame 0 matches it.
    pub source_reference: Option<TriMesh>,
    /// The target surface, to measure how well the last frame matches it.
    pub target_reference: Option<TriMesh>,
    /// The source solid whose surface `source_reference` is: where it knows
    /// its exact distance ([`Solid::exact_distance`]: meshes, analytic
    /// shapes), frame 0's samples are measured by that distance instead of
    /// against a tree built over `source_reference` (faster, and free of the
    /// reference's polygonization error on that side); `source_reference`'s
    /// points are still measured against the frame.
    pub source_solid: Option<Solid>,
    /// The target solid whose surface `target_reference` is, as
    /// `source_solid`.
    pub target_solid: Option<Solid>,
    /// Surface samples per mesh for the endpoint distances.
    pub distance_samples: usize,
    /// Surface samples per mesh for the distance between consecutive frames.
    pub step_samples: usize,
    /// Colour the frames from the inputs' colours (see the [module
    /// docs](self)); `None` (the default) writes no colours.
    pub colors: Option<FrameColors>,
}

/// The inputs' colours, for [`ExportSettings::colors`].
#[derive(Debug, Clone)]
pub struct FrameColors {
    /// The source's colours (in the source's world placement).
    pub source: ColorLookup,
    /// The target's colours (in the target's world placement).
    pub target: ColorLookup,
}

impl FrameColors {
    /// Colours `mesh`, the world-space frame at `t`, whose vertices sit at
    /// `on_source` and `on_target` in the frames at 0 and 1
    /// ([`Morph::ends_of`]).
    fn paint(&self, mesh: &mut TriMesh, t: f32, [on_source, on_target]: [Vec<Vec3>; 2]) {
        let lookup = |lookup: &ColorLookup, points: &[Vec3]| {
            let mut colors = vec![Vec3::ZERO; points.len()];
            lookup.colors_at(points, &mut colors);
            colors
        };
        let from_source = lookup(&self.source, &on_source);
        let from_target = lookup(&self.target, &on_target);
        mesh.colors = Some(from_source.iter().zip(&from_target).map(|(s, g)| s.lerp(*g, t)).collect());
    }
}

impl ExportSettings {
    /// These settings measuring the end frames against the inputs `source`
    /// and `target`: their surfaces ([`reference_surfaces`] at
    /// [`ExportSettings::resolution`]) as `source_reference` and
    /// `target_reference`, and the solids themselves as `source_solid` and
    /// `target_solid` (for their exact distances).
    ///
    /// # Errors
    /// As [`reference_surfaces`].
    pub fn with_inputs(self, source: &Solid, target: &Solid, control: &Control) -> Result<Self, MorphError> {
        let (source_reference, target_reference) =
            reference_surfaces(source, target, self.resolution, control)?;
        Ok(Self {
            source_reference: Some(source_reference),
            target_reference: Some(target_reference),
            source_solid: Some(source.clone()),
            target_solid: Some(target.clone()),
            ..self
        })
    }
}

impl Default for ExportSettings {
    fn default() -> Self {
        Self {
            frames: 9,
            resolution: 64,
            out_dir: PathBuf::from("out"),
            format: MeshFormat::PlyBinaryLittleEndian,
            frame_files: true,
            usd: false,
            contact_sheet: true,
            preview: true,
            sheet_columns: 5,
            render: RenderSettings { width: 240, height: 240, ..RenderSettings::default() },
            source_reference: None,
            target_reference: None,
            source_solid: None,
            target_solid: None,
            distance_samples: 20_000,
            step_samples: 4_000,
            colors: None,
        }
    }
}

/// Errors of [`export_sequence`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The settings cannot work (too few frames, resolution below 2).
    #[error("invalid export settings: {0}")]
    Settings(String),
    /// The morph failed to produce a frame.
    #[error("frame at t = {t}: {source}")]
    Frame {
        /// Time of the frame.
        t: f32,
        /// The morph's error.
        source: BoxedError,
    },
    /// A frame at an end of the morph is empty while its input is not.
    #[error("the frame at t = {t} is empty (no surface) although the {which} is not")]
    EmptyEndpoint {
        /// Time of the frame.
        t: f32,
        /// `"source"` or `"target"`.
        which: &'static str,
    },
    /// A file or folder could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A mesh could not be written.
    #[error(transparent)]
    MeshIo(#[from] crate::mesh::MeshIoError),
    /// The contact sheet could not be written.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// Cancelled through the [`Control`].
    #[error(transparent)]
    Cancelled(#[from] MorphError),
}

/// Metrics of one exported frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameReport {
    /// Morph time.
    pub t: f32,
    /// Mesh file name inside the output folder; `morph.usda@N` (time code
    /// `N` of the USD stage) when only the stage is written, empty when
    /// neither is.
    pub file: String,
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Connected components (outer shells and cavity walls).
    pub components: usize,
    /// Of those, walls of enclosed cavities ([`MeshMetrics::voids`](isomorph_common::mesh::metrics::MeshMetrics::voids)).
    pub voids: usize,
    /// Genus, when the frame is a closed 2-manifold.
    pub genus: Option<i64>,
    /// Surface area (world units²).
    pub area: f64,
    /// Enclosed volume (world units³).
    pub volume: f64,
    /// Wall time to make, polygonize and write this frame.
    pub seconds: f64,
    /// Hausdorff distance to the previous frame (world units); `None` for the
    /// first frame or when either is empty.
    pub step_from_previous: Option<f32>,
}

/// A surface distance in world units and in voxels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EndpointDistance {
    /// Mean two-sided surface distance.
    pub mean: f32,
    /// Two-sided Hausdorff distance.
    pub hausdorff: f32,
    /// `mean` / voxel size.
    pub mean_voxels: f32,
    /// `hausdorff` / voxel size.
    pub hausdorff_voxels: f32,
}

impl EndpointDistance {
    fn new(d: SurfaceDistance, voxel: f32) -> Self {
        Self {
            mean: d.mean,
            hausdorff: d.hausdorff,
            mean_voxels: d.mean / voxel,
            hausdorff_voxels: d.hausdorff / voxel,
        }
    }
}

/// How well the first and last frames match the inputs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Endpoints {
    /// Frame 0 against the source reference.
    pub source: Option<EndpointDistance>,
    /// The last frame against the target reference.
    pub target: Option<EndpointDistance>,
}

/// The contents of `report.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Report {
    /// [`Morph::method`].
    pub method: String,
    /// Nodes along the longest edge.
    pub resolution: u32,
    /// Edge length of one world voxel (world units).
    pub voxel_size: f32,
    /// Wall time of the export (frames, files, pictures, metrics).
    pub export_seconds: f64,
    /// One entry per frame, in time order.
    pub frames: Vec<FrameReport>,
    /// Endpoint distances.
    pub endpoints: Endpoints,
    /// The largest distance between consecutive frames (world units).
    pub largest_step: Option<f32>,
    /// `largest_step` in voxels.
    pub largest_step_voxels: Option<f32>,
    /// The method's own report.
    pub morph: MorphReport,
    /// What the export noticed (e.g. in-between frames with no surface).
    pub warnings: Vec<String>,
}

impl Report {
    /// The largest component count over all frames.
    pub fn max_components(&self) -> usize {
        self.frames.iter().map(|f| f.components).max().unwrap_or(0)
    }

    /// The largest number of outer shells (components that are not cavity
    /// walls) over all frames.
    pub fn max_shells(&self) -> usize {
        self.frames.iter().map(|f| f.components - f.voids).max().unwrap_or(0)
    }

    /// Genus per frame.
    pub fn genus_sequence(&self) -> Vec<Option<i64>> {
        self.frames.iter().map(|f| f.genus).collect()
    }
}

/// The frames' meshes and their report, as [`export_sequence`] made them.
#[derive(Debug, Clone)]
pub struct Exported {
    /// `report.json`'s contents.
    pub report: Report,
    /// The frame meshes in time order (world units).
    pub meshes: Vec<TriMesh>,
}

/// Polygonizes `settings.frames` frames of `morph` (in parallel on the
/// control's threads), writes `frame_NNN.<ext>`, `contact_sheet.png`,
/// `preview.gif` and `report.json` into `settings.out_dir`, and returns the report with the
/// meshes. Progress is reported as stage `"frames"`.
///
/// # Errors
/// [`ExportError`] for bad settings, a failing frame, an empty end frame, IO
/// problems or cancellation.
pub fn export_sequence<M: Morph + ?Sized>(
    morph: &M,
    settings: &ExportSettings,
    control: &Control,
) -> Result<Exported, ExportError> {
    control.install(|| export_on_pool(morph, settings, control))
}

fn export_on_pool<M: Morph + ?Sized>(
    morph: &M,
    settings: &ExportSettings,
    control: &Control,
) -> Result<Exported, ExportError> {
    let start = Instant::now();
    if settings.frames < 2 {
        return Err(ExportError::Settings(format!("need at least 2 frames, got {}", settings.frames)));
    }
    if settings.resolution < 2 {
        return Err(ExportError::Settings(format!(
            "resolution must be at least 2, got {}",
            settings.resolution
        )));
    }
    let dir = &settings.out_dir;
    std::fs::create_dir_all(dir).map_err(|source| ExportError::Io { path: dir.clone(), source })?;
    let total = settings.frames;
    let done = std::sync::atomic::AtomicUsize::new(0);
    // Every distance (steps, endpoints) is computed in one frame, scaled for
    // the box of all frames and references.
    let distance_box = [&settings.source_reference, &settings.target_reference]
        .into_iter()
        .flatten()
        .fold(morph.world_bounds(), |b, r| b.union(&r.bounds()));
    let results: Vec<(FrameReport, TriMesh)> = (0..total)
        .into_par_iter()
        .map(|i| {
            control.check()?;
            let frame_start = Instant::now();
            let t = i as f32 / (total - 1) as f32;
            let mut mesh = morph
                .frame_mesh(t, settings.resolution)
                .map_err(|e| ExportError::Frame { t, source: BoxedError::new(e) })?;
            if let Some(colors) = &settings.colors {
                let ends = morph
                    .ends_of(t, &mesh.positions)
                    .map_err(|e| ExportError::Frame { t, source: BoxedError::new(e) })?;
                colors.paint(&mut mesh, t, ends);
            }
            let file = if settings.frame_files {
                let file = format!("frame_{i:03}.{}", settings.format.extension());
                write_mesh(&mesh, dir.join(&file), settings.format)?;
                file
            } else if settings.usd {
                format!("{USD_FILE}@{i}")
            } else {
                String::new()
            };
            let m = mesh.metrics();
            let report = FrameReport {
                t,
                file,
                vertices: m.vertices,
                triangles: m.triangles,
                components: m.components,
                voids: m.voids,
                genus: m.genus,
                area: m.area,
                volume: m.volume,
                seconds: frame_start.elapsed().as_secs_f64(),
                step_from_previous: None,
            };
            let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            control
                .progress("frames", Some(finished as f32 / total as f32), || format!("{finished}/{total}"));
            Ok((report, mesh))
        })
        .collect::<Result<_, ExportError>>()?;
    let (mut frames, meshes): (Vec<FrameReport>, Vec<TriMesh>) = results.into_iter().unzip();

    for (which, index, reference) in
        [("source", 0, &settings.source_reference), ("target", total - 1, &settings.target_reference)]
    {
        let reference_has_surface = reference.as_ref().is_some_and(|r| !r.triangles.is_empty());
        if meshes[index].triangles.is_empty() && reference_has_surface {
            return Err(ExportError::EmptyEndpoint { t: frames[index].t, which });
        }
    }

    let empty: Vec<String> = frames[1..total - 1]
        .iter()
        .zip(&meshes[1..total - 1])
        .filter(|(_, mesh)| mesh.triangles.is_empty())
        .map(|(frame, _)| format!("{}", frame.t))
        .collect();
    let mut warnings = Vec::new();
    if !empty.is_empty() {
        warnings.push(format!(
            "{} in-between frame(s) have no surface (t = {}): the shape vanishes at this resolution",
            empty.len(),
            empty.join(", ")
        ));
    }

    if settings.usd {
        control.check()?;
        let usd =
            UsdSettings { doc: format!("isomorph morph: {}", morph.method()), ..UsdSettings::default() };
        let path = dir.join(USD_FILE);
        let io_error = |source| ExportError::Io { path: path.clone(), source };
        let mut file = std::io::BufWriter::new(std::fs::File::create(&path).map_err(io_error)?);
        write_usda(&meshes, &usd, &mut file).and_then(|()| file.flush()).map_err(io_error)?;
    }
    control.check()?;
    control.progress("metrics", None, String::new);
    let voxel = world_voxel(&morph.world_bounds(), settings.resolution);
    // The end frames' pieces against their inputs' (an input's metrics are
    // serial work on the largest meshes).
    let piece_warnings = || -> Vec<String> {
        let ends = [
            ("first", "source", &settings.source_reference, frames.first()),
            ("last", "target", &settings.target_reference, frames.last()),
        ];
        ends.into_par_iter()
            .filter_map(|(which, input, reference, frame)| {
                extra_pieces_warning(which, input, reference.as_ref()?, frame?)
            })
            .collect()
    };
    // The pictures, the pieces and the distances at once, so that every
    // core stays busy (writing the pictures is serial, an endpoint's
    // reference mesh is the largest of all).
    let measure = Measure { settings, distance_box, voxel };
    let ((pictures, pieces), (steps, source, target)) = rayon::join(
        || rayon::join(|| write_pictures(&frames, &meshes, settings, control), piece_warnings),
        || measure.frames(&meshes),
    );
    pictures?;
    for (frame, step) in frames.iter_mut().skip(1).zip(&steps) {
        frame.step_from_previous = *step;
    }
    let largest_step = steps.iter().flatten().copied().reduce(f32::max);
    for (which, input, end) in [("first", "source", &source), ("last", "target", &target)] {
        if let Some((e, miss)) = end.as_ref().filter(|(e, _)| e.hausdorff_voxels > ENDPOINT_WARNING_VOXELS) {
            warnings.push(format!(
                "the {which} frame is {:.1} voxels (Hausdorff; mean {:.2}) off the {input}{}",
                e.hausdorff_voxels,
                e.mean_voxels,
                miss.as_deref().unwrap_or_default()
            ));
        }
    }
    let endpoints = Endpoints { source: source.map(|end| end.0), target: target.map(|end| end.0) };
    warnings.extend(pieces);
    let report = Report {
        method: morph.method().to_string(),
        resolution: settings.resolution,
        voxel_size: voxel,
        export_seconds: start.elapsed().as_secs_f64(),
        frames,
        endpoints,
        largest_step,
        largest_step_voxels: largest_step.map(|s| s / voxel),
        morph: morph.report().clone(),
        warnings,
    };
    let path = dir.join("report.json");
    let json = serde_json::to_string_pretty(&report).expect("report serializes");
    std::fs::write(&path, json).map_err(|source| ExportError::Io { path, source })?;
    Ok(Exported { report, meshes })
}

/// Renders the frames (`meshes`, at the times of `frames`) and writes
/// `contact_sheet.png` and `preview.gif` into `settings.out_dir`, as
/// `settings` ask.
fn write_pictures(
    frames: &[FrameReport],
    meshes: &[TriMesh],
    settings: &ExportSettings,
    control: &Control,
) -> Result<(), ExportError> {
    if !(settings.contact_sheet || settings.preview) {
        return Ok(());
    }
    control.check()?;
    control.progress("contact sheet", None, String::new);
    let times: Vec<f32> = frames.iter().map(|f| f.t).collect();
    let tiles = frame_tiles(&times, meshes, &settings.render);
    let dir = &settings.out_dir;
    if settings.contact_sheet {
        contact_sheet(&tiles, settings.sheet_columns).write_png(dir.join("contact_sheet.png"))?;
    }
    if settings.preview {
        let images: Vec<Image> = tiles.into_iter().map(|(image, _)| image).collect();
        write_gif(&images, PREVIEW_DELAY, dir.join("preview.gif"))?;
    }
    Ok(())
}

/// An end frame's distance to its input, with where it misses the input
/// most when that is farther than [`ENDPOINT_WARNING_VOXELS`] (the end of
/// its warning, see [`Measure::farthest_miss`]).
type EndMeasure = Option<(EndpointDistance, Option<String>)>;

/// How the frames' distances are measured: in one frame scaled for
/// `distance_box` (all frames and references), with voxels of `voxel`
/// world units.
struct Measure<'a> {
    settings: &'a ExportSettings,
    distance_box: Aabb,
    voxel: f32,
}

impl Measure<'_> {
    /// The distances between consecutive frames (`steps[i]` from frame `i`
    /// to `i + 1`) and from the end frames to their inputs. The frames'
    /// trees are built a chunk of frames at a time (as many as there are
    /// threads) and dropped once their steps and endpoints are measured,
    /// so that a chunk and one more tree are held, not one per frame (a
    /// tree takes several times its mesh's memory: nine of them were about
    /// 1 GB for bunny → dragon at 512³).
    fn frames(&self, meshes: &[TriMesh]) -> (Vec<Option<f32>>, EndMeasure, EndMeasure) {
        let last = meshes.len() - 1;
        let ids: Vec<usize> = (0..meshes.len()).collect();
        let (mut steps, mut source, mut target) = (Vec::with_capacity(last), None, None);
        let mut previous: Option<IndexedSurface> = None;
        for chunk in ids.chunks(rayon::current_num_threads().max(2)) {
            let trees: Vec<Option<IndexedSurface>> =
                chunk.par_iter().map(|&i| IndexedSurface::new(&meshes[i], &self.distance_box).ok()).collect();
            let end = |input, i: usize, tree: Option<&Option<IndexedSurface>>| {
                self.end(input, &meshes[i], tree?.as_ref()?)
            };
            let (chunk_steps, (first, final_)) = rayon::join(
                || {
                    chunk
                        .par_iter()
                        .enumerate()
                        .filter(|&(_, &i)| i > 0)
                        .map(|(j, _)| {
                            let a = if j == 0 { previous.as_ref() } else { trees[j - 1].as_ref() };
                            let (a, b) = (a?, trees[j].as_ref()?);
                            a.hausdorff_to(b, self.settings.step_samples).ok()
                        })
                        .collect::<Vec<Option<f32>>>()
                },
                || {
                    rayon::join(
                        || if chunk[0] == 0 { end("source", 0, trees.first()) } else { None },
                        || if chunk.last() == Some(&last) { end("target", last, trees.last()) } else { None },
                    )
                },
            );
            steps.extend(chunk_steps);
            source = source.or(first);
            target = target.or(final_);
            previous = trees.into_iter().next_back().flatten();
        }
        (steps, source, target)
    }

    /// The end frame `frame` (with its tree) against its input (`input`:
    /// "source" or "target"); `None` without a reference surface.
    fn end(&self, input: &str, frame: &TriMesh, tree: &IndexedSurface) -> EndMeasure {
        let settings = self.settings;
        let (reference, solid) = if input == "source" {
            (settings.source_reference.as_ref()?, &settings.source_solid)
        } else {
            (settings.target_reference.as_ref()?, &settings.target_solid)
        };
        let samples = settings.distance_samples;
        let mut points = surface_samples(reference, samples)?;
        let (d, known) = match solid.as_ref().filter(|s| s.has_exact_distance()) {
            Some(solid) => {
                if solid.as_mesh().is_none() {
                    // A polygonized shape: its points moved onto the true surface.
                    points =
                        points.par_iter().map(|&p| solid.nearest_surface_point(p).unwrap_or(p)).collect();
                }
                let exact = |p| solid.exact_distance(p).unwrap_or(f32::NAN);
                (tree.distance_to_reference(samples, &points, exact), Known::Solid(solid))
            }
            None => {
                let indexed = IndexedSurface::new(reference, &self.distance_box).ok()?;
                (tree.distance_to(&indexed, samples), Known::Mesh(reference, indexed))
            }
        };
        let e = EndpointDistance::new(d.ok()?, self.voxel);
        let miss = if e.hausdorff_voxels > ENDPOINT_WARNING_VOXELS {
            self.farthest_miss(input, &points, frame, tree, &known)
        } else {
            None
        };
        Some((e, miss))
    }

    /// Where the end frame `frame` (with its tree) and its input's surface
    /// (sampled at `points`, known by `known`) are farthest apart, when by
    /// more than [`ENDPOINT_WARNING_VOXELS`], as the end of a warning. Four
    /// cases, by which surface strays and to which side:
    /// - a part of the input outside the frame, which the grid may be too
    ///   coarse to form (a finer resolution is the remedy: the level set
    ///   does not grow into parts about 3 voxels across);
    /// - a part of the input inside the frame's solid: a hollow or a gap
    ///   the frame fills, or an inner sheet of an open or self-intersecting
    ///   input, which no closed frame surface follows, at any resolution;
    /// - frame surface outside the input: a bulge or a piece the input does
    ///   not have;
    /// - frame surface inside the input's solid: a hollow or a dent.
    ///
    /// `None` when they come within that distance of each other everywhere
    /// (the Hausdorff distance came from other samples).
    fn farthest_miss(
        &self,
        input: &str,
        points: &[Vec3],
        frame: &TriMesh,
        tree: &IndexedSurface,
        known: &Known<'_>,
    ) -> Option<String> {
        let missed = tree.farthest_of(points).map(|(p, d)| (p, d, false));
        let strayed = surface_samples(frame, self.settings.distance_samples)
            .and_then(|here| known.farthest_of(&here))
            .map(|(p, d)| (p, d, true));
        let (p, d, frame_strays) =
            [missed, strayed].into_iter().flatten().max_by(|a, b| a.1.total_cmp(&b.1))?;
        let voxels = d / self.voxel;
        if voxels <= ENDPOINT_WARNING_VOXELS {
            return None;
        }
        let at = format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z);
        Some(match frame_strays {
            true if known.contains(p) => format!(
                ": the frame's surface near {at} lies {voxels:.1} voxels inside the {input} \
                 (a hollow or a dent the {input} does not have)"
            ),
            true => format!(
                ": the frame has surface near {at}, {voxels:.1} voxels outside the {input} \
                 (a bulge or a piece the {input} does not have)"
            ),
            false if WindingNumber::new(frame).winding_number(p) >= 0.5 => format!(
                ": the {input}'s surface near {at} lies {voxels:.1} voxels inside the frame's solid \
                 (a hollow or a gap of the {input} that the frame fills, or an inner sheet of an open or \
                 self-intersecting {input}, which no closed surface follows)"
            ),
            false => {
                let (res, finer) = (self.settings.resolution, self.settings.resolution.saturating_mul(2));
                format!(
                    ": it does not reach the {input} near {at}, {voxels:.1} voxels away, where the {input} \
                     may be thinner than the {res}³ grid can form (about 3 voxels across); a finer \
                     resolution (resolution {finer}: `--res {finer}`) resolves more of it"
                )
            }
        })
    }
}

/// An end frame's input as its distance is known: the solid's exact
/// distance, or (without one) its reference mesh indexed in the distance
/// box.
enum Known<'a> {
    /// A solid with [`Solid::has_exact_distance`].
    Solid(&'a Solid),
    /// The reference mesh and its index.
    Mesh(&'a TriMesh, IndexedSurface),
}

impl Known<'_> {
    /// The point of `points` (world units) farthest from the input's
    /// surface, with its distance (world units).
    fn farthest_of(&self, points: &[Vec3]) -> Option<(Vec3, f32)> {
        match self {
            Known::Solid(solid) => points
                .par_iter()
                .map(|&p| (p, solid.exact_distance(p).unwrap_or(0.0)))
                .max_by(|a, b| a.1.total_cmp(&b.1)),
            Known::Mesh(_, indexed) => indexed.farthest_of(points),
        }
    }

    /// True when `p` is inside the input's solid (positive signed
    /// distance; the winding number of a mesh known by its surface only).
    fn contains(&self, p: Vec3) -> bool {
        match self {
            Known::Solid(solid) => solid.exact_field().is_some_and(|f| f.value(p) > 0.0),
            Known::Mesh(mesh, _) => WindingNumber::new(mesh).winding_number(p) >= 0.5,
        }
    }
}

/// A warning when the end frame `frame` (`which`: "first" or "last") has
/// more outer shells than its input's surface `reference` (`input`:
/// "source" or "target"): pieces the input does not have, specks of the
/// method or parts the grid splits. Only more shells than the input count:
/// an open input's patch soup has a component per patch.
fn extra_pieces_warning(
    which: &str,
    input: &str,
    reference: &TriMesh,
    frame: &FrameReport,
) -> Option<String> {
    let m = reference.metrics();
    let (shells, expected) = (frame.components - frame.voids, m.components - m.voids);
    (shells > expected).then(|| {
        format!(
            "the {which} frame has {shells} separate pieces where the {input} has {expected}: \
             the extra ones are not in the {input} (specks of the method or pieces the grid splits)"
        )
    })
}

/// The inputs' surfaces to measure the end frames against
/// ([`ExportSettings::source_reference`], `target_reference`), both at
/// once: a mesh input is itself; an analytic shape with an exact distance is
/// polygonized at the frames' `resolution` (the endpoint distances move its
/// points onto the true surface); the others at twice that (at most 256).
///
/// # Errors
/// The solids' surface errors, [`MorphError::Cancelled`].
pub fn reference_surfaces(
    source: &Solid,
    target: &Solid,
    resolution: u32,
    control: &Control,
) -> Result<(TriMesh, TriMesh), MorphError> {
    let surface = |solid: &Solid| {
        // An exact shape's reference points are moved onto its surface
        // (`Solid::nearest_surface_point`), so its polygonization only
        // needs to be as fine as the frames'; the others' are twice as fine.
        let exact = solid.as_mesh().is_none() && solid.has_exact_distance();
        let res = if exact { resolution } else { resolution.saturating_mul(2).min(256) };
        solid.surface(res, control).map(std::borrow::Cow::into_owned)
    };
    let (a, b) = rayon::join(|| surface(source), || surface(target));
    Ok((a?, b?))
}

/// One world voxel: the longest edge of `bounds` over `resolution − 1`.
pub fn world_voxel(bounds: &Aabb, resolution: u32) -> f32 {
    bounds.size().max_element() / resolution.saturating_sub(1).max(1) as f32
}

/// The frames rendered with one camera fitted to all of them, labelled
/// with their times.
pub fn frame_tiles(
    times: &[f32],
    meshes: &[TriMesh],
    render_settings: &RenderSettings,
) -> Vec<(Image, String)> {
    let mut settings = *render_settings;
    if settings.camera.is_none() {
        let bounds = meshes.iter().fold(Aabb::EMPTY, |b, m| b.union(&m.bounds()));
        if !bounds.is_empty() {
            settings.camera = Some(Camera::fit(&bounds, Camera::DEFAULT_VIEW_DIR));
        }
    }
    times.par_iter().zip(meshes).map(|(t, m)| (render(m, &settings), format!("t = {t:.2}"))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::mesh::primitives::uv_sphere;

    fn frame_of(components: usize, voids: usize) -> FrameReport {
        FrameReport {
            t: 1.0,
            file: String::new(),
            vertices: 0,
            triangles: 0,
            components,
            voids,
            genus: Some(0),
            area: 1.0,
            volume: 1.0,
            seconds: 0.0,
            step_from_previous: None,
        }
    }

    /// The four ways an end frame and its input come apart, each named with
    /// its place: frames of a ball with a speck beside it (source) and with
    /// a hollow inside (target) measured against the plain ball, then the
    /// plain ball's frames against the speckled and the hollow ones.
    #[test]
    fn end_frames_off_their_inputs_say_where_and_how() {
        use isomorph_common::{BlendSettings, DistanceBlend, Shape};
        let ball = Solid::shape(Shape::sphere(0.3));
        const SPECK: Vec3 = Vec3::new(0.55, 0.0, 0.0);
        let speckled = Solid::shape(Shape::sphere(0.3).union(Shape::sphere(0.07).translated(SPECK)));
        let hollow = Solid::shape(Shape::sphere(0.3).subtract(Shape::sphere(0.12)));
        let control = Control::new();
        let warnings = |case: usize, morph: (&Solid, &Solid), inputs: (&Solid, &Solid)| {
            let settings = BlendSettings { resolution: 48, ..BlendSettings::default() };
            let morph = DistanceBlend::new(morph.0, morph.1, &settings, &control).unwrap();
            let out =
                std::env::temp_dir().join(format!("isomorph-export-miss-{}-{case}", std::process::id()));
            let export = ExportSettings {
                frames: 2,
                resolution: 48,
                out_dir: out.clone(),
                frame_files: false,
                contact_sheet: false,
                preview: false,
                ..ExportSettings::default()
            }
            .with_inputs(inputs.0, inputs.1, &control)
            .unwrap();
            let report = export_sequence(&morph, &export, &control).unwrap().report;
            std::fs::remove_dir_all(out).unwrap();
            let end = |which: &str| {
                let prefix = format!("the {which} frame is ");
                report.warnings.iter().find(|w| w.starts_with(&prefix)).cloned().unwrap_or_default()
            };
            (end("first"), end("last"))
        };
        let place = |warning: &str, after: &str| {
            let start =
                warning.find(after).unwrap_or_else(|| panic!("no {after:?} in {warning:?}")) + after.len();
            let end = start + warning[start..].find(')').unwrap();
            let c: Vec<f32> = warning[start..end].split(", ").map(|c| c.parse().unwrap()).collect();
            Vec3::new(c[0], c[1], c[2])
        };
        let on_the_speck: fn(Vec3) -> bool = |p| p.distance(SPECK) < 0.08 && p.x > 0.5;
        let on_the_hollow: fn(Vec3) -> bool = |p| (p.length() - 0.12).abs() < 0.02;
        // First the frames stray from the ball, then the ball's frames miss
        // the speck and the hollow: per end, where the place follows, what
        // the warning says, and where the place must be.
        let cases = [
            (
                (&speckled, &hollow),
                (&ball, &ball),
                [
                    (
                        "the frame has surface near (",
                        "voxels outside the source (a bulge or a piece",
                        on_the_speck,
                    ),
                    (
                        "the frame's surface near (",
                        "voxels inside the target (a hollow or a dent",
                        on_the_hollow,
                    ),
                ],
            ),
            (
                (&ball, &ball),
                (&speckled, &hollow),
                [
                    ("it does not reach the source near (", "`--res 96`", on_the_speck),
                    (
                        "the target's surface near (",
                        "inside the frame's solid (a hollow or a gap",
                        on_the_hollow,
                    ),
                ],
            ),
        ];
        for (case, (morph, inputs, ends)) in cases.into_iter().enumerate() {
            let (first, last) = warnings(case, morph, inputs);
            for (warning, (after, says, on)) in [first, last].iter().zip(ends) {
                let p = place(warning, after);
                assert!(warning.contains(says), "{warning}");
                assert!(on(p), "{p} is not where {warning:?} should be");
            }
        }
    }

    /// More outer shells than the input is reported (the 25,000-point RBF
    /// dragon's last frame had 4 where the mesh has 1); as many, or fewer
    /// than an input of several pieces (an open patch soup), is not; voids
    /// are not shells.
    #[test]
    fn end_frames_with_more_pieces_than_their_input_are_reported() {
        let one = uv_sphere(Vec3::ZERO, 0.3, 12, 16);
        let warning = extra_pieces_warning("last", "target", &one, &frame_of(4, 0)).unwrap();
        assert!(warning.contains("4 separate pieces where the target has 1"), "{warning}");
        assert_eq!(extra_pieces_warning("last", "target", &one, &frame_of(1, 0)), None);
        assert_eq!(extra_pieces_warning("first", "source", &one, &frame_of(2, 1)), None);
        let mut two = one.clone();
        two.append(&uv_sphere(Vec3::X, 0.3, 12, 16));
        assert_eq!(extra_pieces_warning("last", "target", &two, &frame_of(2, 0)), None);
        assert!(extra_pieces_warning("last", "target", &two, &frame_of(3, 0)).is_some());
    }
}
