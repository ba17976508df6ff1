//! Rasterising splats: footprints, visibility, accumulation and normalisation (module
//! documentation of [`super`]).

use super::{kernel, Slope, Splats, BLEND_DEPTH, MIN_FACING, MIN_RADIUS_PX};
use crate::frame::Camera;
use crate::vec3::dot;

/// The blended surface of one view (supersampled), ready for shading.
pub(crate) struct SplatBuffers {
    width: usize,
    height: usize,
    /// Nearest depth (larger = nearer); −∞ where no splat covers the pixel.
    pub(crate) depth: Vec<f32>,
    /// Blended field Σ w fᵢ / Σ w.
    pub(crate) field: Vec<f64>,
    /// Blended normal Σ w nᵢ (unnormalised, towards the viewer).
    pub(crate) normal: Vec<[f32; 3]>,
    /// Depth difference below which two neighbouring pixels lie on the same sheet of surface
    /// (for the finite differences of the gradient).
    continuity: f32,
}

impl SplatBuffers {
    /// |∇f| at pixel (x, y) in supersampled pixels⁻¹: central differences where both
    /// neighbours lie on the same sheet of surface, one-sided where one does, 0 where none
    /// does (so that no iso-line is drawn along a depth discontinuity).
    pub(crate) fn gradient(&self, x: usize, y: usize) -> f32 {
        let i = y * self.width + x;
        let (z, f) = (self.depth[i], self.field[i]);
        let same = |j: usize| (self.depth[j] - z).abs() <= self.continuity;
        let diff = |prev: Option<usize>, next: Option<usize>| -> f64 {
            match (prev.filter(|&j| same(j)), next.filter(|&j| same(j))) {
                (Some(p), Some(q)) => 0.5 * (self.field[q] - self.field[p]),
                (Some(p), None) => f - self.field[p],
                (None, Some(q)) => self.field[q] - f,
                (None, None) => 0.0,
            }
        };
        let gx = diff((x > 0).then(|| i - 1), (x + 1 < self.width).then(|| i + 1));
        let gy = diff(
            (y > 0).then(|| i - self.width),
            (y + 1 < self.height).then(|| i + self.width),
        );
        (gx * gx + gy * gy).sqrt() as f32
    }
}

/// The pixels one splat covers, with its plane: centre (sx, sy) in pixels and depth z, the
/// camera-frame normal (nr, nu, nd) turned towards the viewer with nd ≥ [`MIN_FACING`].
struct Footprint {
    sx: f64,
    sy: f64,
    z: f64,
    nr: f64,
    nu: f64,
    nd: f64,
    /// Radius in model units (at least [`MIN_RADIUS_PX`]).
    radius: f64,
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl Footprint {
    /// `None` if the splat covers no pixel of the w × h image.
    fn new(
        screen: [f64; 3],
        normal: [f64; 3],
        radius: f64,
        cam: &Camera,
        scale: f64,
        w: usize,
        h: usize,
    ) -> Option<Self> {
        let [sx, sy, z] = screen;
        let (mut nr, mut nu, mut nd) = (dot(normal, cam.right), dot(normal, cam.up), dot(normal, cam.dir));
        if nd < 0.0 {
            (nr, nu, nd) = (-nr, -nu, -nd);
        }
        let nd = nd.max(MIN_FACING);
        let radius = radius.max(MIN_RADIUS_PX / scale);
        // The ellipse a² + b² + (nr·a + nu·b)²/nd² ≤ ρ² (model units a right, b up) has the
        // half-widths ρ·√(1 − nr²/s) and ρ·√(1 − nu²/s), s = nd² + nr² + nu² (the diagonal
        // of the inverse of its matrix, by Sherman–Morrison).
        let s = nd * nd + nr * nr + nu * nu;
        let hx = radius * scale * (1.0 - nr * nr / s).max(0.0).sqrt();
        let hy = radius * scale * (1.0 - nu * nu / s).max(0.0).sqrt();
        let x0 = (sx - hx - 0.5).ceil().max(0.0);
        let x1 = (sx + hx - 0.5).floor().min(w as f64 - 1.0);
        let y0 = (sy - hy - 0.5).ceil().max(0.0);
        let y1 = (sy + hy - 0.5).floor().min(h as f64 - 1.0);
        // NaN (an overflowing projection) fails these tests too.
        if !(x0 <= x1 && y0 <= y1) {
            return None;
        }
        Some(Self {
            sx,
            sy,
            z,
            nr,
            nu,
            nd,
            radius,
            x0: x0 as usize,
            x1: x1 as usize,
            y0: y0 as usize,
            y1: y1 as usize,
        })
    }

    /// Calls `visit(pixel index, depth, ρ², offset)` for every pixel inside the ellipse, with
    /// the depth of the splat's plane there, ρ ≤ 1 the distance from the centre in radii,
    /// and the offset from the centre in the camera frame (right, up, towards the viewer).
    fn for_each_pixel(&self, scale: f64, w: usize, mut visit: impl FnMut(usize, f64, f64, [f64; 3])) {
        let inv_scale = 1.0 / scale;
        let inv_r2 = 1.0 / (self.radius * self.radius);
        for y in self.y0..=self.y1 {
            let b = -(y as f64 + 0.5 - self.sy) * inv_scale;
            for x in self.x0..=self.x1 {
                let a = (x as f64 + 0.5 - self.sx) * inv_scale;
                let m = (self.nr * a + self.nu * b) / self.nd;
                let q = a * a + b * b + m * m;
                let rho2 = q * inv_r2;
                if rho2 <= 1.0 {
                    visit(y * w + x, self.z - m, rho2, [a, b, -m]);
                }
            }
        }
    }
}

/// Rasterises `splats` with their fields `slopes` ([`Splats::slopes`]) into a w × h (supersampled) view:
/// visibility, accumulation and normalisation of the module documentation. `screen` holds
/// each point's pixel position and depth, `scale` the supersampled pixels per model unit.
pub(crate) fn rasterize(
    splats: &Splats,
    slopes: &[Slope],
    screen: &[[f64; 3]],
    cam: &Camera,
    scale: f64,
    w: usize,
    h: usize,
) -> SplatBuffers {
    let footprints: Vec<Option<Footprint>> = (0..splats.len())
        .map(|i| Footprint::new(screen[i], splats.normals[i], splats.radii[i], cam, scale, w, h))
        .collect();

    // 1. Visibility.
    let mut depth = vec![f32::NEG_INFINITY; w * h];
    for fp in footprints.iter().flatten() {
        fp.for_each_pixel(scale, w, |i, z, _, _| {
            let z = z as f32;
            if z > depth[i] {
                depth[i] = z;
            }
        });
    }

    // 2. Accumulation over the sheet of surface nearest to the viewer.
    let mut weight = vec![0.0f32; w * h];
    let mut sum = vec![0.0f64; w * h];
    let mut normal = vec![[0.0f32; 3]; w * h];
    for (i, fp) in footprints.iter().enumerate() {
        let Some(fp) = fp else { continue };
        let tol = (BLEND_DEPTH * fp.radius) as f32;
        let n = splats.normals[i];
        let n = if dot(n, cam.dir) < 0.0 { n.map(|c| -c) } else { n };
        let n = n.map(|c| c as f32);
        let slope = slopes[i];
        let g = slope.gradient;
        let g = [dot(g, cam.right), dot(g, cam.up), dot(g, cam.dir)];
        fp.for_each_pixel(scale, w, |p, z, rho2, [a, b, c]| {
            if (z as f32) >= depth[p] - tol {
                let wt = kernel(rho2);
                let v = (slope.value + g[0] * a + g[1] * b + g[2] * c).clamp(slope.lo, slope.hi);
                weight[p] += wt;
                sum[p] += wt as f64 * v;
                for k in 0..3 {
                    normal[p][k] += wt * n[k];
                }
            }
        });
    }

    // 3. Normalisation (the nearest splat of a covered pixel contributes at least
    // RIM_WEIGHT, so the weight of a covered pixel is positive).
    for p in 0..w * h {
        if weight[p] > 0.0 {
            sum[p] /= weight[p] as f64;
        }
    }
    let mean_radius = splats.radii.iter().sum::<f64>() / splats.len() as f64;
    SplatBuffers {
        width: w,
        height: h,
        depth,
        field: sum,
        normal,
        continuity: (BLEND_DEPTH * mean_radius) as f32,
    }
}
