//! Kernels on tall-skinny blocks shared by the eigensolver (`eigen`) and the Lanczos process
//! (`lanczos`): block Gram–Schmidt in the M-inner product and the row ranges the parallel
//! products are split into. (Its own module so that neither of the two imports the other.)

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Rows per work item of the in-place basis rotation `V ← V Y` at a restart.
pub(crate) const ROTATION_ROWS: usize = 512;

/// One pass of block classical Gram–Schmidt in the M-inner product against an M-orthonormal V:
/// `C = Vᵀ(MW)`, `W ← W − V C`; returns C. `mw` is M W.
///
/// Both products are tall and skinny (n × m times n × b); they run as sequential BLAS-3
/// products on row blocks spread over the rayon pool (C as a sum of per-block partial
/// products), which keeps every core busy without faer's per-product barriers (those stall
/// badly when the machine is shared).
pub(crate) fn project_out(v: MatRef<'_, f64>, w: MatMut<'_, f64>, mw: MatRef<'_, f64>) -> Mat<f64> {
    let (m, b) = (v.ncols(), w.ncols());
    if m == 0 {
        return Mat::zeros(0, b);
    }
    let rows = row_blocks(v.nrows());
    let coef = rows
        .par_iter()
        .map(|&(r0, r1)| {
            let mut c = Mat::<f64>::zeros(m, b);
            matmul(
                c.as_mut(),
                Accum::Replace,
                v.get(r0..r1, ..).transpose(),
                mw.get(r0..r1, ..),
                1.0,
                Par::Seq,
            );
            c
        })
        .reduce(|| Mat::<f64>::zeros(m, b), |a, c| a + c);
    let chunks = split_rows(w, &rows);
    chunks.into_par_iter().for_each(|(r0, mut chunk)| {
        let r1 = r0 + chunk.nrows();
        matmul(
            chunk.as_mut(),
            Accum::Add,
            v.get(r0..r1, ..),
            coef.as_ref(),
            -1.0,
            Par::Seq,
        );
    });
    coef
}

/// Row ranges of about [`ROTATION_ROWS`]·4 rows for the tall-skinny products.
pub(crate) fn row_blocks(n: usize) -> Vec<(usize, usize)> {
    let step = 4 * ROTATION_ROWS;
    (0..n).step_by(step).map(|r| (r, (r + step).min(n))).collect()
}

/// A matrix cut into the disjoint row ranges `rows` (consecutive, from 0, as [`row_blocks`]
/// gives them), each with its first row, for parallel in-place work.
pub(crate) fn split_rows<'a>(mat: MatMut<'a, f64>, rows: &[(usize, usize)]) -> Vec<(usize, MatMut<'a, f64>)> {
    let mut chunks = Vec::with_capacity(rows.len());
    let mut rest = mat;
    let mut done = 0;
    for &(_, r1) in rows {
        let (head, tail) = rest.split_at_row_mut(r1 - done);
        chunks.push((done, head));
        rest = tail;
        done = r1;
    }
    chunks
}
