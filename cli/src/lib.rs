//! The library behind the `isomorph` command line tool: the registry of
//! morph methods ([`methods`]), so that the command line, the comparison
//! tool and other front ends build every method the same way, through the
//! morph contract (`XxxMorph::new(source, target, &settings, &control)`).
//!
//! ```no_run
//! use isomorph_cli::methods::{Method, Settings, build, load_input};
//! use isomorph_common::{Control, Morph};
//!
//! let control = Control::new();
//! let source = load_input(Method::LevelSet, "sphere", &Default::default())?;
//! let target = load_input(Method::LevelSet, "torus", &Default::default())?;
//! let morph = build(Method::LevelSet, &source, &target, &Settings::default(), &control)?;
//! let mesh = morph.frame_mesh(0.5, 64)?;
//! assert!(!mesh.triangles.is_empty());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod methods;
pub mod parse;
