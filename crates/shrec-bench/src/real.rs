//! Real labelled collections nobody on this project made — SHREC'11 non-rigid (the 500-face
//! copy) — and TOSCA-76, evaluated with [`shape_retrieval::eval`] (`cargo xtask real-eval`,
//! docs/RETRIEVAL-RESULTS.md), beside a Shape-DNA baseline computed here.
//!
//! **Shape-DNA baseline** (Reuter et al. 2006, with Weyl's normalisation): the first m = 40
//! non-zero eigenvalues of (L, D) — L the cotangent stiffness (symmetric positive
//! semidefinite), D the lumped Voronoi mass (paper, Eq. (7)) — of the mesh as it is (no
//! cleaning), times the surface area A and divided by their Weyl growth,
//! `g_i = λ_i A / (4π i)`, i = 1 … m, compared with the Euclidean distance. It needs no
//! vocabulary: the 30-line method every descriptor here has to beat. A point cloud
//! ([`ShapeFile::cloud`]) gets the same with its robust L and the Voronoi lumped mass of its
//! intrinsic triangulation.

use crate::protocol::{self, EigenCache, ShapeFile};
use crate::BenchError;
use faer::Mat;
use rayon::prelude::*;
use shape_retrieval::descriptor::{DescriptorParams, ShapeDescriptors};
use shape_retrieval::eval::{evaluate_distances, evaluate_index, EvalReport};
use shape_retrieval::model::{DescriptorSettings, RetrievalSettings, ShapeFeatures};
use std::path::Path;

/// The SHREC'11 folder of the corpus (`labels.csv` = `file,class`).
pub const SHREC11_DIR: &str = "shrec11-meshcnn500";

/// Eigenvalues of the Shape-DNA baseline.
pub const SHAPE_DNA_EIGENVALUES: usize = 40;

/// The 600 SHREC'11 shapes with their classes (family = class), in the order of `labels.csv`.
///
/// # Errors
/// [`BenchError::Data`] if the label file cannot be read or parsed.
pub fn shrec11_files(meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    let dir = meshes_dir.join(SHREC11_DIR);
    let labels = dir.join("labels.csv");
    let text = std::fs::read_to_string(&labels).map_err(|e| BenchError::Data(format!("{}: {e}", labels.display())))?;
    let pairs = shape_retrieval::eval::parse_labels(&text, &labels.display().to_string())
        .map_err(|e| BenchError::Data(e.to_string()))?;
    Ok(pairs
        .into_iter()
        .map(|(file, class)| ShapeFile {
            path: dir.join(&file),
            name: file,
            family: class,
            transform: None,
            strength: 0,
            cloud: None,
        })
        .collect())
}

/// TOSCA's non-isometric set (`tosca-bcicp-5k/TOSCA_nonIsometric`, 24 shapes), family = the
/// body (`8_gorilla_01` → `gorilla`), sorted by name.
///
/// # Errors
/// [`BenchError::Data`] if the folder cannot be read or holds no `.off` file.
pub fn noniso_files(meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    let dir = meshes_dir.join("tosca-bcicp-5k").join("TOSCA_nonIsometric");
    let mut out: Vec<ShapeFile> = std::fs::read_dir(&dir)
        .map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().and_then(|x| x.to_str()) == Some("off"))
        .filter_map(|path| {
            let name = path.file_stem()?.to_str()?.to_string();
            let family = name.split('_').nth(1)?.to_string();
            Some(ShapeFile {
                path,
                name,
                family,
                transform: None,
                strength: 0,
                cloud: None,
            })
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    if out.is_empty() {
        return Err(BenchError::Data(format!("no .off file in {}", dir.display())));
    }
    Ok(out)
}

/// The 20 SHREC'07 four-legged animals (`shrec07-fourleg/`), one class `fourleg`: 20 different
/// animals, a class of shapes that are alike but not isometric, and distractors for the others.
///
/// # Errors
/// [`BenchError::Data`] if the folder cannot be read.
pub fn fourleg_files(meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    let dir = meshes_dir.join("shrec07-fourleg");
    let mut out: Vec<ShapeFile> = std::fs::read_dir(&dir)
        .map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().and_then(|x| x.to_str()) == Some("off"))
        .map(|path| ShapeFile {
            name: format!(
                "shrec07-fourleg/{}",
                path.file_name().map(|s| s.to_string_lossy()).unwrap_or_default()
            ),
            path,
            family: "fourleg".into(),
            transform: None,
            strength: 0,
            cloud: None,
        })
        .collect();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// Vertices of each shape of a remeshed collection ([`remeshed_files`]): the resolution of the
/// held-out people of issue #42.
pub const REMESH_VERTICES: usize = 10_000;

/// The seed of a remeshed collection (mixed with each shape's name).
pub const REMESH_SEED: u64 = 42;

/// `files` remeshed one by one ([`crate::transform::remesh`] to `target` vertices, seed
/// [`REMESH_SEED`] mixed with the shape's name, so every shape gets its own triangulation,
/// whatever the order), written to `dir` as `NAME.off` unless already there; names and
/// classes as in `files`. Point-cloud entries stay clouds of the remeshed file.
///
/// # Errors
/// The first unreadable file or failed remeshing, naming it; [`BenchError::Data`] if `dir`
/// cannot be made or written.
pub fn remeshed_files(files: &[ShapeFile], dir: &Path, target: usize) -> Result<Vec<ShapeFile>, BenchError> {
    std::fs::create_dir_all(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
    files
        .par_iter()
        .map(|file| {
            let stem = file.name.replace(['/', '\\'], "_");
            let path = dir.join(format!("{stem}.off"));
            if !path.is_file() {
                let (mesh, _): (mesh_fem::TriMesh, _) = mesh_fem::io::load(&file.path, &Default::default())?;
                let mut h = crate::Fnv1a::new();
                h.eat(file.name.bytes());
                let remeshed = crate::transform::remesh(&mesh, target, REMESH_SEED ^ h.0)
                    .map_err(|e| BenchError::Data(format!("{}: {e}", file.name)))?;
                mesh_fem::io::write_mesh(&path, &remeshed).map_err(|e| BenchError::Data(e.to_string()))?;
            }
            Ok(ShapeFile { path, ..file.clone() })
        })
        .collect()
}

/// A collection loaded and described with one settings: the features of every shape, ready to
/// be indexed with any vocabulary.
pub struct Described {
    /// The files (their family is the class).
    pub files: Vec<ShapeFile>,
    /// The features, in file order.
    pub features: Vec<ShapeFeatures>,
}

/// Loads and describes `files` with `settings` (eigenbases from `cache`).
///
/// # Errors
/// The first failure, naming the shape.
pub fn describe(
    files: Vec<ShapeFile>,
    settings: &RetrievalSettings,
    cache: &EigenCache,
) -> Result<Described, BenchError> {
    let mut shapes = protocol::load_shapes(files.clone(), &settings.descriptor, cache)?;
    let features = protocol::features(&mut shapes, settings, cache)?;
    Ok(Described { files, features })
}

/// Indexes described shapes with a vocabulary (trained on them when `vocabulary` is `None`,
/// seed of the settings) and evaluates the index leave-one-out from the stored signatures.
///
/// # Errors
/// The first failure.
pub fn evaluate(
    described: &Described,
    settings: &RetrievalSettings,
    vocabulary: Option<&shape_retrieval::model::VocabularyModel>,
    vocabulary_note: &str,
) -> Result<EvalReport, BenchError> {
    let trained;
    let vocabulary = match vocabulary {
        Some(v) => v,
        None => {
            trained = protocol::train(settings, &described.features)?;
            &trained
        }
    };
    let index = protocol::index(vocabulary, settings, &described.features)?;
    let classes: Vec<String> = described.files.iter().map(|f| f.family.clone()).collect();
    evaluate_index(&index, &classes, vocabulary_note).map_err(BenchError::retrieval("evaluation"))
}

/// The Shape-DNA baseline of the module docs on `files` (eigenbases of (L, D) from `cache`).
///
/// # Errors
/// The first unreadable mesh or failed eigensolve, naming the file.
pub fn shape_dna_baseline(files: &[ShapeFile], cache: &EigenCache) -> Result<EvalReport, BenchError> {
    let signatures = shape_dna_signatures(files, cache)?;
    let n = files.len();
    let distances = Mat::from_fn(n, n, |i, j| {
        signatures[i]
            .iter()
            .zip(&signatures[j])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt()
    });
    let names: Vec<String> = files.iter().map(|f| f.name.clone()).collect();
    let classes: Vec<String> = files.iter().map(|f| f.family.clone()).collect();
    evaluate_distances(&names, &classes, distances.as_ref(), "none (no vocabulary)")
        .map_err(BenchError::retrieval("Shape-DNA baseline"))
}

/// The baseline's signatures of `files` (in order).
///
/// # Errors
/// The first unreadable mesh or failed eigensolve, naming the file.
pub fn shape_dna_signatures(files: &[ShapeFile], cache: &EigenCache) -> Result<Vec<Vec<f64>>, BenchError> {
    let settings = DescriptorSettings {
        eigenpairs: SHAPE_DNA_EIGENVALUES + 1,
        despiking: None,
        denoising: None,
        hole_filling: None,
        topology_repair: None,
        ..Default::default()
    };
    let signatures: Vec<Vec<f64>> = files
        .par_iter()
        .map(|file| {
            let wrap = BenchError::retrieval(file.name.clone());
            let params = DescriptorParams {
                eigenpairs: settings.eigenpairs,
                ..Default::default()
            };
            let mut shape = match file.load()? {
                mesh_fem::io::Shape::Mesh(mesh, _) => ShapeDescriptors::new(&mesh, &params),
                mesh_fem::io::Shape::Cloud(cloud) => ShapeDescriptors::from_cloud(&cloud, &params),
            }
            .map_err(wrap)?;
            cache.fill_as(&file.path, &mut shape, true, &settings, file.cloud.is_some())?;
            let area = shape.area();
            let basis = shape
                .eigenbasis(true)
                .map_err(BenchError::retrieval(file.name.clone()))?;
            Ok(weyl_shape_dna(&basis.values, area, SHAPE_DNA_EIGENVALUES))
        })
        .collect::<Result<_, BenchError>>()?;
    Ok(signatures)
}

/// `λ_i A / (4π i)`, i = 1 … m, of ascending eigenvalues (λ₀ = 0 skipped; missing ones are 0).
pub fn weyl_shape_dna(values: &[f64], area: f64, m: usize) -> Vec<f64> {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    (1..=m)
        .map(|i| {
            v.get(i)
                .map_or(0.0, |&l| shape_retrieval::global::Measure::Area(area).weyl_ratio(l, i))
        })
        .collect()
}
