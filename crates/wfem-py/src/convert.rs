//! NumPy ⇄ Rust. Inputs are copied out of the arrays (any strides, any memory order; the
//! arrays are never written); outputs are new C-ordered arrays. The pure-Python layer has
//! already converted dtypes (float32 → float64, int32 → int64) and refused the others.

use crate::errors::{invalid, Error};
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use mesh_fem::TriMesh;

use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

/// A 1-D float64 array as a vector.
pub fn vec_in(a: &PyReadonlyArray1<'_, f64>) -> Vec<f64> {
    a.as_array().iter().copied().collect()
}

/// A 2-D float64 array as a faer matrix.
pub fn mat_in(a: &PyReadonlyArray2<'_, f64>) -> Mat<f64> {
    let v = a.as_array();
    Mat::from_fn(v.nrows(), v.ncols(), |i, j| v[[i, j]])
}

/// A mesh from V (n, 3) float64 and F (m, 3) int64, validated by `TriMesh::new` (indices in
/// range, finite coordinates, not empty).
pub fn mesh_in(py: Python<'_>, v: &PyReadonlyArray2<'_, f64>, f: &PyReadonlyArray2<'_, i64>) -> PyResult<TriMesh> {
    let elements = Elements {
        array: "F",
        shape_kind: "FacesShape",
        shape: "(m, 3) (triangles)",
        element: "face",
        key: "face",
        index_kind: "IndexOutOfRange",
    };
    let (positions, faces) = elements_in::<3>(py, v, f, &elements)?;
    TriMesh::new(positions, faces).map_err(|e| crate::errors::mesh(py, &e))
}

/// How [`elements_in`] names an element array in its errors.
pub struct Elements {
    /// The argument (`F`, `T`).
    pub array: &'static str,
    /// The error kind of a wrong shape.
    pub shape_kind: &'static str,
    /// The shape it must have, as messages say it.
    pub shape: &'static str,
    /// One element, as messages say it (`face`, `tetrahedron`).
    pub element: &'static str,
    /// Its key in the error's details.
    pub key: &'static str,
    /// The error kind of an index out of range.
    pub index_kind: &'static str,
}

/// Positions from V (n, 3) and K-vertex elements from an (m, K) index array, every index
/// checked to fit (the mesh type checks that it names a vertex).
pub fn elements_in<const K: usize>(
    py: Python<'_>,
    v: &PyReadonlyArray2<'_, f64>,
    e: &PyReadonlyArray2<'_, i64>,
    names: &Elements,
) -> PyResult<(Vec<[f64; 3]>, Vec<[u32; K]>)> {
    let (va, ea) = (v.as_array(), e.as_array());
    if va.ncols() != 3 {
        return Err(invalid(
            py,
            "VerticesShape",
            format!("V must have shape (n, 3), got {:?}", va.shape()),
        ));
    }
    if ea.ncols() != K {
        return Err(invalid(
            py,
            names.shape_kind,
            format!("{} must have shape {}, got {:?}", names.array, names.shape, ea.shape()),
        ));
    }
    let positions: Vec<[f64; 3]> = va.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    let mut elements = Vec::with_capacity(ea.nrows());
    for (i, r) in ea.rows().into_iter().enumerate() {
        let mut element = [0u32; K];
        for (c, &x) in r.iter().enumerate() {
            element[c] = u32::try_from(x).map_err(|_| {
                crate::errors::raise(
                    py,
                    crate::errors::Class::Mesh,
                    names.index_kind,
                    format!(
                        "{} {i} uses vertex {x}, but the mesh has {} vertices",
                        names.element,
                        va.nrows()
                    ),
                    vec![
                        (names.key, i.into()),
                        ("index", crate::errors::Value::Int(x.into())),
                        ("n_vertices", va.nrows().into()),
                    ],
                )
            })?;
        }
        elements.push(element);
    }
    Ok((positions, elements))
}

/// A sparse matrix argument: CSC arrays (indptr, indices, data) and its shape.
pub type SparseIn<'py> = (
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray1<'py, f64>,
    (usize, usize),
);

/// [`sparse_in`] of an argument, raising `InvalidInputError` naming it.
pub fn sparse_arg(py: Python<'_>, name: &str, a: &SparseIn<'_>) -> PyResult<SparseColMat<usize, f64>> {
    sparse_in(name, &a.0, &a.1, &a.2, a.3).map_err(|e| e.into_py(py))
}

/// A sparse matrix given as CSC arrays (indptr, indices, data) and a shape, as a faer matrix.
/// Duplicates are summed; every index is checked.
pub fn sparse_in(
    name: &str,
    indptr: &PyReadonlyArray1<'_, i64>,
    indices: &PyReadonlyArray1<'_, i64>,
    data: &PyReadonlyArray1<'_, f64>,
    shape: (usize, usize),
) -> Result<SparseColMat<usize, f64>, Error> {
    let (p, r, x) = (indptr.as_array(), indices.as_array(), data.as_array());
    let (nrows, ncols) = shape;
    let bad = |reason: String| Error::Invalid("SparseMatrix", format!("{name}: {reason}"));
    if p.len() != ncols + 1 {
        return Err(bad(format!("indptr has {} entries for {ncols} columns", p.len())));
    }
    if r.len() != x.len() {
        return Err(bad(format!("{} indices but {} values", r.len(), x.len())));
    }
    let mut triplets = Vec::with_capacity(x.len());
    for j in 0..ncols {
        let (a, b) = (p[j], p[j + 1]);
        if a < 0 || b < a || b as usize > r.len() {
            return Err(bad(format!(
                "indptr is not increasing within 0..={} at column {j}",
                r.len()
            )));
        }
        for q in a as usize..b as usize {
            let i = r[q];
            if i < 0 || i as usize >= nrows {
                return Err(bad(format!("row index {i} in column {j} is outside 0..{nrows}")));
            }
            triplets.push(Triplet::new(i as usize, j, x[q]));
        }
    }
    SparseColMat::try_new_from_triplets(nrows, ncols, &triplets).map_err(|e| bad(format!("{e:?}")))
}
