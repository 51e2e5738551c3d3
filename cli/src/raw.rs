//! The options that describe headerless `.raw` volume inputs, shared by
//! `isomorph morph`, `compare` and `warp`.

use clap::{Args, ValueEnum};
use isomorph_common::glam::UVec3;
use isomorph_io::raw::{RawLayout, RawType};

/// `--raw-dims` and `--raw-type`.
#[derive(Debug, Clone, Default, Args)]
pub struct RawArgs {
    /// Node counts NX,NY,NZ of `.raw` volume inputs (x fastest, no header,
    /// voxel units).
    #[arg(long, value_parser = parse_dims)]
    pub raw_dims: Option<UVec3>,
    /// Value type of `.raw` volume inputs.
    #[arg(long, value_enum, default_value_t = RawTypeArg::U8)]
    pub raw_type: RawTypeArg,
}

impl RawArgs {
    /// The layout `--raw-dims` and `--raw-type` give (none without dims).
    pub fn layout(&self) -> Option<RawLayout> {
        self.raw_dims.map(|dims| RawLayout { dims, value: self.raw_type.into() })
    }
}

/// Value types of `.raw` volumes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum RawTypeArg {
    /// Bytes: densities 0–255, surface at 127.5 (or `--iso`).
    #[default]
    U8,
    /// Little-endian f32: signed distances, positive inside (or a field with
    /// its surface at `--iso`).
    F32,
}

impl From<RawTypeArg> for RawType {
    fn from(t: RawTypeArg) -> Self {
        match t {
            RawTypeArg::U8 => RawType::U8,
            RawTypeArg::F32 => RawType::F32,
        }
    }
}

/// Parses `NX,NY,NZ` (each at least 2).
fn parse_dims(s: &str) -> Result<UVec3, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|x| x.trim().parse::<u32>().map_err(|e| format!("'{x}': {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, z] if x >= 2 && y >= 2 && z >= 2 => Ok(UVec3::new(x, y, z)),
        _ => Err(format!("'{s}' is not three sizes of at least 2")),
    }
}
