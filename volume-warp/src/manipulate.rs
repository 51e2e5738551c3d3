//! Direct manipulation of the map (thesis §6, after Hsu, Hughes & Kaufman,
//! *Direct Manipulation of Free-Form Deformations*, SIGGRAPH 1992).

use crate::{BSplineMap, WarpError};
use glam::{UVec3, Vec3};
use nalgebra::DMatrix;

/// One picked point and where its image should go (both in source voxel
/// coordinates, the map's space).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handle {
    /// The source point that is dragged.
    pub point: Vec3,
    /// Where `B(point)` should be after the edit.
    pub goal: Vec3,
}

/// The solution of a drag: new control point positions and how well the
/// goals are met.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Drag {
    /// Control points to move and their new positions (source voxel units),
    /// ready for [`crate::VolumeWarp::move_control_points`].
    pub moves: Vec<(UVec3, Vec3)>,
    /// Largest distance (voxels) between a handle's new image and its goal:
    /// zero up to rounding when the goals are reachable, the least-squares
    /// misfit when they conflict.
    pub residual: f32,
}

/// Solves the minimum-norm change of control points that moves each
/// handle's image to its goal. `influence`: optional radius (voxels) of the
/// region of influence; only control points whose rest position lies within
/// it of some handle's point may move.
///
/// The user picks points `x_k` of the source and says where their images
/// should go, `y_k`. Each image is linear in the control displacements,
/// `B(x_k) = x_k + Σ_m W_km D_m` with `W_km` the basis-weight product of
/// control point `m` at `x_k`, so the change `ΔD` that moves every picked
/// point to its goal solves `W ΔD = Y − B(X)` (one system per coordinate,
/// same matrix). With fewer constraints than free control points the system
/// is underdetermined and we take Hsu's minimum-norm solution
/// `ΔD = W⁺ (Y − B(X))`; with more (or conflicting) constraints the same
/// pseudo-inverse gives the least-squares compromise. The pseudo-inverse is
/// computed by SVD (singular values below `1e-9 · σ_max` dropped).
///
/// A *region of influence* (Hsu's "magnet tool" size) restricts the free
/// control points to those resting within a radius of some picked point;
/// the others stay put, which keeps the edit local.
///
/// # Errors
/// [`WarpError::NonFinite`] for a NaN or infinite handle,
/// [`MorphError::BadSetting`](isomorph_common::MorphError::BadSetting) for a
/// radius that is not positive and finite, [`WarpError::Unreachable`] when the region of influence leaves a
/// handle without any control point that moves it.
pub fn solve_drag(map: &BSplineMap, handles: &[Handle], influence: Option<f32>) -> Result<Drag, WarpError> {
    for h in handles {
        for (what, v) in [("handle point", h.point), ("handle goal", h.goal)] {
            if !v.is_finite() {
                return Err(WarpError::NonFinite { what, value: v });
            }
        }
    }
    if let Some(r) = influence {
        isomorph_common::check::positive("influence radius", f64::from(r))?;
    }
    let free = |c: UVec3| {
        influence.is_none_or(|r| handles.iter().any(|h| map.rest_position(c).distance(h.point) <= r))
    };
    // Columns: the free control points in the support of some handle.
    let mut columns: Vec<UVec3> = Vec::new();
    let mut rows: Vec<Vec<(usize, f32)>> = Vec::with_capacity(handles.len());
    for (k, h) in handles.iter().enumerate() {
        let corner = map.support_corner(h.point);
        let weights = map.weights_at(h.point);
        let mut row = Vec::new();
        for (n, &w) in weights.iter().enumerate() {
            let c = corner + UVec3::new(n as u32 & 3, (n as u32 >> 2) & 3, n as u32 >> 4);
            if w == 0.0 || !free(c) {
                continue;
            }
            let col = match columns.iter().position(|&q| q == c) {
                Some(col) => col,
                None => {
                    columns.push(c);
                    columns.len() - 1
                }
            };
            row.push((col, w));
        }
        if row.is_empty() {
            return Err(WarpError::Unreachable(k));
        }
        rows.push(row);
    }
    if handles.is_empty() {
        return Ok(Drag { moves: Vec::new(), residual: 0.0 });
    }
    let mut w = DMatrix::<f64>::zeros(handles.len(), columns.len());
    let mut rhs = DMatrix::<f64>::zeros(handles.len(), 3);
    for (k, (row, h)) in rows.iter().zip(handles).enumerate() {
        for &(col, weight) in row {
            w[(k, col)] = f64::from(weight);
        }
        let delta = h.goal - map.eval(h.point);
        for axis in 0..3 {
            rhs[(k, axis)] = f64::from(delta[axis]);
        }
    }
    let svd = w.svd(true, true);
    let eps = 1e-9 * svd.singular_values.max();
    let change = svd.solve(&rhs, eps).expect("U and Vᵀ were computed");
    let mut moved = map.clone();
    let mut moves = Vec::with_capacity(columns.len());
    for (col, &c) in columns.iter().enumerate() {
        let d = Vec3::new(change[(col, 0)] as f32, change[(col, 1)] as f32, change[(col, 2)] as f32);
        let position = map.control_point(c)? + d;
        moved.set_control_point(c, position)?;
        moves.push((c, position));
    }
    let residual = handles.iter().map(|h| moved.eval(h.point).distance(h.goal)).fold(0.0, f32::max);
    Ok(Drag { moves, residual })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(map: &BSplineMap, drag: &Drag) -> BSplineMap {
        let mut out = map.clone();
        for &(c, p) in &drag.moves {
            out.set_control_point(c, p).unwrap();
        }
        out
    }

    #[test]
    fn dragged_points_land_where_asked() {
        let map = BSplineMap::identity(UVec3::splat(30), 9).unwrap();
        let handles = [
            Handle { point: Vec3::new(10.0, 12.0, 15.0), goal: Vec3::new(13.0, 11.0, 15.5) },
            Handle { point: Vec3::new(20.0, 8.0, 5.0), goal: Vec3::new(19.0, 8.0, 7.0) },
            Handle { point: Vec3::new(11.5, 13.0, 15.0), goal: Vec3::new(14.0, 12.5, 15.0) },
        ];
        let drag = solve_drag(&map, &handles, None).unwrap();
        let moved = apply(&map, &drag);
        for h in &handles {
            let got = moved.eval(h.point);
            assert!(got.distance(h.goal) < 1e-3, "B({}) = {got}, goal {}", h.point, h.goal);
        }
        assert!(drag.residual < 1e-3);
    }

    #[test]
    fn one_handle_gets_the_minimum_norm_change() {
        // For one constraint the minimum-norm solution is ΔD_m = w_m δ / Σ w².
        let map = BSplineMap::identity(UVec3::splat(24), 8).unwrap();
        let h = Handle { point: Vec3::new(9.3, 14.1, 6.7), goal: Vec3::new(11.0, 13.0, 8.0) };
        let drag = solve_drag(&map, &[h], None).unwrap();
        let w = map.weights_at(h.point);
        let corner = map.support_corner(h.point);
        let norm2: f32 = w.iter().map(|w| w * w).sum();
        let delta = h.goal - h.point;
        assert_eq!(drag.moves.len(), 64);
        for (c, p) in &drag.moves {
            let d = *c - corner;
            let wm = w[(d.x + 4 * d.y + 16 * d.z) as usize];
            let expected = map.rest_position(*c) + wm / norm2 * delta;
            assert!(p.distance(expected) < 1e-4, "control {c}: {p} vs {expected}");
        }
    }

    #[test]
    fn conflicting_handles_get_the_least_squares_compromise() {
        let map = BSplineMap::identity(UVec3::splat(20), 7).unwrap();
        let p = Vec3::new(8.0, 9.0, 10.0);
        let handles =
            [Handle { point: p, goal: p + Vec3::X * 2.0 }, Handle { point: p, goal: p - Vec3::Y * 2.0 }];
        let drag = solve_drag(&map, &handles, None).unwrap();
        let got = apply(&map, &drag).eval(p);
        let mid = p + Vec3::new(1.0, -1.0, 0.0);
        assert!(got.distance(mid) < 1e-3, "least squares {got}, expected {mid}");
        assert!((drag.residual - 2f32.sqrt()).abs() < 1e-3);
    }

    #[test]
    fn region_of_influence_keeps_far_control_points_still() {
        let map = BSplineMap::identity(UVec3::splat(30), 9).unwrap();
        let h = Handle { point: Vec3::new(14.0, 15.0, 16.0), goal: Vec3::new(16.0, 15.0, 16.0) };
        let radius = 7.0;
        let drag = solve_drag(&map, &[h], Some(radius)).unwrap();
        assert!(drag.moves.len() < 64);
        for (c, _) in &drag.moves {
            assert!(map.rest_position(*c).distance(h.point) <= radius);
        }
        assert!(apply(&map, &drag).eval(h.point).distance(h.goal) < 1e-3);
        assert!(matches!(solve_drag(&map, &[h], Some(0.5)), Err(WarpError::Unreachable(0))));
        let bad = Handle { point: Vec3::NAN, goal: Vec3::ZERO };
        assert!(matches!(solve_drag(&map, &[bad], None), Err(WarpError::NonFinite { .. })));
        let negative = solve_drag(&map, &[h], Some(-19.2)).unwrap_err().to_string();
        assert!(negative.contains("influence radius = -19.2") && negative.contains("> 0"), "{negative}");
    }
}
