//! Point clouds drawn as splats: an oriented disc (surfel) per point, in the point's tangent
//! plane, blended into a closed-looking surface (software surface splatting in the manner of
//! Botsch, Hornung, Zwicker & Kobbelt 2005, "High-quality surface splatting on today's GPUs":
//! a visibility pass, an accumulation pass and a normalisation).
//!
//! 1. **Visibility.** Every splat is rasterised as the ellipse its disc projects to (an
//!    orthographic view), with the depth of the disc's plane at each pixel; the z-buffer keeps
//!    the nearest.
//! 2. **Accumulation.** Every splat adds, at each pixel of its ellipse whose nearest depth it
//!    comes within `BLEND_DEPTH` radii of (the same sheet of surface, not one behind it),
//!    its field value and its normal (turned towards the viewer: the signs of estimated
//!    normals are arbitrary) with the weight w = (1 − ρ²)² (+ a tiny constant), ρ the
//!    distance from the centre in radii. The value is linear across the disc,
//!    fᵢ(x) = fᵢ + gᵢ·(x − pᵢ), when the splats know their neighbours (linear splats: gᵢ is
//!    the least-squares tangential gradient of the field over the neighbours), clamped to
//!    the range of the field over the point and its neighbours; otherwise it is fᵢ.
//! 3. **Normalisation.** f = Σ w fᵢ(x) / Σ w and n = Σ w nᵢ at every covered pixel; the pixel
//!    is then shaded exactly as a mesh pixel (same colormap, lighting and iso-lines), with
//!    the field's gradient for the iso-line width taken by finite differences in the image.
//!
//! The radii come from the triangles the points span ([`Splats::from_triangles`]; the
//! neighbourhood mesh of a cloud): large enough that the discs cover every triangle — the
//! gaps of a random sampling included — and overlap their neighbours for the blending.

mod raster;

pub(crate) use raster::{rasterize, SplatBuffers};

use super::vec3::{cross, dot, normalized};
use super::RenderError;

/// Radius of a splat in mean lengths of the edges at its point, for the blending: a point of
/// a regular sampling then overlaps about five neighbours' discs (π·1.15²/(√3/2) ≈ 4.8 on a
/// hexagonal lattice), enough for the blended field and normals to be smooth.
const EDGE_RADIUS_FACTOR: f64 = 1.15;

/// Largest radius of a splat in median lengths of the edges at its point: triangles across a
/// hole in the sampling (or to an unrelated sheet nearby) cover it only up to this, so that
/// their discs do not stick out of the surface. Uniformly random samplings need more than 2
/// at 1 % of their points, more than 2.7 at 0.1 % (measured on a torus).
const MAX_RADIUS_FACTOR: f64 = 3.0;

/// Depth window of the blending, in radii of the blended splat: splats within it of the
/// nearest depth at a pixel are averaged, deeper ones are hidden.
const BLEND_DEPTH: f64 = 0.5;

/// Weight of a splat at ρ ≤ 1 radii from its centre: (1 − ρ²)², which falls smoothly to 0 at
/// the rim (a weight that jumps there draws every disc's outline into the blended field),
/// plus [`RIM_WEIGHT`], so that a pixel covered by a single splat's rim still has a weight.
fn kernel(rho2: f64) -> f32 {
    let a = 1.0 - rho2;
    (a * a + RIM_WEIGHT) as f32
}

/// See [`kernel`].
const RIM_WEIGHT: f64 = 1e-3;

/// Smallest |n·d| used for a splat seen from direction d: an edge-on disc is drawn as the
/// disc tilted to this, so that the depth of its plane stays finite (its slope at most
/// 1/MIN_FACING); more tilt leaves a visible rim of slivers around the silhouettes.
const MIN_FACING: f64 = 0.01;

/// Smallest drawn radius in supersampled pixels, so that a splat smaller than a pixel still
/// covers the pixel it falls in.
const MIN_RADIUS_PX: f64 = 0.75;

/// A point cloud as splats: positions, unit normals (either sign) and disc radii, one per
/// point, all finite; validated once by [`Splats::new`] or [`Splats::from_triangles`].
#[derive(Clone, Debug, PartialEq)]
pub struct Splats {
    positions: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    radii: Vec<f64>,
    /// The neighbours of every point along the triangles' edges, when built from triangles
    /// (for the linear splats of the module documentation).
    neighbours: Option<mesh_fem::graph::VertexNeighbours>,
}

/// A splat's field: fᵢ(x) = value + gradient·(x − pᵢ), clamped to [lo, hi].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Slope {
    pub(crate) value: f64,
    pub(crate) gradient: [f64; 3],
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Splats {
    /// Splats at `positions` with `normals` (normalised here; the sign does not matter: the
    /// splats are lit from both sides) and `radii` (model units).
    ///
    /// # Errors
    /// [`RenderError::NoPoints`] for no positions, [`RenderError::SplatLength`] when the
    /// normals or radii are not one per point, [`RenderError::InvalidSplat`] for a position
    /// or normal that is not finite, a zero normal, or a radius that is not finite and
    /// positive.
    pub fn new(positions: Vec<[f64; 3]>, normals: Vec<[f64; 3]>, radii: Vec<f64>) -> Result<Self, RenderError> {
        let n = positions.len();
        if n == 0 {
            return Err(RenderError::NoPoints);
        }
        for (what, got) in [("normals", normals.len()), ("radii", radii.len())] {
            if got != n {
                return Err(RenderError::SplatLength { what, expected: n, got });
            }
        }
        if let Some(point) = positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(RenderError::InvalidSplat {
                point,
                what: "its position is not finite",
            });
        }
        if let Some(point) = radii.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(RenderError::InvalidSplat {
                point,
                what: "its radius is not finite and positive",
            });
        }
        let normals = normals
            .iter()
            .enumerate()
            .map(|(point, &nv)| {
                normalized(nv).ok_or(RenderError::InvalidSplat {
                    point,
                    what: "its normal is zero or not finite",
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            positions,
            normals,
            radii,
            neighbours: None,
        })
    }

    /// Splats with radii from `triangles` on the points (e.g. the neighbourhood mesh of a
    /// cloud): rᵢ = min(max(c·ℓ̄ᵢ, ρᵢ), C·ℓ̃ᵢ), where ℓ̄ᵢ and ℓ̃ᵢ are the mean and the median
    /// distance from point i to its neighbours along the triangles' edges, c = 1.15 (a point
    /// of a regular sampling overlaps about five neighbours' discs), C = 3, and ρᵢ the largest covering radius of its triangles.
    /// The covering radius of a triangle, min(R, ℓ_max/√3) with R its circumradius and ℓ_max
    /// its longest edge, is the farthest any of its points can be from all three corners (R
    /// for an acute triangle, less for an obtuse one, never more than ℓ_max/√3), so the discs
    /// cover every triangle, also across the gaps of a random sampling; the cap C·ℓ̃ᵢ keeps
    /// a few triangles across a real hole, or to another sheet of surface, from blowing up
    /// the discs of their corners. The splats also keep the triangles' edges, to draw a field
    /// linear across each disc.
    ///
    /// # Errors
    /// Those of [`Splats::new`], and [`RenderError::TriangleOutOfRange`] for a triangle
    /// corner that is not a point, [`RenderError::InvalidSplat`] for a point in no triangle
    /// (or only in triangles of zero size).
    pub fn from_triangles(
        positions: Vec<[f64; 3]>,
        normals: Vec<[f64; 3]>,
        triangles: &[[u32; 3]],
    ) -> Result<Self, RenderError> {
        let n = positions.len();
        if let Some((triangle, &index)) = triangles
            .iter()
            .enumerate()
            .find_map(|(t, f)| f.iter().find(|&&v| v as usize >= n).map(|v| (t, v)))
        {
            return Err(RenderError::TriangleOutOfRange {
                triangle,
                index,
                n_points: n,
            });
        }
        let dist = |a: u32, b: u32| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        };
        let neighbours = mesh_fem::graph::VertexNeighbours::new(n, triangles);
        // The largest covering radius of the triangles at each point.
        let mut cover = vec![0.0f64; n];
        for &[a, b, c] in triangles {
            let (la, lb, lc) = (dist(b, c), dist(c, a), dist(a, b));
            let longest = la.max(lb).max(lc);
            // Heron's formula in the stable form (Kahan): 16·area² from the sorted sides.
            let mut l = [la, lb, lc];
            l.sort_by(|x, y| y.total_cmp(x));
            let [x, y, z] = l;
            let s16 = (x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z));
            let circumradius = if s16 > 0.0 {
                la * lb * lc / s16.sqrt()
            } else {
                f64::INFINITY
            };
            let rho = circumradius.min(longest / 3f64.sqrt());
            for v in [a, b, c] {
                cover[v as usize] = cover[v as usize].max(rho);
            }
        }
        let mut radii = Vec::with_capacity(n);
        let mut lengths = Vec::new();
        for (i, &cover) in cover.iter().enumerate() {
            lengths.clear();
            lengths.extend(neighbours.of(i as u32).iter().map(|&j| dist(i as u32, j)));
            if lengths.is_empty() {
                return Err(RenderError::InvalidSplat {
                    point: i,
                    what: "it is in no triangle",
                });
            }
            lengths.sort_by(f64::total_cmp);
            let median = lengths[lengths.len() / 2];
            let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
            radii.push((EDGE_RADIUS_FACTOR * mean).max(cover).min(MAX_RADIUS_FACTOR * median));
        }
        let mut splats = Self::new(positions, normals, radii)?;
        splats.neighbours = Some(neighbours);
        Ok(splats)
    }

    /// Every splat's field (module documentation): the gradient g in the
    /// splat's plane minimising Σⱼ (fⱼ − fᵢ − g·(pⱼ − pᵢ))² / |pⱼ − pᵢ|² over its neighbours
    /// j, and the range of f over the point and its neighbours. Splats without neighbours,
    /// or whose neighbours do not span the plane, are constant.
    pub(crate) fn slopes(&self, field: &[f64]) -> Vec<Slope> {
        (0..self.len())
            .map(|i| {
                let f = field[i];
                let constant = Slope {
                    value: f,
                    gradient: [0.0; 3],
                    lo: f,
                    hi: f,
                };
                let Some(neighbours) = &self.neighbours else {
                    return constant;
                };
                let (p, n) = (self.positions[i], self.normals[i]);
                // An orthonormal basis (t1, t2) of the splat's plane.
                let helper = if n[0].abs() < 0.6 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                let Some(t1) = normalized(cross(n, helper)) else {
                    return constant;
                };
                let t2 = cross(n, t1);
                let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
                let (mut lo, mut hi) = (f, f);
                for &j in neighbours.of(i as u32) {
                    let q = self.positions[j as usize];
                    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                    let w = 1.0 / dot(d, d);
                    let (u, v) = (dot(d, t1), dot(d, t2));
                    let df = field[j as usize] - f;
                    (a11, a12, a22) = (a11 + w * u * u, a12 + w * u * v, a22 + w * v * v);
                    (b1, b2) = (b1 + w * u * df, b2 + w * v * df);
                    lo = lo.min(field[j as usize]);
                    hi = hi.max(field[j as usize]);
                }
                let det = a11 * a22 - a12 * a12;
                // Neighbours nearly on a line through the point leave the gradient across
                // the line undetermined.
                let determined = det.is_finite() && det > 1e-6 * (a11 + a22) * (a11 + a22);
                if !determined {
                    return Slope { lo, hi, ..constant };
                }
                let (g1, g2) = ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det);
                let gradient = [0, 1, 2].map(|k| g1 * t1[k] + g2 * t2[k]);
                if gradient.iter().all(|g| g.is_finite()) {
                    Slope {
                        gradient,
                        lo,
                        hi,
                        ..constant
                    }
                } else {
                    Slope { lo, hi, ..constant }
                }
            })
            .collect()
    }

    /// The centres.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }

    /// The unit normals.
    pub fn normals(&self) -> &[[f64; 3]] {
        &self.normals
    }

    /// The radii.
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Number of splats.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Always false (a [`Splats`] has at least one point); for symmetry with [`Splats::len`].
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An m × m grid with a deterministic jitter on the plane z = 0.2x + 0.1y, with two
    /// triangles per cell and the plane's normal.
    /// Points, normals and triangles.
    type Surface = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[u32; 3]>);

    fn tilted_grid(m: usize) -> Surface {
        let mut points = Vec::new();
        for i in 0..m {
            for j in 0..m {
                let (x, y) = (
                    i as f64 + 0.3 * ((7 * i + 3 * j) % 5) as f64 / 5.0,
                    j as f64 + 0.3 * ((2 * i + 5 * j) % 7) as f64 / 7.0,
                );
                points.push([x, y, 0.2 * x + 0.1 * y]);
            }
        }
        let mut triangles = Vec::new();
        for i in 0..m - 1 {
            for j in 0..m - 1 {
                let v = |a: usize, b: usize| (a * m + b) as u32;
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        let normal = normalized([-0.2, -0.1, 1.0]).unwrap_or([0.0; 3]);
        (points.clone(), vec![normal; points.len()], triangles)
    }

    #[test]
    fn slopes_are_exact_for_linear_fields_and_clamped_to_the_neighbours() {
        let (points, normals, triangles) = tilted_grid(6);
        let c = [1.0, -2.0, 0.5];
        let field: Vec<f64> = points.iter().map(|&p| dot(c, p) + 3.0).collect();
        let n = normals[0];
        let cn = dot(c, n);
        let expected = [0, 1, 2].map(|k| c[k] - cn * n[k]);
        let splats = Splats::from_triangles(points, normals, &triangles).unwrap();
        let slopes = splats.slopes(&field);
        for (i, s) in slopes.iter().enumerate() {
            for (g, e) in s.gradient.iter().zip(&expected) {
                assert!((g - e).abs() < 1e-9, "point {i}: {:?}", s.gradient);
            }
            let around = splats
                .neighbours
                .as_ref()
                .map(|nb| nb.of(i as u32).to_vec())
                .unwrap_or_default();
            assert!(!around.is_empty());
            let values = around.iter().map(|&j| field[j as usize]).chain([field[i]]);
            let lo = values.clone().fold(f64::INFINITY, f64::min);
            let hi = values.fold(f64::NEG_INFINITY, f64::max);
            assert_eq!((s.lo, s.hi), (lo, hi));
        }
        // Without neighbours the splats are constant.
        let flat = Splats::new(splats.positions.clone(), splats.normals.clone(), splats.radii.clone()).unwrap();
        assert!(flat
            .slopes(&field)
            .iter()
            .zip(&field)
            .all(|(s, &f)| s.gradient == [0.0; 3] && s.lo == f && s.hi == f));
    }

    #[test]
    fn radii_cover_every_triangle_and_overlap_the_neighbours() {
        let (points, normals, triangles) = tilted_grid(6);
        let splats = Splats::from_triangles(points.clone(), normals, &triangles).unwrap();
        let dist = |a: [f64; 3], b: [f64; 3]| {
            dot(
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
            )
            .sqrt()
        };
        // Every point of every triangle (on a fine barycentric grid) is inside some corner's disc.
        for t in &triangles {
            let [a, b, c] = t.map(|v| points[v as usize]);
            for i in 0..=20 {
                for j in 0..=20 - i {
                    let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                    let x = [0, 1, 2].map(|k| (1.0 - u - v) * a[k] + u * b[k] + v * c[k]);
                    assert!(t
                        .iter()
                        .any(|&v| dist(x, points[v as usize]) <= splats.radii[v as usize] + 1e-12));
                }
            }
        }
        // A triangle to a far point covers its corners only up to 3 median edge lengths.
        let mut far = points.clone();
        far.push([3.0, -20.0, 0.0]);
        let mut with_far = triangles.clone();
        with_far.push([14, 15, far.len() as u32 - 1]);
        let n = far.len();
        let capped = Splats::from_triangles(far.clone(), vec![[0.0, 0.0, 1.0]; n], &with_far).unwrap();
        for i in 0..n {
            let mut lengths: Vec<f64> = capped
                .neighbours
                .as_ref()
                .map(|nb| nb.of(i as u32).iter().map(|&j| dist(far[i], far[j as usize])).collect())
                .unwrap_or_default();
            lengths.sort_by(f64::total_cmp);
            assert!(capped.radii[i] <= 3.0 * lengths[lengths.len() / 2] + 1e-12, "point {i}");
        }
        assert!(capped.radii[14] < 4.0, "{}", capped.radii[14]);
        // And each disc reaches past its nearest neighbour.
        for (i, nb) in (0..points.len()).map(|i| {
            (
                i,
                splats
                    .neighbours
                    .as_ref()
                    .map(|n| n.of(i as u32).to_vec())
                    .unwrap_or_default(),
            )
        }) {
            let nearest = nb
                .iter()
                .map(|&j| dist(points[i], points[j as usize]))
                .fold(f64::INFINITY, f64::min);
            assert!(splats.radii[i] > nearest, "point {i}");
        }
    }
}
