//! 3D shape metamorphosis based on T-spline level sets after Yang & Jüttler,
//! *3D shape metamorphosis based on T-spline level sets*, The Visual Computer
//! 23, 2007.
//!
//! **Status: not implemented yet.** This crate is a placeholder in the
//! workspace layout; the method is tracked by its own issue (octree T-mesh,
//! least-squares fitting, curvature-regularised evolution). It builds on
//! [`isomorph_common`].
