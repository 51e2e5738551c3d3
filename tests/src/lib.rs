//! Cross-crate end-to-end and comparison tests of isomorph (see `tests/`), and
//! the README's examples as doc tests.

#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
