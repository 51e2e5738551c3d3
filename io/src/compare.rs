//! Side-by-side comparison of morph methods on one input pair
//! ([`compare`]): each method's frames and report as the sequence exporter
//! writes them, plus one contact sheet with a row per method
//! (`compare.png`), a table (`compare.json`, `compare.md`) and a
//! self-contained page with the sheet, the table and plots of area, volume
//! and components against `t` (`compare.html`, inline SVG, no network).
//!
//! Peak memory is the process's peak resident set size while a method is
//! built and exported (Linux `VmHWM`, reset before each method through
//! `/proc/self/clear_refs`), so it includes the process's baseline, which is
//! reported beside it; `None` where the system does not tell.

use crate::export::{ExportError, ExportSettings, Exported, PREVIEW_DELAY, Report, frame_tiles};
use crate::render::{Camera, ContactSheet, Image, RenderError, write_gif};
use base64::Engine;
use isomorph_common::{Aabb, BoxedError, BoxedMorph, Control, MorphError, MorphFailure, StageTime, TriMesh};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Builds one method's morph under a [`Control`].
pub type BuildMorph = Box<dyn FnOnce(&Control) -> Result<BoxedMorph, BoxedError>>;

/// One method to compare: its name and how to build it, or why it cannot
/// run on these inputs.
pub struct Candidate {
    /// The method's name (also its output subfolder).
    pub name: String,
    /// Builds the morph, or says why the method does not apply.
    pub build: Result<BuildMorph, String>,
    /// The method's own source and target surfaces for the endpoint
    /// distances, when its inputs differ from the others' (e.g. BlobTree
    /// scenes); `None` uses the export settings' references.
    pub references: Option<(TriMesh, TriMesh)>,
}

/// Errors of [`compare`] (a method's own failure is a row, not an error).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CompareError {
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The sheet could not be written.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Cancelled through the control.
    #[error("cancelled")]
    Cancelled,
}

/// How a method fared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Built and exported.
    Ok,
    /// Does not take these inputs.
    Skipped,
    /// Built or exported with an error.
    Failed,
}

/// One row of the comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// The method.
    pub method: String,
    /// How it fared.
    pub status: Status,
    /// Why it was skipped or how it failed.
    pub reason: Option<String>,
    /// Whether the method reached its goal (its report's `converged`).
    pub converged: Option<bool>,
    /// Wall time of construction (seconds).
    pub build_seconds: Option<f64>,
    /// Construction time per stage, as the method reports it.
    pub stages: Vec<StageTime>,
    /// Wall time of polygonizing, writing and measuring the frames.
    pub export_seconds: Option<f64>,
    /// Process peak resident bytes during this method (see the module docs).
    pub peak_rss_bytes: Option<u64>,
    /// Process resident bytes just before this method.
    pub baseline_rss_bytes: Option<u64>,
    /// The method's own estimate of its peak working memory.
    pub estimated_peak_bytes: Option<usize>,
    /// Mean two-sided distance of frame 0 to the source (world voxels).
    pub source_mean_voxels: Option<f32>,
    /// Hausdorff distance of frame 0 to the source (world voxels).
    pub source_hausdorff_voxels: Option<f32>,
    /// Mean distance of the last frame to the target (world voxels).
    pub target_mean_voxels: Option<f32>,
    /// Hausdorff distance of the last frame to the target (world voxels).
    pub target_hausdorff_voxels: Option<f32>,
    /// The largest number of connected components over the frames.
    pub max_components: Option<usize>,
    /// Genus per frame (`None` where a frame is not a closed 2-manifold).
    pub genus: Vec<Option<i64>>,
    /// Frame times.
    pub t: Vec<f32>,
    /// Surface area per frame (world units²).
    pub area: Vec<f64>,
    /// Enclosed volume per frame (world units³).
    pub volume: Vec<f64>,
    /// Components per frame.
    pub components: Vec<usize>,
    /// Of those, walls of enclosed cavities per frame.
    pub voids: Vec<usize>,
    /// The largest Hausdorff distance between consecutive frames (world voxels).
    pub largest_step_voxels: Option<f32>,
}

impl Row {
    fn new(method: &str, status: Status, reason: Option<String>) -> Self {
        Self {
            method: method.to_string(),
            status,
            reason,
            converged: None,
            build_seconds: None,
            stages: Vec::new(),
            export_seconds: None,
            peak_rss_bytes: None,
            baseline_rss_bytes: None,
            estimated_peak_bytes: None,
            source_mean_voxels: None,
            source_hausdorff_voxels: None,
            target_mean_voxels: None,
            target_hausdorff_voxels: None,
            max_components: None,
            genus: Vec::new(),
            t: Vec::new(),
            area: Vec::new(),
            volume: Vec::new(),
            components: Vec::new(),
            voids: Vec::new(),
            largest_step_voxels: None,
        }
    }

    fn from_report(method: &str, build_seconds: f64, report: &Report) -> Self {
        let end = |e: Option<crate::export::EndpointDistance>| {
            (e.map(|d| d.mean_voxels), e.map(|d| d.hausdorff_voxels))
        };
        let (source_mean_voxels, source_hausdorff_voxels) = end(report.endpoints.source);
        let (target_mean_voxels, target_hausdorff_voxels) = end(report.endpoints.target);
        Self {
            converged: Some(report.morph.converged),
            build_seconds: Some(build_seconds),
            stages: report.morph.stages.clone(),
            export_seconds: Some(report.export_seconds),
            estimated_peak_bytes: report.morph.peak_bytes,
            source_mean_voxels,
            source_hausdorff_voxels,
            target_mean_voxels,
            target_hausdorff_voxels,
            max_components: Some(report.max_components()),
            genus: report.genus_sequence(),
            t: report.frames.iter().map(|f| f.t).collect(),
            area: report.frames.iter().map(|f| f.area).collect(),
            volume: report.frames.iter().map(|f| f.volume).collect(),
            components: report.frames.iter().map(|f| f.components).collect(),
            voids: report.frames.iter().map(|f| f.voids).collect(),
            largest_step_voxels: report.largest_step_voxels,
            ..Self::new(method, Status::Ok, None)
        }
    }
}

/// The whole comparison (`compare.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Comparison {
    /// The source, as the user named it.
    pub source: String,
    /// The target, as the user named it.
    pub target: String,
    /// Nodes along the longest edge.
    pub resolution: u32,
    /// Frames per method.
    pub frames: usize,
    /// One row per method, in the order given.
    pub rows: Vec<Row>,
}

/// Runs every candidate on the pair (`source` and `target` name it in the
/// outputs), exporting each into `settings.out_dir/<name>/`, and writes
/// `compare.png`, `preview.gif` (unless [`ExportSettings::preview`] is
/// off), `compare.json`, `compare.md` and `compare.html` into
/// `settings.out_dir`. A method that fails is a [`Status::Failed`] row, one
/// that does not take the inputs ([`MorphError::UnsupportedInput`]) a
/// [`Status::Skipped`] row; a cancelled run stops everything.
///
/// # Errors
/// [`CompareError`] for files that cannot be written and cancellation.
pub fn compare(
    source: &str,
    target: &str,
    candidates: Vec<Candidate>,
    settings: &ExportSettings,
    control: &Control,
) -> Result<Comparison, CompareError> {
    let dir = settings.out_dir.clone();
    std::fs::create_dir_all(&dir).map_err(|e| CompareError::Io { path: dir.clone(), source: e })?;
    let mut rows = Vec::new();
    let mut shown: Vec<(String, Exported)> = Vec::new();
    for candidate in candidates {
        let name = candidate.name;
        let build = match candidate.build {
            Ok(build) => build,
            Err(reason) => {
                rows.push(Row::new(&name, Status::Skipped, Some(reason)));
                continue;
            }
        };
        control.progress("compare", None, || format!("{name}: building"));
        let baseline = memory::reset_peak();
        let start = Instant::now();
        let built = build(control);
        let build_seconds = start.elapsed().as_secs_f64();
        let morph = match built {
            Ok(m) => m,
            Err(e) if e.is_cancelled() => return Err(CompareError::Cancelled),
            Err(e) => {
                // A method that does not take these inputs is skipped, not failed.
                let unsupported = matches!(e.shared(), Some(MorphError::UnsupportedInput { .. }));
                let status = if unsupported { Status::Skipped } else { Status::Failed };
                rows.push(Row::new(&name, status, Some(error_chain(&e))));
                continue;
            }
        };
        control.progress("compare", None, || format!("{name}: frames"));
        let mut method_settings = ExportSettings { out_dir: dir.join(&name), ..settings.clone() };
        if let Some((source, target)) = candidate.references {
            method_settings.source_reference = Some(source);
            method_settings.target_reference = Some(target);
        }
        match crate::export::export_sequence(&*morph, &method_settings, control) {
            Ok(exported) => {
                let mut row = Row::from_report(&name, build_seconds, &exported.report);
                row.peak_rss_bytes = memory::peak();
                row.baseline_rss_bytes = baseline;
                rows.push(row);
                shown.push((name, exported));
            }
            Err(ExportError::Cancelled(_)) => return Err(CompareError::Cancelled),
            Err(e) => rows.push(Row::new(&name, Status::Failed, Some(error_chain(&e)))),
        }
    }
    let comparison = Comparison {
        source: source.to_string(),
        target: target.to_string(),
        resolution: settings.resolution,
        frames: settings.frames,
        rows,
    };
    let tiles = method_tiles(&shown, settings);
    let mut png = Vec::new();
    comparison_sheet(&tiles, settings).write_png_to(&mut png)?;
    write(&dir.join("compare.png"), &png)?;
    if settings.preview && !tiles.is_empty() {
        write_gif(&comparison_preview(&tiles, settings), PREVIEW_DELAY, dir.join("preview.gif"))?;
    }
    write(
        &dir.join("compare.json"),
        serde_json::to_string_pretty(&comparison).expect("serializes").as_bytes(),
    )?;
    write(&dir.join("compare.md"), markdown(&comparison).as_bytes())?;
    write(&dir.join("compare.html"), html(&comparison, &png).as_bytes())?;
    Ok(comparison)
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), CompareError> {
    std::fs::write(path, bytes).map_err(|source| CompareError::Io { path: path.to_path_buf(), source })
}

/// An error and its causes as one line, each cause once (library errors
/// often repeat their cause in their own message): how the comparison's
/// notes, the command line and the Python package print errors.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let c_text = c.to_string();
        if !text.contains(&c_text) {
            let _ = write!(text, ": {c_text}");
        }
        cause = c.source();
    }
    text
}

/// Every method's frames rendered with one camera (fitted to every frame
/// of every method), in time order, labelled with the method's name and the
/// time.
fn method_tiles(shown: &[(String, Exported)], settings: &ExportSettings) -> Vec<Vec<(Image, String)>> {
    let bounds = shown
        .iter()
        .flat_map(|(_, e)| e.meshes.iter())
        .fold(Aabb::EMPTY, |b, m| if m.triangles.is_empty() { b } else { b.union(&m.bounds()) });
    let mut render = settings.render;
    if !bounds.is_empty() {
        render.camera = Some(Camera::fit(&bounds, Camera::DEFAULT_VIEW_DIR));
    }
    shown
        .iter()
        .map(|(name, exported)| {
            let times: Vec<f32> = exported.report.frames.iter().map(|f| f.t).collect();
            frame_tiles(&times, &exported.meshes, &render)
                .into_iter()
                .map(|(image, label)| (image, format!("{name} {label}")))
                .collect()
        })
        .collect()
}

/// One row of tiles per method, the same times in each column.
fn comparison_sheet(tiles: &[Vec<(Image, String)>], settings: &ExportSettings) -> Image {
    ContactSheet {
        columns: settings.frames as u32,
        title: Some("isomorph compare".into()),
        ..Default::default()
    }
    .compose(&tiles.concat())
}

/// The methods side by side, one animation frame per time.
fn comparison_preview(tiles: &[Vec<(Image, String)>], settings: &ExportSettings) -> Vec<Image> {
    let sheet = ContactSheet { columns: tiles.len() as u32, ..Default::default() };
    (0..settings.frames)
        .map(|i| {
            let column: Vec<(Image, String)> = tiles.iter().filter_map(|row| row.get(i).cloned()).collect();
            sheet.compose(&column)
        })
        .collect()
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map_or_else(|| "–".to_string(), |v| v.to_string())
}

fn fixed(v: Option<f32>, digits: usize) -> String {
    v.map_or_else(|| "–".to_string(), |v| format!("{v:.digits$}"))
}

fn mib(v: Option<u64>) -> String {
    v.map_or_else(|| "–".to_string(), |b| format!("{:.0}", b as f64 / (1 << 20) as f64))
}

fn genus_text(g: &[Option<i64>]) -> String {
    g.iter().map(|g| g.map_or_else(|| "?".into(), |g| g.to_string())).collect::<Vec<_>>().join(" ")
}

fn stages_text(stages: &[StageTime]) -> String {
    stages.iter().map(|s| format!("{} {:.2}", s.stage, s.seconds)).collect::<Vec<_>>().join(", ")
}

const HEADER: [&str; 12] = [
    "method",
    "status",
    "build s",
    "export s",
    "peak RSS MiB",
    "source mean / Hausdorff (voxels)",
    "target mean / Hausdorff (voxels)",
    "max components",
    "genus per frame",
    "largest step (voxels)",
    "stages (s)",
    "note",
];

fn cells(r: &Row) -> [String; 12] {
    let status = match (r.status, r.converged) {
        (Status::Ok, Some(false)) => "ok, not converged".to_string(),
        (Status::Ok, _) => "ok".to_string(),
        (Status::Skipped, _) => "skipped".to_string(),
        (Status::Failed, _) => "failed".to_string(),
    };
    [
        r.method.clone(),
        status,
        r.build_seconds.map_or_else(|| "–".into(), |s| format!("{s:.2}")),
        r.export_seconds.map_or_else(|| "–".into(), |s| format!("{s:.2}")),
        mib(r.peak_rss_bytes),
        format!("{} / {}", fixed(r.source_mean_voxels, 2), fixed(r.source_hausdorff_voxels, 2)),
        format!("{} / {}", fixed(r.target_mean_voxels, 2), fixed(r.target_hausdorff_voxels, 2)),
        opt(r.max_components),
        genus_text(&r.genus),
        fixed(r.largest_step_voxels, 2),
        stages_text(&r.stages),
        r.reason.clone().unwrap_or_default(),
    ]
}

/// `compare.md`: the table in Markdown.
fn markdown(c: &Comparison) -> String {
    let mut s = format!(
        "# isomorph compare: {} → {}\n\n{} frames per method, resolution {}.\n\n",
        c.source, c.target, c.frames, c.resolution
    );
    let _ = writeln!(s, "| {} |", HEADER.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(HEADER.len()));
    for r in &c.rows {
        let row: Vec<String> = cells(r).iter().map(|c| c.replace('|', "\\|")).collect();
        let _ = writeln!(s, "| {} |", row.join(" | "));
    }
    s
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Line colours of the plots, one per method in order.
const COLORS: [&str; 8] =
    ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];

/// An SVG line plot of `series` (name, points) with axes, ticks and a
/// legend; `counts` plots whole numbers from 0 with integer ticks.
fn line_plot(title: &str, y_label: &str, series: &[(&str, Vec<(f64, f64)>)], counts: bool) -> String {
    let (w, h, left, right, top, bottom) = (440.0, 280.0, 62.0, 130.0, 30.0, 40.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let ys = series.iter().flat_map(|(_, p)| p.iter().map(|q| q.1)).filter(|y| y.is_finite());
    let (mut lo, mut hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if counts {
        (lo, hi) = (0.0, (hi + 1.0).ceil().max(2.0));
    } else if hi - lo < 1e-12 {
        (lo, hi) = (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0));
    }
    let steps = if counts { (hi as u32).min(8) } else { 4 };
    let x = |t: f64| left + pw * t;
    let y = |v: f64| top + ph * (1.0 - (v - lo) / (hi - lo));
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n<text x=\"{}\" y=\"18\" font-size=\"13\" \
         font-weight=\"bold\">{}</text>\n",
        left,
        escape(title)
    );
    let _ = writeln!(
        s,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#999\"/>"
    );
    for k in 0..=steps {
        let v = lo + f64::from(k) / f64::from(steps) * (hi - lo);
        let label = if counts { format!("{v:.0}") } else { tick(v) };
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{label}</text>",
            left - 4.0,
            y(v) + 4.0
        );
    }
    for k in 0..=4 {
        let f = f64::from(k) / 4.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{f:.2}</text>",
            x(f),
            top + ph + 14.0
        );
    }
    let _ = writeln!(s, "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">t</text>", x(0.5), h - 6.0);
    let _ = writeln!(
        s,
        "<text transform=\"translate(12 {:.1}) rotate(-90)\" text-anchor=\"middle\">{}</text>",
        top + 0.5 * ph,
        escape(y_label)
    );
    for (i, (name, points)) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let path: Vec<String> = points
            .iter()
            .filter(|p| p.1.is_finite())
            .map(|&(t, v)| format!("{:.1},{:.1}", x(t), y(v)))
            .collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"2\" points=\"{}\"/>",
            path.join(" ")
        );
        let ly = top + 14.0 * i as f64 + 8.0;
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"{color}\" stroke-width=\"2\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
            w - right + 10.0,
            w - right + 28.0,
            w - right + 32.0,
            ly + 4.0,
            escape(name)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A short tick label.
fn tick(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) { format!("{v:.3}") } else { format!("{v:.2e}") }
}

/// `compare.html`: the sheet (embedded), the table and the plots.
fn html(c: &Comparison, png: &[u8]) -> String {
    let ran: Vec<&Row> = c.rows.iter().filter(|r| r.status == Status::Ok).collect();
    let series = |f: &dyn Fn(&Row) -> Vec<f64>| -> Vec<(&str, Vec<(f64, f64)>)> {
        ran.iter()
            .map(|r| (r.method.as_str(), r.t.iter().map(|&t| f64::from(t)).zip(f(r)).collect()))
            .collect()
    };
    let plots = [
        line_plot("Surface area", "area", &series(&|r| r.area.clone()), false),
        line_plot("Enclosed volume", "volume", &series(&|r| r.volume.clone()), false),
        line_plot(
            "Connected components",
            "components",
            &series(&|r| r.components.iter().map(|&n| n as f64).collect()),
            true,
        ),
    ];
    let mut table = String::from("<table>\n<tr>");
    for h in HEADER {
        let _ = write!(table, "<th>{}</th>", escape(h));
    }
    table.push_str("</tr>\n");
    for r in &c.rows {
        table.push_str("<tr>");
        for cell in cells(r) {
            let _ = write!(table, "<td>{}</td>", escape(&cell));
        }
        table.push_str("</tr>\n");
    }
    table.push_str("</table>\n");
    let title = format!("isomorph compare: {} → {}", c.source, c.target);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{t}</title>\n<style>\n\
         body {{ font-family: sans-serif; margin: 24px; color: #222; background: #fafaf8; }}\n\
         table {{ border-collapse: collapse; margin: 16px 0; font-size: 13px; }}\n\
         th, td {{ border: 1px solid #bbb; padding: 4px 8px; text-align: left; vertical-align: top; }}\n\
         th {{ background: #e8e8e4; }}\n img {{ max-width: 100%; border: 1px solid #ccc; }}\n\
         .plots {{ display: flex; flex-wrap: wrap; gap: 12px; }}\n</style>\n</head>\n<body>\n\
         <h1>{t}</h1>\n<p>{frames} frames per method at resolution {res}; distances in world voxels \
         (the longest edge of each morph's world box over resolution − 1).</p>\n\
         <img alt=\"one row of frames per method\" src=\"data:image/png;base64,{png}\">\n{table}\
         <div class=\"plots\">\n{plots}</div>\n</body>\n</html>\n",
        t = escape(&title),
        frames = c.frames,
        res = c.resolution,
        png = base64::engine::general_purpose::STANDARD.encode(png),
        plots = plots.join("\n"),
    )
}

/// Process memory from `/proc/self` (Linux); `None` elsewhere.
mod memory {
    /// Resets the peak resident set size and returns the current one.
    pub fn reset_peak() -> Option<u64> {
        // Writing 5 to clear_refs resets VmHWM (Linux 4.0 and later).
        let _ = std::fs::write("/proc/self/clear_refs", "5");
        field("VmRSS:")
    }

    /// The peak resident set size since the last reset.
    pub fn peak() -> Option<u64> {
        field("VmHWM:")
    }

    fn field(name: &str) -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kib: u64 = line[name.len()..].trim().trim_end_matches("kB").trim().parse().ok()?;
        Some(kib * 1024)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::{BlendSettings, DistanceBlend, MorphError, MorphExt, Solid, models};

    #[test]
    fn writes_the_sheet_tables_and_page() {
        let dir = std::env::temp_dir().join(format!("isomorph-compare-{}", std::process::id()));
        let (a, b) = (Solid::shape(models::sphere()), Solid::shape(models::torus()));
        let blend = move |c: &Control| -> Result<BoxedMorph, BoxedError> {
            let settings = BlendSettings { resolution: 24, ..Default::default() };
            Ok(DistanceBlend::new(&a, &b, &settings, c)?.boxed())
        };
        let candidates = vec![
            Candidate { name: "baseline".into(), build: Ok(Box::new(blend)), references: None },
            Candidate { name: "never".into(), build: Err("does not take shapes".into()), references: None },
            Candidate {
                name: "broken".into(),
                build: Ok(Box::new(|_: &Control| Err(MorphError::InvalidInput("no".into()).into()))),
                references: None,
            },
        ];
        let settings =
            ExportSettings { frames: 3, resolution: 24, out_dir: dir.clone(), ..Default::default() };
        let c = compare("sphere", "torus", candidates, &settings, &Control::new()).unwrap();
        let status: Vec<Status> = c.rows.iter().map(|r| r.status).collect();
        assert_eq!(status, [Status::Ok, Status::Skipped, Status::Failed]);
        let ok = &c.rows[0];
        assert_eq!((ok.t.len(), ok.genus.first().copied()), (3, Some(Some(0))));
        assert_eq!(ok.genus.last().copied(), Some(Some(1)));
        for file in ["compare.png", "compare.json", "compare.md", "compare.html", "baseline/report.json"] {
            assert!(dir.join(file).is_file(), "{file}");
        }
        // The animated previews: 3 frames forward and back are 4 GIF frames.
        for file in ["preview.gif", "baseline/preview.gif"] {
            let bytes = std::fs::read(dir.join(file)).unwrap();
            let mut reader = gif::DecodeOptions::new().read_info(bytes.as_slice()).unwrap();
            let mut count = 0;
            while reader.read_next_frame().unwrap().is_some() {
                count += 1;
            }
            assert_eq!(count, 4, "{file}");
        }
        let page = std::fs::read_to_string(dir.join("compare.html")).unwrap();
        assert!(page.contains("data:image/png;base64,iVBOR") && page.matches("<svg").count() == 3);
        assert!(!page.contains("http://") || page.matches("http://").count() == 3, "only the SVG namespaces");
        let md = std::fs::read_to_string(dir.join("compare.md")).unwrap();
        assert!(md.contains("| never | skipped |") && md.contains("does not take shapes"), "{md}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
