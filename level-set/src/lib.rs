//! Level-set shape metamorphosis after Breen & Whitaker, *A Level-Set Approach
//! for the Metamorphosis of Solid Models*, IEEE TVCG 7(2), 2001.
//!
//! **Status: not implemented yet.** This crate is a placeholder in the
//! workspace layout; the method is tracked by its own issue (dense up-wind
//! solver, Whitaker sparse-field solver, moment alignment and interpolated
//! coordinate transform). It builds on [`isomorph_common`].
