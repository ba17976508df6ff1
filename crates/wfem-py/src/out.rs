//! Rust values to new C-ordered NumPy arrays (outputs; no checks, so no errors: the module
//! every other one may use).

use faer::sparse::SparseColMatRef;
use faer::{Mat, MatRef};
use mesh_fem::TriMesh;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;

/// A faer matrix as a new (rows × cols) array.
pub fn mat_out<'py>(py: Python<'py>, m: MatRef<'_, f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// Several n × k matrices as one (T, n, k) array.
pub fn mats_out<'py>(py: Python<'py>, ms: &[Mat<f64>], n: usize, k: usize) -> Bound<'py, PyArray3<f64>> {
    Array3::from_shape_fn((ms.len(), n, k), |(t, i, j)| ms[t][(i, j)]).into_pyarray(py)
}

/// A vector as a new 1-D array.
pub fn vec_out<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    v.into_pyarray(py)
}

/// A mesh as (V (n, 3) float64, F (m, 3) int64) arrays.
pub fn mesh_out<'py>(py: Python<'py>, mesh: &TriMesh) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>) {
    let p = mesh.positions();
    let f = mesh.faces();
    let v = Array2::from_shape_fn((p.len(), 3), |(i, j)| p[i][j]).into_pyarray(py);
    let f = Array2::from_shape_fn((f.len(), 3), |(i, j)| i64::from(f[i][j])).into_pyarray(py);
    (v, f)
}
/// CSC arrays (indptr, indices, data) of a faer matrix, one entry per stored value.
pub type SparseOut<'py> = (
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<f64>>,
    (usize, usize),
);

/// A faer matrix as CSC arrays for `scipy.sparse.csc_matrix((data, indices, indptr), shape)`.
pub fn sparse_out<'py>(py: Python<'py>, a: SparseColMatRef<'_, usize, f64>) -> SparseOut<'py> {
    let sym = a.symbolic();
    let mut indptr = Vec::with_capacity(a.ncols() + 1);
    let mut indices = Vec::with_capacity(a.val().len());
    let mut data = Vec::with_capacity(a.val().len());
    indptr.push(0i64);
    for j in 0..a.ncols() {
        for q in sym.col_range(j) {
            indices.push(sym.row_idx()[q] as i64);
            data.push(a.val()[q]);
        }
        indptr.push(indices.len() as i64);
    }
    (
        indptr.into_pyarray(py),
        indices.into_pyarray(py),
        data.into_pyarray(py),
        (a.nrows(), a.ncols()),
    )
}
