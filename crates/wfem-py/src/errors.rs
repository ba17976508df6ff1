//! Every Rust error becomes an instance of one of the exception classes of `wfem._errors`
//! (a small hierarchy under `wfem.WfemError`, subclasses of ValueError / RuntimeError /
//! OSError), with `kind` = the Rust variant's name and the culprit's data as attributes
//! (face, vertex, pole, residual, …). Kind and attributes are generated from the library
//! enums' serde form (the library names each field as Python sees it); what is chosen here is
//! only the class of each variant.

use crate::out::{mat_out, vec_out};
use mesh_fem::{MeshError, Remedy};
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

/// A field value of an exception raised by the bindings themselves (library errors bring
/// their own fields).
pub enum Value {
    Int(i128),
    Str(String),
    Object(Py<PyAny>),
}

impl From<usize> for Value {
    fn from(v: usize) -> Self {
        Value::Int(v as i128)
    }
}

impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::Str(v.to_string())
    }
}

/// Builds `wfem._errors.<class>(message, kind=kind, **fields)` as a `PyErr`.
pub fn raise(py: Python<'_>, class: Class, kind: &str, message: String, fields: Vec<(&str, Value)>) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let cls = py.import("wfem._errors")?.getattr(class.name())?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("kind", kind)?;
        set_fields(&kwargs, fields)?;
        Ok(PyErr::from_value(cls.call((message,), Some(&kwargs))?))
    };
    build().unwrap_or_else(|e| e)
}

/// Puts `fields` into `kwargs`.
fn set_fields(kwargs: &Bound<'_, PyDict>, fields: Vec<(&str, Value)>) -> PyResult<()> {
    for (name, value) in fields {
        match value {
            Value::Int(v) => kwargs.set_item(name, v)?,
            Value::Str(v) => kwargs.set_item(name, v)?,
            Value::Object(v) => kwargs.set_item(name, v)?,
        }
    }
    Ok(())
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

/// `wfem._errors.<class>(message, kind=<variant>, **fields)` for a library error, generated
/// from its serde form (`{"Variant": {field: value}}`, or `"Variant"` for a variant without
/// fields; the library names the fields as Python sees them and leaves out what Python cannot
/// hold), plus `extra` fields. A field `pole` (a complex pole, serialized as (re, im)) becomes
/// a Python complex.
fn raise_error<E: serde::Serialize + std::fmt::Display>(
    py: Python<'_>,
    class: Class,
    e: &E,
    extra: Vec<(&str, Value)>,
) -> PyErr {
    raise_error_saying(py, class, e, e.to_string(), extra)
}

/// [`raise_error`] with the message given (a library message with its remedy in Python's words).
fn raise_error_saying<E: serde::Serialize>(
    py: Python<'_>,
    class: Class,
    e: &E,
    message: String,
    extra: Vec<(&str, Value)>,
) -> PyErr {
    let build = || -> PyResult<PyErr> {
        let form = pythonize::pythonize(py, e).map_err(PyErr::from)?;
        let (kind, fields) = match form.extract::<String>() {
            Ok(kind) => (kind, None),
            Err(_) => {
                let variant = form.cast_into::<PyDict>()?;
                let Some((kind, fields)) = variant.iter().next() else {
                    return Ok(raise(py, Class::Internal, "Unknown", message.clone(), Vec::new()));
                };
                (kind.extract::<String>()?, fields.cast_into::<PyDict>().ok())
            }
        };
        let cls = py.import("wfem._errors")?.getattr(class.name())?;
        let kwargs = PyDict::new(py);
        for (name, value) in fields.iter().flat_map(|f| f.iter()) {
            match (name.extract::<String>()?.as_str(), value.extract::<(f64, f64)>()) {
                ("pole", Ok((re, im))) => kwargs.set_item(name, PyComplex::from_doubles(py, re, im))?,
                _ => kwargs.set_item(name, value)?,
            }
        }
        set_fields(&kwargs, extra)?;
        kwargs.set_item("kind", kind)?;
        Ok(PyErr::from_value(cls.call((message.clone(),), Some(&kwargs))?))
    };
    build().unwrap_or_else(|e| e)
}

/// A [`MeshError`] as a Python exception.
pub fn mesh(py: Python<'_>, e: &MeshError) -> PyErr {
    use MeshError::*;
    let class = match e {
        Io { .. } => Class::MeshFile,
        ScalarFieldLength { .. }
        | NonFiniteScalarField { .. }
        | FieldLength { .. }
        | NonFiniteValue { .. }
        | InvalidRepairOption { .. } => Class::InvalidInput,
        _ => Class::Mesh,
    };
    let extra = match e.remedy() {
        Some(r) => vec![("remedy", Value::Str(python_fix(r)))],
        None => Vec::new(),
    };
    raise_error_saying(py, class, e, e.message_with(&python_fix), extra)
}

/// A remedy in the Python package's words (the exception's `remedy` attribute).
pub fn python_fix(remedy: Remedy) -> String {
    match remedy {
        Remedy::DropUnreferencedVertices => "wfem.repair(V, F, drop_unreferenced_vertices=True)",
        Remedy::DropDegenerateFaces => "wfem.repair(V, F, drop_degenerate_faces=True, drop_unreferenced_vertices=True)",
        Remedy::DropDuplicateFaces => "wfem.repair(V, F, drop_duplicate_faces=True)",
        Remedy::OrientFaces => "wfem.repair(V, F, orient_faces=True)",
        Remedy::TriangulatePolygons => "wfem.read_mesh(path, triangulate=True) (fan triangulation)",
        Remedy::ScaleDown => "scale the coordinates down",
        other => other.in_library(),
    }
    .to_string()
}

/// A [`SolveError`] as a Python exception.
pub fn solve(py: Python<'_>, e: &SolveError) -> PyErr {
    use SolveError::*;
    let class = match e {
        DimensionMismatch { .. }
        | NotSquare { .. }
        | Empty
        | UnsupportedDegree { .. }
        | InvalidTime { .. }
        | NonFinite { .. }
        | NotSymmetric { .. }
        | BadDiagonal { .. }
        | MassNotPositiveDefinite { .. }
        | StiffnessIndefinite { .. }
        | InvalidParameter { .. } => Class::InvalidInput,
        NoConvergence { .. } | KrylovNoConvergence { .. } => Class::Convergence,
        _ => Class::Solver,
    };
    raise_error(py, class, e, Vec::new())
}

/// A [`HeatError`] as a Python exception.
pub fn heat(py: Python<'_>, e: &HeatError) -> PyErr {
    use HeatError::*;
    let class = match e {
        Solve(s) => return solve(py, s),
        Mesh(m) => return mesh(py, m),
        InvalidTime { .. }
        | LengthMismatch { .. }
        | NonFiniteInput { .. }
        | TooLargeForDense { .. }
        | InvalidParameter { .. }
        | MisplacedOption { .. }
        | InconsistentOperators { .. }
        | VertexOutOfRange { .. }
        | InvalidOperatorEntry { .. } => Class::InvalidInput,
        EigenNoConvergence { .. } | KrylovNoConvergence { .. } => Class::Convergence,
        IllConditionedInverse { .. } => Class::IllConditioned,
        _ => Class::Solver,
    };
    let mut extra = Vec::new();
    if let EigenNoConvergence { found, .. } = e {
        // The converged pairs are kept: `err.found` is an Eigenbasis of them.
        if let Ok(obj) = found_arrays(py, found) {
            extra.push(("found", Value::Object(obj)));
        }
    }
    raise_error(py, class, e, extra)
}

/// A [`RetrievalError`] as a Python exception.
pub fn retrieval(py: Python<'_>, e: &RetrievalError) -> PyErr {
    use RetrievalError::*;
    let class = match e {
        Heat(h) => return heat(py, h),
        Mesh(m) => return mesh(py, m),
        DimensionMismatch { .. }
        | Empty { .. }
        | NonFinite { .. }
        | InvalidParameter { .. }
        | MassRequired
        | TooFewDescriptors { .. }
        | VertexOutOfRange { .. }
        | Labels { .. }
        | UnknownShape { .. } => Class::InvalidInput,
        Storage { .. } | CorruptIndex { .. } => Class::Store,
        _ => Class::Retrieval,
    };
    raise_error(py, class, e, Vec::new())
}

/// A [`StoreError`] as a Python exception.
pub fn store(py: Python<'_>, e: &StoreError) -> PyErr {
    use StoreError::*;
    let class = match e {
        Dimension { .. } | NonFinite { .. } | DuplicateName { .. } | EmptyName { .. } | InvalidParameter { .. } => {
            Class::InvalidInput
        }
        NanDistance { .. } => Class::Retrieval,
        _ => Class::Store,
    };
    raise_error(py, class, e, Vec::new())
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
fn found_arrays(py: Python<'_>, basis: &wfem_heat::spectral::Eigenbasis) -> PyResult<Py<PyAny>> {
    let values = vec_out(py, basis.values.clone());
    let vectors = mat_out(py, basis.vectors.as_ref());
    Ok((values, vectors).into_pyobject(py)?.into_any().unbind())
}
