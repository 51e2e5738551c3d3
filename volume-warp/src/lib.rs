//! Volume warping with trivariate cubic B-splines after T. J. True, *Volume
//! Warping*, M.S. thesis, 1992.
//!
//! **Status: not implemented yet.** This crate is a placeholder in the
//! workspace layout; the method is tracked by its own issue (precomputed
//! B-spline table, antialiased pushforward, local updates, direct
//! manipulation). It builds on [`isomorph_common`].
