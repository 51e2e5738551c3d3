//! `isomorph demo`: a complete example from built-in shapes, in seconds.

use crate::inputs::BUNNY;
use crate::level_set::{Align, Solver};
use crate::morph::{Format, Method, MorphArgs, morph, print_summary};
use crate::rbf::{self, ContoursArgs, KernelArg};
use crate::tspline::SpeedArg;
use crate::warp::{self, FilterArg, RawType, WarpArgs};
use clap::Args;
use isomorph_common::glam::Vec3;
use std::path::PathBuf;

/// Arguments of `isomorph demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder; each morph gets a subfolder.
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// Grid nodes along the longest edge.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(8..=512))]
    res: u32,
    /// Frames per morph.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(2..=200))]
    frames: u32,
}

/// Runs every demo morph.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    // Ball → C overlaps as modelled (Breen Fig. 4); the mug is placed on the
    // chain by moment alignment so that every link overlaps it.
    // The T-spline morphs: sphere → torus at depth 4, and Yang & Jüttler's
    // Example 2, sphere → holed cube, with `isomorph_tspline::demo::
    // holed_cube_settings` (depth 3, margin 0.5).
    let demos = [
        (Method::Baseline, "ball", "c-shape", Align::None, "baseline_ball_to_c", None),
        (Method::LevelSet, "ball", "c-shape", Align::None, "level_set_ball_to_c", None),
        (Method::LevelSet, "mug", "chain", Align::Auto, "level_set_mug_to_chain", None),
        (Method::Blobtree, "rook", "queen", Align::None, "blobtree_rook_to_queen", None),
        (Method::Rbf, "sphere", "torus", Align::None, "rbf_sphere_to_torus", None),
        (Method::Tspline, "sphere", "torus", Align::None, "tspline_sphere_to_torus", Some((4, None))),
        (
            Method::Tspline,
            "sphere",
            "holed-cube",
            Align::None,
            "tspline_sphere_to_holed_cube",
            Some((3, Some(0.5))),
        ),
    ];
    for (method, source, target, align, folder, tspline) in demos {
        let morph_args = MorphArgs {
            method,
            source: source.into(),
            target: target.into(),
            res: args.res,
            frames: args.frames,
            out: args.out.join(folder),
            format: Format::Ply,
            keep_scale: false,
            align,
            solver: Solver::Sparse,
            curvature: None,
            report: false,
            links: None,
            points: 300,
            separation: 1.0,
            kernel: KernelArg::Tps,
            speed: Some(SpeedArg::Robust),
            nt: None,
            depth: tspline.map(|(depth, _)| depth),
            step: None,
            margin: tspline.and_then(|(_, margin)| margin),
            refine: None,
            refine_rounds: 3,
        };
        let report = morph(&morph_args)?;
        print_summary(&report, &morph_args);
        let most = report.max_components();
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
        out: args.out.join("rbf_x_to_o"),
    })?;
    // True's kind of edit (the thesis' teapot spout): drag the bunny's ear
    // tip up by 2.5 units (a quarter of its height), with a region of
    // influence of 3 units so the rest of the bunny stays put.
    let warp_args = WarpArgs {
        input: BUNNY.into(),
        raw_dims: None,
        raw_type: RawType::U8,
        drags: vec![(Vec3::new(0.0027, 9.65, -1.356), Vec3::new(0.0, 2.5, 0.0))],
        moves: Vec::new(),
        radius: Some(3.0),
        csize: 9,
        filter: FilterArg::Box,
        res: args.res,
        pad: None,
        out: args.out.join("warp_bunny_ear"),
    };
    warp::run(&warp_args)?;
    println!("demo written to {}", args.out.display());
    Ok(())
}
