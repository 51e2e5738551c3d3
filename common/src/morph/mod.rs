//! The morph contract: the [`Morph`] trait every method implements, its
//! typed [`MorphReport`], the shared [`MorphError`] kinds, the boxed form
//! ([`BoxedMorph`]) for lists of different methods, and the naive baseline
//! ([`DistanceBlend`]).
//!
//! Every method is built the same way,
//! `XxxMorph::new(&source, &target, &settings, &control)`, from two
//! [`Solid`](crate::Solid)s, plain `Settings` structs with `Default`, and a
//! [`Control`](crate::Control) (progress, cancellation, threads).
//!
//! # Spaces
//! A frame's field lives in the morph's *field space*; the frame's
//! `transform` places it in the *world*. [`Morph::field_bounds`] is a box in
//! field space containing every frame's surface, [`Morph::world_bounds`] a
//! box in world space containing every frame mesh. Voxel sizes in reports
//! are world sizes.
//!
//! ```
//! use isomorph_common::{BlendSettings, DistanceBlend, Morph, MorphExt};
//! use isomorph_common::{Control, Solid, models};
//!
//! let (ball, c) = (Solid::shape(models::ball()), Solid::shape(models::c_shape()));
//! let settings = BlendSettings { resolution: 32, ..Default::default() };
//! let morph = DistanceBlend::new(&ball, &c, &settings, &Control::new())?;
//! assert!(morph.report().converged);
//! // A list of different methods holds them boxed.
//! let methods = vec![morph.boxed()];
//! let mesh = methods[0].frame_mesh(0.5, 32)?;
//! assert!(methods[0].world_bounds().contains(mesh.bounds().center()));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod blend;
mod boxed;
mod contour_blend;
mod error;
mod report;

pub use blend::{BlendSettings, DistanceBlend};
pub use boxed::{BoxedError, BoxedMorph, DynField, MorphExt};
pub use contour_blend::ContourBlend;
pub use error::{MissedPart, MorphError, MorphFailure, Side, check, check_time};
pub use report::{Details, MorphReport, Outcome, Residual, StageTime, Stages, Value};

use crate::marching_cubes::level_set_mesh;
use crate::{Aabb, Field3, TriMesh};
use glam::{Affine3A, Vec3};

/// One in-between shape: a field (positive inside, surface at `iso`) in the
/// morph's field space, and the map that places it in the world.
#[derive(Debug, Clone)]
pub struct Frame<F> {
    /// The shape as a field.
    pub field: F,
    /// The surface is the level set `field == iso`.
    pub iso: f32,
    /// Field space → world space (Breen eq. 25's `T(x, t)`; identity when the
    /// method needs no placement).
    pub transform: Affine3A,
}

/// A time-parameterized shape: `frame(0)` is the source, `frame(1)` the
/// target (see the [crate docs](crate) and `docs/ARCHITECTURE.md` for the contract).
pub trait Morph: Send + Sync {
    /// The field of one frame.
    type Field: Field3 + Send;
    /// What can go wrong when making a frame; wraps the shared kinds.
    type Error: MorphFailure + From<MorphError>;

    /// Short method name used in reports (`"baseline"`, `"level-set"`, ...).
    fn method(&self) -> &'static str;

    /// The shape at time `t ∈ [0, 1]`.
    ///
    /// # Errors
    /// [`MorphError::InvalidTime`] for `t` outside `[0, 1]` or NaN; method
    /// specific errors otherwise.
    fn frame(&self, t: f32) -> Result<Frame<Self::Field>, Self::Error>;

    /// A box in field space containing the surface of every frame.
    fn field_bounds(&self) -> Aabb;

    /// A box in world space containing every frame mesh.
    fn world_bounds(&self) -> Aabb;

    /// How construction went (outcome, iterations, residuals, time, memory).
    fn report(&self) -> &MorphReport;

    /// The frame at `t` as a world-space mesh, outward oriented.
    ///
    /// The default polygonizes the field's level set at the frame's iso
    /// value over [`Morph::field_bounds`] with `res` nodes along its longest
    /// edge, evaluating the field only near the surface
    /// ([`crate::marching_cubes::level_set_mesh`]: the mesh of marching cubes
    /// on the full grid), and places the mesh by the frame's transform. Exceptions,
    /// documented by each method: methods whose frames are grids (the
    /// baseline, the level set, the volume warp) polygonize their own
    /// lattice, whose resolution their settings chose, because resampling
    /// could only lose detail; frames that are meshes (the T-spline's
    /// projection frames) are returned as they are.
    ///
    /// # Errors
    /// As [`Morph::frame`], plus grid allocation errors.
    fn frame_mesh(&self, t: f32, res: u32) -> Result<TriMesh, Self::Error> {
        let frame = self.frame(t)?;
        let mut mesh = level_set_mesh(&frame.field, &self.field_bounds(), res, frame.iso)?;
        mesh.transform(&frame.transform);
        Ok(mesh)
    }

    /// [`Frame::transform`] of the frame at `t` alone (field space → world
    /// space), e.g. to find where a world point of frame `t` sits in frames
    /// 0 and 1 (`world_transform(0) · world_transform(t)⁻¹` places it on the
    /// source, as the sequence exporter's colour lookup does). The default
    /// makes the whole frame; methods whose placement is known without it
    /// override this.
    ///
    /// # Errors
    /// As [`Morph::frame`].
    fn world_transform(&self, t: f32) -> Result<Affine3A, Self::Error> {
        Ok(self.frame(t)?.transform)
    }

    /// Where the world points `points` of frame `t` sit in the frames at 0
    /// and at 1 (the same field point placed as the source and as the
    /// target are): what the exporter's colour lookup reads the inputs'
    /// colours at. The default maps by `world_transform(0 | 1) ·
    /// world_transform(t)⁻¹`; methods placed by a non-affine map override it.
    ///
    /// # Errors
    /// As [`Morph::world_transform`].
    fn ends_of(&self, t: f32, points: &[Vec3]) -> Result<[Vec<Vec3>; 2], Self::Error> {
        let back = self.world_transform(t)?.inverse();
        let to = |end: Affine3A| {
            let map = end * back;
            points.iter().map(|&p| map.transform_point3(p)).collect()
        };
        Ok([to(self.world_transform(0.0)?), to(self.world_transform(1.0)?)])
    }
}

/// The box containing `bounds` placed by every transform of `placements`
/// (for methods whose frames are placed by a few known maps).
pub fn placed_bounds(bounds: &Aabb, placements: impl IntoIterator<Item = Affine3A>) -> Aabb {
    placements.into_iter().fold(Aabb::EMPTY, |acc, map| acc.union(&bounds.transformed(&map)))
}
