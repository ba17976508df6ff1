//! The retrieval index shared with the CLI: shape-retrieval's model (the default recipe of
//! `wfem retrieval build`) in retrieval-store's SQLite file (`retrieval_store::index::SqliteIndex`).
//! A file built here is queried by `wfem retrieval query` and vice versa.

use crate::convert::mesh_in;
use crate::errors::Error;
use crate::run::{run, run_reporting, Progress};
use mesh_fem::io::{load_shape, LoadOptions, Shape};
use mesh_fem::Laplacian;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use retrieval_store::index::SqliteIndex;
use shape_retrieval::collection::{build_index, describe_entries, Refusal, Tolerance};
use shape_retrieval::eval::{evaluate_index, vocabulary_source, ClassRule};
use shape_retrieval::model::{RetrievalIndex, RetrievalSettings};
use shape_retrieval::store::{IndexStore, JsonFile, VocabularyStore};
use shape_retrieval::RetrievalError;
use std::path::PathBuf;
use wfem_base::Choice;

/// Rust side of `wfem.RetrievalIndex`.
#[pyclass(name = "RetrievalIndex", module = "wfem._wfem", frozen)]
pub struct PyRetrievalIndex {
    path: PathBuf,
}

/// Files of a collection left out, with why (`(file, reason)`, in input order).
type Refused = Vec<(String, String)>;

/// Reads every file, a mesh or a point cloud (`mesh_fem::io::load_shape`); one that cannot be
/// read is refused (or, strict, the error).
fn read_all(
    paths: &[PathBuf],
    tolerance: Tolerance,
    progress: &Progress,
) -> Result<(Vec<(String, Shape)>, Refused), Error> {
    let mut meshes = Vec::with_capacity(paths.len());
    let mut refused = Refused::new();
    for p in paths {
        let name = p.display().to_string();
        match load_shape(p, &LoadOptions::default()) {
            Ok(shape) => meshes.push((name, shape)),
            Err(e) if tolerance == Tolerance::Skip => {
                // A refused file is a finished step too: the bar counts every file.
                progress.step(&name);
                refused.push((name, e.to_string()));
            }
            Err(e) => return Err(e.into()),
        }
    }
    Ok((meshes, refused))
}

fn tolerance(strict: bool) -> Tolerance {
    if strict {
        Tolerance::Strict
    } else {
        Tolerance::Skip
    }
}

/// Adds the library's refusals to the files that could not be read, in the order of `paths`;
/// no usable shape left is the error naming every file.
fn merge_refused(
    paths: &[PathBuf],
    mut refused: Refused,
    left_out: Vec<Refusal>,
    kept: usize,
) -> Result<Refused, Error> {
    refused.extend(left_out.into_iter().map(|r| (r.name, r.reason.to_string())));
    let order: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    refused.sort_by_key(|(name, _)| order.iter().position(|o| o == name));
    if kept == 0 && !refused.is_empty() {
        let reasons: Vec<String> = refused.iter().map(|(f, why)| format!("{f}: {why}")).collect();
        return Err(RetrievalError::NothingUsable {
            shapes: refused.len(),
            reasons: reasons.join("; "),
        }
        .into());
    }
    Ok(refused)
}

/// `laplacian=` must name `recorded` (an index's or a vocabulary's Laplacian): shapes described
/// with another one would not be comparable with the stored ones.
fn same_laplacian(asked: Option<Laplacian>, recorded: Laplacian, whose: &str) -> Result<(), Error> {
    match asked {
        Some(asked) if asked != recorded => Err(Error::Invalid(
            "InvalidParameter",
            format!(
                "invalid parameter `laplacian`: {:?}, but {whose} was built with the {:?} Laplacian and shapes are described as its own were (omit laplacian=)",
                asked.name(),
                recorded.name()
            ),
        )),
        _ => Ok(()),
    }
}

/// The Laplacian a `laplacian=` names, if given (parsed with the registry's names).
fn laplacian_arg(py: Python<'_>, laplacian: Option<&str>) -> PyResult<Option<Laplacian>> {
    laplacian
        .map(|name| crate::choices::parse::<Laplacian>(py, "laplacian", Some(name)))
        .transpose()
}

fn open(path: &PathBuf) -> Result<RetrievalIndex, Error> {
    Ok(SqliteIndex::new(path).open()?.0)
}

#[pymethods]
impl PyRetrievalIndex {
    /// Indexes mesh and point-cloud files with the default recipe (spikes put back, rough and incoherent shapes
    /// denoised, holes closed, thin handles cut, SI-HKS in area units, z-scored, 512 words, soft
    /// assignment, capped area weights, χ²) into a new SQLite file; `vocabulary`: a vocabulary file of `wfem retrieval vocab` to reuse instead
    /// of training on these shapes (its descriptor settings, cleaning included, are used);
    /// `despike` / `fill_holes` / `denoise` / `refine`: the spike threshold, the largest hole
    /// perimeter (in √area), the target roughness and the vertices per eigenpair below which
    /// a mesh is refined, `None` for off; `overwrite`: replace an existing
    /// `out` (never an input); `laplacian`: the Laplacian of the meshes (a name of
    /// `mesh_fem::Laplacian`, default cotan; point clouds always use the robust one), recorded
    /// in the index, which must be the vocabulary's when one is given.
    #[staticmethod]
    #[pyo3(signature = (paths, out, vocabulary=None, words=None, seed=shape_retrieval::model::TrainingParams::default().seed,
        despike=Some(shape_retrieval::model::DEFAULT_SPIKE_THRESHOLD),
        fill_holes=Some(shape_retrieval::model::DEFAULT_MAX_HOLE_PERIMETER),
        denoise=Some(shape_retrieval::model::DEFAULT_TARGET_ROUGHNESS), overwrite=false,
        spatial=shape_retrieval::model::BagSettings::default().spatial.map(|s| s.time), strict=false, progress=None,
        laplacian=None, spatial_groups=None,
        refine=Some(shape_retrieval::model::DEFAULT_VERTICES_PER_EIGENPAIR)))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        paths: Vec<PathBuf>,
        out: PathBuf,
        vocabulary: Option<PathBuf>,
        words: Option<usize>,
        seed: u64,
        despike: Option<f64>,
        fill_holes: Option<f64>,
        denoise: Option<f64>,
        overwrite: bool,
        spatial: Option<f64>,
        strict: bool,
        progress: Option<Py<PyAny>>,
        laplacian: Option<&str>,
        spatial_groups: Option<usize>,
        refine: Option<f64>,
    ) -> PyResult<(Self, Refused)> {
        let path = out.clone();
        let asked = laplacian_arg(py, laplacian)?;
        let refused = run_reporting(py, progress, move |cancel, progress| {
            let inputs: Vec<&std::path::Path> = paths.iter().chain(&vocabulary).map(PathBuf::as_path).collect();
            shape_retrieval::check_index_output(&out, &inputs, overwrite)?;
            let mut settings = RetrievalSettings::default();
            if let Some(w) = words {
                settings.training.words = w;
            }
            settings.training.seed = seed;
            settings.descriptor.despiking = despike.map(|threshold| shape_retrieval::model::Despiking { threshold });
            settings.descriptor.hole_filling =
                fill_holes.map(|max_perimeter| shape_retrieval::model::HoleFilling { max_perimeter });
            settings.descriptor.refinement =
                refine.map(|vertices_per_eigenpair| shape_retrieval::model::Refinement { vertices_per_eigenpair });
            settings.descriptor.denoising = denoise.map(|roughness| shape_retrieval::model::Denoising {
                roughness,
                ..Default::default()
            });
            if spatial.is_none() && spatial_groups.is_some() {
                return Err(shape_retrieval::RetrievalError::InvalidParameter {
                    name: "spatial_groups",
                    value: spatial_groups.unwrap_or(0) as f64,
                    reason: "needs spatially sensitive bags (spatial=…)",
                }
                .into());
            }
            settings.bags.spatial = spatial.map(|time| shape_retrieval::spatial::SpatialBag {
                time,
                groups: spatial_groups,
            });
            settings.descriptor.laplacian = asked.unwrap_or_default();
            let vocabulary = vocabulary.map(|v| JsonFile::new(v).load_vocabulary()).transpose()?;
            if let Some(v) = &vocabulary {
                same_laplacian(asked, v.descriptor().laplacian, "the vocabulary")?;
            }
            match &vocabulary {
                Some(v) => shape_retrieval::limits::check_sizes(v.descriptor().eigenpairs, v.vocabulary().size())?,
                None => shape_retrieval::limits::check_sizes(settings.descriptor.eigenpairs, settings.training.words)?,
            }
            let (meshes, refused) = read_all(&paths, tolerance(strict), progress)?;
            if meshes.is_empty() {
                merge_refused(&paths, refused, Vec::new(), 0)?;
                return Err(RetrievalError::Empty { what: "paths" }.into());
            }
            let built = build_index(&meshes, &settings, vocabulary, tolerance(strict), &|name| {
                progress.step(name)
            });
            let (index, left_out) = match built {
                // Every read file refused too: name the unreadable ones as well.
                Err(RetrievalError::NothingUsable { shapes, reasons }) if !refused.is_empty() => {
                    let mut all: Vec<String> = refused.iter().map(|(f, why)| format!("{f}: {why}")).collect();
                    all.push(reasons);
                    return Err(RetrievalError::NothingUsable {
                        shapes: shapes + refused.len(),
                        reasons: all.join("; "),
                    }
                    .into());
                }
                other => other?,
            };
            let refused = merge_refused(&paths, refused, left_out, index.entries().len())?;
            // An interrupted call (Ctrl-C, a raising progress callback) writes nothing.
            progress.flush();
            cancel.check()?;
            SqliteIndex::new(&out).save_index(&index)?;
            Ok(refused)
        })?;
        Ok((Self { path }, refused))
    }

    /// Opens an index file (written by `build` here or by `wfem retrieval build`).
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let p = path.clone();
        run(py, move |_| open(&p).map(|_| ()))?;
        Ok(Self { path })
    }

    /// Verifies the index file at `path` (every record against its checksum, the settings,
    /// every bag) and reports all damage.
    #[staticmethod]
    fn check(py: Python<'_>, path: PathBuf) -> PyResult<crate::store::CheckTuple> {
        run(py, move |_| {
            Ok(crate::store::check_tuple(SqliteIndex::new(&path).check()?))
        })
    }

    /// The file.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// The indexed names, in insertion order.
    fn names(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let path = self.path.clone();
        run(py, move |_| {
            let (_, store) = SqliteIndex::new(&path).open()?;
            Ok(store.shapes()?.into_iter().map(|s| s.name).collect())
        })
    }

    /// The recipe recorded in the file (descriptor, window, words, distance, …) as JSON.
    fn settings(&self, py: Python<'_>) -> PyResult<String> {
        let path = self.path.clone();
        run(py, move |_| Ok(shape_retrieval::store::index_settings(&open(&path)?)?))
    }

    /// Appends mesh or point-cloud files (bags from the stored vocabulary, described with the
    /// index's Laplacian; one transaction; nothing rebuilt);
    /// returns how many were added and the refused files (`strict`: the first failure instead).
    #[pyo3(signature = (paths, strict=false, progress=None))]
    fn add_paths(
        &self,
        py: Python<'_>,
        paths: Vec<PathBuf>,
        strict: bool,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<(usize, Refused)> {
        let path = self.path.clone();
        run_reporting(py, progress, move |cancel, progress| {
            let index = SqliteIndex::new(&path);
            let settings = index.open()?.0;
            let (meshes, refused) = read_all(&paths, tolerance(strict), progress)?;
            let (entries, left_out) =
                describe_entries(&settings, &meshes, tolerance(strict), &|name| progress.step(name))?;
            let refused = merge_refused(&paths, refused, left_out, entries.len())?;
            progress.flush();
            cancel.check()?;
            index.append(&settings, &entries)?;
            Ok((entries.len(), refused))
        })
    }

    /// The k nearest indexed shapes to a mesh (`v`, `f`) or a point cloud (`v` alone):
    /// [(name, distance)], nearest first. The query is described with the index's Laplacian;
    /// `laplacian`, if given, must name it.
    #[pyo3(signature = (v, f=None, k=shape_retrieval::model::DEFAULT_RESULTS, laplacian=None))]
    fn query<'py>(
        &self,
        py: Python<'py>,
        v: PyReadonlyArray2<'py, f64>,
        f: Option<PyReadonlyArray2<'py, i64>>,
        k: usize,
        laplacian: Option<&str>,
    ) -> PyResult<Vec<(String, f64)>> {
        // A mesh, or (no F) a point cloud.
        let shape = match &f {
            Some(f) => Ok(mesh_in(py, &v, f)?),
            None => Err(crate::cloud::cloud_in(py, &v, None)?.0),
        };
        let asked = laplacian_arg(py, laplacian)?;
        let path = self.path.clone();
        run(py, move |_| {
            let index = SqliteIndex::new(&path);
            let (settings, store) = index.open()?;
            same_laplacian(asked, settings.vocabulary().descriptor().laplacian, "the index")?;
            let shape: shape_retrieval::model::ShapeRef<'_> = match &shape {
                Ok(mesh) => mesh.into(),
                Err(cloud) => cloud.into(),
            };
            let query = settings.describe("query", &shape)?;
            Ok(index
                .search(&settings, &store, &query.signature, k)?
                .into_iter()
                .map(|h| (h.name, h.distance))
                .collect())
        })
    }

    /// The k indexed shapes nearest to the indexed shape `name` (its stored name, file name or
    /// stem: `shape_retrieval::model::resolve_name`), ranked from its stored signature with the
    /// shape itself left out; nothing is read or described (`wfem retrieval query INDEX --id
    /// NAME`). Returns the stored name `name` resolved to and [(name, distance)], nearest first.
    #[pyo3(signature = (name, k=shape_retrieval::model::DEFAULT_RESULTS))]
    fn query_id(&self, py: Python<'_>, name: String, k: usize) -> PyResult<(String, Vec<(String, f64)>)> {
        let path = self.path.clone();
        run(py, move |_| {
            let index = SqliteIndex::new(&path);
            let (settings, store) = index.open()?;
            let (resolved, hits) = index.search_stored(&settings, &store, &name, k)?;
            Ok((resolved, hits.into_iter().map(|h| (h.name, h.distance)).collect()))
        })
    }

    /// Leave-one-out evaluation of the indexed shapes from their stored signatures
    /// (`shape_retrieval::eval`): `classes[i]` labels the i-th indexed name, or, without
    /// `classes`, each name's class by `class_from` (a `ClassRule`). Returns the report as JSON
    /// and as the text of `wfem retrieval eval`.
    #[pyo3(signature = (classes=None, class_from=None))]
    fn evaluate(
        &self,
        py: Python<'_>,
        classes: Option<Vec<String>>,
        class_from: Option<String>,
    ) -> PyResult<(String, String)> {
        let rule: ClassRule = crate::choices::parse(py, "class_from", class_from.as_deref())?;
        let path = self.path.clone();
        run(py, move |_| {
            let index = SqliteIndex::new(&path).load_index()?;
            let classes = match classes {
                Some(c) => c,
                None => index
                    .entries()
                    .iter()
                    .map(|e| rule.class_of(std::path::Path::new(&e.name)))
                    .collect::<Result<_, _>>()?,
            };
            let report = evaluate_index(&index, &classes, &vocabulary_source(&index))?;
            let json = serde_json::to_string(&report).map_err(|e| shape_retrieval::RetrievalError::Storage {
                path: path.clone(),
                reason: e.to_string(),
            })?;
            Ok((json, report.to_text()))
        })
    }

    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        let path = self.path.clone();
        run(py, move |_| Ok(SqliteIndex::new(&path).open()?.1.len()?))
    }
}

/// Registers the class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRetrievalIndex>()
}
