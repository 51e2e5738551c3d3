//! Every morph method by name: [`Method`], the settings of all of them
//! ([`Settings`], the libraries' defaults), their inputs ([`load_input`])
//! and one constructor for any of them ([`build`], a boxed
//! [`isomorph_common::Morph`]).

use isomorph_blobtree::{BlobMorph, BlobSettings, BlobTree, scenes};
use isomorph_common::glam::Vec3;
use isomorph_common::{
    Aabb, BlendSettings, BoxedError, BoxedMorph, Control, DistanceBlend, Landmarks, MorphExt, Solid,
};
use isomorph_io::inputs::{InputError, LoadOptions, load_solid_with_warnings};
use isomorph_levelset::{LevelSetMorph, LevelSetSettings, Warp};
use isomorph_rbf::{
    DisplacementWarp, FitSettings, InfluencePath, RbfMorph, RbfSettings, WarpedMorph, WarpedSettings,
};
use isomorph_tspline::{TsplineMorph, TsplineSettings};
use isomorph_warp::{WarpMorph, WarpMorphSettings, WorldMap};
use std::sync::Arc;

/// The morph methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Method {
    /// Linear interpolation of the two signed distance volumes (the naive
    /// baseline every method should beat).
    Baseline,
    /// Breen & Whitaker 2001: the source surface moves along its normals
    /// with the target's signed distance as speed.
    LevelSet,
    /// Turk & O'Brien 1999: one variational implicit in 4D whose slices are
    /// the in-between shapes.
    Rbf,
    /// True 1992: trivariate cubic B-spline volume warps of both shapes
    /// toward each other, cross-dissolved.
    Warp,
    /// Yang & Jüttler 2007: T-spline level sets on an adaptive octree.
    Tspline,
    /// Galin, Leclercq & Akkouche 2000: skeletal implicit BlobTrees (inputs
    /// are BlobTree scenes).
    Blobtree,
}

impl Method {
    /// Every method, in the order of the comparison tables.
    pub const ALL: [Method; 6] =
        [Method::Baseline, Method::LevelSet, Method::Rbf, Method::Warp, Method::Tspline, Method::Blobtree];

    /// The name used on the command line, in reports and as the output
    /// folder (the same as the morph's `Morph::method`).
    pub fn name(self) -> &'static str {
        match self {
            Method::Baseline => "baseline",
            Method::LevelSet => "level-set",
            Method::Rbf => "rbf",
            Method::Warp => "warp",
            Method::Tspline => "tspline",
            Method::Blobtree => "blobtree",
        }
    }

    /// The method named `name` (as [`Method::name`] prints it).
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The settings of every method; `Settings::default()` holds each
/// library's defaults.
#[derive(Debug, Clone, Default)]
pub struct Settings {
    /// The distance-volume blend.
    pub baseline: BlendSettings,
    /// Breen & Whitaker's level set.
    pub level_set: LevelSetSettings,
    /// Turk & O'Brien's variational implicit.
    pub rbf: RbfSettings,
    /// Corresponding points (source, target) for the variational implicit:
    /// when given, the shapes are warped half-way to each other first (the
    /// paper's appendix, [`WarpedMorph`]).
    pub rbf_correspondences: Vec<(Vec3, Vec3)>,
    /// One or two influence shapes for the variational implicit (§7): when
    /// given, the morph runs from the source to the target pulled towards
    /// them ([`InfluencePath::from_solids`]).
    pub rbf_influence: Vec<Solid>,
    /// True's B-spline warp with a cross-dissolve.
    pub warp: WarpMorphSettings,
    /// Yang & Jüttler's T-spline level sets.
    pub tspline: TsplineSettings,
    /// Galin et al.'s BlobTree morph.
    pub blobtree: BlobSettings,
}

impl Settings {
    /// Sets the grid resolution (nodes along the longest edge) of every
    /// method that samples its inputs on a grid (baseline, level set, warp).
    pub fn with_resolution(mut self, res: u32) -> Self {
        self.baseline.resolution = res;
        self.level_set.resolution = res;
        self.warp.resolution = res;
        self
    }
}

/// Which map carries the level set's speed through landmark pairs (Breen
/// & Whitaker's generalized warp `W`, §6.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum LandmarkWarp {
    /// Turk & O'Brien's displacement warp: interpolates the pairs, with an
    /// affine part, smooth everywhere.
    #[default]
    Rbf,
    /// True's trivariate cubic B-spline warp, fitted to the pairs by
    /// minimum-norm direct manipulation from the identity: local (the
    /// identity far from the landmarks).
    Bspline,
}

/// The warp `W` through `landmarks` for [`Align::Warp`](isomorph_levelset::Align::Warp).
/// For [`LandmarkWarp::Bspline`] the control lattice covers the landmarks'
/// box padded by half its size, with a control point every
/// `control_spacing` of its 64 voxels along the longest edge.
///
/// # Errors
/// The fit's errors (e.g. landmarks that no warp of the kind interpolates).
pub fn landmark_warp(
    landmarks: &Landmarks,
    kind: LandmarkWarp,
    control_spacing: u32,
) -> Result<Warp, BoxedError> {
    Ok(match kind {
        LandmarkWarp::Rbf => {
            let warp = DisplacementWarp::from_landmarks(landmarks, &FitSettings::default())
                .map_err(BoxedError::new)?;
            Arc::new(move |x| warp.apply(x))
        }
        LandmarkWarp::Bspline => {
            let box_of = landmarks.pairs().iter().fold(Aabb::EMPTY, |b, &(p, q)| b.including(p).including(q));
            let bounds = box_of.expanded(0.5 * box_of.size().max_element());
            let map =
                WorldMap::from_landmarks(&bounds, 64, control_spacing, landmarks).map_err(BoxedError::new)?;
            Arc::new(move |x| map.apply(x))
        }
    })
}

/// Errors of [`load_input`].
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A shape, mesh or volume input.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A BlobTree scene.
    #[error(transparent)]
    Scene(#[from] isomorph_blobtree::BlobError),
    /// The input cannot be a solid.
    #[error(transparent)]
    Solid(#[from] isomorph_common::MorphError),
}

/// The input `spec` for `method`: a `.ron`/`.json` BlobTree scene file, or
/// for the BlobTree method a built-in scene name; otherwise a built-in
/// shape, `bunny`, a mesh file or a `.npy` volume ([`isomorph_io::inputs::load_solid`]), else a
/// built-in BlobTree scene, which every method can sample as an implicit
/// (the BlobTree method refuses non-BlobTree solids when it is built).
///
/// # Errors
/// [`LoadError`] naming the input and what is wrong with it.
pub fn load_input(method: Method, spec: &str, options: &LoadOptions) -> Result<Solid, LoadError> {
    load_input_with_warnings(method, spec, options).map(|(solid, _)| solid)
}

/// [`load_input`], with the file readers' warnings
/// ([`isomorph_io::inputs::load_solid_with_warnings`]).
///
/// # Errors
/// As [`load_input`].
pub fn load_input_with_warnings(
    method: Method,
    spec: &str,
    options: &LoadOptions,
) -> Result<(Solid, Vec<String>), LoadError> {
    let is_scene_file = spec.ends_with(".ron") || spec.ends_with(".json");
    if is_scene_file || (method == Method::Blobtree && scenes::NAMES.contains(&spec)) {
        return Ok((scene_solid(scenes::load(spec)?)?, Vec::new()));
    }
    match load_solid_with_warnings(spec, options) {
        Err(InputError::Unknown { .. }) if scenes::NAMES.contains(&spec) => {
            Ok((scene_solid(scenes::load(spec)?)?, Vec::new()))
        }
        other => Ok(other?),
    }
}

/// A BlobTree as a solid (the BlobTree morph recovers the tree from it).
pub fn scene_solid(tree: BlobTree) -> Result<Solid, isomorph_common::MorphError> {
    Solid::implicit(Arc::new(tree))
}

/// Builds `method` from `source` to `target` with its part of `settings`.
///
/// # Errors
/// The method's error, boxed: bad settings, unsupported inputs,
/// cancellation, and the method's own failures.
pub fn build(
    method: Method,
    source: &Solid,
    target: &Solid,
    settings: &Settings,
    control: &Control,
) -> Result<BoxedMorph, BoxedError> {
    Ok(match method {
        Method::Baseline => {
            DistanceBlend::new(source, target, &settings.baseline, control).map_err(BoxedError::new)?.boxed()
        }
        Method::LevelSet => {
            LevelSetMorph::new(source, target, &settings.level_set, control).map_err(BoxedError::new)?.boxed()
        }
        Method::Rbf if !settings.rbf_influence.is_empty() => {
            InfluencePath::from_solids(source, target, &settings.rbf_influence, &settings.rbf, control)
                .map_err(BoxedError::new)?
                .boxed()
        }
        Method::Rbf if !settings.rbf_correspondences.is_empty() => {
            let warped = WarpedSettings {
                rbf: settings.rbf.clone(),
                correspondences: settings.rbf_correspondences.clone(),
            };
            WarpedMorph::new(source, target, &warped, control).map_err(BoxedError::new)?.boxed()
        }
        Method::Rbf => {
            RbfMorph::new(source, target, &settings.rbf, control).map_err(BoxedError::new)?.boxed()
        }
        Method::Warp => {
            WarpMorph::new(source, target, &settings.warp, control).map_err(BoxedError::new)?.boxed()
        }
        Method::Tspline => {
            TsplineMorph::new(source, target, &settings.tspline, control).map_err(BoxedError::new)?.boxed()
        }
        Method::Blobtree => {
            BlobMorph::new(source, target, &settings.blobtree, control).map_err(BoxedError::new)?.boxed()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for m in Method::ALL {
            assert_eq!(Method::from_name(m.name()), Some(m));
        }
        assert_eq!(Method::from_name("nope"), None);
    }
}
