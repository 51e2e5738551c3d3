//! The error kinds every morph method shares ([`MorphError`]) and the trait
//! that lets generic code recognize them in any method's error
//! ([`MorphFailure`]).

use crate::alignment::AlignError;
use crate::fast_marching::FastMarchingError;
use crate::scan_conversion::ScanError;
use crate::sdf::SdfError;
use crate::{GridError, MemoryLimitError, MeshError, TransformError};
use glam::Vec3;
use std::fmt;

/// Which input of a morph a message is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The shape at `t = 0`.
    Source,
    /// The shape at `t = 1`.
    Target,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::Source => "source",
            Side::Target => "target",
        })
    }
}

/// One connected part of the target that the source does not reach (see
/// [`MorphError::NoOverlap`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MissedPart {
    /// Grid nodes inside the part.
    pub nodes: usize,
    /// Its share of the target's inside nodes, in `[0, 1]`.
    pub share: f32,
    /// The box of its nodes (world units).
    pub min: Vec3,
    /// The box of its nodes (world units).
    pub max: Vec3,
}

/// The error kinds every method shares: bad times, settings and inputs,
/// cancellation, memory, and the conversions of input solids. Each method
/// crate's error type wraps it (`From<MorphError>`), so the CLI, the
/// conformance suite and the Python package can match on these kinds for any
/// method through [`MorphFailure::shared`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MorphError {
    /// A morph time that is NaN or outside `[0, 1]`.
    #[error("time {0} is outside [0, 1]")]
    InvalidTime(f32),
    /// A setting is out of its range.
    #[error("setting {name} = {value} is out of range: expected {expected}")]
    BadSetting {
        /// The setting's name, as written in the settings struct.
        name: &'static str,
        /// The offending value.
        value: String,
        /// What is accepted.
        expected: String,
    },
    /// An input cannot be used as given (non-finite values, no bounds, ...).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// An input has a NaN or infinite value.
    #[error("the {side} {what} has a NaN or infinite value")]
    NonFinite {
        /// Which input.
        side: Side,
        /// Which part of it (`"volume"`, `"mesh"`, `"field"`, ...).
        what: &'static str,
    },
    /// An input has no inside (or no outside) where the method looks: there
    /// is no surface to morph.
    #[error("the {side} shape is empty: {detail}")]
    EmptyShape {
        /// Which input.
        side: Side,
        /// What was found (e.g. "no grid node is inside it").
        detail: String,
    },
    /// A closed mesh whose faces point inward: its signed volume is
    /// negative, so its inside (positive) region is the unbounded outside.
    #[error(
        "the {side} mesh is inside out (signed volume {volume:.3e}): its faces point inward; reverse \
         the triangles' vertex order"
    )]
    InsideOut {
        /// Which input.
        side: Side,
        /// The mesh's signed volume (negative), cubed world units.
        volume: f64,
    },
    /// Parts of the target that the source does not overlap, which a method
    /// that grows the source cannot reach (Breen & Whitaker §4).
    #[error(
        "{} of {total} target part(s) do not overlap the source ({:.1} % of the target's inside, more \
         than the {:.1} % allowed); align the shapes (e.g. moment alignment), move them together, or \
         allow a larger unreached share (max_unreached_share)",
        missed.len(),
        100.0 * missed.iter().map(|p| p.share).sum::<f32>(),
        100.0 * allowed
    )]
    NoOverlap {
        /// The parts not reached, largest first.
        missed: Vec<MissedPart>,
        /// All connected parts of the target.
        total: usize,
        /// The largest share of the target's inside the method lets go
        /// unreached (0 when every part must be reached).
        allowed: f32,
    },
    /// The method cannot take this kind of input.
    #[error("the {method} method cannot take the {side} input ({kind}): {hint}")]
    UnsupportedInput {
        /// The method's name.
        method: &'static str,
        /// Which input.
        side: Side,
        /// The input's kind ([`crate::Solid::kind`]).
        kind: &'static str,
        /// What it takes instead.
        hint: &'static str,
    },
    /// The operation was cancelled through its [`crate::Control`].
    #[error("cancelled")]
    Cancelled,
    /// A grid could not be made (memory limit, bad lattice) or two grids
    /// do not share a lattice.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// A computation sized by the input would exceed the memory limit.
    #[error(transparent)]
    Memory(#[from] MemoryLimitError),
    /// A mesh input is invalid.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// An input's distance field could not be built.
    #[error(transparent)]
    Distance(#[from] SdfError),
    /// An analytic input could not be scan converted.
    #[error(transparent)]
    ScanConversion(#[from] ScanError),
    /// A field could not be redistanced.
    #[error(transparent)]
    FastMarching(#[from] FastMarchingError),
    /// The moment alignment failed (degenerate or open shapes).
    #[error(transparent)]
    Alignment(#[from] AlignError),
    /// A placement transform cannot be interpolated.
    #[error(transparent)]
    Transform(#[from] TransformError),
}

impl MorphError {
    /// A [`MorphError::BadSetting`] for `name = value`, accepted `expected`.
    pub fn bad_setting(name: &'static str, value: impl fmt::Display, expected: impl Into<String>) -> Self {
        MorphError::BadSetting { name, value: value.to_string(), expected: expected.into() }
    }
}

/// What every morph method's error offers generic code: the shared kind,
/// when the error is one of [`MorphError`]'s.
pub trait MorphFailure: std::error::Error + Send + Sync + 'static {
    /// The shared error kind, when this is one.
    fn shared(&self) -> Option<&MorphError>;

    /// Whether the operation was cancelled.
    fn is_cancelled(&self) -> bool {
        matches!(self.shared(), Some(MorphError::Cancelled))
    }
}

impl MorphFailure for MorphError {
    fn shared(&self) -> Option<&MorphError> {
        Some(self)
    }
}

/// Checks that `t` is a valid morph time.
///
/// # Errors
/// [`MorphError::InvalidTime`] for NaN or `t ∉ [0, 1]`.
pub fn check_time(t: f32) -> Result<f32, MorphError> {
    if (0.0..=1.0).contains(&t) { Ok(t) } else { Err(MorphError::InvalidTime(t)) }
}

/// Range checks for settings: each returns [`MorphError::BadSetting`]
/// naming the field, the value and the accepted range.
pub mod check {
    use super::MorphError;

    /// `value` as a short, readable number: the shortest form of the `f32`
    /// it came from when it is one (`-19.2`, not `-19.200000762939453`),
    /// scientific notation when very small or large (`1e-300`, not 300
    /// digits).
    ///
    /// ```
    /// use isomorph_common::check::number;
    /// assert_eq!(number(f64::from(-19.2f32)), "-19.2");
    /// assert_eq!(number(1e-300), "1e-300");
    /// assert_eq!(number(0.25), "0.25");
    /// ```
    pub fn number(value: f64) -> String {
        let magnitude = value.abs();
        let scientific = value != 0.0 && !(1e-4..1e9).contains(&magnitude);
        let narrow = value as f32;
        match (scientific, f64::from(narrow) == value) {
            (false, true) => narrow.to_string(),
            (false, false) => value.to_string(),
            (true, true) => format!("{narrow:e}"),
            (true, false) => format!("{value:e}"),
        }
    }

    /// `lo ≤ value ≤ hi` and finite.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`].
    pub fn range(name: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), MorphError> {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            Err(MorphError::bad_setting(
                name,
                number(value),
                format!("a number in [{}, {}]", number(lo), number(hi)),
            ))
        }
    }

    /// `value > 0` and finite.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`].
    pub fn positive(name: &'static str, value: f64) -> Result<(), MorphError> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(MorphError::bad_setting(name, number(value), "a finite number > 0"))
        }
    }

    /// `lo ≤ value ≤ hi` for a count.
    ///
    /// # Errors
    /// [`MorphError::BadSetting`].
    pub fn count(name: &'static str, value: u64, lo: u64, hi: u64) -> Result<(), MorphError> {
        if (lo..=hi).contains(&value) {
            Ok(())
        } else {
            Err(MorphError::bad_setting(name, value, format!("an integer in [{lo}, {hi}]")))
        }
    }
}
