//! Headless software rendering of a scalar field on a triangle mesh or a point cloud, for
//! figures such as the level-set pictures of K_t e_i in the paper (Figs. 2, 4, 5, 8).
//!
//! The mesh is drawn from a few fixed orthographic views side by side, coloured by the
//! piecewise-linear interpolant of the per-vertex field through a perceptually uniform
//! [`Colormap`], Lambert-shaded with two-sided lighting, with dark anti-aliased iso-lines at
//! `n_isolines` equally spaced levels, optional red dots on highlighted vertices (e.g. the
//! anchor p_i of K_t e_i), a legend bar with tick labels and an optional title. Everything is
//! pure Rust (z-buffer rasteriser, built-in 5×7 font, PNG through the `png` crate).
//!
//! A point cloud is drawn as [`Splats`] — an oriented disc per point, blended into a closed
//! surface — by [`render_splats_png`] / [`render_splats_rgb`], with the same views, colours,
//! lighting, iso-lines, highlights and legend as a mesh.
//!
//! ```no_run
//! use wfem_render::{render_png, RenderParams};
//! let mesh = mesh_fem::generate::bumpy(3);
//! let field: Vec<f64> = mesh.positions().iter().map(|p| p[1]).collect();
//! let png = render_png(&mesh, &field, &RenderParams::default())?;
//! std::fs::write("/tmp/height.png", png)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod colormap;
mod font;
mod frame;
mod legend;
mod raster;
mod splat;
mod vec3;

pub use colormap::Colormap;
pub use frame::{direction_label, Frame, Up, UpAxis};
pub use splat::Splats;

use mesh_fem::TriMesh;
use rayon::prelude::*;

/// Failures of [`render_png`] / [`render_rgb`]; each names the offending input.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The field does not have one value per vertex (per point of [`Splats`]).
    #[error("field has {got} values, but the surface has {expected} vertices (or points)")]
    FieldLength {
        /// Number of mesh vertices or splats.
        expected: usize,
        /// Length of the field passed in.
        got: usize,
    },
    /// A field value is NaN or infinite.
    #[error("field value at vertex {vertex} is not finite ({value})")]
    NonFiniteValue {
        /// Index of the vertex.
        vertex: usize,
        /// The offending value.
        value: f64,
    },
    /// `params.views` is empty.
    #[error("no views to render (params.views is empty)")]
    NoViews,
    /// A view direction is zero, not finite, or parallel to its up vector.
    #[error("view {index} is degenerate: direction {direction:?}, up {up:?}")]
    DegenerateView {
        /// Index into `params.views`.
        index: usize,
        /// The view direction.
        direction: [f64; 3],
        /// The view's up vector.
        up: [f64; 3],
    },
    /// Width or height is zero or too large, or the supersampling factor is outside 1..=4.
    #[error("invalid image size {width}×{height} per view (supersample {supersample}); need sides in 1..=8192, supersample in 1..=4 and width·height·supersample² ≤ 2^25")]
    InvalidSize {
        /// Requested width per view.
        width: u32,
        /// Requested height.
        height: u32,
        /// Requested supersampling factor.
        supersample: u32,
    },
    /// The colour range is not finite or not increasing.
    #[error("invalid colour range ({0}, {1}): need finite lo < hi")]
    InvalidRange(f64, f64),
    /// A highlighted vertex does not exist.
    #[error("highlighted vertex {vertex} is out of range (mesh has {n_vertices} vertices)")]
    HighlightOutOfRange {
        /// The requested vertex.
        vertex: u32,
        /// Number of mesh vertices.
        n_vertices: usize,
    },
    /// [`Splats`] without points.
    #[error("no points to draw as splats")]
    NoPoints,
    /// The normals or radii of [`Splats`] are not one per point.
    #[error("{got} {what} for {expected} splats: need one per point")]
    SplatLength {
        /// "normals" or "radii".
        what: &'static str,
        /// Number of points.
        expected: usize,
        /// Number given.
        got: usize,
    },
    /// A triangle given for the radii of [`Splats`] uses a point that does not exist.
    #[error("triangle {triangle} uses point {index}, but there are {n_points} points")]
    TriangleOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The offending corner.
        index: u32,
        /// Number of points.
        n_points: usize,
    },
    /// A splat cannot be drawn.
    #[error("splat {point}: {what}")]
    InvalidSplat {
        /// Index of the point.
        point: usize,
        /// What is wrong with it.
        what: &'static str,
    },
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Encode(String),
}

/// An orthographic view: the camera sits far away along `direction` (from the mesh centre
/// towards the camera) and looks back at the mesh, with `up` projected to the screen's up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Unit-free direction from the mesh towards the camera.
    pub direction: [f64; 3],
    /// Approximate screen-up direction (must not be parallel to `direction`).
    pub up: [f64; 3],
}

impl View {
    /// A view from `direction` with screen-up `up`.
    pub fn new(direction: [f64; 3], up: [f64; 3]) -> Self {
        Self { direction, up }
    }

    /// The four standard views — front, side (from +x), top and an oblique
    /// front-right-above view — for a mesh whose up axis is `up` ([`Frame::from_up`]).
    pub fn standard(up: UpAxis) -> Vec<View> {
        Self::standard_in(&Frame::from_up(up))
    }

    /// The four standard views in a frame: front (from `frame.front`), side (from
    /// `frame.right`), top (from `frame.up`) and an oblique front-right-above view, with
    /// `frame.up` up (the top view has the back at the top).
    pub fn standard_in(frame: &Frame) -> Vec<View> {
        // Defined in the y-up frame (x right, y up, z front) and mapped into `frame`.
        let y_up = [
            View::new([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            View::new([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            View::new([0.0, 1.0, 0.0], [0.0, 0.0, -1.0]),
            View::new([0.8, 0.6, 1.0], [0.0, 1.0, 0.0]),
        ];
        y_up.iter()
            .map(|v| View::new(frame.map(v.direction), frame.map(v.up)))
            .collect()
    }
}

/// Parameters of [`render_png`] / [`render_rgb`].
#[derive(Clone, Debug)]
pub struct RenderParams {
    /// Width of each view in pixels.
    pub width: u32,
    /// Height of each view (and of the legend column) in pixels.
    pub height: u32,
    /// The views, drawn left to right; default [`View::standard`]`(UpAxis::Y)`.
    pub views: Vec<View>,
    /// Number of iso-lines, at the levels lo + k(hi − lo)/(n + 1), k = 1..=n; 0 disables them.
    pub n_isolines: usize,
    /// Colormap; [`Colormap::Viridis`] by default.
    pub colormap: Colormap,
    /// Field values mapped to the ends of the colormap (values outside are clamped);
    /// `None` uses the field's minimum and maximum.
    pub range: Option<(f64, f64)>,
    /// Draw the legend bar with tick labels right of the views.
    pub legend: bool,
    /// Title printed centred above the views.
    pub title: Option<String>,
    /// Vertices (points of [`Splats`]) marked with red dots (e.g. the anchor of K_t e_i),
    /// when visible.
    pub highlight: Vec<u32>,
    /// Supersampling factor per axis (1..=4) used to anti-alias edges and iso-lines.
    pub supersample: u32,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self {
            width: 480,
            height: 480,
            views: View::standard(UpAxis::Y),
            n_isolines: 12,
            colormap: Colormap::Viridis,
            range: None,
            legend: true,
            title: None,
            highlight: Vec::new(),
            supersample: 2,
        }
    }
}

/// A packed 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `3 · width · height` bytes, row-major, RGB.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// An image filled with `color`.
    pub fn new(width: u32, height: u32, color: [u8; 3]) -> Self {
        let n = width as usize * height as usize;
        let mut data = Vec::with_capacity(3 * n);
        for _ in 0..n {
            data.extend_from_slice(&color);
        }
        Self { width, height, data }
    }

    /// The images one below the other, left-aligned on a white background as wide as the
    /// widest (a figure and the figure of its cut).
    pub fn stacked(images: &[RgbImage]) -> Self {
        let width = images.iter().map(|i| i.width).max().unwrap_or(0);
        let height = images.iter().map(|i| i.height).sum();
        let mut out = Self::new(width, height, [255; 3]);
        let mut top = 0;
        for img in images {
            out.blit(img, 0, top);
            top += img.height;
        }
        out
    }

    /// Copies `img` into this image with its top-left corner at (x, y); it must fit.
    fn blit(&mut self, img: &RgbImage, x: u32, y: u32) {
        let row = 3 * img.width as usize;
        for r in 0..img.height as usize {
            let src = r * row;
            let dst = 3 * ((y as usize + r) * self.width as usize + x as usize);
            self.data[dst..dst + row].copy_from_slice(&img.data[src..src + row]);
        }
    }

    /// The colour at (x, y); panics if out of bounds (like slice indexing).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}×{}",
            self.width,
            self.height
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Sets (x, y) if it lies inside the image.
    pub(crate) fn put(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u64) < self.width as u64 && (y as u64) < self.height as u64 {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.data[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Fills the rectangle [x0, x1) × [y0, y1), clipped to the image.
    pub(crate) fn fill_rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, c: [u8; 3]) {
        for y in y0.max(0)..y1.min(self.height as i64) {
            for x in x0.max(0)..x1.min(self.width as i64) {
                self.put(x, y, c);
            }
        }
    }

    /// Encodes the image as an 8-bit RGB PNG.
    ///
    /// # Errors
    /// [`RenderError::Encode`] if the encoder fails.
    pub fn to_png(&self) -> Result<Vec<u8>, RenderError> {
        let mut out = Vec::new();
        let mut encoder = png::Encoder::new(&mut out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // fdeflate: an order of magnitude faster than the default level, files ≈ 20% larger.
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(|e| RenderError::Encode(e.to_string()))?;
        writer
            .write_image_data(&self.data)
            .map_err(|e| RenderError::Encode(e.to_string()))?;
        writer.finish().map_err(|e| RenderError::Encode(e.to_string()))?;
        Ok(out)
    }
}

/// An axis-aligned pixel rectangle [x, x + width) × [y, y + height).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// Left column.
    pub x: u32,
    /// Top row.
    pub y: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

/// Where [`render_rgb`] puts things; a function of the parameters only (not of the field,
/// except that the legend column is wide enough for the labels of `range`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Total image width.
    pub width: u32,
    /// Total image height.
    pub height: u32,
    /// One rectangle per view, left to right.
    pub views: Vec<Rect>,
    /// The colour bar (inside its frame), top = maximum of the range.
    pub legend_bar: Option<Rect>,
    /// The title band at the top.
    pub title: Option<Rect>,
}

/// Font scale for a view of the given height: 1 for small images, 2 at ≈480 px.
fn font_scale(height: u32) -> u32 {
    (height / 240).clamp(1, 4)
}

/// Computes the layout for a field whose colour range is `range` (= (lo, hi) after defaults).
pub fn layout(params: &RenderParams, range: (f64, f64)) -> Result<Layout, RenderError> {
    check_size(params)?;
    if params.views.is_empty() {
        return Err(RenderError::NoViews);
    }
    let fs = font_scale(params.height);
    let title_h = match &params.title {
        Some(_) => font::text_height(fs) + 6 * fs,
        None => 0,
    };
    let n = params.views.len() as u32;
    let views: Vec<Rect> = (0..n)
        .map(|i| Rect {
            x: i * params.width,
            y: title_h,
            width: params.width,
            height: params.height,
        })
        .collect();
    let views_w = n * params.width;
    let (legend_bar, legend_w) = if params.legend {
        let (bar, w) = legend::bar_rect(views_w, title_h, params.height, fs, range);
        (Some(bar), w)
    } else {
        (None, 0)
    };
    let mut width = views_w + legend_w;
    let title = params.title.as_ref().map(|t| {
        width = width.max(font::text_width(t, fs) + 8 * fs);
        Rect {
            x: 0,
            y: 0,
            width,
            height: title_h,
        }
    });
    Ok(Layout {
        width,
        height: title_h + params.height,
        views,
        legend_bar,
        title,
    })
}

/// Upper bound on width · height · supersample² of one view.
const MAX_SUPERSAMPLED_PIXELS: u64 = 1 << 25;

fn check_size(params: &RenderParams) -> Result<(), RenderError> {
    let ok_dim = |d: u32| (1..=8192).contains(&d);
    let ss = params.supersample as u64;
    // Each view needs ≈ 19 bytes per supersampled pixel (≈ 31 for splats); cap that at 2²⁵
    // pixels (≈ 640 MB, 1 GB for splats).
    let too_many = params.width as u64 * params.height as u64 * ss * ss > MAX_SUPERSAMPLED_PIXELS;
    if !ok_dim(params.width) || !ok_dim(params.height) || !(1..=4).contains(&params.supersample) || too_many {
        return Err(RenderError::InvalidSize {
            width: params.width,
            height: params.height,
            supersample: params.supersample,
        });
    }
    Ok(())
}

/// The range (−m, m) with m = max |fᵢ|, for signed fields drawn with [`Colormap::Coolwarm`] so
/// that zero is the white centre of the map; `None` if the field is empty, identically zero or
/// has a non-finite value.
pub fn symmetric_range(field: &[f64]) -> Option<(f64, f64)> {
    let mut m = 0.0f64;
    for &v in field {
        if !v.is_finite() {
            return None;
        }
        m = m.max(v.abs());
    }
    (m > 0.0).then_some((-m, m))
}

/// Validates the inputs for a surface of `n_vertices` vertices (or splats) and returns the
/// colour range (lo, hi); lo == hi for a constant field without an explicit range.
fn validate(n_vertices: usize, field: &[f64], params: &RenderParams) -> Result<(f64, f64), RenderError> {
    check_size(params)?;
    if params.views.is_empty() {
        return Err(RenderError::NoViews);
    }
    if field.len() != n_vertices {
        return Err(RenderError::FieldLength {
            expected: n_vertices,
            got: field.len(),
        });
    }
    if let Some((vertex, &value)) = field.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(RenderError::NonFiniteValue { vertex, value });
    }
    if let Some(&vertex) = params.highlight.iter().find(|&&v| v as usize >= n_vertices) {
        return Err(RenderError::HighlightOutOfRange { vertex, n_vertices });
    }
    for (index, v) in params.views.iter().enumerate() {
        if frame::Camera::new(v).is_none() {
            return Err(RenderError::DegenerateView {
                index,
                direction: v.direction,
                up: v.up,
            });
        }
    }
    match params.range {
        Some((lo, hi)) if !(lo.is_finite() && hi.is_finite() && lo < hi) => Err(RenderError::InvalidRange(lo, hi)),
        Some(r) => Ok(r),
        None => {
            let lo = field.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = field.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            Ok((lo, hi))
        }
    }
}

/// Renders `field` (one value per vertex) on `mesh` and returns the raw RGB image.
///
/// The colour of a pixel is `colormap((f − lo)/(hi − lo))` of the linearly interpolated field
/// f, times the Lambert shading; iso-lines mark f = lo + k(hi − lo)/(n + 1), k = 1..=n, and are
/// drawn with a width measured in screen space from the per-triangle gradient of f. A
/// constant field (lo = hi) is drawn in the middle colour without iso-lines.
///
/// # Errors
/// [`RenderError::FieldLength`], [`RenderError::NonFiniteValue`], [`RenderError::NoViews`],
/// [`RenderError::DegenerateView`], [`RenderError::InvalidSize`], [`RenderError::InvalidRange`],
/// [`RenderError::HighlightOutOfRange`].
pub fn render_rgb(mesh: &TriMesh, field: &[f64], params: &RenderParams) -> Result<RgbImage, RenderError> {
    let range = validate(mesh.n_vertices(), field, params)?;
    let surface = raster::Surface::mesh(mesh.positions(), mesh.faces());
    render_surface(mesh.positions(), surface, field, params, range)
}

/// Renders `field` (one value per point) on a point cloud drawn as splats (module
/// documentation of [`Splats`]): the same figure as [`render_rgb`] draws for a mesh, with
/// the field blended between neighbouring splats and iso-lines at the same levels.
///
/// # Errors
/// Those of [`render_rgb`], with [`RenderError::FieldLength`] and
/// [`RenderError::HighlightOutOfRange`] counting points.
pub fn render_splats_rgb(splats: &Splats, field: &[f64], params: &RenderParams) -> Result<RgbImage, RenderError> {
    let range = validate(splats.len(), field, params)?;
    render_surface(
        splats.positions(),
        raster::Surface::splats(splats, field),
        field,
        params,
        range,
    )
}

/// Renders like [`render_splats_rgb`] and encodes the result as PNG bytes.
///
/// # Errors
/// Those of [`render_splats_rgb`], and [`RenderError::Encode`].
pub fn render_splats_png(splats: &Splats, field: &[f64], params: &RenderParams) -> Result<Vec<u8>, RenderError> {
    render_splats_rgb(splats, field, params)?.to_png()
}

/// The figure of a validated surface and field: the views side by side, legend and title.
fn render_surface(
    positions: &[[f64; 3]],
    surface: raster::Surface<'_>,
    field: &[f64],
    params: &RenderParams,
    range: (f64, f64),
) -> Result<RgbImage, RenderError> {
    let lay = layout(params, range)?;
    let mut img = RgbImage::new(lay.width, lay.height, [255; 3]);
    let scene = raster::Scene::new(positions, surface, field, params, range);
    let views: Vec<RgbImage> = params.views.par_iter().map(|v| scene.render_view(v, params)).collect();
    for (rect, view) in lay.views.iter().zip(&views) {
        img.blit(view, rect.x, rect.y);
    }
    let fs = font_scale(params.height);
    if let Some(bar) = lay.legend_bar {
        legend::draw(&mut img, bar, range, params, fs);
    }
    if let (Some(t), Some(r)) = (&params.title, lay.title) {
        let tw = font::text_width(t, fs) as i64;
        let x = (r.width as i64 - tw) / 2;
        let y = r.y as i64 + (r.height as i64 - font::text_height(fs) as i64) / 2;
        font::draw_text(&mut img, x, y, t, fs, [20; 3]);
    }
    Ok(img)
}

/// Renders like [`render_rgb`] and encodes the result as PNG bytes (the caller writes them,
/// e.g. atomically via a temporary file).
///
/// # Errors
/// Those of [`render_rgb`], and [`RenderError::Encode`].
pub fn render_png(mesh: &TriMesh, field: &[f64], params: &RenderParams) -> Result<Vec<u8>, RenderError> {
    render_rgb(mesh, field, params)?.to_png()
}
