//! Z-buffer rasterisation and per-pixel shading of one orthographic view: triangles here,
//! splats in [`crate::splat`]; both end in the same per-pixel shading ([`Scene::color`]).

use super::splat::{self, Slope, Splats};
use super::{RenderParams, RgbImage, View};
use rayon::prelude::*;

use super::frame::Camera;
use super::vec3::{cross, dot, normalized, V3};

/// Entries of the colour lookup table (more than 8-bit precision in t, so no banding).
const LUT_SIZE: usize = 1024;
/// Iso-line colour and opacity.
const ISO_COLOR: [f32; 3] = [0.0, 0.0, 0.0];
const ISO_OPACITY: f32 = 0.8;
/// Iso-line width in output pixels.
const ISO_WIDTH: f32 = 1.3;
/// Fraction of the view left empty on each side.
const MARGIN: f64 = 0.05;

/// What is drawn: the triangles of a mesh (with its area-weighted vertex normals) or the
/// splats of a point cloud.
pub(crate) enum Surface<'a> {
    /// A triangle mesh.
    Mesh {
        faces: &'a [[u32; 3]],
        normals: Vec<[f32; 3]>,
    },
    /// Oriented discs, one per point, with their fields ([`Splats::slopes`]).
    Splats { splats: &'a Splats, slopes: Vec<Slope> },
}

impl<'a> Surface<'a> {
    /// The triangles of `faces` on `positions`.
    pub(crate) fn mesh(positions: &[[f64; 3]], faces: &'a [[u32; 3]]) -> Self {
        Surface::Mesh {
            faces,
            normals: vertex_normals(positions, faces),
        }
    }

    /// The splats of a cloud with the field `field` on it.
    pub(crate) fn splats(splats: &'a Splats, field: &[f64]) -> Self {
        Surface::Splats {
            splats,
            slopes: splats.slopes(field),
        }
    }
}

/// Everything shared by the views of one render.
pub(crate) struct Scene<'a> {
    positions: &'a [[f64; 3]],
    surface: Surface<'a>,
    field: &'a [f64],
    lut: Vec<[u8; 3]>,
    lo: f64,
    /// 1/(hi − lo), or 0 for a constant field (then t = 1/2 everywhere).
    inv_range: f64,
    /// Level spacing Δ = (hi − lo)/(n + 1); 0 disables iso-lines.
    level_step: f64,
    n_levels: usize,
    /// Pixels per model unit in output pixels, common to all views.
    scale: f64,
    /// Bounding-box diagonal, for depth tolerances.
    diameter: f64,
    highlight: &'a [u32],
}

impl<'a> Scene<'a> {
    pub(crate) fn new(
        positions: &'a [[f64; 3]],
        surface: Surface<'a>,
        field: &'a [f64],
        params: &'a RenderParams,
        range: (f64, f64),
    ) -> Self {
        let (lo, hi) = range;
        let constant = hi <= lo;
        let inv_range = if constant { 0.0 } else { 1.0 / (hi - lo) };
        let level_step = if constant || params.n_isolines == 0 {
            0.0
        } else {
            (hi - lo) / (params.n_isolines + 1) as f64
        };

        // One common scale for all views, so that the object has the same size in each: the
        // largest that fits every view's projected bounding box inside the margins.
        let avail_w = params.width as f64 * (1.0 - 2.0 * MARGIN);
        let avail_h = params.height as f64 * (1.0 - 2.0 * MARGIN);
        let mut scale = f64::INFINITY;
        for view in &params.views {
            if let Some(cam) = Camera::new(view) {
                let (ex, ey) = extent(positions, &cam);
                if ex > 0.0 {
                    scale = scale.min(avail_w / ex);
                }
                if ey > 0.0 {
                    scale = scale.min(avail_h / ey);
                }
            }
        }
        if !scale.is_finite() {
            scale = 1.0; // a single point: any scale will do
        }
        let (bmin, bmax) = mesh_fem::vec3::bounding_box(positions);
        let diameter = dot(sub(bmax, bmin), sub(bmax, bmin)).sqrt();

        Self {
            positions,
            surface,
            field,
            lut: params.colormap.table(LUT_SIZE),
            lo,
            inv_range,
            level_step,
            n_levels: params.n_isolines,
            scale,
            diameter,
            highlight: &params.highlight,
        }
    }

    /// Renders one view at `params.width × params.height` (supersampled internally).
    pub(crate) fn render_view(&self, view: &View, params: &RenderParams) -> RgbImage {
        let Some(cam) = Camera::new(view) else {
            // Validated before; a degenerate view is drawn empty rather than panicking.
            return RgbImage::new(params.width, params.height, [255; 3]);
        };
        let ss = params.supersample as usize;
        let (w, h) = (params.width as usize * ss, params.height as usize * ss);
        let scale = self.scale * ss as f64;

        // Screen position (pixel units, y down) and depth (larger = nearer) of each vertex.
        let (cx, cy) = centre(self.positions, &cam);
        let screen: Vec<[f64; 3]> = self
            .positions
            .iter()
            .map(|&p| {
                let (x, y, z) = cam.project(p);
                [(x - cx) * scale + w as f64 / 2.0, h as f64 / 2.0 - (y - cy) * scale, z]
            })
            .collect();

        let shading = Shading::new(&cam, ss);
        let (mut pixels, depth) = match &self.surface {
            Surface::Mesh { faces, normals } => {
                let buf = self.rasterize(faces, &screen, w, h);
                (self.shade(faces, normals, &buf, &shading, w, h), buf.depth)
            }
            Surface::Splats { splats, slopes } => {
                let buf = splat::rasterize(splats, slopes, &screen, &cam, scale, w, h);
                (self.shade_splats(&buf, &shading, w), buf.depth)
            }
        };
        self.draw_highlights(&mut pixels, &depth, &screen, w, h, ss);
        downsample(&pixels, w, h, ss)
    }

    fn rasterize(&self, faces: &[[u32; 3]], screen: &[[f64; 3]], w: usize, h: usize) -> Buffers {
        let mut buf = Buffers {
            depth: vec![f32::NEG_INFINITY; w * h],
            face: vec![u32::MAX; w * h],
            bary: vec![[0.0; 2]; w * h],
            grad: vec![0.0; faces.len()],
        };
        for (fi, f) in faces.iter().enumerate() {
            let [a, b, c] = f.map(|v| screen[v as usize]);
            let area = edge(a, b, c);
            // Edge-on and zero-area triangles cover no pixel centre; skipping them also keeps
            // the barycentric division below finite.
            // (NaN only arises from coordinates near f64::MAX overflowing in the projection.)
            if area.is_nan() || area.abs() < 1e-12 {
                continue;
            }
            let inv = 1.0 / area;
            // Screen-space gradient of the linear interpolant of the field over this face.
            let [f0, f1, f2] = f.map(|v| self.field[v as usize]);
            let gx = ((b[1] - c[1]) * f0 + (c[1] - a[1]) * f1 + (a[1] - b[1]) * f2) * inv;
            let gy = ((c[0] - b[0]) * f0 + (a[0] - c[0]) * f1 + (b[0] - a[0]) * f2) * inv;
            buf.grad[fi] = (gx * gx + gy * gy).sqrt() as f32;

            let x0 = (a[0].min(b[0]).min(c[0]) - 0.5).ceil().max(0.0) as usize;
            let x1 = (a[0].max(b[0]).max(c[0]) - 0.5).floor().min(w as f64 - 1.0);
            let y0 = (a[1].min(b[1]).min(c[1]) - 0.5).ceil().max(0.0) as usize;
            let y1 = (a[1].max(b[1]).max(c[1]) - 0.5).floor().min(h as f64 - 1.0);
            if x1 < 0.0 || y1 < 0.0 {
                continue;
            }
            let (x1, y1) = (x1 as usize, y1 as usize);
            // The barycentric weights are affine in the pixel position: step them along rows.
            let (dw0, dw1) = ((b[1] - c[1]) * inv, (c[1] - a[1]) * inv);
            for y in y0..=y1 {
                let p = [x0 as f64 + 0.5, y as f64 + 0.5, 0.0];
                let mut w0 = edge(b, c, p) * inv;
                let mut w1 = edge(c, a, p) * inv;
                let row = y * w;
                for x in x0..=x1 {
                    let w2 = 1.0 - w0 - w1;
                    // Inclusive test: pixels on a shared edge are claimed by both faces and the
                    // depth test picks one, so there are no cracks.
                    const EPS: f64 = -1e-9;
                    if w0 >= EPS && w1 >= EPS && w2 >= EPS {
                        let z = (w0 * a[2] + w1 * b[2] + w2 * c[2]) as f32;
                        let i = row + x;
                        if z > buf.depth[i] {
                            buf.depth[i] = z;
                            buf.face[i] = fi as u32;
                            buf.bary[i] = [w0 as f32, w1 as f32];
                        }
                    }
                    w0 += dw0;
                    w1 += dw1;
                }
            }
        }
        buf
    }

    fn shade(
        &self,
        faces: &[[u32; 3]],
        normals: &[[f32; 3]],
        buf: &Buffers,
        shading: &Shading,
        w: usize,
        h: usize,
    ) -> Vec<[u8; 3]> {
        let mut out = vec![[255u8; 3]; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let i = y * w + x;
                let fi = buf.face[i];
                if fi == u32::MAX {
                    continue;
                }
                let face = faces[fi as usize];
                let [b0, b1] = buf.bary[i];
                let b2 = 1.0 - b0 - b1;
                let [v0, v1, v2] = face.map(|v| v as usize);
                let f = b0 as f64 * self.field[v0] + b1 as f64 * self.field[v1] + b2 as f64 * self.field[v2];
                // Interpolated vertex normal.
                let (n0, n1, n2) = (normals[v0], normals[v1], normals[v2]);
                let n = [0, 1, 2].map(|k| b0 * n0[k] + b1 * n1[k] + b2 * n2[k]);
                *px = self.color(shading, f, n, buf.grad[fi as usize]);
            }
        });
        out
    }

    /// The pixels of a splat view: the blended field and normal of every covered pixel
    /// ([`splat::rasterize`]), with the iso-line width from the field's screen-space gradient.
    fn shade_splats(&self, buf: &splat::SplatBuffers, shading: &Shading, w: usize) -> Vec<[u8; 3]> {
        let mut out = vec![[255u8; 3]; buf.depth.len()];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let i = y * w + x;
                if buf.depth[i] == f32::NEG_INFINITY {
                    continue;
                }
                *px = self.color(shading, buf.field[i], buf.normal[i], buf.gradient(x, y));
            }
        });
        out
    }

    /// The colour of a surface pixel with field value `f`, (unnormalised) normal `n` and
    /// field gradient `g` in supersampled pixels⁻¹: `colormap((f − lo)/(hi − lo))` times the
    /// Lambert shading plus a weak specular highlight, darkened near an iso-level.
    fn color(&self, shading: &Shading, f: f64, n: [f32; 3], g: f32) -> [u8; 3] {
        let Shading {
            light,
            half,
            view_dir,
            half_width,
        } = *shading;
        let lut_max = (LUT_SIZE - 1) as f64;
        let t = if self.inv_range > 0.0 {
            (f - self.lo) * self.inv_range
        } else {
            0.5
        };
        let base = self.lut[(t.clamp(0.0, 1.0) * lut_max).round() as usize];

        // The normal flipped towards the viewer (two-sided lighting, so that open meshes,
        // inconsistent orientations and the arbitrary signs of a cloud's normals look right).
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let mut n = if len > 1e-12 { n.map(|c| c / len) } else { view_dir };
        if n[0] * view_dir[0] + n[1] * view_dir[1] + n[2] * view_dir[2] < 0.0 {
            n = n.map(|c| -c);
        }
        let diffuse = (n[0] * light[0] + n[1] * light[1] + n[2] * light[2]).max(0.0);
        let spec = (n[0] * half[0] + n[1] * half[1] + n[2] * half[2]).max(0.0).powi(48);
        let shade = 0.42 + 0.58 * diffuse;
        let mut c = base.map(|v| v as f32 * shade + 255.0 * 0.12 * spec);

        if self.level_step > 0.0 {
            // Distance (in supersampled pixels) to the nearest level set, from the value
            // distance and the screen-space gradient.
            let s = (f - self.lo) / self.level_step;
            let k = s.round().clamp(1.0, self.n_levels as f64);
            let dv = ((s - k) * self.level_step).abs() as f32;
            let dpx = if g > 0.0 {
                dv / g
            } else if dv == 0.0 {
                0.0
            } else {
                f32::INFINITY
            };
            let alpha = (half_width + 0.5 - dpx).clamp(0.0, 1.0) * ISO_OPACITY;
            if alpha > 0.0 {
                // Blend towards the line colour, never lightening a pixel darker than it.
                c = [0, 1, 2].map(|k| c[k] * (1.0 - alpha) + c[k].min(ISO_COLOR[k]) * alpha);
            }
        }
        c.map(|v| (v + 0.5).clamp(0.0, 255.0) as u8)
    }

    /// Red dots with a dark rim at visible highlighted vertices.
    fn draw_highlights(
        &self,
        pixels: &mut [[u8; 3]],
        depth: &[f32],
        screen: &[[f64; 3]],
        w: usize,
        h: usize,
        ss: usize,
    ) {
        let radius = (0.012 * w.min(h) as f64).max(3.0 * ss as f64);
        let rim = 1.2 * ss as f64;
        let tol = (0.02 * self.diameter) as f32;
        for &v in self.highlight {
            let [sx, sy, z] = screen[v as usize];
            if !(sx >= 0.0 && sy >= 0.0 && sx < w as f64 && sy < h as f64) {
                continue;
            }
            let i = sy as usize * w + sx as usize;
            // Hidden behind other parts of the surface? (An uncovered pixel has depth −∞.)
            if (z as f32) < depth[i] - tol {
                continue;
            }
            let r_out = radius + rim;
            let x0 = (sx - r_out).floor().max(0.0) as usize;
            let x1 = ((sx + r_out).ceil() as usize).min(w - 1);
            let y0 = (sy - r_out).floor().max(0.0) as usize;
            let y1 = ((sy + r_out).ceil() as usize).min(h - 1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let d = ((x as f64 + 0.5 - sx).powi(2) + (y as f64 + 0.5 - sy).powi(2)).sqrt();
                    if d <= radius {
                        pixels[y * w + x] = [225, 25, 30];
                    } else if d <= r_out {
                        pixels[y * w + x] = [30, 10, 10];
                    }
                }
            }
        }
    }
}

/// The lights of one view, in world coordinates: a key light from the viewer's upper left and
/// the half vector of a weak specular highlight; and the iso-line half-width in supersampled
/// pixels.
#[derive(Clone, Copy)]
struct Shading {
    light: [f32; 3],
    half: [f32; 3],
    view_dir: [f32; 3],
    half_width: f32,
}

impl Shading {
    fn new(cam: &Camera, ss: usize) -> Self {
        let light = normalized([
            cam.dir[0] + 0.5 * cam.up[0] - 0.35 * cam.right[0],
            cam.dir[1] + 0.5 * cam.up[1] - 0.35 * cam.right[1],
            cam.dir[2] + 0.5 * cam.up[2] - 0.35 * cam.right[2],
        ])
        .unwrap_or(cam.dir);
        let half = normalized([light[0] + cam.dir[0], light[1] + cam.dir[1], light[2] + cam.dir[2]]).unwrap_or(cam.dir);
        Self {
            light: light.map(|c| c as f32),
            half: half.map(|c| c as f32),
            view_dir: cam.dir.map(|c| c as f32),
            half_width: 0.5 * ISO_WIDTH * ss as f32,
        }
    }
}

struct Buffers {
    depth: Vec<f32>,
    face: Vec<u32>,
    /// Barycentric weights of the first two corners.
    bary: Vec<[f32; 2]>,
    /// |∇f| in supersampled pixels⁻¹ per face.
    grad: Vec<f32>,
}

/// Twice the signed area of (a, b, p) in the screen plane.
fn edge(a: [f64; 3], b: [f64; 3], p: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The projected bounding box `(x0, x1, y0, y1)`, or `None` for no positions.
fn projected_bounds(positions: &[[f64; 3]], cam: &Camera) -> Option<(f64, f64, f64, f64)> {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &p in positions {
        let (x, y, _) = cam.project(p);
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    (x0 <= x1).then_some((x0, x1, y0, y1))
}

/// Width and height of the projected bounding box.
fn extent(positions: &[[f64; 3]], cam: &Camera) -> (f64, f64) {
    projected_bounds(positions, cam).map_or((0.0, 0.0), |(x0, x1, y0, y1)| ((x1 - x0).max(0.0), (y1 - y0).max(0.0)))
}

/// Centre of the projected bounding box.
fn centre(positions: &[[f64; 3]], cam: &Camera) -> (f64, f64) {
    projected_bounds(positions, cam).map_or((0.0, 0.0), |(x0, x1, y0, y1)| (0.5 * (x0 + x1), 0.5 * (y0 + y1)))
}

/// Area-weighted vertex normals (the unnormalised face normal is twice the area times the unit
/// normal); zero for isolated vertices or vertices with only degenerate faces.
fn vertex_normals(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|v| positions[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &v in f {
            for k in 0..3 {
                acc[v as usize][k] += n[k];
            }
        }
    }
    acc.into_iter()
        .map(|n| normalized(n).unwrap_or([0.0; 3]).map(|c| c as f32))
        .collect()
}

/// Box filter from the supersampled buffer to the output resolution.
fn downsample(pixels: &[[u8; 3]], w: usize, h: usize, ss: usize) -> RgbImage {
    let (ow, oh) = (w / ss, h / ss);
    let mut img = RgbImage::new(ow as u32, oh as u32, [255; 3]);
    let n = (ss * ss) as u32;
    img.data.par_chunks_mut(3 * ow).enumerate().for_each(|(oy, row)| {
        for ox in 0..ow {
            let mut sum = [0u32; 3];
            for dy in 0..ss {
                for dx in 0..ss {
                    let p = pixels[(oy * ss + dy) * w + ox * ss + dx];
                    for k in 0..3 {
                        sum[k] += p[k] as u32;
                    }
                }
            }
            for k in 0..3 {
                row[3 * ox + k] = ((sum[k] + n / 2) / n) as u8;
            }
        }
    });
    img
}
