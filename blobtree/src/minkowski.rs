//! Minkowski-sum interpolation of convex skeletons (§3.4.1):
//! `S(t) = (1 − t) S_A ⊕ t S_B`.

use crate::hull::convex_hull;
use crate::skeleton::Polytope;
use glam::Vec3;

/// The Minkowski interpolation between two convex skeletons, with its
/// generic topology.
///
/// For convex `A`, `B` the face structure of `S(t)` is the same for every
/// `t ∈ (0, 1)`: each vertex is `(1 − t) a_i + t b_j` for a fixed pair
/// `(i, j)` (its *parent vertices*). The *generic topology* — the pairs and
/// the boundary triangles — is built once from the convex hull of the
/// candidate points `(a_i + b_j) / 2`; each instant only moves vertices.
/// At `t = 0` and `t = 1` the skeletons `A` and `B` themselves are returned
/// (the generic faces degenerate there). Intermediate skeletons may have a
/// higher dimension than both ends (two skew segments sweep a parallelogram).
#[derive(Debug, Clone, PartialEq)]
pub struct MinkowskiPath {
    a: Polytope,
    b: Polytope,
    pairs: Vec<(usize, usize)>,
    generic: Polytope,
}

impl MinkowskiPath {
    /// Builds the generic topology of `A ⊕ B` once.
    pub fn new(a: &Polytope, b: &Polytope) -> Self {
        let (va, vb) = (a.vertices(), b.vertices());
        let mut cand = Vec::with_capacity(va.len() * vb.len());
        let mut index = Vec::with_capacity(va.len() * vb.len());
        for (i, p) in va.iter().enumerate() {
            for (j, q) in vb.iter().enumerate() {
                cand.push((p.as_dvec3() + q.as_dvec3()) * 0.5);
                index.push((i, j));
            }
        }
        // The incremental hull may keep candidates lying on an edge or face
        // at t = 1/2 (e.g. a_i + b_j on an edge of A ⊕ B when A and B have
        // parallel edges); they are not vertices of the generic topology and
        // would make the triangulation non-convex at other t. Keep only the
        // extreme points: those outside the hull of the others.
        let first = convex_hull(&cand).vertices();
        let diam = first.iter().map(|&k| (cand[k] - cand[first[0]]).length()).fold(0.0f64, f64::max);
        let extreme: Vec<usize> = first
            .iter()
            .copied()
            .filter(|&k| {
                let others: Vec<glam::Vec3> =
                    first.iter().filter(|&&o| o != k).map(|&o| cand[o].as_vec3()).collect();
                others.is_empty()
                    || Polytope::hull(&others).distance(cand[k].as_vec3(), 2.0).0 as f64 > 1e-5 * diam
            })
            .collect();
        let kept: Vec<glam::DVec3> = extreme.iter().map(|&k| cand[k]).collect();
        let hull = convex_hull(&kept);
        let (generic, order) = Polytope::from_hull(&hull, |k| kept[k].as_vec3());
        let order: Vec<usize> = order.into_iter().map(|k| extreme[k]).collect();
        let pairs = order.iter().map(|&k| index[k]).collect();
        Self { a: a.clone(), b: b.clone(), pairs, generic }
    }

    /// This generic topology on other ends `a`, `b` with the same vertex
    /// counts, whose vertices correspond to this path's ends' one by one
    /// and whose normal cones overlap as theirs do (positive combinations
    /// of the same skeletons, vertex by vertex); `None` if the counts differ.
    pub(crate) fn reseated(&self, a: &Polytope, b: &Polytope) -> Option<Self> {
        let same =
            a.vertices().len() == self.a.vertices().len() && b.vertices().len() == self.b.vertices().len();
        same.then(|| Self {
            a: a.clone(),
            b: b.clone(),
            pairs: self.pairs.clone(),
            generic: self.generic.clone(),
        })
    }

    /// The parent-vertex pairs `(i, j)` of the generic vertices.
    pub fn pairs(&self) -> &[(usize, usize)] {
        &self.pairs
    }

    /// The dimension of the intermediate skeletons (`0 < t < 1`).
    pub fn generic_dimension(&self) -> usize {
        self.generic.dimension()
    }

    /// The skeleton at `t ∈ [0, 1]`.
    pub fn at(&self, t: f32) -> Polytope {
        if t <= 0.0 {
            return self.a.clone();
        }
        if t >= 1.0 {
            return self.b.clone();
        }
        let (va, vb) = (self.a.vertices(), self.b.vertices());
        let v: Vec<Vec3> = self.pairs.iter().map(|&(i, j)| va[i] * (1.0 - t) + vb[j] * t).collect();
        self.generic.moved(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Skeleton;

    fn skeletons() -> Vec<Polytope> {
        vec![
            Skeleton::Point(Vec3::new(0.3, -0.2, 0.1)).polytope().unwrap(),
            Skeleton::Segment(Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.1, 0.0)).polytope().unwrap(),
            Skeleton::Segment(Vec3::new(0.0, -0.4, 0.2), Vec3::new(0.1, 0.4, -0.2)).polytope().unwrap(),
            Skeleton::Polygon(vec![Vec3::ZERO, Vec3::X, Vec3::new(0.2, 0.8, 0.0)]).polytope().unwrap(),
            Skeleton::cuboid(Vec3::new(0.3, 0.2, 0.1)).polytope().unwrap(),
            Skeleton::Polyhedron(vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::new(0.3, 0.3, 0.9),
                Vec3::new(0.6, 0.7, 0.4),
            ])
            .polytope()
            .unwrap(),
        ]
    }

    /// Against brute force: the convex hull of all `(1 − t) a_i + t b_j`,
    /// rebuilt at every `t` — same support function and same distances.
    #[test]
    fn minkowski_sums_match_brute_force_hulls() {
        let sk = skeletons();
        let dirs: Vec<Vec3> = (0..40)
            .map(|k| {
                let k = k as f32;
                Vec3::new((k * 1.7).sin(), (k * 2.3).cos(), (k * 0.9).sin() - 0.3).normalize()
            })
            .collect();
        let probes: Vec<Vec3> = (0..30)
            .map(|k| {
                let k = k as f32;
                Vec3::new((k * 0.7).sin(), (k * 1.3).cos(), (k * 2.1).sin()) * 1.2
            })
            .collect();
        for a in &sk {
            for b in &sk {
                let path = MinkowskiPath::new(a, b);
                for &t in &[0.0f32, 0.1, 0.5, 0.83, 1.0] {
                    let s = path.at(t);
                    let all: Vec<Vec3> = a
                        .vertices()
                        .iter()
                        .flat_map(|p| b.vertices().iter().map(move |q| *p * (1.0 - t) + *q * t))
                        .collect();
                    let brute = Polytope::hull(&all);
                    for u in &dirs {
                        let h = s.support(*u).dot(*u);
                        let expect = (1.0 - t) * a.support(*u).dot(*u) + t * b.support(*u).dot(*u);
                        assert!((h - expect).abs() < 1e-5, "support {h} vs {expect}");
                    }
                    for x in &probes {
                        let (d, e) = (s.distance(*x, 2.0).0, brute.distance(*x, 2.0).0);
                        assert!(
                            (d - e).abs() < 1e-4,
                            "t={t} at {x}: {d} vs brute {e}; dims {} {} {} {}",
                            a.dimension(),
                            b.dimension(),
                            s.dimension(),
                            brute.dimension()
                        );
                    }
                    if t > 0.0 && t < 1.0 {
                        assert_eq!(s.dimension(), brute.dimension());
                    }
                }
            }
        }
        // Two skew segments sweep a 2D parallelogram in between.
        let path = MinkowskiPath::new(&sk[1], &sk[2]);
        assert_eq!(path.generic_dimension(), 2);
        assert_eq!(path.pairs().len(), 4);
    }
}
