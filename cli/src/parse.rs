//! Parsers of the values a user types or writes for the command line:
//! correspondence pairs (`--landmark`, `--drag`, `--move`) and alignment map
//! files (`--align map.json`). In the library so that they can be fuzzed and
//! reused by other front ends.

use anyhow::{Context, bail};
use isomorph_common::glam::{Affine3A, Mat4, Vec3};
use std::path::Path;

/// Parses `A,B,C:D,E,F` into two vectors.
pub fn parse_pair(s: &str) -> Result<(Vec3, Vec3), String> {
    let (a, b) = s.split_once(':').ok_or_else(|| format!("'{s}' is not of the form A,B,C:D,E,F"))?;
    let vec = |t: &str| -> Result<Vec3, String> {
        let v: Vec<f32> = t
            .split(',')
            .map(|x| x.trim().parse::<f32>().map_err(|e| format!("'{x}': {e}")))
            .collect::<Result<_, _>>()?;
        match v[..] {
            [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
            _ => Err(format!("'{t}' is not three finite numbers")),
        }
    };
    Ok((vec(a)?, vec(b)?))
}

/// Reads an affine map written by `isomorph align` (its `matrix` entry).
///
/// # Errors
/// Unreadable files, a missing or malformed `matrix`, a last row other than
/// `0 0 0 1`, non-finite entries or a singular map.
pub fn read_map(path: &Path) -> anyhow::Result<Affine3A> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let rows: [[f32; 4]; 4] = serde_json::from_value(json["matrix"].clone())
        .with_context(|| format!("{}: expected \"matrix\": 4 rows of 4 numbers", path.display()))?;
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        bail!("{}: the matrix's last row must be 0 0 0 1 (an affine map)", path.display());
    }
    let map = Affine3A::from_mat4(Mat4::from_cols_array_2d(&rows).transpose());
    if !map.is_finite() || map.matrix3.determinant().abs() < 1e-12 {
        bail!("{}: the map is not finite and invertible", path.display());
    }
    Ok(map)
}
