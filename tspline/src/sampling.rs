//! Points on the current zero set (paper §3.3 samples `x_j` along `L_τ`),
//! by one of two [`Sampler`]s: marching cubes on a lattice of the finest
//! cell size restricted to the leaves whose coefficients change sign, or
//! the paper's marching triangulation (Hartmann 1998, uniformly spaced
//! points); either way every point is then moved onto `f = 0` by Newton
//! projection (note §7.1, Hartmann's surface-point step) in double
//! precision.
//!
//! Culling is exact: `f` is a convex combination of the coefficients of the
//! leaf's anchors (`R_i ≥ 0`, `Σ R_i = 1`), so a leaf whose coefficients all
//! have one sign contains no zero.

use crate::basis::{Eval, RowValues};
use crate::tspline::TSpline;
use glam::{DVec3, UVec3, Vec3};
use isomorph_common::marching_cubes::marching_cubes;
use isomorph_common::marching_triangulation::{TriangulationSettings, marching_triangulation};
use isomorph_common::{Aabb, Grid3, GridError, MorphError, TriMesh};
use rayon::prelude::*;

/// Where the evolution's zero-set samples `x_j` (paper §3.3) come from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Sampler {
    /// The vertices of a marching-cubes mesh with
    /// [`EvolveSettings::samples_per_cell`](crate::EvolveSettings::samples_per_cell)
    /// nodes per finest cell, evaluated only in leaves that hold a zero
    /// (fast; the points cluster where the surface cuts the lattice
    /// obliquely).
    #[default]
    MarchingCubes,
    /// The vertices of Hartmann's marching triangulation, as the paper does
    /// ("uniformly distributed sample points", §3.3): near-equilateral
    /// triangles with edges of `edge_cells` finest cells (0.05–4), seeded
    /// from a lattice of one node per finest cell.
    MarchingTriangulation {
        /// The triangles' edge length in finest cells of the T-mesh.
        edge_cells: f64,
    },
}

impl Sampler {
    /// The sampler as the morph's report names it (e.g. `marching
    /// triangulation, edge 0.5 finest cells`).
    pub fn describe(&self) -> String {
        match self {
            Sampler::MarchingCubes => "marching cubes".to_string(),
            Sampler::MarchingTriangulation { edge_cells } => {
                format!("marching triangulation, edge {edge_cells} finest cells")
            }
        }
    }
}

/// A point on the zero set with the function's derivatives there.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    pub p: DVec3,
    pub eval: Eval,
}

/// The lattice for the zero-set mesh: `sub` nodes per edge of the smallest
/// leaf (not of the maximum depth, which the tree may not reach).
fn lattice(spline: &TSpline, sub: u32) -> (u32, f64) {
    let cells = (2.0 / spline.mesh().finest_cell()).round() as u32 * sub;
    (cells + 1, 2.0 / f64::from(cells))
}

/// The zero set of `spline` as a marching-cubes mesh in domain coordinates,
/// evaluated only in leaves whose coefficients change sign.
pub(crate) fn zero_set_mesh(spline: &TSpline, sub: u32) -> Result<TriMesh, GridError> {
    let mesh = spline.mesh();
    let c = spline.coefficients();
    let (n, step) = lattice(spline, sub);
    // Per leaf: the coefficient range (a bound of f on the leaf).
    let ranges: Vec<(f64, f64)> = (0..mesh.leaf_count())
        .map(|l| {
            mesh.leaf_anchors(l)
                .iter()
                .fold((f64::MAX, f64::MIN), |(lo, hi), &i| (lo.min(c[i as usize]), hi.max(c[i as usize])))
        })
        .collect();
    let mut grid = Grid3::new(UVec3::splat(n), Vec3::splat(-1.0), step as f32, 0.0f32)?;
    let nn = n as usize;
    // Row by row along x, one leaf at a time: a leaf without a zero fills
    // its run of nodes with a bound of the right sign (exact on the closed
    // leaf, so nodes on its faces may go to either neighbour).
    grid.data_mut().par_chunks_mut(nn * nn).enumerate().for_each_init(
        RowValues::default,
        |row, (k, slab)| {
            for (j, out) in slab.chunks_exact_mut(nn).enumerate() {
                let mut i = 0;
                while i < nn {
                    let p = DVec3::new(i as f64, j as f64, k as f64) * step - DVec3::ONE;
                    let leaf = mesh.locate(p);
                    let end = (((mesh.leaf_box(leaf).1.x + 1.0) / step).ceil() as usize).clamp(i + 1, nn);
                    let (lo, hi) = ranges[leaf];
                    for (n, v) in out[i..end].iter_mut().enumerate() {
                        *v = if lo > 0.0 {
                            lo as f32
                        } else if hi < 0.0 {
                            hi as f32
                        } else {
                            let q = DVec3::new((i + n) as f64 * step - 1.0, p.y, p.z);
                            row.value(mesh, c, leaf, q.clamp(DVec3::splat(-1.0), DVec3::ONE)) as f32
                        };
                    }
                    i = end;
                }
            }
        },
    );
    Ok(marching_cubes(&grid, 0.0))
}

/// Newton projection of `x` onto `f = 0` along the gradient (note §7.1):
/// `None` when it does not converge within `max_drift` of the start.
pub(crate) fn project(spline: &TSpline, x: DVec3, max_drift: f64) -> Option<Sample> {
    let mut p = x;
    for _ in 0..12 {
        let (value, gradient) = spline.value_gradient(p);
        let g2 = gradient.length_squared();
        if g2 < 1e-16 {
            return None;
        }
        let delta = value / g2 * gradient;
        // Positive inside: ∇f points to larger values, so step against it
        // when f > 0.
        p -= delta;
        if (p - x).length() > max_drift || p.abs().max_element() > 1.0 {
            return None;
        }
        if delta.length() < 1e-12 {
            break;
        }
    }
    let eval = spline.eval(p);
    (eval.value.abs() < 1e-6).then_some(Sample { p, eval })
}

/// Samples of the zero set by `sampler` (`sub` marching-cubes nodes per
/// finest cell), each projected onto it.
pub(crate) fn zero_set_samples(
    spline: &TSpline,
    sampler: Sampler,
    sub: u32,
) -> Result<Vec<Sample>, MorphError> {
    let (_, step) = lattice(spline, sub);
    let points = match sampler {
        Sampler::MarchingCubes => zero_set_mesh(spline, sub)?.positions,
        Sampler::MarchingTriangulation { edge_cells } => {
            let h = spline.mesh().finest_cell();
            let settings = TriangulationSettings {
                edge: (edge_cells * h) as f32,
                seed_resolution: lattice(spline, 1).0,
                ..Default::default()
            };
            marching_triangulation(spline, &Aabb::cube(1.0), 0.0, &settings)?.0.positions
        }
    };
    Ok(points.par_iter().filter_map(|&v| project(spline, v.as_dvec3(), 2.0 * step)).collect())
}
