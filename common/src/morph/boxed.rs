//! Type erasure: any [`Morph`] as a [`BoxedMorph`], so that a program can
//! hold a list of different methods and treat them alike.

use super::{Frame, Morph, MorphError, MorphFailure, MorphReport};
use crate::{Aabb, Field3, TriMesh};
use glam::{Affine3A, UVec3, Vec3};
use std::fmt;

/// A frame field of any method.
pub type DynField = Box<dyn Field3 + Send>;

/// Any method's morph, with boxed fields and errors.
pub type BoxedMorph = Box<dyn Morph<Field = DynField, Error = BoxedError>>;

/// Any method's error, keeping its message, its source chain and its
/// shared kind ([`MorphFailure::shared`]).
pub struct BoxedError(Box<dyn MorphFailure>);

impl BoxedError {
    /// Wraps a method's error.
    pub fn new(error: impl MorphFailure) -> Self {
        Self(Box::new(error))
    }

    /// The method's error.
    pub fn inner(&self) -> &(dyn MorphFailure + 'static) {
        self.0.as_ref()
    }
}

impl fmt::Debug for BoxedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.0, f)
    }
}

impl fmt::Display for BoxedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl std::error::Error for BoxedError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

impl MorphFailure for BoxedError {
    fn shared(&self) -> Option<&MorphError> {
        self.0.shared()
    }
}

impl From<MorphError> for BoxedError {
    fn from(e: MorphError) -> Self {
        Self::new(e)
    }
}

impl Field3 for DynField {
    fn value(&self, p: Vec3) -> f32 {
        (**self).value(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        (**self).gradient(p)
    }
    fn values(&self, points: &[Vec3], out: &mut [f32]) {
        (**self).values(points, out)
    }
    fn values_on_lattice(&self, dims: UVec3, origin: Vec3, spacing: f32, out: &mut [f32]) {
        (**self).values_on_lattice(dims, origin, spacing, out)
    }
    fn bounds(&self) -> Option<Aabb> {
        (**self).bounds()
    }
    fn range(&self, region: &Aabb) -> Option<[f32; 2]> {
        (**self).range(region)
    }
}

/// The adapter behind [`MorphExt::boxed`].
struct Erased<M>(M);

impl<M> Morph for Erased<M>
where
    M: Morph,
    M::Field: 'static,
{
    type Field = DynField;
    type Error = BoxedError;

    fn method(&self) -> &'static str {
        self.0.method()
    }

    fn frame(&self, t: f32) -> Result<Frame<DynField>, BoxedError> {
        let f = self.0.frame(t).map_err(BoxedError::new)?;
        Ok(Frame { field: Box::new(f.field), iso: f.iso, transform: f.transform })
    }

    fn field_bounds(&self) -> Aabb {
        self.0.field_bounds()
    }

    fn world_bounds(&self) -> Aabb {
        self.0.world_bounds()
    }

    fn report(&self) -> &MorphReport {
        self.0.report()
    }

    fn frame_mesh(&self, t: f32, res: u32) -> Result<TriMesh, BoxedError> {
        self.0.frame_mesh(t, res).map_err(BoxedError::new)
    }

    fn world_transform(&self, t: f32) -> Result<Affine3A, BoxedError> {
        self.0.world_transform(t).map_err(BoxedError::new)
    }

    fn ends_of(&self, t: f32, points: &[Vec3]) -> Result<[Vec<Vec3>; 2], BoxedError> {
        self.0.ends_of(t, points).map_err(BoxedError::new)
    }
}

/// [`MorphExt::boxed`] for every morph.
pub trait MorphExt: Morph + Sized + 'static {
    /// This morph as a [`BoxedMorph`]; it keeps its own `frame_mesh`.
    fn boxed(self) -> BoxedMorph
    where
        Self::Field: 'static,
    {
        Box::new(Erased(self))
    }
}

impl<M: Morph + 'static> MorphExt for M {}

#[cfg(test)]
mod tests {
    use super::*;

    /// A field whose lattice path differs from its pointwise one, to see
    /// which one a wrapper calls.
    struct LatticeMarked;

    impl Field3 for LatticeMarked {
        fn value(&self, _: Vec3) -> f32 {
            1.0
        }
        fn values_on_lattice(&self, _: UVec3, _: Vec3, _: f32, out: &mut [f32]) {
            out.fill(2.0);
        }
    }

    #[test]
    fn boxed_fields_keep_their_lattice_evaluation() {
        let field: DynField = Box::new(LatticeMarked);
        let mut out = vec![0.0; 8];
        field.values_on_lattice(UVec3::splat(2), Vec3::ZERO, 1.0, &mut out);
        assert_eq!(out, vec![2.0; 8]);
    }
}
