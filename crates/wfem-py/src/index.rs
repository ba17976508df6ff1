//! The retrieval index shared with the CLI: shape-retrieval's model (the default recipe of
//! `wfem retrieval build`) in retrieval-store's SQLite file (`retrieval_store::SqliteIndex`).
//! A file built here is queried by `wfem retrieval query` and vice versa.

use crate::convert::mesh_in;
use crate::errors::{invalid_param, Error};
use crate::run::run;
use mesh_fem::io::{load_shape, LoadOptions, Shape};
use mesh_fem::Laplacian;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use retrieval_store::SqliteIndex;
use shape_retrieval::eval::{evaluate_index, vocabulary_source, ClassRule};
use shape_retrieval::{IndexStore, JsonFile, RetrievalIndex, RetrievalSettings, VocabularyStore};
use std::path::PathBuf;
use wfem_choice::Choice;

/// Rust side of `wfem.RetrievalIndex`.
#[pyclass(name = "RetrievalIndex", module = "wfem._wfem", frozen)]
pub struct PyRetrievalIndex {
    path: PathBuf,
}

/// Meshes and point clouds, whichever each file holds (`mesh_fem::io::load_shape`).
fn read_all(paths: &[PathBuf]) -> Result<Vec<(String, Shape)>, Error> {
    paths
        .iter()
        .map(|p| Ok((p.display().to_string(), load_shape(p, &LoadOptions::default())?)))
        .collect()
}

/// The Laplacian of `laplacian=`, which must be `recorded` (an index's or a vocabulary's):
/// shapes described with another one would not be comparable with the stored ones.
fn same_laplacian(py: Python<'_>, laplacian: Option<&str>, recorded: Laplacian, whose: &str) -> PyResult<()> {
    if laplacian.is_none() {
        return Ok(());
    }
    let asked: Laplacian = crate::choices::parse(py, "laplacian", laplacian)?;
    if asked == recorded {
        return Ok(());
    }
    Err(invalid_param(
        py,
        "laplacian",
        format!(
            "{:?}: {whose} was built with the {:?} Laplacian, and shapes are described as its own were (omit laplacian=)",
            asked.name(),
            recorded.name()
        ),
    ))
}

fn open(path: &PathBuf) -> Result<RetrievalIndex, Error> {
    Ok(SqliteIndex::new(path).open()?.0)
}

#[pymethods]
impl PyRetrievalIndex {
    /// Indexes mesh and point-cloud files with the default recipe (spikes put back, rough and incoherent shapes
    /// denoised, holes closed, thin handles cut, SI-HKS in area units, z-scored, 96 words, soft
    /// assignment, capped area weights, spatially sensitive bags, χ²) into a new SQLite file; `vocabulary`: a vocabulary file of `wfem retrieval vocab` to reuse instead
    /// of training on these shapes (its descriptor settings, cleaning included, are used);
    /// `despike` / `fill_holes` / `denoise`: the spike threshold, the largest hole perimeter
    /// (in √area) and the target roughness, `None` for off; `overwrite`: replace an existing
    /// `out` (never an input); `laplacian`: the Laplacian of the meshes (a name of
    /// `mesh_fem::Laplacian`, default cotan; point clouds always use the robust one), which
    /// must be the vocabulary's when one is given.
    #[staticmethod]
    #[pyo3(signature = (paths, out, vocabulary=None, words=None, seed=0,
        despike=Some(mesh_fem::filter::DEFAULT_SPIKE_THRESHOLD),
        fill_holes=Some(mesh_fem::holes::DEFAULT_MAX_HOLE_PERIMETER),
        denoise=Some(shape_retrieval::DEFAULT_TARGET_ROUGHNESS), overwrite=false,
        spatial=Some(shape_retrieval::spatial::DEFAULT_SPATIAL_TIME), laplacian=None))]
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
        laplacian: Option<&str>,
    ) -> PyResult<Self> {
        let path = out.clone();
        let chosen: Laplacian = crate::choices::parse(py, "laplacian", laplacian)?;
        let (inputs, target) = (paths.clone(), out.clone());
        let vocabulary = run(py, move |_| {
            let inputs: Vec<&std::path::Path> = inputs.iter().chain(&vocabulary).map(PathBuf::as_path).collect();
            shape_retrieval::check_index_output(&target, &inputs, overwrite)?;
            Ok(vocabulary.map(|v| JsonFile::new(v).load_vocabulary()).transpose()?)
        })?;
        if let Some(v) = &vocabulary {
            same_laplacian(py, laplacian, v.descriptor().laplacian, "the vocabulary")?;
        }
        run(py, move |_| {
            let mut settings = RetrievalSettings::default();
            if let Some(w) = words {
                settings.training.words = w;
            }
            settings.training.seed = seed;
            settings.descriptor.despiking = despike.map(|threshold| shape_retrieval::Despiking { threshold });
            settings.descriptor.hole_filling =
                fill_holes.map(|max_perimeter| shape_retrieval::HoleFilling { max_perimeter });
            settings.descriptor.denoising = denoise.map(|roughness| shape_retrieval::Denoising {
                roughness,
                ..Default::default()
            });
            settings.bags.spatial = spatial.map(|time| shape_retrieval::spatial::SpatialBag { time });
            settings.descriptor.laplacian = chosen;
            match &vocabulary {
                Some(v) => shape_retrieval::limits::check_sizes(v.descriptor().eigenpairs, v.vocabulary().size())?,
                None => shape_retrieval::limits::check_sizes(settings.descriptor.eigenpairs, settings.training.words)?,
            }
            let meshes = read_all(&paths)?;
            let index = RetrievalIndex::build(&meshes, &settings, vocabulary)?;
            SqliteIndex::new(&out).save_index(&index)?;
            Ok(())
        })?;
        Ok(Self { path })
    }

    /// Opens an index file (written by `build` here or by `wfem retrieval build`).
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let p = path.clone();
        run(py, move |_| open(&p).map(|_| ()))?;
        Ok(Self { path })
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
        run(py, move |_| Ok(shape_retrieval::index_settings(&open(&path)?)?))
    }

    /// Appends mesh or point-cloud files (bags from the stored vocabulary, described with the
    /// index's Laplacian; one transaction; nothing rebuilt).
    fn add_paths(&self, py: Python<'_>, paths: Vec<PathBuf>) -> PyResult<usize> {
        let path = self.path.clone();
        run(py, move |_| {
            let index = SqliteIndex::new(&path);
            let settings = index.open()?.0;
            let entries = read_all(&paths)?
                .iter()
                .map(|(name, mesh)| settings.describe(name, mesh))
                .collect::<Result<Vec<_>, _>>()?;
            index.append(&settings, &entries)?;
            Ok(entries.len())
        })
    }

    /// The k nearest indexed shapes to a mesh (`v`, `f`) or a point cloud (`v` alone):
    /// [(name, distance)], nearest first. The query is described with the index's Laplacian;
    /// `laplacian`, if given, must name it.
    #[pyo3(signature = (v, f=None, k=10, laplacian=None))]
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
        let path = self.path.clone();
        if laplacian.is_some() {
            let p = path.clone();
            let recorded = run(py, move |_| Ok(open(&p)?.vocabulary().descriptor().laplacian))?;
            same_laplacian(py, laplacian, recorded, "the index")?;
        }
        run(py, move |_| {
            let index = SqliteIndex::new(&path);
            let (settings, store) = index.open()?;
            let shape: shape_retrieval::ShapeRef<'_> = match &shape {
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
