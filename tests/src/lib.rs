//! Cross-crate end-to-end and comparison tests of isomorph (see `tests/`), the
//! README's examples as doc tests, and the entry points of the fuzz targets
//! ([`fuzzing`]).

#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;

pub mod fuzzing;
