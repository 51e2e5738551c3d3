//! `isomorph demo`: a complete example from built-in shapes, in seconds,
//! with every method's library defaults.

use crate::morph::{Format, Io, morph, print_summary};
use crate::options::KernelArg;
use crate::raw::RawArgs;
use crate::rbf::{self, ContourMethod, ContoursArgs};
use crate::warp::{self, FilterArg, WarpArgs};
use anyhow::Context;
use clap::Args;
use isomorph_cli::methods::{LandmarkWarp, Method, Settings, landmark_warp};
use isomorph_common::glam::Vec3;
use isomorph_common::mesh::primitives::torus;
use isomorph_common::{Control, Solid, TriMesh, models};
use isomorph_io::inputs::{BUNNY, bunny};
use isomorph_io::mesh::{MeshFormat, write_mesh};
use isomorph_levelset::Align;
use std::f32::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

/// Arguments of `isomorph demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder; each morph gets a subfolder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Grid nodes along the longest edge of the frames (and of the grid
    /// methods) [default: 64, the libraries' defaults].
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=512))]
    res: Option<u32>,
    /// Frames per morph.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(2..=200))]
    frames: u32,
    /// Threads to use (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
}

/// Writes the finned ball with its fin along +x and along +y (meshes) and
/// the landmarks between them into `dir`; returns the three paths.
fn fin_inputs(dir: &Path) -> anyhow::Result<(String, String, String)> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let control = Control::new();
    let path = |name: &str| dir.join(name).to_string_lossy().into_owned();
    for (angle, name) in [(0.0, "fin_x.ply"), (FRAC_PI_2, "fin_y.ply")] {
        let mesh = Solid::shape(models::finned_ball(angle)).surface(96, &control)?.into_owned();
        write_mesh(&mesh, Path::new(&path(name)), MeshFormat::PlyBinaryLittleEndian)
            .with_context(|| format!("cannot write {}", path(name)))?;
    }
    let landmarks = path("fin_landmarks.json");
    std::fs::write(&landmarks, models::fin_turn_landmarks().to_json())
        .with_context(|| format!("cannot write {landmarks}"))?;
    Ok((path("fin_x.ply"), path("fin_y.ply"), landmarks))
}

/// Runs every demo morph.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let defaults = match args.res {
        Some(res) => Settings::default().with_resolution(res),
        None => Settings::default(),
    };
    // The mug is placed on the chain by moment alignment so that every link
    // overlaps it; Yang & Jüttler's Example 2 uses its own settings.
    let mug_on_chain = {
        let mut s = defaults.clone();
        s.level_set.align = Align::Auto;
        s
    };
    let holed_cube = Settings { tspline: isomorph_tspline::demo::holed_cube_settings(), ..defaults.clone() };
    let rook_queen = Settings {
        blobtree: isomorph_blobtree::BlobSettings {
            spec: isomorph_blobtree::scenes::demo_spec("rook", "queen").unwrap_or_default(),
            ..Default::default()
        },
        ..defaults.clone()
    };
    // The rook becomes the queen (its built-in links) and then the bear:
    // a morph through a key shape.
    let rook_queen_bear = Settings {
        blobtree: isomorph_blobtree::BlobSettings {
            via: vec![isomorph_blobtree::KeyShape {
                shape: isomorph_blobtree::scenes::queen(),
                spec: rook_queen.blobtree.spec.clone(),
            }],
            via_mode: isomorph_blobtree::ViaMode::Chain,
            ..Default::default()
        },
        ..defaults.clone()
    };
    // The same shapes as a Bézier-like morph: the queen is a control shape.
    let mut rook_queen_bear_bezier = rook_queen_bear.clone();
    rook_queen_bear_bezier.blobtree.via_mode = isomorph_blobtree::ViaMode::Bezier;
    let demos = [
        (Method::Baseline, "mug", "chain", &defaults, "baseline_mug_to_chain"),
        (Method::LevelSet, "ball", "c-shape", &defaults, "level_set_ball_to_c"),
        (Method::LevelSet, "mug", "chain", &mug_on_chain, "level_set_mug_to_chain"),
        (Method::Blobtree, "rook", "queen", &rook_queen, "blobtree_rook_to_queen"),
        (Method::Blobtree, "rook", "bear", &rook_queen_bear, "blobtree_rook_via_queen_to_bear"),
        (Method::Blobtree, "rook", "bear", &rook_queen_bear_bezier, "blobtree_rook_bezier_queen_to_bear"),
        (Method::Rbf, "sphere", "torus", &defaults, "rbf_sphere_to_torus"),
        (Method::Warp, "sphere", "torus", &defaults, "warp_sphere_to_torus"),
        (Method::Tspline, "sphere", "torus", &defaults, "tspline_sphere_to_torus"),
        (Method::Tspline, "sphere", "holed-cube", &holed_cube, "tspline_sphere_to_holed_cube"),
    ];
    // Breen & Whitaker §6.2: a fin that should turn a quarter circle. The
    // inputs and the landmarks are written as files, as a user gives them.
    let fins = fin_inputs(&args.out.join("inputs"))?;
    let fin_guided = {
        let mut s = defaults.clone();
        s.level_set.align = Align::Warp(
            landmark_warp(&models::fin_turn_landmarks(), LandmarkWarp::Rbf, 8)
                .map_err(|e| anyhow::anyhow!("{e}"))?,
        );
        s
    };
    // Breen & Whitaker's Fig. 13: colour carried through the morph, from a
    // bunny painted by height into a torus painted around its ring.
    let (painted_bunny, painted_torus) = painted_inputs(&args.out.join("colour_inputs"))?;
    let written = [
        (Method::LevelSet, fins.0.clone(), fins.1.clone(), &defaults, "level_set_fin_without_landmarks"),
        (Method::LevelSet, fins.0.clone(), fins.1.clone(), &fin_guided, "level_set_fin_with_landmarks"),
        (Method::LevelSet, painted_bunny, painted_torus, &defaults, "level_set_colour_bunny_to_torus"),
    ];
    let demos =
        demos.into_iter().map(|(m, s, t, settings, f)| (m, s.to_string(), t.to_string(), settings, f));
    for (method, source, target, settings, folder) in demos.chain(written) {
        let io = Io {
            source,
            target,
            res: args.res,
            frames: args.frames,
            // The fin meshes are in the landmarks' coordinates.
            keep_scale: folder.contains("_fin_"),
            iso: None,
            raw: RawArgs::default(),
            threads: args.threads,
            format: Format::Ply,
            no_preview: false,
            colour: false,
        };
        let out = args.out.join(folder);
        let report = morph(method, &io, settings, &out)?;
        print_summary(&report, &io, &out);
        let most = report.max_components();
        if folder == "level_set_fin_with_landmarks" {
            println!(
                "  note: the fin turns with the landmarks of {}; without them it shrinks and regrows",
                fins.2
            );
        }
        if method == Method::Baseline && most > 1 {
            println!(
                "  note: up to {most} components in one frame — the distance blend pops pieces of the \
                 target out of thin air (Breen & Whitaker, Fig. 6)"
            );
        }
    }
    // Turk & O'Brien's Fig. 1: the X becomes the O through one 3D implicit.
    rbf::contours(&ContoursArgs {
        a: "x".into(),
        b: "o".into(),
        frames: args.frames.max(2),
        res: 128,
        separation: 1.0,
        kernel: KernelArg::Tps,
        method: ContourMethod::Rbf,
        out: args.out.join("rbf_x_to_o"),
    })?;
    // True's kind of edit (the thesis' teapot spout): drag the bunny's ear
    // tip up by 2.5 units (a quarter of its height), with a region of
    // influence of 3 units so the rest of the bunny stays put.
    let warp_args = WarpArgs {
        input: BUNNY.into(),
        raw: RawArgs::default(),
        drags: vec![(Vec3::new(0.0027, 9.65, -1.356), Vec3::new(0.0, 2.5, 0.0))],
        moves: Vec::new(),
        radius: Some(3.0),
        csize: 9,
        filter: FilterArg::Box,
        res: args.res.unwrap_or(64),
        pad: None,
        frames: None,
        out: args.out.join("warp_bunny_ear"),
    };
    warp::run(&warp_args)?;
    println!("demo written to {}", args.out.display());
    Ok(())
}

/// Writes two differently coloured inputs into `dir` and returns their
/// paths: the bunny painted by height (dark red at its feet to yellow at
/// its ears) and a torus painted around its ring (teal to violet and back).
fn painted_inputs(dir: &Path) -> anyhow::Result<(String, String)> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let bunny = bunny();
    let bounds = bunny.bounds();
    let (low, high) = (Vec3::new(0.6, 0.05, 0.1), Vec3::new(1.0, 0.85, 0.2));
    let by_height =
        bunny.positions.iter().map(|p| low.lerp(high, (p.y - bounds.min.y) / bounds.size().y)).collect();
    let torus = torus(0.35, 0.14, 96, 48);
    let (teal, violet) = (Vec3::new(0.1, 0.6, 0.7), Vec3::new(0.5, 0.25, 0.85));
    let around =
        torus.positions.iter().map(|p| teal.lerp(violet, 0.5 - 0.5 * p.y.atan2(p.x).cos())).collect();
    let write = |name: &str, mesh: TriMesh, colors| -> anyhow::Result<String> {
        let path = dir.join(name);
        write_mesh(&mesh.with_colors(colors)?, &path, MeshFormat::PlyBinaryLittleEndian)?;
        Ok(path.to_string_lossy().into_owned())
    };
    Ok((write("bunny_by_height.ply", bunny, by_height)?, write("torus_around.ply", torus, around)?))
}
