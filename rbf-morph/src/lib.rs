//! Shape transformation with variational implicit functions after Turk &
//! O'Brien, *Shape Transformation Using Variational Implicit Functions*,
//! SIGGRAPH 1999.
//!
//! **Status: not implemented yet.** This crate is a placeholder in the
//! workspace layout; the method is tracked by its own issue (polyharmonic RBF
//! interpolation in N+1 dimensions, influence shapes, contour reconstruction,
//! warping). It builds on [`isomorph_common`].
