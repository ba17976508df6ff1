//! Retrieval protocols: SHREC'10's cumulative "strength ≤ s" mAP, queries against a clean
//! collection, and leave-one-out retrieval on TOSCA-76.
//!
//! Average precision of one query q over its ranked list (the query itself excluded):
//! `AP(q) = (1/R_q) Σ_k P_q(k)·rel_q(k)` ([`shape_retrieval::retrieval::average_precision`]); mAP is its
//! mean over the queries.
//!
//! * **SHREC'10, cumulative** ([`shrec_protocol`]). The column "≤ s" of the paper's Table 5: the
//!   database is the null shapes and every transformed shape of strength ≤ s (all classes), the
//!   queries are the transformed shapes of strength ≤ s, and an item is relevant to a query if it
//!   comes from the same null shape. A shape of strength 5 is therefore not in the database of
//!   column "≤ 1" (it would count, as relevant, against every clean query). The report also gives
//!   the same queries against the full database (every strength), for reference.
//! * **Against a clean collection** ([`ShrecReport::cumulative_clean`]): the same queries ranked against the
//!   76 clean TOSCA shapes; relevant = the TOSCA shapes of the query's family (class).
//! * **TOSCA-76** ([`leave_one_out`]): every shape queries the other 75; relevant = same class
//!   (name without its trailing digits).

use crate::synth::{Class, Manifest};
use crate::BenchError;
use faer::Mat;
use mesh_fem::TriMesh;
use rayon::prelude::*;
use shape_retrieval::descriptor::{Descriptor, ShapeDescriptors};
use shape_retrieval::model::{DescriptorSettings, RetrievalIndex, RetrievalSettings, ShapeFeatures, VocabularyModel};
use shape_retrieval::retrieval::average_precision;
use std::io::Read;
use std::path::{Path, PathBuf};
use wfem_base::rng::SplitMix64;
use wfem_heat::spectral::Eigenbasis;

/// The paper's Table 5 (mAP in %, strength ≤ 1 … ≤ 5): method, description, values.
pub const PAPER_TABLE5: [(&str, &str, [f64; 5]); 10] = [
    (
        "VS1",
        "clock matching BoF, modified manifold ranking",
        [95.92, 90.81, 86.48, 81.94, 77.78],
    ),
    ("VS2", "clock matching BoF", [99.03, 97.73, 96.71, 95.66, 94.33]),
    ("VS3", "geodesic sphere multi-view", [96.93, 93.89, 92.24, 90.56, 89.29]),
    (
        "PB1",
        "part-based BoW, large vocabulary",
        [95.28, 92.11, 88.41, 85.06, 82.20],
    ),
    (
        "PB2",
        "part-based BoW, training-set vocabulary",
        [94.64, 90.52, 86.19, 82.35, 78.72],
    ),
    (
        "PB3",
        "part-based BoW, test-set vocabulary",
        [94.25, 90.16, 86.09, 82.78, 79.57],
    ),
    (
        "SG1",
        "Shape Google, HKS, Voronoi-cot",
        [94.94, 93.12, 90.84, 87.82, 85.00],
    ),
    ("SG2", "Shape Google, HKS, wFEM", [95.73, 93.81, 90.46, 87.40, 84.71]),
    (
        "SG3",
        "Shape Google, SI-HKS, Voronoi-cot",
        [97.05, 95.16, 94.03, 92.54, 90.79],
    ),
    (
        "SS1",
        "HKS, 96-bit similarity-sensitive hash",
        [99.84, 99.48, 99.30, 99.10, 98.27],
    ),
];

/// A mesh file of an evaluation collection with its labels.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeFile {
    /// The file.
    pub path: PathBuf,
    /// A name for reports.
    pub name: String,
    /// Its family: the TOSCA class or the null shape it comes from (`cat`, `david`, …).
    pub family: String,
    /// Its SHREC transformation (`None` for a clean shape).
    pub transform: Option<Class>,
    /// Its strength (0 for a clean shape).
    pub strength: u8,
    /// Described as a point cloud sampled from the file's mesh instead of the mesh itself
    /// (`None`: the mesh).
    pub cloud: Option<CloudSampling>,
}

/// How a mesh file becomes a point cloud: `points` points uniformly distributed on its surface
/// ([`mesh_fem::cloud::sample_surface`]), drawn by the workspace's generator seeded with
/// `seed` and the file's name (so every shape has its own stream, whatever the order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CloudSampling {
    /// Number of points.
    pub points: usize,
    /// Seed (mixed with the name).
    pub seed: u64,
}

/// The points of the issue #27 evaluation: TOSCA-76 as clouds of 5,000 points.
pub const DEFAULT_CLOUD_POINTS: usize = 5000;

impl ShapeFile {
    /// The same file described as a point cloud of `sampling` (named `NAME-cloud`, same family).
    pub fn as_cloud(&self, sampling: CloudSampling) -> ShapeFile {
        ShapeFile {
            name: format!("{}-cloud", self.name),
            cloud: Some(sampling),
            ..self.clone()
        }
    }

    /// What is described: the mesh of the file, or the point cloud sampled from it.
    ///
    /// # Errors
    /// [`BenchError::Mesh`] for an unreadable file or a mesh that cannot be sampled.
    pub fn load(&self) -> Result<mesh_fem::io::Shape, BenchError> {
        let (mesh, report): (TriMesh, _) = mesh_fem::io::load(&self.path, &Default::default())?;
        let Some(sampling) = self.cloud else {
            return Ok(mesh_fem::io::Shape::Mesh(mesh, report));
        };
        let mut h = crate::Fnv1a::new();
        h.eat(self.name.bytes());
        let mut rng = SplitMix64::new(sampling.seed ^ h.0);
        let cloud = mesh_fem::cloud::sample_surface(&mesh, sampling.points, &mut || rng.next_f64())?;
        Ok(mesh_fem::io::Shape::Cloud(cloud))
    }
}

/// A loaded shape: its labels and its operators with the wFEM eigenbasis computed (or cached).
#[derive(Debug)]
pub struct BenchShape {
    /// Labels.
    pub file: ShapeFile,
    /// Operators and eigenbases.
    pub shape: ShapeDescriptors,
    /// Dense descriptors already computed, by descriptor settings: the methods of one evaluation
    /// share descriptors and differ in the vocabulary or the bags, and the SI-HKS of ~500 shapes
    /// is the bulk of a method's cost.
    descriptors: Vec<(DescriptorSettings, Mat<f64>)>,
}

/// The family of a TOSCA shape name: the name without its trailing digits (`michael12` →
/// `michael`; `cat0` → `cat`).
pub fn family(name: &str) -> String {
    name.trim_end_matches(|c: char| c.is_ascii_digit()).to_string()
}

/// The 76 shapes of `tosca-bcicp-5k/TOSCA_Isometric` under the corpus folder, sorted by name.
///
/// # Errors
/// [`BenchError::Data`] if the folder cannot be read or holds no `.off` file.
pub fn tosca_files(meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    let dir = meshes_dir.join("tosca-bcicp-5k").join("TOSCA_Isometric");
    let mut out = off_files(&dir)?
        .into_iter()
        .map(|(path, name)| ShapeFile {
            family: family(&name),
            path,
            name,
            transform: None,
            strength: 0,
            cloud: None,
        })
        .collect::<Vec<_>>();
    out.sort_by(|a, b| a.name.cmp(&b.name));
    if out.is_empty() {
        return Err(BenchError::Data(format!("no .off file in {}", dir.display())));
    }
    Ok(out)
}

/// Closed meshes of the corpus that are **not** in TOSCA-76, for training a vocabulary outside
/// the indexed collection: the 20 SHREC'07 four-legged animals, the 24 shapes of TOSCA's
/// non-isometric set (gorilla, man, woman; other bodies than TOSCA-76's), and ten models of
/// other collections (spot, homer, cheburashka, armadillo, bunny, koala, penguin, SMPL man,
/// goat head, hand). 54 shapes, all labelled family `outside`.
///
/// # Errors
/// [`BenchError::Data`] if a folder cannot be read.
pub fn outside_files(meshes_dir: &Path) -> Result<Vec<ShapeFile>, BenchError> {
    let mut out = Vec::new();
    for sub in ["shrec07-fourleg", "tosca-bcicp-5k/TOSCA_nonIsometric"] {
        for (path, stem) in off_files(&meshes_dir.join(sub))? {
            out.push((path, format!("{sub}/{stem}")));
        }
    }
    for rel in OUTSIDE_MODELS {
        let path = meshes_dir.join(rel);
        if path.is_file() {
            out.push((path, rel.to_string()));
        }
    }
    out.sort_by(|a, b| a.1.cmp(&b.1));
    Ok(out
        .into_iter()
        .map(|(path, name)| ShapeFile {
            path,
            name,
            family: "outside".into(),
            transform: None,
            strength: 0,
            cloud: None,
        })
        .collect())
}

/// The single models of [`outside_files`] (relative to the corpus folder).
pub const OUTSIDE_MODELS: [&str; 10] = [
    "common-3d-test-models/spot.obj",
    "common-3d-test-models/homer.obj",
    "common-3d-test-models/cheburashka.obj",
    "odedstein-meshes/armadillo/armadillo.obj",
    "odedstein-meshes/bunny/bunny.obj",
    "odedstein-meshes/koala/koala_low_resolution.obj",
    "odedstein-meshes/penguin/penguin.obj",
    "odedstein-meshes/human/human_man.obj",
    "odedstein-meshes/goathead/goathead.obj",
    "odedstein-meshes/hand/hand_closed.obj",
];

fn off_files(dir: &Path) -> Result<Vec<(PathBuf, String)>, BenchError> {
    let entries = std::fs::read_dir(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
    let mut out = Vec::new();
    for e in entries {
        let path = e
            .map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?
            .path();
        if path.extension().and_then(|x| x.to_str()) == Some("off") {
            if let Some(stem) = path.file_stem().and_then(|s| s.to_str()) {
                let stem = stem.to_string();
                out.push((path, stem));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The null shapes and the synthetic transformed shapes of a generated data folder (the `pose`
/// class is left out: it is not a SHREC'10 class).
pub fn shrec_files(data_dir: &Path, manifest: &Manifest) -> Vec<ShapeFile> {
    let mut out: Vec<ShapeFile> = manifest
        .bases
        .iter()
        .map(|b| ShapeFile {
            path: data_dir.join(&b.mesh),
            name: b.mesh.clone(),
            family: family(&b.shape),
            transform: None,
            strength: 0,
            cloud: None,
        })
        .collect();
    out.extend(
        manifest
            .outputs
            .iter()
            .filter(|o| o.class != Class::Pose)
            .map(|o| ShapeFile {
                path: data_dir.join(&o.mesh),
                name: o.mesh.clone(),
                family: family(&o.shape),
                transform: Some(o.class),
                strength: o.strength,
                cloud: None,
            }),
    );
    out
}

/// An optional on-disk cache of eigenbases, keyed by file path, size, modification time, k and
/// the kind of mass (raw little-endian f64: n, k, the k eigenvalues, the n × k eigenvectors
/// column by column). Unreadable or mismatched entries are recomputed.
#[derive(Clone, Debug, Default)]
pub struct EigenCache {
    dir: Option<PathBuf>,
}

impl EigenCache {
    /// No cache.
    pub fn none() -> Self {
        Self { dir: None }
    }

    /// A cache in `dir` (created if needed).
    ///
    /// # Errors
    /// [`BenchError::Data`] if the folder cannot be created.
    pub fn in_dir(dir: &Path) -> Result<Self, BenchError> {
        std::fs::create_dir_all(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
        Ok(Self {
            dir: Some(dir.to_path_buf()),
        })
    }

    /// The cache file of a prepared shape: keyed by the mesh the eigenbasis is computed on
    /// (positions and faces after every preprocessing step, bit for bit), k, the mass and the
    /// eigensolver's tolerance, so a change of the preprocessing, of its code or of the
    /// tolerance (retrieval's [`shape_retrieval::descriptor::RETRIEVAL_EIGEN_TOLERANCE`]) can
    /// never return a stale basis.
    ///
    /// The operators are those of the mesh's Laplacian or, for a point cloud (`cloud`), of the
    /// cloud whose neighbourhood mesh `shape.mesh()` is; both are in the key (the cotangent
    /// mesh keeps the key it had before the choice existed).
    fn entry(
        &self,
        shape: &ShapeDescriptors,
        settings: &DescriptorSettings,
        lumped: bool,
        cloud: bool,
    ) -> Option<PathBuf> {
        let dir = self.dir.as_ref()?;
        let mut h = crate::Fnv1a::new();
        h.eat(format!("v2|{}|{lumped}|", settings.eigenpairs).bytes());
        // The eigensolver's tolerance, when not the general default (the keys of bases computed
        // before the retrieval tolerance existed stay what they were).
        let tol = shape.params().eigen.tol;
        if tol != wfem_heat::spectral::EigenParams::default().tol {
            h.eat(format!("tol{tol:e}|").bytes());
        }
        if cloud {
            h.eat(b"cloud|".iter().copied());
        } else if settings.laplacian != mesh_fem::Laplacian::Cotan {
            h.eat(format!("{:?}|", settings.laplacian).bytes());
        }
        for p in shape.mesh().positions() {
            for c in p {
                h.eat(c.to_bits().to_le_bytes());
            }
        }
        for f in shape.mesh().faces() {
            for v in f {
                h.eat(v.to_le_bytes());
            }
        }
        Some(dir.join(format!("{:016x}.eig", h.0)))
    }

    fn read(path: &Path) -> Option<Eigenbasis> {
        let mut bytes = Vec::new();
        std::fs::File::open(path).ok()?.read_to_end(&mut bytes).ok()?;
        let word = |i: usize| -> Option<[u8; 8]> { bytes.get(8 * i..8 * i + 8)?.try_into().ok() };
        let (n, k) = (
            u64::from_le_bytes(word(0)?) as usize,
            u64::from_le_bytes(word(1)?) as usize,
        );
        if bytes.len() != 8 * (2 + k + n * k) {
            return None;
        }
        let f = |i: usize| word(i).map_or(f64::NAN, f64::from_le_bytes);
        let values: Vec<f64> = (0..k).map(|j| f(2 + j)).collect();
        let vectors = Mat::from_fn(n, k, |i, j| f(2 + k + j * n + i));
        Some(Eigenbasis { values, vectors })
    }

    fn write(path: &Path, b: &Eigenbasis) {
        let (n, k) = (b.vectors.nrows(), b.vectors.ncols());
        let mut bytes = Vec::with_capacity(8 * (2 + k + n * k));
        bytes.extend((n as u64).to_le_bytes());
        bytes.extend((k as u64).to_le_bytes());
        b.values.iter().for_each(|v| bytes.extend(v.to_le_bytes()));
        for j in 0..k {
            (0..n).for_each(|i| bytes.extend(b.vectors[(i, j)].to_le_bytes()));
        }
        // A cache is best effort: a failed write only costs a recomputation next time.
        let _ = mesh_fem::io::write_atomic(path, |w| w.write_all(&bytes));
    }

    /// The eigenbasis of `shape` (lumped or wFEM), from the cache or computed and stored;
    /// `shape` was made from `file` with `settings` (whose eigenpairs and smoothing are part of
    /// the key).
    ///
    /// # Errors
    /// The eigensolver's.
    pub fn fill(
        &self,
        file: &Path,
        shape: &mut ShapeDescriptors,
        lumped: bool,
        settings: &DescriptorSettings,
    ) -> Result<(), BenchError> {
        self.fill_as(file, shape, lumped, settings, false)
    }

    /// [`Self::fill`] for a shape that is a point cloud (`cloud`) or a mesh.
    ///
    /// # Errors
    /// The eigensolver's.
    pub fn fill_as(
        &self,
        file: &Path,
        shape: &mut ShapeDescriptors,
        lumped: bool,
        settings: &DescriptorSettings,
        cloud: bool,
    ) -> Result<(), BenchError> {
        let entry = self.entry(shape, settings, lumped, cloud);
        if let Some(basis) = entry.as_deref().and_then(Self::read) {
            if shape.set_eigenbasis(lumped, basis).is_ok() {
                return Ok(());
            }
        }
        let basis = shape
            .eigenbasis(lumped)
            .map_err(BenchError::retrieval(file.display().to_string()))?;
        if let Some(e) = entry {
            Self::write(&e, basis);
        }
        Ok(())
    }
}

/// Loads shapes (in parallel), prepares them with `settings` (eigenpairs, smoothing) and computes
/// (or reads) their wFEM eigenbasis.
///
/// # Errors
/// The first unreadable mesh or failed eigensolve, naming the file.
pub fn load_shapes(
    files: Vec<ShapeFile>,
    settings: &DescriptorSettings,
    cache: &EigenCache,
) -> Result<Vec<BenchShape>, BenchError> {
    let total = files.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    files
        .into_par_iter()
        .map(|file| {
            let input = file.load()?;
            let mut shape = settings
                .shape(&input)
                .map_err(BenchError::retrieval(file.name.clone()))?;
            cache.fill_as(&file.path, &mut shape, false, settings, file.cloud.is_some())?;
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d % 50 == 0 || d == total {
                eprintln!("shrec-bench: eigenbases of {d}/{total} shapes");
            }
            Ok(BenchShape {
                file,
                shape,
                descriptors: Vec::new(),
            })
        })
        .collect()
}

/// The features of every shape under `settings` (in parallel, in order). DHK1 needs the lumped
/// eigenbasis, which comes from `cache` when it has it.
///
/// # Errors
/// The first failure, naming the shape.
pub fn features(
    shapes: &mut [BenchShape],
    settings: &RetrievalSettings,
    cache: &EigenCache,
) -> Result<Vec<ShapeFeatures>, BenchError> {
    let lumped = matches!(settings.descriptor.descriptor, Descriptor::Dhk1 { .. });
    shapes
        .par_iter_mut()
        .map(|s| {
            if lumped {
                cache.fill_as(
                    &s.file.path,
                    &mut s.shape,
                    true,
                    &settings.descriptor,
                    s.file.cloud.is_some(),
                )?;
            }
            let name = s.file.name.clone();
            let wrap = |source| BenchError::Retrieval {
                shape: name.clone(),
                source,
            };
            let known = s.descriptors.iter().find(|(d, _)| *d == settings.descriptor);
            let descriptors = match known {
                Some((_, m)) => m.clone(),
                None => {
                    settings.bags.validate(settings.descriptor.eigenpairs).map_err(wrap)?;
                    let m = settings.descriptor.descriptor.compute(&mut s.shape).map_err(wrap)?;
                    s.descriptors.push((settings.descriptor.clone(), m.clone()));
                    m
                }
            };
            let weights = settings.bags.weights.compute(&s.shape).map_err(wrap)?;
            let global = match &settings.bags.global {
                Some(g) => g.compute(&mut s.shape).map_err(wrap)?,
                None => Vec::new(),
            };
            let mut f = ShapeFeatures::new(&s.file.name, &s.shape, descriptors, weights, global).map_err(wrap)?;
            if settings.bags.spatial.is_some() {
                f.attach_spectrum(&mut s.shape).map_err(wrap)?;
            }
            Ok(f)
        })
        .collect()
}

/// An index of `features` with the given vocabulary.
///
/// # Errors
/// [`BenchError::Retrieval`].
pub fn index(
    vocabulary: &VocabularyModel,
    settings: &RetrievalSettings,
    features: &[ShapeFeatures],
) -> Result<RetrievalIndex, BenchError> {
    let mut index =
        RetrievalIndex::new(vocabulary.clone(), settings.bags.clone()).map_err(BenchError::retrieval("index"))?;
    for f in features {
        index.insert(f).map_err(BenchError::retrieval(f.name.clone()))?;
    }
    Ok(index)
}

/// Trains a vocabulary on `features` with `settings`.
///
/// # Errors
/// [`BenchError::Retrieval`].
pub fn train(settings: &RetrievalSettings, features: &[ShapeFeatures]) -> Result<VocabularyModel, BenchError> {
    VocabularyModel::train(&settings.descriptor, &settings.training, features)
        .map_err(BenchError::retrieval("vocabulary"))
}

/// mAP over queries, with the mean per family.
#[derive(Clone, Debug, PartialEq)]
pub struct LooReport {
    /// Mean AP over all queries.
    pub map: f64,
    /// (family, mean AP of its queries), by family name.
    pub per_family: Vec<(String, f64)>,
}

impl LooReport {
    /// The lowest per-family mAP.
    pub fn worst_family(&self) -> Option<(&str, f64)> {
        self.per_family
            .iter()
            .map(|(f, v)| (f.as_str(), *v))
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        f64::NAN
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

/// Leave-one-out retrieval on an index: every entry queries the others, relevant = same family
/// (`families[i]` labels entry i).
///
/// # Errors
/// [`BenchError::Data`] if the labels do not match the entries; [`BenchError::Retrieval`].
pub fn leave_one_out(index: &RetrievalIndex, families: &[String]) -> Result<LooReport, BenchError> {
    let entries = index.entries();
    if entries.len() != families.len() {
        return Err(BenchError::Data(format!(
            "{} labels for {} entries",
            families.len(),
            entries.len()
        )));
    }
    let aps: Vec<Option<f64>> = entries
        .par_iter()
        .enumerate()
        .map(|(q, e)| {
            let ranked = index
                .rank(&e.signature)
                .map_err(BenchError::retrieval(e.name.clone()))?;
            let relevance: Vec<bool> = ranked
                .iter()
                .filter(|r| r.entry != q)
                .map(|r| families[r.entry] == families[q])
                .collect();
            Ok(average_precision(&relevance))
        })
        .collect::<Result<_, BenchError>>()?;
    Ok(summarise(&aps, families))
}

fn summarise(aps: &[Option<f64>], families: &[String]) -> LooReport {
    let mut names: Vec<String> = families.to_vec();
    names.sort();
    names.dedup();
    let per_family = names
        .into_iter()
        .filter_map(|f| {
            let v: Vec<f64> = aps
                .iter()
                .zip(families)
                .filter(|(_, g)| **g == f)
                .filter_map(|(a, _)| *a)
                .collect();
            (!v.is_empty()).then(|| (f, mean(&v)))
        })
        .collect();
    LooReport {
        map: mean(&aps.iter().flatten().copied().collect::<Vec<_>>()),
        per_family,
    }
}

/// One query of the SHREC protocol with its average precisions.
#[derive(Clone, Debug, PartialEq)]
pub struct QueryResult {
    /// The query's family (null shape).
    pub family: String,
    /// Its transformation.
    pub transform: Class,
    /// Its strength (1…5).
    pub strength: u8,
    /// AP against the database of strength ≤ s, for s = 1 … 5 (`None` for s < strength).
    pub ap_cumulative: [Option<f64>; 5],
    /// AP against the full database (every strength).
    pub ap_full: f64,
    /// AP against the clean collection (relevant = same family), if one was given.
    pub ap_clean: Option<f64>,
}

/// The SHREC'10 protocol's tables (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ShrecReport {
    /// Every query.
    pub queries: Vec<QueryResult>,
}

impl ShrecReport {
    /// Cumulative mAP, column s = 1 … 5: queries of strength ≤ s against the database of
    /// strength ≤ s, restricted to the queries that `keep` accepts.
    pub fn cumulative(&self, keep: impl Fn(&QueryResult) -> bool) -> [f64; 5] {
        std::array::from_fn(|c| {
            mean(
                &self
                    .queries
                    .iter()
                    .filter(|q| keep(q))
                    .filter_map(|q| q.ap_cumulative[c])
                    .collect::<Vec<_>>(),
            )
        })
    }

    /// As [`Self::cumulative`], against the full database.
    pub fn cumulative_full(&self, keep: impl Fn(&QueryResult) -> bool) -> [f64; 5] {
        self.cumulative_by(keep, |q| Some(q.ap_full))
    }

    /// As [`Self::cumulative`], against the clean collection (`NaN` without one).
    pub fn cumulative_clean(&self, keep: impl Fn(&QueryResult) -> bool) -> [f64; 5] {
        self.cumulative_by(keep, |q| q.ap_clean)
    }

    fn cumulative_by(
        &self,
        keep: impl Fn(&QueryResult) -> bool,
        value: impl Fn(&QueryResult) -> Option<f64>,
    ) -> [f64; 5] {
        std::array::from_fn(|c| {
            mean(
                &self
                    .queries
                    .iter()
                    .filter(|q| keep(q) && q.strength as usize <= c + 1)
                    .filter_map(&value)
                    .collect::<Vec<_>>(),
            )
        })
    }

    /// The transformations present, in SHREC'10 order.
    pub fn transforms(&self) -> Vec<Class> {
        Class::SYNTHETIC
            .into_iter()
            .filter(|c| self.queries.iter().any(|q| q.transform == *c))
            .collect()
    }

    /// The families present, sorted.
    pub fn families(&self) -> Vec<String> {
        let mut f: Vec<String> = self.queries.iter().map(|q| q.family.clone()).collect();
        f.sort();
        f.dedup();
        f
    }
}

/// Runs the SHREC'10 protocol. `database` holds one entry per shape of `shapes` (same order):
/// the null shapes (strength 0) and the transformed ones. `clean` optionally ranks every query
/// against a clean collection whose entries are labelled by `clean_families`.
///
/// # Errors
/// [`BenchError::Data`] for mismatched inputs; [`BenchError::Retrieval`].
pub fn shrec_protocol(
    database: &RetrievalIndex,
    shapes: &[ShapeFile],
    clean: Option<(&RetrievalIndex, &[String])>,
) -> Result<ShrecReport, BenchError> {
    let entries = database.entries();
    if entries.len() != shapes.len() {
        return Err(BenchError::Data(format!(
            "{} shapes for {} index entries",
            shapes.len(),
            entries.len()
        )));
    }
    let queries = (0..shapes.len())
        .into_par_iter()
        .filter_map(|q| shapes[q].transform.map(|t| (q, t)))
        .map(|(q, transform)| {
            let query = &shapes[q];
            let signature = &entries[q].signature;
            let ranked = database
                .rank(signature)
                .map_err(BenchError::retrieval(query.name.clone()))?;
            let others: Vec<(bool, u8)> = ranked
                .iter()
                .filter(|r| r.entry != q)
                .map(|r| (shapes[r.entry].family == query.family, shapes[r.entry].strength))
                .collect();
            let ap_within = |s: u8| {
                let rel: Vec<bool> = others.iter().filter(|(_, st)| *st <= s).map(|(r, _)| *r).collect();
                average_precision(&rel).unwrap_or(0.0)
            };
            let ap_cumulative = std::array::from_fn(|c| {
                let s = c as u8 + 1;
                (query.strength <= s).then(|| ap_within(s))
            });
            let ap_full = ap_within(u8::MAX);
            let ap_clean = match clean {
                Some((index, families)) => {
                    let ranked = index
                        .rank(signature)
                        .map_err(BenchError::retrieval(query.name.clone()))?;
                    let rel: Vec<bool> = ranked.iter().map(|r| families[r.entry] == query.family).collect();
                    Some(average_precision(&rel).unwrap_or(0.0))
                }
                None => None,
            };
            Ok(QueryResult {
                family: query.family.clone(),
                transform,
                strength: query.strength,
                ap_cumulative,
                ap_full,
                ap_clean,
            })
        })
        .collect::<Result<Vec<_>, BenchError>>()?;
    Ok(ShrecReport { queries })
}
