//! Every Rust error becomes an instance of one of the exception classes of `wfem._errors`
//! (a small hierarchy under `wfem.WfemError`, subclasses of ValueError / RuntimeError /
//! OSError), with `kind` = the Rust variant's name and the culprit's data as attributes
//! (face, vertex, pole, residual, …), mirroring the Rust enums.

use crate::out::{mat_out, vec_out};
use mesh_fem::MeshError;
use pyo3::prelude::*;
use pyo3::types::{PyComplex, PyDict};
use retrieval_store::StoreError;
use shape_retrieval::RetrievalError;
use shifted_solve::SolveError;
use wfem_heat::HeatError;

/// The exception classes (names in `wfem._errors`).
#[derive(Clone, Copy, Debug)]
pub enum Class {
    InvalidInput,
    Mesh,
    MeshFile,
    Solver,
    Convergence,
    IllConditioned,
    Retrieval,
    Store,
    Internal,
}

impl Class {
    fn name(self) -> &'static str {
        match self {
            Class::InvalidInput => "InvalidInputError",
            Class::Mesh => "MeshError",
            Class::MeshFile => "MeshFileError",
            Class::Solver => "SolverError",
            Class::Convergence => "ConvergenceError",
            Class::IllConditioned => "IllConditionedError",
            Class::Retrieval => "RetrievalError",
            Class::Store => "StoreError",
            Class::Internal => "InternalError",
        }
    }
}

/// A field value of an exception.
pub enum Value {
    Int(i128),
    Float(f64),
    Str(String),
    Complex(f64, f64),
    Ints(Vec<i128>),
    Object(Py<PyAny>),
}

impl From<usize> for Value {
    fn from(v: usize) -> Self {
        Value::Int(v as i128)
    }
}
impl From<u32> for Value {
    fn from(v: u32) -> Self {
        Value::Int(v.into())
    }
}
impl From<u64> for Value {
    fn from(v: u64) -> Self {
        Value::Int(v.into())
    }
}
impl From<i64> for Value {
    fn from(v: i64) -> Self {
        Value::Int(v.into())
    }
}
impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Float(v)
    }
}
impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::Str(v.into())
    }
}
impl From<&String> for Value {
    fn from(v: &String) -> Self {
        Value::Str(v.clone())
    }
}
impl From<&std::path::PathBuf> for Value {
    fn from(v: &std::path::PathBuf) -> Self {
        Value::Str(v.display().to_string())
    }
}
impl From<faer::c64> for Value {
    fn from(v: faer::c64) -> Self {
        Value::Complex(v.re, v.im)
    }
}
impl From<&[u32]> for Value {
    fn from(v: &[u32]) -> Self {
        Value::Ints(v.iter().map(|&x| x.into()).collect())
    }
}

/// Builds `wfem._errors.<class>(message, kind=kind, **fields)` as a `PyErr`.
pub fn raise(py: Python<'_>, class: Class, kind: &str, message: String, fields: Vec<(&str, Value)>) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let cls = py.import("wfem._errors")?.getattr(class.name())?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("kind", kind)?;
        for (name, value) in fields {
            match value {
                Value::Int(v) => kwargs.set_item(name, v)?,
                Value::Float(v) => kwargs.set_item(name, v)?,
                Value::Str(v) => kwargs.set_item(name, v)?,
                Value::Complex(re, im) => kwargs.set_item(name, PyComplex::from_doubles(py, re, im))?,
                Value::Ints(v) => kwargs.set_item(name, v)?,
                Value::Object(v) => kwargs.set_item(name, v)?,
            }
        }
        Ok(PyErr::from_value(cls.call((message,), Some(&kwargs))?))
    };
    build().unwrap_or_else(|e| e)
}

/// A bad argument detected by the bindings themselves.
pub fn invalid(py: Python<'_>, kind: &str, message: impl Into<String>) -> PyErr {
    raise(py, Class::InvalidInput, kind, message.into(), Vec::new())
}

/// A bad argument naming the parameter.
pub fn invalid_param(py: Python<'_>, name: &str, reason: impl std::fmt::Display) -> PyErr {
    raise(
        py,
        Class::InvalidInput,
        "InvalidParameter",
        format!("invalid parameter `{name}`: {reason}"),
        vec![("name", name.into())],
    )
}

/// The variant name of a `#[non_exhaustive]` enum value, from its `Debug` form.
fn variant_name(debug: &str) -> String {
    debug
        .split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .next()
        .unwrap_or("Unknown")
        .to_string()
}

macro_rules! fields {
    ($($name:ident = $value:expr),* $(,)?) => {
        vec![$((stringify!($name), Value::from($value))),*]
    };
}

/// A [`MeshError`] as a Python exception.
pub fn mesh(py: Python<'_>, e: &MeshError) -> PyErr {
    let message = e.to_string();
    let (class, kind, fields): (Class, &str, Vec<(&str, Value)>) = match e {
        MeshError::Empty { n_vertices, n_faces } => (
            Class::Mesh,
            "Empty",
            fields!(n_vertices = *n_vertices, n_faces = *n_faces),
        ),
        MeshError::NonFiniteCoordinate { vertex, .. } => {
            (Class::Mesh, "NonFiniteCoordinate", fields!(vertex = *vertex))
        }
        MeshError::IndexOutOfRange {
            face,
            index,
            n_vertices,
        } => (
            Class::Mesh,
            "IndexOutOfRange",
            fields!(face = *face, index = *index, n_vertices = *n_vertices),
        ),
        MeshError::DegenerateMesh { area } => (Class::Mesh, "DegenerateMesh", fields!(area = *area)),
        MeshError::RepeatedIndex { face, vertices } => (
            Class::Mesh,
            "RepeatedIndex",
            fields!(face = *face, vertices = vertices.as_slice()),
        ),
        MeshError::DegenerateFace { face, vertices } => (
            Class::Mesh,
            "DegenerateFace",
            fields!(face = *face, vertices = vertices.as_slice()),
        ),
        MeshError::Polygon { path, face, corners } => (
            Class::Mesh,
            "Polygon",
            fields!(path = path, face = *face, corners = *corners),
        ),
        MeshError::UnreferencedVertex { vertex } => (Class::Mesh, "UnreferencedVertex", fields!(vertex = *vertex)),
        MeshError::UnknownFormat { path, extension } => (
            Class::Mesh,
            "UnknownFormat",
            fields!(path = path, extension = extension),
        ),
        MeshError::Parse { path, line, message } => (
            Class::Mesh,
            "Parse",
            fields!(path = path, line = *line, reason = message),
        ),
        MeshError::Io { path, source } => {
            let mut f = fields!(path = path);
            if let Some(errno) = source.raw_os_error() {
                f.push(("errno", Value::Int(errno.into())));
            }
            (Class::MeshFile, "Io", f)
        }
        MeshError::Invalid { reason } => (Class::Mesh, "Invalid", fields!(reason = reason)),
        MeshError::MatrixMarket { path, message } => {
            (Class::Mesh, "MatrixMarket", fields!(path = path, reason = message))
        }
        MeshError::ScalarFieldLength { len, n_vertices } => (
            Class::InvalidInput,
            "ScalarFieldLength",
            fields!(len = *len, n_vertices = *n_vertices),
        ),
        MeshError::NonFiniteScalarField { vertex, value } => (
            Class::InvalidInput,
            "NonFiniteScalarField",
            fields!(vertex = *vertex, value = *value),
        ),
        MeshError::NegativeIndex {
            path,
            line,
            face,
            index,
        } => (
            Class::Mesh,
            "NegativeIndex",
            fields!(path = path, line = *line, face = *face, index = *index),
        ),
        MeshError::FieldLength {
            path,
            name,
            expected,
            found,
        } => (
            Class::InvalidInput,
            "FieldLength",
            fields!(path = path, name = name, expected = *expected, found = *found),
        ),
        MeshError::NonFiniteValue {
            path,
            name,
            vertex,
            value,
        } => (
            Class::InvalidInput,
            "NonFiniteValue",
            fields!(path = path, name = name, vertex = *vertex, value = *value),
        ),
        MeshError::InvalidRepairOption { option, message } => (
            Class::InvalidInput,
            "InvalidRepairOption",
            fields!(option = *option, reason = message),
        ),
        MeshError::MatrixMarketLine { path, line, message } => (
            Class::Mesh,
            "MatrixMarketLine",
            fields!(path = path, line = *line, reason = message),
        ),
        other => {
            let kind = variant_name(&format!("{other:?}"));
            return raise(py, Class::Mesh, &kind, message, Vec::new());
        }
    };
    raise(py, class, kind, message, fields)
}

/// A [`SolveError`] as a Python exception.
pub fn solve(py: Python<'_>, e: &SolveError) -> PyErr {
    let message = e.to_string();
    let (class, kind, fields): (Class, &str, Vec<(&str, Value)>) = match e {
        SolveError::DimensionMismatch { what, expected, got } => (
            Class::InvalidInput,
            "DimensionMismatch",
            fields!(what = *what, expected = *expected, found = *got),
        ),
        SolveError::NotSquare { which, nrows, ncols } => (
            Class::InvalidInput,
            "NotSquare",
            fields!(matrix = *which, nrows = *nrows, ncols = *ncols),
        ),
        SolveError::Empty => (Class::InvalidInput, "Empty", Vec::new()),
        SolveError::UnsupportedDegree { degree, available } => {
            let available: Vec<i128> = available.iter().map(|&d| d as i128).collect();
            (
                Class::InvalidInput,
                "UnsupportedDegree",
                vec![("degree", Value::from(*degree)), ("available", Value::Ints(available))],
            )
        }
        SolveError::InvalidTime { t } => (Class::InvalidInput, "InvalidTime", fields!(t = *t)),
        SolveError::NonFinite { what, row, col, value } => (
            Class::InvalidInput,
            "NonFinite",
            fields!(what = *what, row = *row, column = *col, value = *value),
        ),
        SolveError::NotSymmetric {
            which,
            row,
            col,
            value,
            transposed,
        } => (
            Class::InvalidInput,
            "NotSymmetric",
            fields!(
                matrix = *which,
                row = *row,
                column = *col,
                value = *value,
                transposed = *transposed
            ),
        ),
        SolveError::BadDiagonal {
            which,
            index,
            value,
            requirement,
        } => (
            Class::InvalidInput,
            "BadDiagonal",
            fields!(
                matrix = *which,
                index = *index,
                value = *value,
                requirement = *requirement
            ),
        ),
        SolveError::MassNotPositiveDefinite { detail } => {
            (Class::InvalidInput, "MassNotPositiveDefinite", fields!(reason = detail))
        }
        SolveError::StiffnessIndefinite { delta } => {
            (Class::InvalidInput, "StiffnessIndefinite", fields!(delta = *delta))
        }
        SolveError::SingularShiftedMatrix { t, pole } => {
            (Class::Solver, "SingularShiftedMatrix", fields!(t = *t, pole = *pole))
        }
        SolveError::NoConvergence {
            residual,
            iterations,
            pole,
        } => (
            Class::Convergence,
            "NoConvergence",
            fields!(residual = *residual, iterations = *iterations, pole = *pole),
        ),
        SolveError::KrylovNoConvergence { iterations, estimate } => (
            Class::Convergence,
            "KrylovNoConvergence",
            fields!(iterations = *iterations, estimate = *estimate),
        ),
        SolveError::InvalidParameter { name, value, reason } => (
            Class::InvalidInput,
            "InvalidParameter",
            fields!(name = *name, value = *value, reason = *reason),
        ),
        SolveError::Factorization { what, detail } => {
            (Class::Solver, "Factorization", fields!(what = *what, reason = detail))
        }
        other => {
            let kind = variant_name(&format!("{other:?}"));
            return raise(py, Class::Solver, &kind, message, Vec::new());
        }
    };
    raise(py, class, kind, message, fields)
}

/// A [`HeatError`] as a Python exception.
pub fn heat(py: Python<'_>, e: &HeatError) -> PyErr {
    let message = e.to_string();
    let (class, kind, fields): (Class, &str, Vec<(&str, Value)>) = match e {
        HeatError::Solve(s) => return solve(py, s),
        HeatError::Mesh(m) => return mesh(py, m),
        HeatError::InvalidTime { t } => (Class::InvalidInput, "InvalidTime", fields!(t = *t)),
        HeatError::LengthMismatch { expected, found } => (
            Class::InvalidInput,
            "LengthMismatch",
            fields!(expected = *expected, found = *found),
        ),
        HeatError::NonFiniteInput { row, column, value } => (
            Class::InvalidInput,
            "NonFiniteInput",
            fields!(row = *row, column = *column, value = *value),
        ),
        HeatError::TooLargeForDense { n_vertices, limit } => (
            Class::InvalidInput,
            "TooLargeForDense",
            fields!(n_vertices = *n_vertices, limit = *limit),
        ),
        HeatError::InvalidParameter { name, reason } => (
            Class::InvalidInput,
            "InvalidParameter",
            fields!(name = *name, reason = reason),
        ),
        HeatError::MisplacedOption { option, method, owner } => (
            Class::InvalidInput,
            "MisplacedOption",
            fields!(option = *option, method = *method, owner = *owner),
        ),
        HeatError::InconsistentOperators { reason } => {
            (Class::InvalidInput, "InconsistentOperators", fields!(reason = reason))
        }
        HeatError::NotPositiveDefinite { matrix } => (Class::Solver, "NotPositiveDefinite", fields!(matrix = matrix)),
        HeatError::DenseEigen => (Class::Solver, "DenseEigen", Vec::new()),
        HeatError::EigenNoConvergence {
            requested,
            converged,
            dimension,
            max_residual,
            found,
        } => {
            let mut f = fields!(
                requested = *requested,
                converged = *converged,
                dimension = *dimension,
                max_residual = *max_residual,
            );
            // The converged pairs are kept: `err.found` is an Eigenbasis of them.
            if let Ok(obj) = found_arrays(py, found) {
                f.push(("found", Value::Object(obj)));
            }
            (Class::Convergence, "EigenNoConvergence", f)
        }
        HeatError::KrylovNoConvergence {
            column,
            iterations,
            estimate,
        } => (
            Class::Convergence,
            "KrylovNoConvergence",
            fields!(column = *column, iterations = *iterations, estimate = *estimate),
        ),
        HeatError::IllConditionedInverse {
            t,
            reason,
            amplification,
            cap,
            iterations,
            relative_residual,
        } => (
            Class::IllConditioned,
            "IllConditionedInverse",
            fields!(
                t = *t,
                reason = reason,
                amplification = *amplification,
                cap = *cap,
                iterations = *iterations,
                residual = *relative_residual,
            ),
        ),
        HeatError::VertexOutOfRange { index, n_vertices } => (
            Class::InvalidInput,
            "VertexOutOfRange",
            fields!(vertex = *index, n_vertices = *n_vertices),
        ),
        HeatError::InvalidOperatorEntry {
            matrix,
            row,
            col,
            value,
            requirement,
        } => (
            Class::InvalidInput,
            "InvalidOperatorEntry",
            fields!(
                matrix = *matrix,
                row = *row,
                column = *col,
                value = *value,
                requirement = *requirement
            ),
        ),
        other => {
            let kind = variant_name(&format!("{other:?}"));
            return raise(py, Class::Solver, &kind, message, Vec::new());
        }
    };
    raise(py, class, kind, message, fields)
}

/// A [`RetrievalError`] as a Python exception.
pub fn retrieval(py: Python<'_>, e: &RetrievalError) -> PyErr {
    let message = e.to_string();
    let (class, kind, fields): (Class, &str, Vec<(&str, Value)>) = match e {
        RetrievalError::Heat(h) => return heat(py, h),
        RetrievalError::Mesh(m) => return mesh(py, m),
        RetrievalError::DimensionMismatch { what, expected, actual } => (
            Class::InvalidInput,
            "DimensionMismatch",
            fields!(what = *what, expected = *expected, found = *actual),
        ),
        RetrievalError::Empty { what } => (Class::InvalidInput, "Empty", fields!(what = *what)),
        RetrievalError::NonFinite { what, index } => {
            (Class::InvalidInput, "NonFinite", fields!(what = *what, index = *index))
        }
        RetrievalError::InvalidParameter { name, value, reason } => (
            Class::InvalidInput,
            "InvalidParameter",
            fields!(name = *name, value = *value, reason = *reason),
        ),
        RetrievalError::NegativeEigenvalue { index, value } => (
            Class::Retrieval,
            "NegativeEigenvalue",
            fields!(index = *index, value = *value),
        ),
        RetrievalError::MassRequired => (Class::InvalidInput, "MassRequired", Vec::new()),
        RetrievalError::NoNonzeroEigenvalue => (Class::Retrieval, "NoNonzeroEigenvalue", Vec::new()),
        RetrievalError::NonPositiveSignature { vertex, time, value } => (
            Class::Retrieval,
            "NonPositiveSignature",
            fields!(vertex = *vertex, t = *time, value = *value),
        ),
        RetrievalError::TooFewDescriptors { n_points, k } => (
            Class::InvalidInput,
            "TooFewDescriptors",
            fields!(n_points = *n_points, k = *k),
        ),
        RetrievalError::VertexOutOfRange {
            what,
            index,
            n_vertices,
        } => (
            Class::InvalidInput,
            "VertexOutOfRange",
            fields!(what = *what, vertex = *index, n_vertices = *n_vertices),
        ),
        RetrievalError::ZeroDescriptor { vertex } => (Class::Retrieval, "ZeroDescriptor", fields!(vertex = *vertex)),
        RetrievalError::NothingToAverage { what } => (Class::Retrieval, "NothingToAverage", fields!(what = *what)),
        // The index file (README: RetrievalIndex raises StoreError for its file).
        RetrievalError::Storage { path, reason } => (Class::Store, "Storage", fields!(path = path, reason = reason)),
        RetrievalError::InvalidDistance { from, to, value } => (
            Class::Retrieval,
            "InvalidDistance",
            fields!(source = *from, target = *to, value = *value),
        ),
        RetrievalError::Labels { location, reason } => (
            Class::InvalidInput,
            "Labels",
            fields!(location = location, reason = reason),
        ),
        other => {
            let kind = variant_name(&format!("{other:?}"));
            return raise(py, Class::Retrieval, &kind, message, Vec::new());
        }
    };
    raise(py, class, kind, message, fields)
}

/// A [`StoreError`] as a Python exception.
pub fn store(py: Python<'_>, e: &StoreError) -> PyErr {
    let message = e.to_string();
    let (class, kind, fields): (Class, &str, Vec<(&str, Value)>) = match e {
        StoreError::Sqlite { path, .. } => (Class::Store, "Sqlite", fields!(path = path)),
        StoreError::Io { path, source } => {
            let mut f = fields!(path = path);
            if let Some(errno) = source.raw_os_error() {
                f.push(("errno", Value::Int(errno.into())));
            }
            (Class::Store, "Io", f)
        }
        StoreError::NotAStore { path, reason } => (Class::Store, "NotAStore", fields!(path = path, reason = reason)),
        StoreError::UnsupportedVersion { path, found, supported } => (
            Class::Store,
            "UnsupportedVersion",
            fields!(path = path, found = *found, supported = *supported),
        ),
        StoreError::Exists { path } => (Class::Store, "Exists", fields!(path = path)),
        StoreError::InUse { path, wal } => (Class::Store, "InUse", fields!(path = path, wal = wal)),
        StoreError::Dimension { name, expected, found } => (
            Class::InvalidInput,
            "Dimension",
            fields!(name = name, expected = *expected, found = *found),
        ),
        StoreError::NonFinite { name, index, value } => (
            Class::InvalidInput,
            "NonFinite",
            fields!(name = name, index = *index, value = *value),
        ),
        StoreError::DuplicateName { name } => (Class::InvalidInput, "DuplicateName", fields!(name = name)),
        StoreError::EmptyName { index } => (Class::InvalidInput, "EmptyName", fields!(index = *index)),
        StoreError::InvalidParameter { name, reason } => (
            Class::InvalidInput,
            "InvalidParameter",
            fields!(name = *name, reason = reason),
        ),
        StoreError::Corrupt { path, reason } => (Class::Store, "Corrupt", fields!(path = path, reason = reason)),
        StoreError::NanDistance { id } => (Class::Retrieval, "NanDistance", fields!(id = *id)),
        StoreError::NotAFile { path, kind } => (Class::Store, "NotAFile", fields!(path = path, reason = *kind)),
        StoreError::Replaced { path } => (Class::Store, "Replaced", fields!(path = path)),
        StoreError::InvalidRow { path, id, reason } => (
            Class::Store,
            "InvalidRow",
            fields!(path = path, id = *id, reason = reason),
        ),
        StoreError::TooLarge { path, what } => (Class::Store, "TooLarge", fields!(path = path, reason = what)),
        other => {
            let kind = variant_name(&format!("{other:?}"));
            return raise(py, Class::Store, &kind, message, Vec::new());
        }
    };
    raise(py, class, kind, message, fields)
}

/// Errors of the library crates, carried out of a worker thread and converted once the GIL is
/// held again.
#[derive(Debug)]
pub enum Error {
    Mesh(MeshError),
    Heat(HeatError),
    Solve(SolveError),
    Retrieval(RetrievalError),
    Store(StoreError),
    /// A bad argument found by the bindings (kind, message).
    Invalid(&'static str, String),
    /// A panic in the Rust code: a bug, reported as `wfem.InternalError`.
    Panic(String),
}

impl From<MeshError> for Error {
    fn from(e: MeshError) -> Self {
        Error::Mesh(e)
    }
}
impl From<HeatError> for Error {
    fn from(e: HeatError) -> Self {
        Error::Heat(e)
    }
}
impl From<SolveError> for Error {
    fn from(e: SolveError) -> Self {
        Error::Solve(e)
    }
}
impl From<RetrievalError> for Error {
    fn from(e: RetrievalError) -> Self {
        Error::Retrieval(e)
    }
}
impl From<StoreError> for Error {
    fn from(e: StoreError) -> Self {
        Error::Store(e)
    }
}

impl Error {
    /// The Python exception (needs the GIL).
    pub fn into_py(self, py: Python<'_>) -> PyErr {
        match self {
            Error::Mesh(e) => mesh(py, &e),
            Error::Heat(e) => heat(py, &e),
            Error::Solve(e) => solve(py, &e),
            Error::Retrieval(e) => retrieval(py, &e),
            Error::Store(e) => store(py, &e),
            Error::Invalid(kind, message) => invalid(py, kind, message),
            Error::Panic(message) => raise(
                py,
                Class::Internal,
                "Panic",
                format!("internal error in wfem (a bug, please report it): {message}"),
                Vec::new(),
            ),
        }
    }
}

/// `(values, vectors)` arrays of a basis (for `ConvergenceError.found`).
fn found_arrays(py: Python<'_>, basis: &wfem_heat::Eigenbasis) -> PyResult<Py<PyAny>> {
    let values = vec_out(py, basis.values.clone());
    let vectors = mat_out(py, basis.vectors.as_ref());
    Ok((values, vectors).into_pyobject(py)?.into_any().unbind())
}
