//! `cargo xtask shrec-eval`: the paper's Sect. 5 experiment (Tables 3–5) end to end on the
//! synthetic SHREC'10-style data of [`crate::synth`].
//!
//! For every null shape X and every transformed shape Y of it (class × strength):
//!
//! 1. **Features** SHK1/SHK2 ([`shape_retrieval::descriptor::FeatureDetector`]) on X and Y and their
//!    repeatability `(rep(Y, X) + rep(X, Y))/2` within R = 5 % of the diameter of X
//!    ([`shape_retrieval::features::repeatability`]).
//!    *Approximation:* geodesic distances are edge-graph (Dijkstra) distances
//!    ([`mesh_fem::graph::EdgeGraph::distances`]), which overestimate surface geodesics by a
//!    few per cent, and the diameter is the double-sweep lower bound of the edge-graph diameter
//!    (farthest vertex from vertex 0, then farthest from that one). The X → Y map is the inverse
//!    of the ground truth (null vertices without a preimage, e.g. removed by sampling, are
//!    ignored).
//! 2. **Robustness** of the dense descriptors DHK1, DHK2, DHK3 and SI-HKS (the default of
//!    [`shape_retrieval::model::DescriptorSpec`], area time unit): the average relative L2 distance
//!    `‖f_X(x) − f_Y(y)‖/‖f_X(x)‖` over all ground-truth pairs
//!    ([`shape_retrieval::features::descriptor_distance`]), Table 4 style.
//! 3. **Retrieval** (Table 5): every [`Method`] of the subset through the protocols of
//!    [`crate::protocol`] — SHREC'10's cumulative "strength ≤ s" mAP beside the paper's rows,
//!    the same queries against the clean TOSCA collection, per transformation and per family —
//!    and, on the default subset, TOSCA-76 leave-one-out with a vocabulary trained on the 76
//!    and with one trained outside them.
//!
//! DHK1/DHK2 times are global (chosen once from the first null shape's spectrum), so these
//! scale-covariant descriptors are *expected* to fail on the `scale` class, while DHK3 and
//! SI-HKS should not.

use crate::protocol::{
    self, leave_one_out, shrec_protocol, EigenCache, LooReport, ShapeFile, ShrecReport, PAPER_TABLE5,
};
use crate::synth::{generate, Class, GenerateOptions, Manifest};
use crate::BenchError;
use faer::Mat;
use mesh_fem::graph::EdgeGraph;
use rayon::prelude::*;
use shape_retrieval::bof::Assignment;
use shape_retrieval::descriptor::FeatureDetector;
use shape_retrieval::distance::BagDistance;
use shape_retrieval::features::{descriptor_distance, repeatability, FeatureSet};
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::model::{
    BagSettings, DescriptorSettings, DescriptorSpec, GlobalSignature, RetrievalSettings, TrainingParams, VertexWeights,
};
use shape_retrieval::RetrievalError;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Which part of the benchmark to run (parsed from `default` / `small`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subset {
    /// The 8 default TOSCA shapes × 9 synthetic classes × strengths 1–5, k = 100 (360 shapes),
    /// the 76 TOSCA shapes as the clean collection, the 54 [`protocol::outside_files`] for
    /// vocabularies trained outside, and the ablations.
    Default,
    /// 2 shapes × 4 classes × strengths 1 and 5, k = 24 (the test): the clean collection is the
    /// TOSCA shapes of the two families, no outside vocabulary, no ablations.
    Small,
}

impl Subset {
    /// Base shapes.
    pub fn shapes(self) -> Vec<String> {
        let names: &[&str] = match self {
            Subset::Default => &crate::synth::DEFAULT_SHAPES,
            Subset::Small => &["cat", "wolf"],
        };
        names.iter().map(|s| s.to_string()).collect()
    }

    /// Transformation classes.
    pub fn classes(self) -> Vec<Class> {
        match self {
            Subset::Default => Class::SYNTHETIC.to_vec(),
            Subset::Small => vec![Class::Isometry, Class::Scale, Class::Sampling, Class::Noise],
        }
    }

    /// Strengths.
    pub fn strengths(self) -> Vec<u8> {
        match self {
            Subset::Default => (1..=5).collect(),
            Subset::Small => vec![1, 5],
        }
    }

    /// Number k of eigenpairs.
    pub fn eigenpairs(self) -> usize {
        match self {
            Subset::Default => 100,
            Subset::Small => 24,
        }
    }

    /// Its name (`default`, `small`).
    pub fn name(self) -> &'static str {
        match self {
            Subset::Default => "default",
            Subset::Small => "small",
        }
    }
}

impl std::str::FromStr for Subset {
    type Err = BenchError;

    fn from_str(s: &str) -> Result<Self, BenchError> {
        match s {
            "default" => Ok(Subset::Default),
            "small" => Ok(Subset::Small),
            other => Err(BenchError::Argument(format!(
                "unknown subset {other:?}; known: default, small"
            ))),
        }
    }
}

/// Options of [`run`].
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Folder of the generated data (reused if its `manifest.json` covers the subset).
    pub data_dir: PathBuf,
    /// Corpus folder for generation and for the clean/outside collections (`cargo xtask`
    /// defaults to the shared corpus, `wfem_corpus::meshes_dir`).
    pub meshes_dir: PathBuf,
    /// The subset.
    pub subset: Subset,
    /// Seed of the generator and of k-means.
    pub seed: u64,
    /// Eigenbasis cache ([`EigenCache::none`] to recompute everything).
    pub cache: EigenCache,
}

/// Number of HKS times of DHK1–DHK3 (Shape Google uses 6 scales).
const NUM_TIMES: usize = 6;
/// Repeatability radius as a fraction of the diameter (SHREC'10).
const RADIUS_FRACTION: f64 = 0.05;
/// Columns of the robustness table.
const ROBUSTNESS_COLUMNS: [&str; 4] = ["DHK1", "DHK2", "DHK3", "SI-HKS"];

/// Where a method's vocabulary is trained.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VocabularySource {
    /// On the null shapes of the benchmark (the clean shapes of the indexed collection).
    NullShapes,
    /// On [`protocol::outside_files`]: shapes in neither the benchmark nor TOSCA-76.
    Outside,
}

/// One retrieval method of the report.
#[derive(Clone, Debug)]
pub struct Method {
    /// Short name.
    pub name: String,
    /// What it is / what it tests.
    pub note: String,
    /// Its settings.
    pub settings: RetrievalSettings,
    /// Where its vocabulary is trained for the SHREC tables.
    pub vocabulary: VocabularySource,
    /// Also run TOSCA-76 leave-one-out (default subset only).
    pub tosca: bool,
}

/// The methods of a subset: the default recipe (with both vocabularies), Shape Google SG1/SG2 as
/// in the paper (HKS at 6 global times, no z-scoring, L1), and on the default subset the
/// ablations of the robustness ideas.
pub fn methods(subset: Subset, k: usize, hks_times: &[f64]) -> Vec<Method> {
    let with_k = |mut s: RetrievalSettings| {
        s.descriptor.eigenpairs = k;
        s
    };
    let default = with_k(RetrievalSettings::default());
    let shape_google = |descriptor: DescriptorSpec| {
        with_k(RetrievalSettings {
            descriptor: DescriptorSettings {
                eigenpairs: k,
                laplacian: Default::default(),
                descriptor,
                smoothing: None,
                despiking: None,
                denoising: None,
                hole_filling: None,
                topology_repair: None,
                refinement: None,
            },
            // Shape Google: 48 words, raw descriptors, plain area-weighted bags, L1.
            training: TrainingParams {
                words: 48,
                standardize: false,
                ..Default::default()
            },
            bags: BagSettings {
                weights: VertexWeights::Area,
                assignment: Assignment::Normalized,
                distance: BagDistance::L1,
                global: None,
                spatial: None,
            },
        })
    };
    let variant = |f: &dyn Fn(&mut RetrievalSettings)| {
        let mut s = default.clone();
        f(&mut s);
        s
    };
    let method = |name: &str, note: &str, settings, vocabulary, tosca| Method {
        name: name.into(),
        note: note.into(),
        settings,
        vocabulary,
        tosca,
    };
    let mut out = vec![
        method(
            "wFEM SI-HKS (default)",
            "the CLI's defaults; vocabulary trained on the null shapes",
            default.clone(),
            VocabularySource::NullShapes,
            false,
        ),
        method(
            "SG1 (ours)",
            "Shape Google: DHK1 (lumped kernel, Eq. (7)) at 6 global times, L1, no z-scoring",
            shape_google(DescriptorSpec::Dhk1 {
                times: TimeSampling::Explicit(hks_times.to_vec()),
            }),
            VocabularySource::NullShapes,
            false,
        ),
        method(
            "SG2 (ours)",
            "Shape Google: DHK2 (wFEM kernel, Eq. (6)) at 6 global times, L1, no z-scoring",
            shape_google(DescriptorSpec::Dhk2 {
                times: TimeSampling::Explicit(hks_times.to_vec()),
            }),
            VocabularySource::NullShapes,
            false,
        ),
    ];
    if subset == Subset::Small {
        return out;
    }
    out.insert(
        1,
        method(
            "wFEM SI-HKS, outside vocabulary",
            "the CLI's defaults with a vocabulary trained on 54 shapes outside the benchmark",
            default.clone(),
            VocabularySource::Outside,
            true,
        ),
    );
    let ablations: Vec<(&str, &str, RetrievalSettings)> = vec![
        (
            "DHK3 (old CLI)",
            "the CLI before issue #13: DHK3 at 6 times in units of 1/λ_max, L1, no z-scoring",
            shape_google(DescriptorSpec::dhk3_default()),
        ),
        (
            "previous default",
            "the default before hole filling and capped areas: spike removal and denoising, area weights",
            variant(&|s| {
                s.descriptor.hole_filling = None;
                s.bags.weights = VertexWeights::Area;
            }),
        ),
        (
            "no cleaning",
            "default without spike removal, hole filling and denoising",
            variant(&|s| {
                s.descriptor.despiking = None;
                s.descriptor.hole_filling = None;
                s.descriptor.denoising = None;
            }),
        ),
        (
            "no hole filling",
            "default without hole filling",
            variant(&|s| s.descriptor.hole_filling = None),
        ),
        (
            "no denoising",
            "default without denoising",
            variant(&|s| s.descriptor.denoising = None),
        ),
        (
            "no spike removal",
            "default without spike removal",
            variant(&|s| s.descriptor.despiking = None),
        ),
        (
            "area weights",
            "default with plain (uncapped) area weights",
            variant(&|s| s.bags.weights = VertexWeights::Area),
        ),
        (
            "no z-scoring",
            "default without per-dimension z-scoring",
            variant(&|s| s.training.standardize = false),
        ),
        (
            "L1",
            "default with the L1 distance",
            variant(&|s| s.bags.distance = BagDistance::L1),
        ),
        (
            "+ Shape-DNA (w = 1)",
            "default fused with ln(λ_i A), i = 1…20, weight 1",
            variant(&|s| {
                s.bags.global = Some(GlobalSignature {
                    kind: Default::default(),
                    eigenvalues: 20,
                    weight: 1.0,
                })
            }),
        ),
        (
            "64 words",
            "default with a vocabulary of 64 words",
            variant(&|s| s.training.words = 64),
        ),
        (
            "boundary damping (3 hops)",
            "vertex weights × smoothstep(hops to the boundary / 3)",
            variant(&|s| s.bags.weights = VertexWeights::BoundaryDamped { hops: 3 }),
        ),
    ];
    out.extend(
        ablations
            .into_iter()
            .map(|(n, note, s)| method(n, note, s, VocabularySource::Outside, true)),
    );
    out
}

/// One row of a table: a class (or `null`) and strength with one value per column
/// (`None` where nothing could be averaged).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Class name.
    pub class: String,
    /// Strength.
    pub strength: u8,
    /// One mean per column.
    pub values: Vec<Option<f64>>,
}

/// The results of one retrieval method.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodReport {
    /// Its name.
    pub name: String,
    /// Its note.
    pub note: String,
    /// Where its vocabulary was trained.
    pub vocabulary: VocabularySource,
    /// The SHREC'10 protocol.
    pub shrec: ShrecReport,
    /// TOSCA-76 leave-one-out with a vocabulary trained on the 76, then outside them.
    pub tosca: Option<[LooReport; 2]>,
}

/// Everything `shrec-eval` measures.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalReport {
    /// Subset name.
    pub subset: String,
    /// Number of null shapes.
    pub n_null: usize,
    /// Number of transformed shapes.
    pub n_transformed: usize,
    /// Number of shapes of the clean collection.
    pub n_clean: usize,
    /// Number of shapes the outside vocabularies were trained on.
    pub n_outside: usize,
    /// Eigenpairs k.
    pub eigenpairs: usize,
    /// Mean number of SHK1 and SHK2 features per shape.
    pub mean_features: [f64; 2],
    /// Repeatability, columns SHK1, SHK2.
    pub repeatability: Vec<Row>,
    /// Robustness (relative L2 distance), columns DHK1, DHK2, DHK3, SI-HKS.
    pub robustness: Vec<Row>,
    /// Retrieval, one entry per [`Method`].
    pub retrieval: Vec<MethodReport>,
}

fn read_gt(path: &Path, n: usize) -> Result<Vec<i64>, BenchError> {
    let text = std::fs::read_to_string(path).map_err(|e| BenchError::Data(format!("{}: {e}", path.display())))?;
    let gt: Vec<i64> = text
        .lines()
        .map(|l| l.trim().parse::<i64>())
        .collect::<Result<_, _>>()
        .map_err(|e| BenchError::Data(format!("{}: {e}", path.display())))?;
    if gt.len() != n {
        return Err(BenchError::Data(format!(
            "{}: {} lines for {n} vertices",
            path.display(),
            gt.len()
        )));
    }
    Ok(gt)
}

/// Loads the manifest if it covers the subset, else generates the data.
fn data(opts: &EvalOptions, meshes_dir: &Path) -> Result<Manifest, BenchError> {
    let (shapes, classes, strengths) = (opts.subset.shapes(), opts.subset.classes(), opts.subset.strengths());
    let path = opts.data_dir.join("manifest.json");
    if let Ok(text) = std::fs::read_to_string(&path) {
        if let Ok(m) = serde_json::from_str::<Manifest>(&text) {
            let covers = m.seed == opts.seed
                && shapes
                    .iter()
                    .all(|s| m.bases.iter().any(|b| b.shape == format!("{s}0")))
                && shapes.iter().all(|s| {
                    classes.iter().all(|&c| {
                        strengths.iter().all(|&st| {
                            m.outputs
                                .iter()
                                .any(|o| o.shape == format!("{s}0") && o.class == c && o.strength == st)
                        })
                    })
                });
            if covers {
                return Ok(m);
            }
        }
    }
    generate(&GenerateOptions {
        meshes_dir: meshes_dir.to_path_buf(),
        out_dir: opts.data_dir.clone(),
        shapes,
        classes,
        strengths,
        seed: opts.seed,
    })
}

/// Double-sweep lower bound of the edge-graph diameter.
fn diameter(graph: &EdgeGraph) -> Result<f64, BenchError> {
    let far = |d: &[f64]| -> (u32, f64) {
        d.iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .fold(
                (0u32, 0.0f64),
                |acc, (i, &v)| if v > acc.1 { (i as u32, v) } else { acc },
            )
    };
    let (a, _) = far(&graph.distances(&[0], f64::INFINITY)?);
    Ok(far(&graph.distances(&[a], f64::INFINITY)?).1)
}

/// Distances (cut off at `radius`; beyond it `f64::MAX`) from each feature: a sparse oracle.
fn feature_balls(graph: &EdgeGraph, features: &[u32], radius: f64) -> Result<Vec<(u32, Vec<f64>)>, BenchError> {
    features
        .iter()
        .map(|&f| Ok((f, graph.distances(&[f], radius)?)))
        .collect()
}

fn oracle(balls: &[(u32, Vec<f64>)]) -> impl Fn(u32, u32) -> f64 + '_ {
    move |from: u32, to: u32| {
        balls
            .iter()
            .find(|(f, _)| *f == to)
            .map(|(_, d)| d[from as usize])
            .filter(|d| d.is_finite())
            .unwrap_or(f64::MAX)
    }
}

/// Dense descriptors (the robustness columns) and sparse features of one shape.
struct Analysed {
    dense: Vec<Mat<f64>>,
    features: [Vec<u32>; 2],
}

fn analyse(
    s: &mut protocol::BenchShape,
    hks_times: &[f64],
    dhk3_times: &[f64],
    cache: &EigenCache,
    settings: &DescriptorSettings,
) -> Result<Analysed, BenchError> {
    let wrap = BenchError::retrieval(s.file.name.clone());
    cache.fill(&s.file.path, &mut s.shape, true, settings)?;
    let shape = &mut s.shape;
    let mut dense = Vec::new();
    let (hks, dhk3) = (
        TimeSampling::Explicit(hks_times.to_vec()),
        TimeSampling::Explicit(dhk3_times.to_vec()),
    );
    for spec in [
        DescriptorSpec::Dhk1 { times: hks.clone() },
        DescriptorSpec::Dhk2 { times: hks },
        DescriptorSpec::Dhk3 { times: dhk3 },
        DescriptorSpec::default(),
    ] {
        dense.push(
            spec.compute(shape)
                .map_err(BenchError::retrieval(s.file.name.clone()))?,
        );
    }
    let features = [
        shape
            .features(FeatureDetector::Shk1)
            .map_err(BenchError::retrieval(s.file.name.clone()))?,
        shape.features(FeatureDetector::Shk2).map_err(wrap)?,
    ];
    Ok(Analysed { dense, features })
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Runs the evaluation (see the module docs).
///
/// # Errors
/// The first failure, naming the shape.
pub fn run(opts: &EvalOptions) -> Result<EvalReport, BenchError> {
    let meshes_dir = opts.meshes_dir.clone();
    let manifest = data(opts, &meshes_dir)?;
    let subset = opts.subset;
    let (names, classes, strengths) = (subset.shapes(), subset.classes(), subset.strengths());
    let k = subset.eigenpairs();
    let nulls_wanted: Vec<String> = names.iter().map(|s| protocol::family(s)).collect();
    let files: Vec<ShapeFile> = protocol::shrec_files(&opts.data_dir, &manifest)
        .into_iter()
        .filter(|f| {
            nulls_wanted.contains(&f.family)
                && f.transform
                    .is_none_or(|c| classes.contains(&c) && strengths.contains(&f.strength))
        })
        .collect();
    // Tables 3–4 describe the shapes as they are (no cleaning); the retrieval methods prepare
    // them as their settings say (below).
    let plain = DescriptorSettings {
        eigenpairs: k,
        despiking: None,
        denoising: None,
        smoothing: None,
        hole_filling: None,
        topology_repair: None,
        refinement: None,
        ..Default::default()
    };
    let mut shapes = protocol::load_shapes(files.clone(), &plain, &opts.cache)?;
    let nulls: Vec<usize> = (0..shapes.len()).filter(|&i| files[i].transform.is_none()).collect();
    if nulls.is_empty() {
        return Err(BenchError::Data("the benchmark has no null shape".into()));
    }
    let null_of = |i: usize| nulls.iter().copied().find(|&n| files[n].family == files[i].family);
    let ground_truth: Vec<Vec<i64>> = files
        .iter()
        .zip(&shapes)
        .map(|(f, s)| {
            let gt = f.path.with_extension("gt");
            read_gt(&gt, s.shape.mesh().n_vertices())
        })
        .collect::<Result<_, _>>()?;

    // Global times from the first null shape's spectrum.
    let reference = shapes[nulls[0]]
        .shape
        .eigenbasis(false)
        .map_err(BenchError::retrieval(files[nulls[0]].name.clone()))?
        .values
        .clone();
    let lambda_max = reference.iter().copied().fold(0.0, f64::max);
    let lambda_2 = reference.get(1).copied().unwrap_or(lambda_max);
    let c = 4.0 * std::f64::consts::LN_10;
    let hks_times = log_spaced(c / lambda_max, c / lambda_2, NUM_TIMES);
    // DHK3 uses times in units of 1/λ_max: the same range on the reference shape.
    let dhk3_times = log_spaced(c, c * lambda_max / lambda_2, NUM_TIMES);

    // Tables 3–4: descriptors and features of every shape, in parallel.
    let done = std::sync::atomic::AtomicUsize::new(0);
    let analysed: Vec<Analysed> = shapes
        .par_iter_mut()
        .map(|s| {
            let a = analyse(s, &hks_times, &dhk3_times, &opts.cache, &plain)?;
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d % 50 == 0 || d == files.len() {
                eprintln!("shrec-eval: descriptors of {d}/{}", files.len());
            }
            Ok(a)
        })
        .collect::<Result<_, BenchError>>()?;
    let (repeatability_rows, robustness_rows) =
        tables_3_4(&files, &shapes, &ground_truth, &analysed, &nulls, &null_of)?;

    // Table 5: retrieval.
    let clean_files: Vec<ShapeFile> = protocol::tosca_files(&meshes_dir)?
        .into_iter()
        .filter(|f| subset == Subset::Default || nulls_wanted.contains(&f.family))
        .collect();
    let clean_families: Vec<String> = clean_files.iter().map(|f| f.family.clone()).collect();
    let clean = protocol::load_shapes(clean_files.clone(), &plain, &opts.cache)?;
    let outside = match subset {
        Subset::Default => protocol::load_shapes(protocol::outside_files(&meshes_dir)?, &plain, &opts.cache)?,
        Subset::Small => Vec::new(),
    };
    // Methods that prepare the shapes alike (spike removal, denoising, smoothing) share one
    // set of prepared shapes and eigenbases; one set is held at a time, the plain one first.
    let methods = methods(subset, k, &hks_times);
    let preparation = |m: &Method| DescriptorSettings {
        eigenpairs: k,
        despiking: m.settings.descriptor.despiking,
        denoising: m.settings.descriptor.denoising,
        smoothing: m.settings.descriptor.smoothing,
        hole_filling: m.settings.descriptor.hole_filling,
        topology_repair: m.settings.descriptor.topology_repair,
        refinement: m.settings.descriptor.refinement,
        ..plain.clone()
    };
    let mut groups: Vec<DescriptorSettings> = vec![plain.clone()];
    for m in &methods {
        let p = preparation(m);
        if !groups.contains(&p) {
            groups.push(p);
        }
    }
    let n_clean = clean.len();
    let n_outside = outside.len();
    let mut reports: Vec<Option<MethodReport>> = methods.iter().map(|_| None).collect();
    let mut sets = Some((shapes, clean, outside));
    for group in &groups {
        let (mut g_shapes, mut g_clean, mut g_outside) = match sets.take() {
            Some(plain_sets) if *group == plain => plain_sets,
            _ => (
                protocol::load_shapes(files.clone(), group, &opts.cache)?,
                protocol::load_shapes(clean_files.clone(), group, &opts.cache)?,
                match subset {
                    Subset::Default => {
                        protocol::load_shapes(protocol::outside_files(&meshes_dir)?, group, &opts.cache)?
                    }
                    Subset::Small => Vec::new(),
                },
            ),
        };
        for (i, m) in methods.iter().enumerate() {
            if preparation(m) != *group {
                continue;
            }
            eprintln!("shrec-eval: retrieval with {}", m.name);
            reports[i] = Some(run_method(
                m,
                &mut g_shapes,
                &files,
                &nulls,
                &mut g_clean,
                &clean_families,
                &mut g_outside,
                opts,
            )?);
        }
    }
    let retrieval: Vec<MethodReport> = reports.into_iter().flatten().collect();
    let n_features = |d: usize| mean(&analysed.iter().map(|a| a.features[d].len() as f64).collect::<Vec<_>>());
    Ok(EvalReport {
        subset: subset.name().into(),
        n_null: nulls.len(),
        n_transformed: files.len() - nulls.len(),
        n_clean,
        n_outside,
        eigenpairs: k,
        mean_features: [n_features(0).unwrap_or(0.0), n_features(1).unwrap_or(0.0)],
        repeatability: repeatability_rows,
        robustness: robustness_rows,
        retrieval,
    })
}

#[allow(clippy::too_many_arguments)]
fn run_method(
    m: &Method,
    shapes: &mut [protocol::BenchShape],
    files: &[ShapeFile],
    nulls: &[usize],
    clean: &mut [protocol::BenchShape],
    clean_families: &[String],
    outside: &mut [protocol::BenchShape],
    opts: &EvalOptions,
) -> Result<MethodReport, BenchError> {
    let mut settings = m.settings.clone();
    settings.training.seed = opts.seed;
    let f_shapes = protocol::features(shapes, &settings, &opts.cache)?;
    let f_clean = protocol::features(clean, &settings, &opts.cache)?;
    let f_outside = match (m.vocabulary, m.tosca) {
        (VocabularySource::Outside, _) | (_, true) if !outside.is_empty() => {
            protocol::features(outside, &settings, &opts.cache)?
        }
        _ => Vec::new(),
    };
    let vocabulary = match m.vocabulary {
        VocabularySource::NullShapes => {
            let null_features: Vec<_> = nulls.iter().map(|&i| f_shapes[i].clone()).collect();
            protocol::train(&settings, &null_features)?
        }
        VocabularySource::Outside if !f_outside.is_empty() => protocol::train(&settings, &f_outside)?,
        VocabularySource::Outside => {
            return Err(BenchError::Data(format!("{}: no outside shapes to train on", m.name)));
        }
    };
    let database = protocol::index(&vocabulary, &settings, &f_shapes)?;
    let clean_index = protocol::index(&vocabulary, &settings, &f_clean)?;
    let shrec = shrec_protocol(&database, files, Some((&clean_index, clean_families)))?;
    let tosca = if m.tosca && !f_outside.is_empty() {
        let inside = protocol::train(&settings, &f_clean)?;
        let outside_vocabulary = protocol::train(&settings, &f_outside)?;
        Some([
            leave_one_out(&protocol::index(&inside, &settings, &f_clean)?, clean_families)?,
            leave_one_out(
                &protocol::index(&outside_vocabulary, &settings, &f_clean)?,
                clean_families,
            )?,
        ])
    } else {
        None
    };
    Ok(MethodReport {
        name: m.name.clone(),
        note: m.note.clone(),
        vocabulary: m.vocabulary,
        shrec,
        tosca,
    })
}

type Tables = (Vec<Row>, Vec<Row>);

fn tables_3_4(
    files: &[ShapeFile],
    shapes: &[protocol::BenchShape],
    ground_truth: &[Vec<i64>],
    analysed: &[Analysed],
    nulls: &[usize],
    null_of: &(dyn Fn(usize) -> Option<usize> + Sync),
) -> Result<Tables, BenchError> {
    // Per null: graph, diameter, balls around its features.
    struct NullGeo {
        radius: f64,
        balls: [Vec<(u32, Vec<f64>)>; 2],
    }
    let geo: Vec<NullGeo> = nulls
        .iter()
        .map(|&i| {
            let graph = EdgeGraph::new(shapes[i].shape.mesh());
            let radius = RADIUS_FRACTION * diameter(&graph)?;
            let balls = [
                feature_balls(&graph, &analysed[i].features[0], radius)?,
                feature_balls(&graph, &analysed[i].features[1], radius)?,
            ];
            Ok(NullGeo { radius, balls })
        })
        .collect::<Result<_, BenchError>>()?;

    // Per transformed shape: repeatability (2) and robustness (4).
    let transformed: Vec<usize> = (0..files.len()).filter(|&i| files[i].transform.is_some()).collect();
    let per_shape: Vec<(Vec<Option<f64>>, Vec<f64>)> = transformed
        .par_iter()
        .map(|&i| {
            let base = null_of(i).ok_or_else(|| BenchError::Data(format!("{}: no null shape", files[i].name)))?;
            let ni = nulls.iter().position(|&n| n == base).unwrap_or(0);
            let (null, this) = (shapes[base].shape.mesh(), shapes[i].shape.mesh());
            let y_to_x: Vec<Option<u32>> = ground_truth[i].iter().map(|&g| (g >= 0).then_some(g as u32)).collect();
            let mut x_to_y: Vec<Option<u32>> = vec![None; null.n_vertices()];
            for (y, x) in y_to_x.iter().enumerate() {
                if let Some(x) = x {
                    x_to_y[*x as usize].get_or_insert(y as u32);
                }
            }
            let graph_y = EdgeGraph::new(this);
            let wrap = BenchError::retrieval(files[i].name.clone());
            let mut reps = Vec::new();
            for det in 0..2 {
                let balls_y = feature_balls(&graph_y, &analysed[i].features[det], geo[ni].radius)?;
                let r = repeatability(
                    FeatureSet {
                        features: &analysed[base].features[det],
                        n_vertices: null.n_vertices(),
                        correspondence: &x_to_y,
                    },
                    FeatureSet {
                        features: &analysed[i].features[det],
                        n_vertices: this.n_vertices(),
                        correspondence: &y_to_x,
                    },
                    geo[ni].radius,
                    &oracle(&geo[ni].balls[det]),
                    &oracle(&balls_y),
                );
                reps.push(match r {
                    Ok(r) => Some(r.overall),
                    Err(RetrievalError::NothingToAverage { .. }) => None,
                    Err(e) => return Err(BenchError::retrieval(files[i].name.clone())(e)),
                });
            }
            let pairs: Vec<(u32, u32)> = y_to_x
                .iter()
                .enumerate()
                .filter_map(|(y, x)| x.map(|x| (x, y as u32)))
                .collect();
            let robust = (0..ROBUSTNESS_COLUMNS.len())
                .map(|c| descriptor_distance(analysed[base].dense[c].as_ref(), analysed[i].dense[c].as_ref(), &pairs))
                .collect::<Result<Vec<_>, _>>()
                .map_err(wrap)?;
            Ok((reps, robust))
        })
        .collect::<Result<_, BenchError>>()?;

    let mut classes: Vec<Class> = files.iter().filter_map(|f| f.transform).collect();
    classes.sort();
    classes.dedup();
    classes.sort_by_key(|c| Class::ALL.iter().position(|x| x == c));
    let mut strengths: Vec<u8> = files
        .iter()
        .filter(|f| f.transform.is_some())
        .map(|f| f.strength)
        .collect();
    strengths.sort_unstable();
    strengths.dedup();
    let (mut repeatability_rows, mut robustness_rows) = (Vec::new(), Vec::new());
    for &c in &classes {
        for &s in &strengths {
            let members: Vec<usize> = (0..transformed.len())
                .filter(|&j| files[transformed[j]].transform == Some(c) && files[transformed[j]].strength == s)
                .collect();
            let col =
                |f: &dyn Fn(usize) -> Option<f64>| mean(&members.iter().filter_map(|&j| f(j)).collect::<Vec<_>>());
            repeatability_rows.push(Row {
                class: c.name().into(),
                strength: s,
                values: (0..2).map(|d| col(&|j| per_shape[j].0[d])).collect(),
            });
            robustness_rows.push(Row {
                class: c.name().into(),
                strength: s,
                values: (0..ROBUSTNESS_COLUMNS.len())
                    .map(|d| col(&|j| Some(per_shape[j].1[d])))
                    .collect(),
            });
        }
    }
    Ok((repeatability_rows, robustness_rows))
}

fn log_spaced(a: f64, b: f64, num: usize) -> Vec<f64> {
    let (la, lb) = (a.ln(), b.ln());
    (0..num)
        .map(|j| (la + (lb - la) * j as f64 / (num - 1).max(1) as f64).exp())
        .collect()
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.filter(|x| x.is_finite())
        .map_or_else(|| "–".into(), |v| format!("{v:.digits$}"))
}

fn table(out: &mut String, header: &[&str], rows: &[Row], digits: usize) {
    let _ = writeln!(out, "| class | s | {} |", header.join(" | "));
    let _ = writeln!(out, "|---|---|{}", "---|".repeat(header.len()));
    for r in rows {
        let vals: Vec<String> = r.values.iter().map(|v| fmt(*v, digits)).collect();
        let _ = writeln!(out, "| {} | {} | {} |", r.class, r.strength, vals.join(" | "));
    }
    // Average over classes per strength (the paper's Table 4 layout).
    let mut strengths: Vec<u8> = rows.iter().map(|r| r.strength).collect();
    strengths.sort_unstable();
    strengths.dedup();
    for s in strengths {
        let vals: Vec<String> = (0..header.len())
            .map(|c| {
                fmt(
                    mean(
                        &rows
                            .iter()
                            .filter(|r| r.strength == s)
                            .filter_map(|r| r.values[c])
                            .collect::<Vec<_>>(),
                    ),
                    digits,
                )
            })
            .collect();
        let _ = writeln!(out, "| **average** | {s} | {} |", vals.join(" | "));
    }
}

/// Mean of column `c` over the rows of `class`.
fn class_mean(rows: &[Row], class: &str, c: usize) -> Option<f64> {
    mean(
        &rows
            .iter()
            .filter(|r| r.class == class)
            .filter_map(|r| r.values[c])
            .collect::<Vec<_>>(),
    )
}

/// The claims of the paper, checked on our numbers (one line each).
pub fn verdicts(report: &EvalReport) -> Vec<String> {
    let mut out = Vec::new();
    let holds = |h: bool| if h { "HOLDS" } else { "DOES NOT HOLD" };
    for class in ["sampling", "topology", "localscale"] {
        if let (Some(l), Some(w)) = (
            class_mean(&report.robustness, class, 0),
            class_mean(&report.robustness, class, 1),
        ) {
            out.push(format!(
                "{class}: DHK2 (wFEM) {w:.4} vs DHK1 (lumped) {l:.4} mean relative distance → claim \"wFEM at least as robust\" {}",
                holds(w <= l * 1.001)
            ));
        }
    }
    if report.robustness.iter().any(|r| r.class == "scale") {
        let means: Vec<Option<f64>> = (0..4).map(|c| class_mean(&report.robustness, "scale", c)).collect();
        let best = (0..4)
            .filter_map(|c| means[c].map(|v| (c, v)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((c, v)) = best {
            out.push(format!(
                "scale (robustness): lowest distance {} = {v:.4} → claim \"scale-invariant descriptor best on scale\" {}",
                ROBUSTNESS_COLUMNS[c],
                holds(c >= 2)
            ));
        }
        let scale_map = |name: &str| {
            report
                .retrieval
                .iter()
                .find(|m| m.name.starts_with(name))
                .map(|m| m.shrec.cumulative(|q| q.transform == Class::Scale)[4])
        };
        if let (Some(a), Some(b), Some(si)) = (scale_map("SG1"), scale_map("SG2"), scale_map("wFEM SI-HKS")) {
            out.push(format!(
                "scale (retrieval, ≤ 5): SI-HKS mAP {si:.3} vs SG1 {a:.3}, SG2 {b:.3} → claim \"scale-invariant descriptor best on scale\" {}",
                holds(si >= a.max(b) - 1e-12)
            ));
        }
    }
    out
}

fn row5(values: [f64; 5], digits: usize) -> String {
    values
        .iter()
        .map(|v| fmt(Some(*v), digits))
        .collect::<Vec<_>>()
        .join(" | ")
}

/// The markdown report.
pub fn markdown(report: &EvalReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# SHREC'10-style evaluation of wFEM heat kernel descriptors\n");
    let _ = writeln!(
        out,
        "Generated by `cargo xtask shrec-eval --subset {}` (protocols: `crates/shrec-bench/src/protocol.rs`). \
         {} null shapes, {} transformed shapes, clean collection of {} TOSCA shapes, {} shapes outside both for \
         outside vocabularies, k = {} eigenpairs. Mean feature count per shape: SHK1 {:.1}, SHK2 {:.1}.\n",
        report.subset,
        report.n_null,
        report.n_transformed,
        report.n_clean,
        report.n_outside,
        report.eigenpairs,
        report.mean_features[0],
        report.mean_features[1]
    );
    retrieval_markdown(&mut out, report);
    let _ = writeln!(out, "## Claims of the paper on these data\n");
    for v in verdicts(report) {
        let _ = writeln!(out, "* {v}");
    }
    let _ = writeln!(
        out,
        "\n## Feature repeatability (higher is better; Table 3/4 style)\n\n\
         Geodesic distances and the diameter are edge-graph (Dijkstra) approximations; R = 5 % of \
         the double-sweep edge-graph diameter of the null shape.\n"
    );
    table(&mut out, &["SHK1", "SHK2"], &report.repeatability, 3);
    let _ = writeln!(
        out,
        "\n## Descriptor robustness: mean ‖f_X(x) − f_Y(y)‖/‖f_X(x)‖ at corresponding points (lower is better; Table 4 style)\n\n\
         DHK1/DHK2 at {NUM_TIMES} global times, DHK3 at {NUM_TIMES} times in units of 1/λ_max, SI-HKS = the retrieval \
         default (area time unit).\n"
    );
    table(&mut out, &ROBUSTNESS_COLUMNS, &report.robustness, 4);
    out
}

fn retrieval_markdown(out: &mut String, report: &EvalReport) {
    let all = |_: &protocol::QueryResult| true;
    let _ = writeln!(
        out,
        "## Retrieval, SHREC'10 protocol: cumulative mAP (%) for strength ≤ s (Table 5)\n\n\
         Column ≤ s: the queries are the transformed shapes of strength ≤ s, the database is the null shapes and \
         every transformed shape of strength ≤ s (all classes), relevant = the same null shape, the query itself \
         excluded. The paper's rows are copied from its Table 5 (SHREC'10's own data: 13 null shapes, 715 queries); \
         ours run on the synthetic data of `cargo xtask shrec`.\n"
    );
    let _ = writeln!(out, "| method | ≤1 | ≤2 | ≤3 | ≤4 | ≤5 |\n|---|---|---|---|---|---|");
    for (name, note, v) in PAPER_TABLE5 {
        let _ = writeln!(out, "| paper {name} ({note}) | {} |", row5(v, 2));
    }
    for m in &report.retrieval {
        let _ = writeln!(
            out,
            "| **{}** | {} |",
            m.name,
            row5(m.shrec.cumulative(all).map(|x| 100.0 * x), 2)
        );
    }
    let _ = writeln!(out, "\nMethods:\n");
    for m in &report.retrieval {
        let vocab = match m.vocabulary {
            VocabularySource::NullShapes => "vocabulary on the null shapes",
            VocabularySource::Outside => "vocabulary outside",
        };
        let _ = writeln!(out, "* **{}**: {} ({vocab}).", m.name, m.note);
    }
    let _ = writeln!(
        out,
        "\n### The same queries against the full database (every strength in the database), mAP (%)\n\n\
         Here every strength-5 shape of the query's null counts as relevant to every query.\n\n\
         | method | ≤1 | ≤2 | ≤3 | ≤4 | ≤5 |\n|---|---|---|---|---|---|"
    );
    for m in &report.retrieval {
        let _ = writeln!(
            out,
            "| {} | {} |",
            m.name,
            row5(m.shrec.cumulative_full(all).map(|x| 100.0 * x), 2)
        );
    }
    let _ = writeln!(
        out,
        "\n### The same queries against the clean collection ({} TOSCA shapes; relevant = same class), mAP (%)\n\n\
         | method | ≤1 | ≤2 | ≤3 | ≤4 | ≤5 |\n|---|---|---|---|---|---|",
        report.n_clean
    );
    for m in &report.retrieval {
        let _ = writeln!(
            out,
            "| {} | {} |",
            m.name,
            row5(m.shrec.cumulative_clean(all).map(|x| 100.0 * x), 2)
        );
    }
    if let Some(m) = report.retrieval.first() {
        let _ = writeln!(
            out,
            "\n### Per transformation: {} (cumulative mAP for strength ≤ s; in brackets: against the clean collection)\n\n\
             | transformation | ≤1 | ≤2 | ≤3 | ≤4 | ≤5 |\n|---|---|---|---|---|---|",
            m.name
        );
        for t in m.shrec.transforms() {
            let a = m.shrec.cumulative(|q| q.transform == t);
            let b = m.shrec.cumulative_clean(|q| q.transform == t);
            let cells: Vec<String> = (0..5)
                .map(|i| format!("{} ({})", fmt(Some(a[i]), 3), fmt(Some(b[i]), 3)))
                .collect();
            let _ = writeln!(out, "| {} | {} |", t.name(), cells.join(" | "));
        }
        let families = m.shrec.families();
        let _ = writeln!(
            out,
            "\n### Per class and transformation at strength ≤ 3: {} (cumulative mAP; **bold** below 0.80)\n\n| class | {} |\n|---|{}",
            m.name,
            m.shrec.transforms().iter().map(|t| t.name()).collect::<Vec<_>>().join(" | "),
            "---|".repeat(m.shrec.transforms().len())
        );
        for f in &families {
            let cells: Vec<String> = m
                .shrec
                .transforms()
                .iter()
                .map(|&t| {
                    let v = m.shrec.cumulative(|q| &q.family == f && q.transform == t)[2];
                    if v < 0.8 {
                        format!("**{}**", fmt(Some(v), 3))
                    } else {
                        fmt(Some(v), 3)
                    }
                })
                .collect();
            let _ = writeln!(out, "| {f} | {} |", cells.join(" | "));
        }
    }
    let tosca: Vec<&MethodReport> = report.retrieval.iter().filter(|m| m.tosca.is_some()).collect();
    if !tosca.is_empty() {
        let _ = writeln!(
            out,
            "\n## TOSCA-76 leave-one-out (each shape queries the other 75; relevant = same class)\n\n\
             | method | vocabulary | mAP | worst class | per class |\n|---|---|---|---|---|"
        );
        for m in tosca {
            if let Some([inside, outside]) = &m.tosca {
                for (label, r) in [("the 76 (optimistic)", inside), ("outside (54 shapes)", outside)] {
                    let worst = r.worst_family().map_or("–".into(), |(f, v)| format!("{f} {v:.3}"));
                    let per: Vec<String> = r.per_family.iter().map(|(f, v)| format!("{f} {v:.3}")).collect();
                    let _ = writeln!(
                        out,
                        "| {} | {label} | {:.4} | {worst} | {} |",
                        m.name,
                        r.map,
                        per.join(", ")
                    );
                }
            }
        }
    }
    let _ = writeln!(out);
}

/// TOSCA-76 leave-one-out with given settings (`cargo xtask tosca-eval`).
#[derive(Clone, Debug, PartialEq)]
pub struct ToscaEval {
    /// The settings evaluated.
    pub settings: RetrievalSettings,
    /// Number of outside training shapes.
    pub n_outside: usize,
    /// Vocabulary trained on the 76 with the settings' seed (what `wfem retrieval build` does).
    pub inside: LooReport,
    /// Vocabulary trained on the outside shapes with the settings' seed.
    pub outside: LooReport,
    /// mAP over the seeds `0 .. seeds` of k-means: (inside, outside) per seed.
    pub over_seeds: Vec<(u64, f64, f64)>,
}

/// Runs TOSCA-76 leave-one-out: each of the 76 shapes queries the other 75, relevant = same
/// class, with a vocabulary trained on the 76 (the CLI's `build` without `--vocab`) and with one
/// trained on [`protocol::outside_files`]; then the same for k-means seeds `0 .. seeds`.
///
/// # Errors
/// The first failure, naming the shape.
pub fn tosca_eval(
    meshes_dir: &Path,
    settings: &RetrievalSettings,
    cache: &EigenCache,
    seeds: u64,
) -> Result<ToscaEval, BenchError> {
    let tosca_files = protocol::tosca_files(meshes_dir)?;
    let families: Vec<String> = tosca_files.iter().map(|f| f.family.clone()).collect();
    let mut tosca = protocol::load_shapes(tosca_files, &settings.descriptor, cache)?;
    let mut outside = protocol::load_shapes(protocol::outside_files(meshes_dir)?, &settings.descriptor, cache)?;
    let f_tosca = protocol::features(&mut tosca, settings, cache)?;
    let f_outside = protocol::features(&mut outside, settings, cache)?;
    let run = |seed: u64| -> Result<(LooReport, LooReport), BenchError> {
        let mut s = settings.clone();
        s.training.seed = seed;
        let inside = protocol::train(&s, &f_tosca)?;
        let outside = protocol::train(&s, &f_outside)?;
        Ok((
            leave_one_out(&protocol::index(&inside, &s, &f_tosca)?, &families)?,
            leave_one_out(&protocol::index(&outside, &s, &f_tosca)?, &families)?,
        ))
    };
    let (inside, outside_report) = run(settings.training.seed)?;
    let over_seeds = (0..seeds)
        .map(|seed| run(seed).map(|(a, b)| (seed, a.map, b.map)))
        .collect::<Result<_, _>>()?;
    Ok(ToscaEval {
        settings: settings.clone(),
        n_outside: outside.len(),
        inside,
        outside: outside_report,
        over_seeds,
    })
}

/// The markdown section of a [`ToscaEval`].
pub fn tosca_markdown(t: &ToscaEval) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## TOSCA-76 with the CLI's defaults (`cargo xtask tosca-eval`)\n\n\
         Index = the 76 shapes of `tosca-bcicp-5k/TOSCA_Isometric`; each queries the other 75 (self excluded); \
         relevant = same class (name without trailing digits). Settings: {}.\n",
        serde_json::to_string(&t.settings).unwrap_or_default()
    );
    let _ = writeln!(out, "| vocabulary | mAP | worst class | per class |\n|---|---|---|---|");
    for (label, r) in [
        (
            "trained on the 76 (`wfem retrieval build`; optimistic)".to_string(),
            &t.inside,
        ),
        (
            format!("trained on {} shapes outside (`build --vocab`)", t.n_outside),
            &t.outside,
        ),
    ] {
        let worst = r.worst_family().map_or("–".into(), |(f, v)| format!("{f} {v:.3}"));
        let per: Vec<String> = r.per_family.iter().map(|(f, v)| format!("{f} {v:.3}")).collect();
        let _ = writeln!(out, "| {label} | {:.4} | {worst} | {} |", r.map, per.join(", "));
    }
    if !t.over_seeds.is_empty() {
        let stat = |v: Vec<f64>| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let sd = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / v.len() as f64).sqrt();
            let min = v.iter().copied().fold(f64::INFINITY, f64::min);
            format!("{m:.4} ± {sd:.4} (min {min:.4})")
        };
        let _ = writeln!(
            out,
            "\nOver k-means seeds 0…{}: vocabulary on the 76: {}; outside: {}.",
            t.over_seeds.len() - 1,
            stat(t.over_seeds.iter().map(|x| x.1).collect()),
            stat(t.over_seeds.iter().map(|x| x.2).collect())
        );
    }
    out
}
