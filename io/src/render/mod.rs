//! Software preview renderer and contact sheets: people would rather look at
//! a morph than read numbers.
//!
//! [`render`] draws a [`TriMesh`] into an [`Image`] with a perspective
//! [`Camera`], a z-buffer and fixed studio lighting (key, fill, ambient and a
//! highlight, relative to the camera). Both sides of every triangle are
//! drawn, the back side in [`RenderSettings::back_color`], so open meshes and
//! inside-out patches are visible. [`contact_sheet`] tiles labelled frames
//! into one image, [`Image::write_png`] saves any of them and [`write_gif`]
//! saves a sequence as a looping animation.
//!
//! ```
//! use isomorph_io::render::{render, RenderSettings};
//! use isomorph_common::{glam::Vec3, TriMesh};
//!
//! let tetrahedron = TriMesh::new(
//!     vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
//!     vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//! )?;
//! let settings = RenderSettings::default();
//! let image = render(&tetrahedron, &settings);
//! let drawn = image.pixels().iter().filter(|&&p| p != settings.background).count();
//! assert!(drawn > 1000);
//! # Ok::<(), isomorph_common::MeshError>(())
//! ```
//!
//! For a sequence of frames, fit one camera to the bounds of the whole
//! sequence ([`Camera::fit`]) and pass it in the settings, so that every frame
//! is seen from the same place at the same scale.
//!
//! Rendering is deterministic: the same input gives the same pixels whatever
//! the thread count. Broken input never panics: triangles with a non-finite
//! corner or an out-of-range index are skipped, an empty mesh gives a plain
//! background image.

mod animation;
mod camera;
mod font;
mod image;
mod raster;
mod shade;
mod sheet;

pub use animation::{write_gif, write_gif_to};
pub use camera::Camera;
pub use font::text_size;
pub use image::Image;
pub use sheet::{ContactSheet, contact_sheet, contact_sheet_titled};

use glam::{Vec2, Vec3};
use isomorph_common::{Aabb, TriMesh};
use raster::{Projection, rasterize};
use rayon::prelude::*;
use shade::{Shader, linear_to_srgb, srgb_to_linear};

/// Errors of image output.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The file could not be created or written.
    #[error("could not write the image: {0}")]
    Io(#[from] std::io::Error),
    /// The PNG or GIF encoder rejected the image(s).
    #[error("{0}")]
    Encode(String),
    /// The image has no pixels, or more than a GIF can hold (65535 per
    /// side).
    #[error(
        "cannot save a {width}×{height} image: it needs a width and height of at least 1 (at most 65535 for a GIF)"
    )]
    EmptyImage {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
}

/// How surface normals vary across a triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Shading {
    /// Normals interpolated from area-weighted vertex normals (or the mesh's
    /// own normals): curved surfaces look curved.
    #[default]
    Smooth,
    /// One normal per triangle: facets stay visible, as in a mesh inspector.
    Flat,
}

/// What [`render`] draws and how.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The camera; `None` frames the mesh's bounding box from
    /// [`Camera::DEFAULT_VIEW_DIR`] ([`Camera::fit_default`]).
    pub camera: Option<Camera>,
    /// Smooth or flat shading.
    pub shading: Shading,
    /// sRGB colour of the outside of the surface (the side its triangles'
    /// normals point to), unless the mesh has vertex colours
    /// ([`TriMesh::colors`]): those are then interpolated across each
    /// triangle and shaded instead.
    pub color: [u8; 3],
    /// sRGB colour of the inside (back faces, seen through holes).
    pub back_color: [u8; 3],
    /// sRGB colour where no surface is seen.
    pub background: [u8; 3],
    /// Samples per pixel along each axis (1 to 4; 2 means 2 × 2 samples):
    /// anti-aliases edges at a cost that grows with its square. Lowered
    /// automatically for very large images.
    pub supersampling: u32,
}

impl Default for RenderSettings {
    /// 320 × 320 pixels, auto-framed, smooth, steel blue on near-white with
    /// a terracotta inside, 2 × 2 supersampling.
    fn default() -> Self {
        Self {
            width: 320,
            height: 320,
            camera: None,
            shading: Shading::Smooth,
            color: [120, 160, 205],
            back_color: [205, 120, 90],
            background: [248, 248, 246],
            supersampling: 2,
        }
    }
}

/// Most samples rendered per image (8 bytes each); supersampling is lowered
/// to stay under it.
const MAX_SAMPLES: u64 = 1 << 25;

/// Renders `mesh` into a new `width × height` image (see the module docs).
///
/// Allocates the image plus 8 bytes per sample, i.e. per pixel times
/// `supersampling²`.
pub fn render(mesh: &TriMesh, settings: &RenderSettings) -> Image {
    let (width, height) = (settings.width, settings.height);
    let mut image = Image::new(width, height, settings.background);
    if image.pixels().is_empty() || mesh.is_empty() {
        return image;
    }
    let pixels = u64::from(width) * u64::from(height);
    let ss = (1..=settings.supersampling.clamp(1, 4))
        .rev()
        .find(|&s| pixels * u64::from(s * s) <= MAX_SAMPLES)
        .unwrap_or(1);
    let camera = settings.camera.unwrap_or_else(|| Camera::fit_default(&finite_bounds(mesh)));
    let (sample_width, sample_height) = (width * ss, height * ss);
    let projection = Projection::new(&camera, sample_width, sample_height);
    let fragments = rasterize(mesh, &projection, sample_width, sample_height);
    let shader = Shader::new(mesh, settings, &projection);
    let background = srgb_to_linear(settings.background);
    let (ss, sample_width) = (ss as usize, sample_width as usize);
    image.pixels_mut().par_chunks_mut(width as usize).enumerate().for_each(|(y, row)| {
        for (x, pixel) in row.iter_mut().enumerate() {
            let mut sum = Vec3::ZERO;
            let mut covered = false;
            for sy in y * ss..(y + 1) * ss {
                for (sx, fragment) in (x * ss..).zip(&fragments[sy * sample_width + x * ss..][..ss]) {
                    if fragment.is_covered() {
                        covered = true;
                        let sample = Vec2::new(sx as f32 + 0.5, sy as f32 + 0.5);
                        sum += shader.shade(fragment, sample).min(Vec3::ONE);
                    } else {
                        sum += background;
                    }
                }
            }
            if covered {
                *pixel = linear_to_srgb(sum / (ss * ss) as f32);
            }
        }
    });
    image
}

/// Bounding box of the finite vertices.
fn finite_bounds(mesh: &TriMesh) -> Aabb {
    mesh.positions.iter().filter(|p| p.is_finite()).fold(Aabb::EMPTY, |b, &p| b.including(p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use isomorph_common::mesh::primitives::uv_sphere;

    fn drawn(image: &Image, background: [u8; 3]) -> Vec<(u32, u32)> {
        (0..image.height())
            .flat_map(|y| (0..image.width()).map(move |x| (x, y)))
            .filter(|&(x, y)| image.get(x, y) != Some(background))
            .collect()
    }

    fn brightness(p: [u8; 3]) -> u32 {
        p.iter().map(|&c| u32::from(c)).sum()
    }

    #[test]
    fn sphere_is_centred_and_fills_a_plausible_fraction() {
        let sphere = uv_sphere(Vec3::new(3.0, -1.0, 2.0), 0.5, 24, 48);
        assert!(sphere.vertex_normals()[0].dot(Vec3::Z) > 0.99, "test sphere is outward");
        let settings = RenderSettings::default();
        let image = render(&sphere, &settings);
        let pixels = drawn(&image, settings.background);
        let fraction = pixels.len() as f32 / (320.0 * 320.0);
        // The box around the sphere fills ~90 % of the frame; the sphere's
        // disc is about a third of the image area.
        assert!((0.2..0.6).contains(&fraction), "covered fraction {fraction}");
        let centroid = pixels.iter().fold((0.0, 0.0), |(sx, sy), &(x, y)| (sx + x as f32, sy + y as f32));
        let centroid = (centroid.0 / pixels.len() as f32, centroid.1 / pixels.len() as f32);
        assert!(
            (centroid.0 - 159.5).abs() < 8.0 && (centroid.1 - 159.5).abs() < 8.0,
            "centroid {centroid:?}"
        );
    }

    #[test]
    fn key_light_side_is_brighter_than_the_shadow_side() {
        let sphere = uv_sphere(Vec3::ZERO, 1.0, 32, 64);
        let settings = RenderSettings {
            camera: Some(Camera::look_at(Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO)),
            shading: Shading::Smooth,
            ..RenderSettings::default()
        };
        let image = render(&sphere, &settings);
        // The key light comes from the upper left, so the upper-left part of
        // the disc is lit and the lower-right one in shadow.
        let upper_left = image.get(130, 130).unwrap();
        let lower_right = image.get(190, 190).unwrap();
        assert!(
            brightness(upper_left) > brightness(lower_right) + 150,
            "lit {upper_left:?} vs shadow {lower_right:?}"
        );
        for shading in [Shading::Smooth, Shading::Flat] {
            let flat = render(&sphere, &RenderSettings { shading, ..settings });
            assert_eq!(flat.get(5, 5), Some(settings.background));
            assert_ne!(flat.get(160, 160), Some(settings.background));
        }
    }

    #[test]
    fn near_triangle_occludes_far_triangle() {
        // A big far triangle and a small near one, listed in both orders.
        let big = [Vec3::new(-5.0, -5.0, -2.0), Vec3::new(5.0, -5.0, -2.0), Vec3::new(0.0, 5.0, -2.0)];
        let small = [Vec3::new(-0.2, -0.2, 1.0), Vec3::new(0.2, -0.2, 1.0), Vec3::new(0.0, 0.2, 1.0)];
        let settings = RenderSettings {
            width: 64,
            height: 64,
            camera: Some(Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO)),
            color: [200, 200, 200],
            back_color: [220, 60, 60],
            supersampling: 1,
            ..RenderSettings::default()
        };
        let mut images = Vec::new();
        for corners in [[big, small].concat(), [small, big].concat()] {
            let near = usize::from(corners[0].z < 0.0);
            let mesh = TriMesh::new(corners, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
            images.push(render(&mesh, &settings));
            // Turn the near triangle round: its red back must show at the centre.
            let mut tinted = mesh.clone();
            tinted.triangles[near].swap(1, 2);
            let image = render(&tinted, &settings);
            let center = image.get(32, 34).unwrap();
            assert!(center[0] > center[2] + 40, "near back face not on top: {center:?}");
            let corner = image.get(10, 50).unwrap();
            assert_eq!(corner[0], corner[2], "far triangle should show away from the small one");
        }
        assert_eq!(images[0], images[1], "result depends on triangle order");
    }

    #[test]
    fn empty_and_broken_meshes_give_background_without_panicking() {
        let settings = RenderSettings { width: 40, height: 30, ..RenderSettings::default() };
        let plain = Image::new(40, 30, settings.background);
        assert_eq!(render(&TriMesh::default(), &settings), plain);
        let nan = TriMesh {
            positions: vec![Vec3::NAN, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, f32::INFINITY)],
            triangles: vec![[0, 1, 2], [1, 2, 3], [1, 2, 7]],
            normals: Some(vec![Vec3::NAN; 2]),
            colors: None,
        };
        assert_eq!(render(&nan, &settings), plain);
        let mut partly = uv_sphere(Vec3::ZERO, 1.0, 8, 16);
        partly.positions[0] = Vec3::NAN;
        let image = render(&partly, &settings);
        assert!(!drawn(&image, settings.background).is_empty());
        let zero = RenderSettings { width: 0, ..settings };
        assert!(render(&partly, &zero).pixels().is_empty());
    }

    #[test]
    fn camera_inside_the_mesh_sees_the_inside() {
        let sphere = uv_sphere(Vec3::ZERO, 1.0, 16, 32);
        let settings = RenderSettings {
            width: 32,
            height: 32,
            camera: Some(Camera::look_at(Vec3::ZERO, Vec3::X)),
            ..RenderSettings::default()
        };
        let image = render(&sphere, &settings);
        // Every pixel shows the back colour's hue (red over blue).
        assert!(image.pixels().iter().all(|p| p[0] > p[2]), "{:?}", image.get(16, 16));
    }

    #[test]
    fn supersampling_softens_edges_only() {
        let sphere = uv_sphere(Vec3::ZERO, 1.0, 16, 32);
        let base = RenderSettings { width: 48, height: 48, supersampling: 1, ..RenderSettings::default() };
        let aliased = render(&sphere, &base);
        let smooth = render(&sphere, &RenderSettings { supersampling: 3, ..base });
        let levels = |image: &Image| drawn(image, base.background).len();
        // Edge pixels become partly covered blends: more pixels differ from the background.
        assert!(levels(&smooth) > levels(&aliased));
        assert_eq!(smooth.get(0, 0), Some(base.background));
    }

    #[test]
    fn vertex_colours_are_shaded_instead_of_the_surface_colour() {
        // Red where x < 0, blue where x > 0 (the camera sees more of x > 0).
        let sphere = uv_sphere(Vec3::ZERO, 1.0, 24, 48);
        let colors = sphere
            .positions
            .iter()
            .map(|p| Vec3::new((0.5 - 4.0 * p.x).clamp(0.0, 1.0), 0.0, (0.5 + 4.0 * p.x).clamp(0.0, 1.0)))
            .collect();
        let painted = sphere.clone().with_colors(colors).unwrap();
        let settings = RenderSettings::default();
        let count = |image: &Image, keep: &dyn Fn([u8; 3]) -> bool| {
            drawn(image, settings.background).iter().filter(|&&(x, y)| keep(image.get(x, y).unwrap())).count()
        };
        let plain = render(&sphere, &settings);
        let coloured = render(&painted, &settings);
        let all = drawn(&coloured, settings.background).len();
        assert_eq!(all, drawn(&plain, settings.background).len(), "the same pixels are covered");
        let above = |a: u8, b: u8| u32::from(a) > u32::from(b) + 20;
        let reddish = |p: [u8; 3]| above(p[0], p[2]) && above(p[0], p[1]);
        let bluish = |p: [u8; 3]| above(p[2], p[0]) && above(p[2], p[1]);
        assert_eq!(count(&plain, &reddish), 0);
        for (what, keep) in [("red", &reddish as &dyn Fn([u8; 3]) -> bool), ("blue", &bluish)] {
            let n = count(&coloured, keep);
            assert!(n > all / 8, "{what}: {n} of {all} pixels");
        }
    }
}
