//! The crate's typed errors.

use isomorph_common::{GridError, MeshError, MorphError, MorphFailure};

/// What can go wrong when fitting, slicing or morphing a variational
/// implicit: the kinds every method shares ([`MorphError`]: bad settings and
/// times, cancellation, input conversion) and the method's own.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RbfError {
    /// One of the kinds every method shares.
    #[error(transparent)]
    Morph(#[from] MorphError),
    /// Fewer constraints than the degree-one polynomial has coefficients
    /// (`D + 1` in `D` dimensions); the interpolant is not determined.
    #[error(
        "{got} constraints in {dim} dimensions; at least {needed} are needed (one more than the dimension)"
    )]
    TooFewConstraints {
        /// Constraints given (after merging duplicates).
        got: usize,
        /// Constraints needed: `dim + 1`.
        needed: usize,
        /// The dimension of the constraint space.
        dim: usize,
    },
    /// The constraint positions lie in a lower-dimensional affine subspace
    /// (all coplanar in `D` dimensions), so the degree-one polynomial is not
    /// determined (the points are not unisolvent). Add constraints off that
    /// subspace, or fit in fewer dimensions.
    #[error(
        "the constraint positions span only {rank} of {dim} dimensions (coplanar / not unisolvent for a degree-one polynomial)"
    )]
    NotUnisolvent {
        /// Numerical rank of the positions' affine hull.
        rank: usize,
        /// The dimension of the constraint space.
        dim: usize,
    },
    /// A position or value is NaN or infinite.
    #[error("constraint {index} has a NaN or infinite {what}")]
    NonFinite {
        /// Index of the offending constraint in the input.
        index: usize,
        /// `"position"`, `"value"` or `"correspondence"`.
        what: &'static str,
    },
    /// Two constraints are closer than the duplicate tolerance but ask for
    /// different values (or the policy rejects all duplicates).
    #[error(
        "constraints {first} and {second} are {distance:e} apart (near-duplicates) with values {first_value} and {second_value}"
    )]
    NearDuplicate {
        /// Index of the first constraint in the input.
        first: usize,
        /// Index of the second constraint in the input.
        second: usize,
        /// Their distance, in input units.
        distance: f64,
        /// The value asked for at `first`.
        first_value: f32,
        /// The value asked for at `second`.
        second_value: f32,
    },
    /// The linear system is singular to working precision even with the
    /// symmetric-indefinite fallback (e.g. near-duplicate constraints below
    /// the merge tolerance). Raise the smoothing parameter or the duplicate
    /// tolerance.
    #[error("the interpolation system is singular to working precision (reciprocal condition {rcond:e})")]
    Singular {
        /// Reciprocal condition estimate of the projected system (0 when no
        /// factorization succeeded).
        rcond: f64,
    },
    /// The hierarchical solver's iteration did not converge and the dense
    /// system, the fallback, would not fit in memory. Use fewer constraints
    /// (or greedy centre selection), or raise the smoothing parameter.
    #[error(
        "the iterative solver did not converge ({iterations} iterations, relative residual {residual:e}) and the dense fallback does not fit in memory"
    )]
    NotConverged {
        /// GMRES iterations taken.
        iterations: usize,
        /// The last relative residual of the projected system.
        residual: f64,
    },
    /// A slice was asked for with the wrong number of fixed coordinates.
    #[error(
        "slicing a {dim}-dimensional interpolant to {slice_dim} dimensions needs {expected} fixed coordinates, got {got}"
    )]
    SliceArity {
        /// Dimension of the interpolant.
        dim: usize,
        /// Dimension of the slice (2 or 3).
        slice_dim: usize,
        /// Fixed coordinates needed: `dim - slice_dim`.
        expected: usize,
        /// Fixed coordinates given.
        got: usize,
    },
    /// A shape yields no constraint (an image without any mid-gray
    /// crossing, an empty point set).
    #[error("the {0} shape has no boundary: no constraint could be made")]
    EmptyShape(&'static str),
    /// Points and normals differ in length, or a normal is zero.
    #[error("invalid points/normals input: {0}")]
    InvalidInput(String),
    /// A contour plane has a zero or non-finite origin or axis, or parallel
    /// axes (it spans no plane).
    #[error("degenerate contour plane: {0}")]
    DegeneratePlane(&'static str),
    /// A contour polyline cannot give constraints (fewer than three distinct
    /// points, zero area).
    #[error("contour {contour}: {reason}")]
    InvalidContour {
        /// Index of the polyline in the call that added it.
        contour: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The point lists of a warp's correspondences differ in length.
    #[error("{on_source} points on the source but {on_target} on the target: correspondences come in pairs")]
    CorrespondenceCount {
        /// Points given on the source shape.
        on_source: usize,
        /// Points given on the target shape.
        on_target: usize,
    },
    /// Too few correspondences for a displacement warp with a degree-one
    /// polynomial part.
    #[error(
        "{got} correspondences in {dim} dimensions; a warp needs at least {needed}, not all on one hyperplane"
    )]
    TooFewCorrespondences {
        /// Correspondences given.
        got: usize,
        /// Correspondences needed: `dim + 1`.
        needed: usize,
        /// The dimension of the shapes.
        dim: usize,
    },
}

impl From<GridError> for RbfError {
    fn from(e: GridError) -> Self {
        RbfError::Morph(MorphError::Grid(e))
    }
}

impl From<MeshError> for RbfError {
    fn from(e: MeshError) -> Self {
        RbfError::Morph(MorphError::Mesh(e))
    }
}

impl MorphFailure for RbfError {
    fn shared(&self) -> Option<&MorphError> {
        match self {
            RbfError::Morph(e) => Some(e),
            _ => None,
        }
    }
}
