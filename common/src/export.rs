//! The generic sequence exporter: polygonize frames of any [`Morph`], write
//! the meshes, a PNG contact sheet and `report.json`.
//!
//! # `report.json`
//! Stable keys (all distances in world units unless suffixed `_voxels`):
//!
//! ```json
//! {
//!   "method": "baseline", "resolution": 64, "voxel_size": 0.0159,
//!   "total_seconds": 0.41,
//!   "frames": [ { "t": 0.0, "file": "frame_000.ply", "vertices": 1234, "triangles": 2464,
//!                 "components": 1, "genus": 0, "area": 0.9, "volume": 0.1, "seconds": 0.02 } ],
//!   "endpoints": { "source": { "mean": 0.001, "hausdorff": 0.004,
//!                              "mean_voxels": 0.06, "hausdorff_voxels": 0.25 },
//!                  "target": { ... } }
//! }
//! ```
//! `genus` is `null` for frames that are not closed 2-manifolds; an endpoint is
//! `null` when no reference mesh was given.

use crate::TriMesh;
use crate::mesh::distance::{SurfaceDistance, surface_distance};
use crate::mesh::io::{MeshFormat, write_mesh};
use crate::morph::Morph;
use crate::render::{Image, RenderSettings, contact_sheet, render};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// Write `contact_sheet.png`.
    pub contact_sheet: bool,
    /// Frames per row of the contact sheet.
    pub sheet_columns: u32,
    /// Preview settings of each contact-sheet tile (camera fitted to all frames when `None`).
    pub render: RenderSettings,
    /// The source surface, to measure how well frame 0 matches it.
    pub source_reference: Option<TriMesh>,
    /// The target surface, to measure how well the last frame matches it.
    pub target_reference: Option<TriMesh>,
    /// Surface samples per mesh for the endpoint distances.
    pub distance_samples: usize,
}

impl Default for ExportSettings {
    fn default() -> Self {
        Self {
            frames: 9,
            resolution: 64,
            out_dir: PathBuf::from("out"),
            format: MeshFormat::PlyBinaryLittleEndian,
            contact_sheet: true,
            sheet_columns: 5,
            render: RenderSettings { width: 240, height: 240, ..RenderSettings::default() },
            source_reference: None,
            target_reference: None,
            distance_samples: 20_000,
        }
    }
}

/// Progress of an export, passed to the callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ExportProgress {
    /// `done` of `total` frames polygonized and written.
    Frame {
        /// Frames finished.
        done: usize,
        /// Frames in all.
        total: usize,
    },
    /// Rendering the contact sheet.
    ContactSheet,
    /// Measuring endpoint distances.
    Endpoints,
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
        source: Box<dyn std::error::Error + Send + Sync>,
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
    MeshIo(#[from] crate::mesh::io::MeshIoError),
    /// The contact sheet could not be written.
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    /// The callback asked to stop.
    #[error("cancelled")]
    Cancelled,
}

/// Metrics of one exported frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameReport {
    /// Morph time.
    pub t: f32,
    /// Mesh file name inside the output folder.
    pub file: String,
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Connected components.
    pub components: usize,
    /// Genus, when the frame is a closed 2-manifold.
    pub genus: Option<i64>,
    /// Surface area (world units²).
    pub area: f64,
    /// Enclosed volume (world units³).
    pub volume: f64,
    /// Wall time to make, polygonize and write this frame.
    pub seconds: f64,
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
    /// Edge length of one voxel (world units).
    pub voxel_size: f32,
    /// Wall time of the whole export.
    pub total_seconds: f64,
    /// One entry per frame, in time order.
    pub frames: Vec<FrameReport>,
    /// Endpoint distances.
    pub endpoints: Endpoints,
    /// [`Morph::details`]: method-specific convergence and cost figures.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub details: Option<serde_json::Value>,
}

impl Report {
    /// The largest component count over all frames.
    pub fn max_components(&self) -> usize {
        self.frames.iter().map(|f| f.components).max().unwrap_or(0)
    }
}

/// Polygonizes `settings.frames` frames of `morph` (in parallel), writes
/// `frame_NNN.<ext>`, `contact_sheet.png` and `report.json` into
/// `settings.out_dir`, and returns the report. `progress` is called as work
/// finishes; returning `false` cancels.
///
/// # Errors
/// [`ExportError`] for bad settings, a failing frame, IO problems or
/// cancellation.
pub fn export_sequence<M: Morph + ?Sized>(
    morph: &M,
    settings: &ExportSettings,
    progress: &(dyn Fn(ExportProgress) -> bool + Sync),
) -> Result<Report, ExportError> {
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
    let results: Vec<(FrameReport, TriMesh)> = (0..total)
        .into_par_iter()
        .map(|i| {
            let frame_start = Instant::now();
            let t = i as f32 / (total - 1) as f32;
            let mesh = morph
                .frame_mesh(t, settings.resolution)
                .map_err(|e| ExportError::Frame { t, source: Box::new(e) })?;
            let file = format!("frame_{i:03}.{}", settings.format.extension());
            write_mesh(&mesh, dir.join(&file), settings.format)?;
            let m = mesh.metrics();
            let report = FrameReport {
                t,
                file,
                vertices: m.vertices,
                triangles: m.triangles,
                components: m.components,
                genus: m.genus,
                area: m.area,
                volume: m.volume,
                seconds: frame_start.elapsed().as_secs_f64(),
            };
            let finished = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if !progress(ExportProgress::Frame { done: finished, total }) {
                return Err(ExportError::Cancelled);
            }
            Ok((report, mesh))
        })
        .collect::<Result<_, _>>()?;

    if settings.contact_sheet {
        if !progress(ExportProgress::ContactSheet) {
            return Err(ExportError::Cancelled);
        }
        write_contact_sheet(&results, settings, &dir.join("contact_sheet.png"))?;
    }

    if !progress(ExportProgress::Endpoints) {
        return Err(ExportError::Cancelled);
    }
    let voxel = morph.bounds().size().max_element() / (settings.resolution - 1) as f32;
    let endpoint = |reference: &Option<TriMesh>, mesh: &TriMesh| {
        let reference = reference.as_ref()?;
        let d = surface_distance(mesh, reference, settings.distance_samples).ok()?;
        Some(EndpointDistance::new(d, voxel))
    };
    let endpoints = Endpoints {
        source: endpoint(&settings.source_reference, &results[0].1),
        target: endpoint(&settings.target_reference, &results[total - 1].1),
    };
    let report = Report {
        method: morph.method().to_string(),
        resolution: settings.resolution,
        voxel_size: voxel,
        total_seconds: start.elapsed().as_secs_f64(),
        frames: results.into_iter().map(|(r, _)| r).collect(),
        endpoints,
        details: morph.details(),
    };
    let path = dir.join("report.json");
    let json = serde_json::to_string_pretty(&report).expect("report serializes");
    std::fs::write(&path, json).map_err(|source| ExportError::Io { path, source })?;
    Ok(report)
}

/// Renders every frame with one camera fitted to all of them and tiles the
/// images, labelled with their times.
fn write_contact_sheet(
    frames: &[(FrameReport, TriMesh)],
    settings: &ExportSettings,
    path: &Path,
) -> Result<(), ExportError> {
    let mut render_settings = settings.render;
    if render_settings.camera.is_none() {
        let bounds = frames.iter().fold(crate::Aabb::EMPTY, |b, (_, m)| b.union(&m.bounds()));
        if !bounds.is_empty() {
            render_settings.camera =
                Some(crate::render::Camera::fit(&bounds, crate::render::Camera::DEFAULT_VIEW_DIR));
        }
    }
    let tiles: Vec<(Image, String)> =
        frames.par_iter().map(|(r, m)| (render(m, &render_settings), format!("t = {:.2}", r.t))).collect();
    contact_sheet(&tiles, settings.sheet_columns).write_png(path)?;
    Ok(())
}
