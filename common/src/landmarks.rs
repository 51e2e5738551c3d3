//! Landmark correspondences between a source and a target shape.

use glam::{DMat3, DVec3, Vec3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Fewest pairs a warp through the landmarks needs: four points not on one
/// plane fix an affine map of 3D space.
pub const MIN_LANDMARKS: usize = 4;

/// Why a landmark set was refused.
#[derive(Debug, thiserror::Error)]
pub enum LandmarkError {
    /// The file could not be read.
    #[error("cannot read the landmarks file {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// What the system said.
        source: std::io::Error,
    },
    /// The text is not a JSON list of `{"source": [x, y, z], "target": [x, y, z]}`.
    #[error(
        "the landmarks are not a JSON list of {{\"source\": [x, y, z], \"target\": [x, y, z]}} pairs: {0}"
    )]
    Format(String),
    /// Fewer pairs than [`MIN_LANDMARKS`] (after merging repeated pairs).
    #[error("{count} landmark pair(s) given; a warp needs at least {MIN_LANDMARKS} (not on one plane)")]
    TooFew {
        /// Distinct pairs given.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("landmark pair {index} has a NaN or infinite coordinate")]
    NonFinite {
        /// Index of the pair in the file.
        index: usize,
    },
    /// One source point is sent to two different target points.
    #[error(
        "landmark pairs {first} and {second} start at the same source point {point:?} but end at different target points"
    )]
    Conflict {
        /// Index of the first pair.
        first: usize,
        /// Index of the second pair.
        second: usize,
        /// The shared source point.
        point: Vec3,
    },
    /// The points of one side lie on a plane (or a line), so no affine map
    /// is fixed by them.
    #[error(
        "the {side} landmarks lie on one plane (thickness {thickness:.3e} of their extent): add a point off that plane"
    )]
    Coplanar {
        /// `"source"` or `"target"`.
        side: &'static str,
        /// Smallest over largest spread of the points (0 for exactly coplanar).
        thickness: f64,
    },
}

/// Pairs of corresponding points: `source[i]` on (or near) the source shape
/// should become `target[i]` on the target, in world units. Validated on
/// construction: at least [`MIN_LANDMARKS`] distinct pairs, finite, each
/// source point sent to one target point, and neither side on one plane.
///
/// Used by the level-set morph's generalized warp (Breen & Whitaker §6.2),
/// the RBF morph's correspondence warping (Turk & O'Brien's appendix) and the
/// B-spline volume warp (True's landmarks).
///
/// ```
/// use isomorph_common::Landmarks;
///
/// let text = r#"[
///   {"source": [0, 0, 0], "target": [0, 0, 0]},
///   {"source": [1, 0, 0], "target": [0, 1, 0]},
///   {"source": [0, 1, 0], "target": [-1, 0, 0]},
///   {"source": [0, 0, 1], "target": [0, 0, 1]}
/// ]"#;
/// let landmarks = Landmarks::from_json(text)?;
/// // A quarter turn about z, recovered as the landmarks' affine part.
/// let map = landmarks.affine();
/// let q = map.transform_point3(isomorph_common::glam::Vec3::new(2.0, 0.0, 0.0));
/// assert!((q - isomorph_common::glam::Vec3::new(0.0, 2.0, 0.0)).length() < 1e-5);
/// # Ok::<(), isomorph_common::LandmarkError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Landmarks {
    pairs: Vec<(Vec3, Vec3)>,
}

/// One pair as written in a landmarks file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PairRecord {
    source: [f32; 3],
    target: [f32; 3],
}

impl Landmarks {
    /// Validates `pairs` (source point, target point); repeated identical
    /// pairs are merged.
    ///
    /// # Errors
    /// [`LandmarkError::NonFinite`], [`LandmarkError::Conflict`],
    /// [`LandmarkError::TooFew`], [`LandmarkError::Coplanar`].
    pub fn new(pairs: &[(Vec3, Vec3)]) -> Result<Self, LandmarkError> {
        if let Some(index) = pairs.iter().position(|(p, q)| !(p.is_finite() && q.is_finite())) {
            return Err(LandmarkError::NonFinite { index });
        }
        let extent =
            pairs.iter().flat_map(|&(p, q)| [p, q]).fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        let same = 1e-6 * extent.max(1e-30);
        let mut kept: Vec<(usize, Vec3, Vec3)> = Vec::with_capacity(pairs.len());
        for (i, &(p, q)) in pairs.iter().enumerate() {
            match kept.iter().find(|(_, p0, _)| p0.distance(p) <= same) {
                Some(&(first, _, q0)) if q0.distance(q) > same => {
                    return Err(LandmarkError::Conflict { first, second: i, point: p });
                }
                Some(_) => {}
                None => kept.push((i, p, q)),
            }
        }
        if kept.len() < MIN_LANDMARKS {
            return Err(LandmarkError::TooFew { count: kept.len() });
        }
        let pairs: Vec<(Vec3, Vec3)> = kept.into_iter().map(|(_, p, q)| (p, q)).collect();
        for (side, points) in [
            ("source", pairs.iter().map(|p| p.0).collect::<Vec<_>>()),
            ("target", pairs.iter().map(|p| p.1).collect()),
        ] {
            let thickness = thickness(&points);
            if thickness < 1e-4 {
                return Err(LandmarkError::Coplanar { side, thickness });
            }
        }
        Ok(Self { pairs })
    }

    /// Parses a JSON list of `{"source": [x, y, z], "target": [x, y, z]}`
    /// objects (world units) and validates it as [`Landmarks::new`] does.
    ///
    /// # Errors
    /// [`LandmarkError::Format`] for anything else, then [`Landmarks::new`]'s.
    pub fn from_json(text: &str) -> Result<Self, LandmarkError> {
        let records: Vec<PairRecord> =
            serde_json::from_str(text).map_err(|e| LandmarkError::Format(e.to_string()))?;
        let pairs: Vec<(Vec3, Vec3)> =
            records.iter().map(|r| (Vec3::from_array(r.source), Vec3::from_array(r.target))).collect();
        Self::new(&pairs)
    }

    /// The pairs as a landmarks file ([`Landmarks::from_json`] reads it
    /// back).
    pub fn to_json(&self) -> String {
        let records: Vec<PairRecord> = self
            .pairs
            .iter()
            .map(|&(p, q)| PairRecord { source: p.to_array(), target: q.to_array() })
            .collect();
        serde_json::to_string_pretty(&records).expect("finite numbers always serialize")
    }

    /// Reads a landmarks file (see [`Landmarks::from_json`]).
    ///
    /// # Errors
    /// [`LandmarkError::Read`], then [`Landmarks::from_json`]'s.
    pub fn load(path: &Path) -> Result<Self, LandmarkError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| LandmarkError::Read { path: path.display().to_string(), source })?;
        Self::from_json(&text)
    }

    /// The pairs (source point, target point), repeated pairs merged.
    pub fn pairs(&self) -> &[(Vec3, Vec3)] {
        &self.pairs
    }

    /// The source points.
    pub fn sources(&self) -> Vec<Vec3> {
        self.pairs.iter().map(|p| p.0).collect()
    }

    /// The least-squares affine map `x ↦ A x + b` carrying the source
    /// points onto the target points (exact for four pairs), in f64.
    pub fn affine(&self) -> glam::Affine3A {
        let n = self.pairs.len() as f64;
        let (ps, qs): (Vec<DVec3>, Vec<DVec3>) =
            self.pairs.iter().map(|&(p, q)| (p.as_dvec3(), q.as_dvec3())).unzip();
        let (pc, qc) = (ps.iter().sum::<DVec3>() / n, qs.iter().sum::<DVec3>() / n);
        let (mut spp, mut sqp) = (DMat3::ZERO, DMat3::ZERO);
        for (p, q) in ps.iter().zip(&qs) {
            let (dp, dq) = (*p - pc, *q - qc);
            spp += outer(dp, dp);
            sqp += outer(dq, dp);
        }
        // Validation guarantees the source points span 3D, so spp is
        // invertible.
        let a = sqp * spp.inverse();
        let b = qc - a * pc;
        glam::Affine3A::from_mat3_translation(a.as_mat3(), b.as_vec3())
    }
}

/// `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

/// Smallest over largest standard deviation of `points` along their
/// principal axes: 0 when they lie on one plane.
fn thickness(points: &[Vec3]) -> f64 {
    let n = points.len() as f64;
    let c = points.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / n;
    let cov = points.iter().fold(DMat3::ZERO, |m, p| {
        let d = p.as_dvec3() - c;
        m + outer(d, d)
    });
    let eig = nalgebra::Matrix3::from_fn(|r, c| cov.col(c)[r]).symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if hi <= 0.0 { 0.0 } else { (lo.max(0.0) / hi).sqrt() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corners() -> Vec<(Vec3, Vec3)> {
        let m = glam::Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 0.5),
            glam::Quat::from_rotation_y(0.4),
            Vec3::new(1.0, -2.0, 3.0),
        );
        [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE].map(|p| (p, m.transform_point3(p))).to_vec()
    }

    #[test]
    fn the_affine_part_of_affine_pairs_is_exact() {
        let pairs = corners();
        let landmarks = Landmarks::new(&pairs).unwrap();
        assert_eq!(Landmarks::from_json(&landmarks.to_json()).unwrap(), landmarks);
        let map = landmarks.affine();
        for (p, q) in pairs {
            assert!(map.transform_point3(p).distance(q) < 1e-5, "{p} -> {q}");
        }
    }

    #[test]
    fn bad_landmark_sets_are_refused_with_their_reason() {
        let pairs = corners();
        assert!(matches!(Landmarks::new(&pairs[..3]), Err(LandmarkError::TooFew { count: 3 })));
        // A repeated pair is merged, not counted twice.
        let repeated = [&pairs[..3], &pairs[..1]].concat();
        assert!(matches!(Landmarks::new(&repeated), Err(LandmarkError::TooFew { count: 3 })));
        let mut nan = pairs.clone();
        nan[2].1.y = f32::NAN;
        assert!(matches!(Landmarks::new(&nan), Err(LandmarkError::NonFinite { index: 2 })));
        let mut conflict = pairs.clone();
        conflict.push((pairs[1].0, pairs[1].1 + Vec3::X));
        assert!(matches!(
            Landmarks::new(&conflict),
            Err(LandmarkError::Conflict { first: 1, second: 5, .. })
        ));
        // Sources on the plane z = 0, targets spanning 3D.
        let flat: Vec<_> = pairs
            .iter()
            .enumerate()
            .map(|(i, &(_, q))| (Vec3::new(i as f32, (i * i) as f32, 0.0), q))
            .collect();
        assert!(matches!(Landmarks::new(&flat), Err(LandmarkError::Coplanar { side: "source", .. })));
        let swapped: Vec<_> = flat.iter().map(|&(p, q)| (q, p)).collect();
        assert!(matches!(Landmarks::new(&swapped), Err(LandmarkError::Coplanar { side: "target", .. })));
    }

    #[test]
    fn files_must_be_lists_of_source_target_objects() {
        for bad in [
            "{}",
            "[[0, 0, 0]]",
            r#"[{"source": [0, 0], "target": [0, 0, 0]}]"#,
            r#"[{"source": [0, 0, 0], "goal": [0, 0, 0]}]"#,
        ] {
            assert!(matches!(Landmarks::from_json(bad), Err(LandmarkError::Format(_))), "{bad}");
        }
        let e = Landmarks::load(Path::new("/nonexistent/pairs.json")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/pairs.json"), "{e}");
    }
}
