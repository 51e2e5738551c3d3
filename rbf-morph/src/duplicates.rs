//! Near-duplicate constraints: merged or rejected before the solve.
//!
//! Two constraints closer than the tolerance make the system (nearly)
//! singular. They are found in `O(n log n)` by sorting along a fixed generic
//! direction and sweeping a window of the tolerance's width.

use crate::error::RbfError;

/// What to do with constraints closer than
/// [`FitSettings::duplicate_tolerance`](crate::FitSettings::duplicate_tolerance).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DuplicatePolicy {
    /// Keep the first of each group when all values agree (to 1e-9 of the
    /// largest value); different values are a [`RbfError::NearDuplicate`]
    /// error. The default: shared mesh vertices are merged, contradictions
    /// reported.
    #[default]
    MergeEqual,
    /// Keep one constraint per group with the mean of the group's values
    /// (an approximation: the interpolant is no longer exact there).
    Average,
    /// Any near-duplicate is a [`RbfError::NearDuplicate`] error.
    Reject,
}

/// Indices kept (into the input) and their values, after applying `policy`.
pub(crate) fn dedup<const D: usize>(
    positions: &[[f64; D]],
    values: &[f64],
    tolerance: f64,
    policy: DuplicatePolicy,
) -> Result<(Vec<usize>, Vec<f64>), RbfError> {
    let n = positions.len();
    if tolerance <= 0.0 || n < 2 {
        return Ok(((0..n).collect(), values.to_vec()));
    }
    // A generic direction: no two distinct lattice-like points project alike.
    let dir: [f64; D] = std::array::from_fn(|k| 1.0 + 0.618_033_988_7 * (k as f64 + 1.0).sqrt());
    let norm = dir.iter().map(|x| x * x).sum::<f64>().sqrt();
    let key = |p: &[f64; D]| p.iter().zip(&dir).map(|(a, b)| a * b).sum::<f64>() / norm;
    let mut order: Vec<usize> = (0..n).collect();
    let keys: Vec<f64> = positions.iter().map(key).collect();
    order.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]).then(a.cmp(&b)));
    // Union of each point with the smallest-index point within tolerance.
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    let tol2 = tolerance * tolerance;
    for (a, &i) in order.iter().enumerate() {
        for &j in &order[a + 1..] {
            if keys[j] - keys[i] > tolerance {
                break;
            }
            let d2: f64 = positions[i].iter().zip(&positions[j]).map(|(x, y)| (x - y) * (x - y)).sum();
            if d2 > tol2 {
                continue;
            }
            let (first, second) = (i.min(j), i.max(j));
            let differ = (values[i] - values[j]).abs() > 1e-9 * scale;
            if policy == DuplicatePolicy::Reject || (policy == DuplicatePolicy::MergeEqual && differ) {
                return Err(RbfError::NearDuplicate {
                    first,
                    second,
                    distance: d2.sqrt(),
                    first_value: values[first] as f32,
                    second_value: values[second] as f32,
                });
            }
            let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
            let (lo, hi) = (ri.min(rj), ri.max(rj));
            parent[hi] = lo;
        }
    }
    let mut sums = vec![(0.0f64, 0usize); n];
    for i in 0..n {
        let r = find(&mut parent, i);
        sums[r].0 += values[i];
        sums[r].1 += 1;
    }
    let kept: Vec<usize> = (0..n).filter(|&i| parent[i] == i).collect();
    let vals = kept.iter().map(|&i| sums[i].0 / sums[i].1 as f64).collect();
    Ok((kept, vals))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_equal_and_rejects_conflicts() {
        let p = [[0.0, 0.0], [1.0, 0.0], [1e-12, 0.0], [0.0, 1.0]];
        let (kept, vals) = dedup(&p, &[0.0, 1.0, 0.0, 2.0], 1e-9, DuplicatePolicy::MergeEqual).unwrap();
        assert_eq!(kept, vec![0, 1, 3]);
        assert_eq!(vals, vec![0.0, 1.0, 2.0]);
        let err = dedup(&p, &[0.0, 1.0, 0.5, 2.0], 1e-9, DuplicatePolicy::MergeEqual).unwrap_err();
        assert!(matches!(err, RbfError::NearDuplicate { first: 0, second: 2, .. }), "{err}");
        let (kept, vals) = dedup(&p, &[0.0, 1.0, 0.5, 2.0], 1e-9, DuplicatePolicy::Average).unwrap();
        assert_eq!(kept, vec![0, 1, 3]);
        assert_eq!(vals[0], 0.25);
        assert!(dedup(&p, &[0.0, 1.0, 0.0, 2.0], 1e-9, DuplicatePolicy::Reject).is_err());
        assert_eq!(dedup(&p, &[0.0; 4], 1e-15, DuplicatePolicy::Reject).unwrap().0.len(), 4);
    }
}
