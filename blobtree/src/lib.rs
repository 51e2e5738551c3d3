//! Skeletal implicit BlobTrees and their metamorphosis after Galin, Leclercq &
//! Akkouche, *Morphing the BlobTree*, Computer Graphics Forum 19(4), 2000.
//!
//! **Status: not implemented yet.** This crate is a placeholder in the
//! workspace layout; the method is tracked by its own issue (skeletal
//! primitives, correspondence, decomposition, generic time-varying tree). It
//! builds on [`isomorph_common`].
