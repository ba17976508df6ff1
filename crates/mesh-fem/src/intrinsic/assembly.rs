//! L, B and D on an intrinsic triangulation (paper Eq. (3) and (7), on edge lengths).
//!
//! A triangle with edge lengths l₀, l₁, l₂ (l_k from corner k to corner k + 1) has the area
//! |T| of Heron's formula and at corner k the cotangent `cot θ_k = (a² + b² − c²) / 4|T|`
//! (a, b the edges at the corner, c the opposite one). Its local matrices are the linear FEM
//! ones of the paper's Eq. (3): stiffness `−½ cot θ` on each edge (opposite the angle θ),
//! consistent mass |T|/6 on each corner and |T|/12 on each edge, lumped mass |T|/3 on each
//! corner (Eq. (7); or the mixed Voronoi areas). They are summed into the vertex matrices by
//! the vertex at each corner. An intrinsic triangle may have one vertex at two corners; the
//! hat function of that vertex is then the sum of the two corners' barycentric coordinates,
//! so the edge between the two corners adds to the diagonal of B (2 × |T|/12) and nothing to
//! L (its stiffness cancels against the corners' diagonal terms).
//!
//! Every entry is multiplied by a weight w: ½ on a tufted cover (every face is there twice),
//! 1/6 on a point cloud's cover (and every triangle three times). L stays symmetric positive
//! semidefinite with `L·1 = 0`; B is symmetric positive definite with row sums equal to the
//! barycentric D. The columns are merged as in [`crate::operators`]: one pass counts the
//! distinct rows, the second writes L, B and D in place, in parallel over columns; each
//! face's contribution to an entry is added in face order on both sides of the diagonal, so
//! L and B are exactly symmetric.

use super::{cot_opposite, triangle_area, IntrinsicTriangulation};
use crate::mesh::mul_pow2;
use crate::operators::{
    column_layout, faces_around_vertices, write_columns, ColumnDiagonal, Columns, FemOperators, Lumping,
};
use crate::MeshError;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

/// The measures of one intrinsic triangle.
#[derive(Clone, Copy)]
struct Element {
    area: f64,
    /// Cotangent of the angle at each corner.
    cots: [f64; 3],
    /// Lumped mass at each corner (|T|/3, or the mixed Voronoi area).
    corner_mass: [f64; 3],
}

/// The element of a triangle with edge lengths `l` (l[k] from corner k to k + 1); `None`
/// for a triangle of zero or non-finite area or a non-finite cotangent.
#[inline]
fn element(l: [f64; 3], voronoi: bool) -> Option<Element> {
    let area = triangle_area(l[0], l[1], l[2]);
    if !(area > 0.0 && area.is_finite()) {
        return None;
    }
    // Corner k lies between edges k and k + 2 and faces edge k + 1.
    let cots = [0, 1, 2].map(|k| cot_opposite(l[k], l[(k + 2) % 3], l[(k + 1) % 3], area));
    if cots.iter().any(|c| !c.is_finite()) {
        return None;
    }
    let corner_mass = if !voronoi {
        [area / 3.0; 3]
    } else {
        match (0..3).find(|&k| cots[k] < 0.0) {
            // Meyer et al.'s Voronoi region of corner k: the edge k (opposite corner k + 2)
            // and the edge k + 2 (opposite corner k + 1).
            None => [0, 1, 2]
                .map(|k| (l[k] * l[k] * cots[(k + 2) % 3] + l[(k + 2) % 3] * l[(k + 2) % 3] * cots[(k + 1) % 3]) / 8.0),
            Some(o) => [0, 1, 2].map(|k| if k == o { area / 2.0 } else { area / 4.0 }),
        }
    };
    Some(Element {
        area,
        cots,
        corner_mass,
    })
}

/// L, B, D of `tri`, every entry multiplied by `weight` (module documentation).
///
/// # Errors
/// [`MeshError::DegenerateIntrinsicTriangle`] for the first triangle of zero or non-finite
/// area, [`MeshError::UnreferencedVertex`] for a vertex in no triangle,
/// [`MeshError::DegenerateMesh`] if the total area overflows.
pub(crate) fn assemble(tri: &IntrinsicTriangulation, weight: f64, lumped: Lumping) -> Result<FemOperators, MeshError> {
    let n = tri.n_vertices();
    let triangles = tri.triangles();
    let (lengths, scale) = tri.scaled_lengths();
    let voronoi = lumped == Lumping::Voronoi;
    let bad = lengths
        .par_iter()
        .enumerate()
        .find_first(|(_, l)| element(**l, voronoi).is_none())
        .map(|(t, _)| t);
    if let Some(triangle) = bad {
        return Err(MeshError::DegenerateIntrinsicTriangle {
            triangle,
            lengths: tri.triangle_lengths(triangle),
        });
    }
    let total_area: f64 = lengths.par_iter().map(|l| triangle_area(l[0], l[1], l[2])).sum::<f64>();
    let total_area = weight * mul_pow2(total_area, 2 * scale);
    if !total_area.is_finite() {
        return Err(MeshError::DegenerateMesh { area: total_area });
    }
    let first = crate::graph::corner_offsets(triangles, n);
    if let Some(vertex) = (0..n).find(|&j| first[j + 1] == first[j]) {
        return Err(MeshError::UnreferencedVertex { vertex });
    }
    let around = faces_around_vertices(triangles, &first);
    let element_of = |f: usize| -> Element {
        // Checked above for every triangle.
        element(lengths[f], voronoi).unwrap_or(Element {
            area: 0.0,
            cots: [0.0; 3],
            corner_mass: [0.0; 3],
        })
    };
    // 1. Count the distinct rows of each column.
    let (chunks, col_ptr) = column_layout(&around, &first, triangles);
    // 2. Write the merged entries (the pass shared with the cotangent assembly).
    let area_scale = |x: f64| if scale == 0 { x } else { mul_pow2(x, 2 * scale) };
    let columns = write_columns(&chunks, col_ptr, |j, buf| {
        let ju = j as u32;
        let (mut d_jj, mut b_jj) = (0.0f64, 0.0f64);
        let mut previous = u32::MAX;
        for &f in &around[first[j]..first[j + 1]] {
            // A triangle with j at two corners is listed twice, consecutively.
            if f == previous {
                continue;
            }
            previous = f;
            let t = triangles[f as usize];
            let e = element_of(f as usize);
            let b_edge = weight * e.area / 12.0;
            for k in 0..3 {
                let (x, y) = (t[k], t[(k + 1) % 3]);
                if x == ju && y == ju {
                    b_jj += 2.0 * b_edge;
                } else if x == ju || y == ju {
                    let i = if x == ju { y } else { x };
                    // Edge k faces corner k + 2.
                    let lv = -0.5 * weight * e.cots[(k + 2) % 3];
                    match buf.iter_mut().find(|entry| entry.0 == i) {
                        Some(entry) => {
                            entry.1 += lv;
                            entry.2 += b_edge;
                        }
                        None => buf.push((i, lv, b_edge)),
                    }
                }
            }
            for k in (0..3).filter(|&k| t[k] == ju) {
                d_jj += weight * e.corner_mass[k];
                b_jj += weight * e.area / 6.0;
            }
        }
        // The lengths were scaled by 2^−scale: areas come back by 2^(2·scale).
        for entry in buf.iter_mut() {
            entry.2 = area_scale(entry.2);
        }
        ColumnDiagonal {
            lumped: area_scale(d_jj),
            mass: Some(area_scale(b_jj)),
        }
    });
    let Columns {
        col_ptr,
        row_idx,
        l_val,
        b_val,
        lumped_diagonal,
    } = columns;
    drop(around);
    let [l_rows, b_rows] = row_idx;
    let pattern = |rows: Vec<usize>| SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, rows);
    let (stiffness_pattern, mass_pattern) = rayon::join(|| pattern(l_rows), || pattern(b_rows));
    Ok(FemOperators {
        stiffness: SparseColMat::new(stiffness_pattern, l_val),
        mass: SparseColMat::new(mass_pattern, b_val),
        lumped_diagonal,
        lumping: lumped,
    })
}
