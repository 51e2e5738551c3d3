//! Breen's coordinate transform `T(x, α)` (eq. 25–26), applied to the
//! polygonized frames so that size, position and shape change smoothly while
//! the level set deforms.

use isomorph_common::glam::{Affine3A, Mat3, Vec3};
use isomorph_common::{AffinePath, TriMesh};
use std::fmt;
use std::sync::Arc;

/// A generalized warp `W` from source space to target space (Breen §6.2):
/// a B-spline volume warp, an RBF warp, or any other smooth map.
pub type Warp = Arc<dyn Fn(Vec3) -> Vec3 + Send + Sync>;

/// How kept frame `n` of `N` is placed: by `T(x, α)` with `α = n/(N − 1)`,
/// where `T(x, 0) = x` and `T(x, 1)` is the map used for the speed.
#[derive(Clone, Default)]
pub enum Placement {
    /// Frames stay where they were evolved (`T` is the identity).
    #[default]
    Identity,
    /// An affine map interpolated over time (translation and scale
    /// linearly, rotation by slerp): eq. 26 generalized.
    Affine(AffinePath),
    /// A generalized warp, blended per vertex: `T(x, α) = (1 − α) x + α W(x)`.
    /// Frames of [`Morph::frame`](isomorph_common::Morph::frame) then carry
    /// the identity transform (no affine map represents the warp); their
    /// meshes are placed vertex by vertex.
    Warp(Warp),
}

impl fmt::Debug for Placement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Placement::Identity => f.write_str("Identity"),
            Placement::Affine(path) => f.debug_tuple("Affine").field(path).finish(),
            Placement::Warp(_) => f.write_str("Warp(..)"),
        }
    }
}

impl From<AffinePath> for Placement {
    fn from(path: AffinePath) -> Self {
        Placement::Affine(path)
    }
}

impl Placement {
    /// A warp placement from any map `W` (source → target space).
    pub fn warp(map: impl Fn(Vec3) -> Vec3 + Send + Sync + 'static) -> Self {
        Placement::Warp(Arc::new(map))
    }

    /// `"identity"`, `"affine"` or `"warp"` (for reports).
    pub fn kind(&self) -> &'static str {
        match self {
            Placement::Identity => "identity",
            Placement::Affine(_) => "affine",
            Placement::Warp(_) => "warp",
        }
    }

    /// The affine part of `T(·, α)`: the interpolated map, or the identity
    /// for [`Placement::Identity`] and [`Placement::Warp`].
    pub fn affine_at(&self, alpha: f32) -> Affine3A {
        match self {
            Placement::Affine(path) => path.at(alpha),
            Placement::Identity | Placement::Warp(_) => Affine3A::IDENTITY,
        }
    }

    /// `T(x, α)` at one point.
    pub fn point_at(&self, x: Vec3, alpha: f32) -> Vec3 {
        match self {
            Placement::Identity => x,
            Placement::Affine(path) => path.at(alpha).transform_point3(x),
            Placement::Warp(w) => x.lerp(w(x), alpha),
        }
    }

    /// The point `x` with `T(x, α) = p`: the affine path's inverse, or for
    /// a warp Newton's method on `(1 − α) x + α W(x) = p` from `x = p`
    /// (Jacobian by central differences of step `scale · 1e-4`, stopping at
    /// `scale · 1e-6`; `scale` is the shapes' size). Where the warp folds
    /// (singular Jacobian) the last iterate is returned.
    pub fn unplace(&self, p: Vec3, alpha: f32, scale: f32) -> Vec3 {
        match self {
            Placement::Identity => p,
            Placement::Affine(path) => path.at(alpha).inverse().transform_point3(p),
            Placement::Warp(w) => {
                let (h, tolerance) = (scale * 1e-4, scale * 1e-6);
                let mut x = p;
                for _ in 0..20 {
                    let residual = x.lerp(w(x), alpha) - p;
                    if residual.length() <= tolerance {
                        break;
                    }
                    let column = |e: Vec3| {
                        let d = (w(x + h * e) - w(x - h * e)) / (2.0 * h);
                        (1.0 - alpha) * e + alpha * d
                    };
                    let jacobian = Mat3::from_cols(column(Vec3::X), column(Vec3::Y), column(Vec3::Z));
                    if jacobian.determinant().abs() < 1e-12 {
                        break;
                    }
                    x -= jacobian.inverse() * residual;
                }
                x
            }
        }
    }

    /// Places `mesh` by `T(·, α)`; normals, if any, are recomputed for a warp.
    pub fn apply(&self, mesh: &mut TriMesh, alpha: f32) {
        match self {
            Placement::Identity => {}
            Placement::Affine(path) => mesh.transform(&path.at(alpha)),
            Placement::Warp(w) => {
                for p in &mut mesh.positions {
                    *p = p.lerp(w(*p), alpha);
                }
                if mesh.normals.is_some() {
                    mesh.compute_normals();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warp_placement_runs_from_identity_to_the_warp() {
        let bend = Placement::warp(|p: Vec3| Vec3::new(p.x, p.y + p.x * p.x, p.z));
        let x = Vec3::new(0.5, 0.1, -0.2);
        assert_eq!(bend.point_at(x, 0.0), x);
        assert!((bend.point_at(x, 1.0) - Vec3::new(0.5, 0.35, -0.2)).length() < 1e-6);
        assert!((bend.point_at(x, 0.5) - Vec3::new(0.5, 0.225, -0.2)).length() < 1e-6);
        assert_eq!(bend.affine_at(0.7), Affine3A::IDENTITY);
        for alpha in [0.0, 0.3, 1.0] {
            let back = bend.unplace(bend.point_at(x, alpha), alpha, 1.0);
            assert!(back.distance(x) < 1e-5, "alpha {alpha}: {back} vs {x}");
        }
    }

    #[test]
    fn affine_placement_interpolates_the_path() {
        let end = Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            isomorph_common::glam::Quat::IDENTITY,
            Vec3::X,
        );
        let p = Placement::from(AffinePath::from_identity(&end).unwrap());
        let x = Vec3::new(1.0, 1.0, 0.0);
        assert!((p.point_at(x, 1.0) - Vec3::new(3.0, 2.0, 0.0)).length() < 1e-5);
        assert!((p.point_at(x, 0.0) - x).length() < 1e-6);
        let mut mesh = TriMesh::new(vec![x, Vec3::Y, Vec3::Z], vec![[0, 1, 2]]).unwrap();
        p.apply(&mut mesh, 1.0);
        assert!((mesh.positions[0] - Vec3::new(3.0, 2.0, 0.0)).length() < 1e-5);
    }
}
