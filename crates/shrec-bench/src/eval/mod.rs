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
//!    [`shape_retrieval::descriptor::Descriptor`], area time unit): the average relative L2 distance
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

use crate::protocol::{self, leave_one_out, shrec_protocol, EigenCache, LooReport, ShapeFile, ShrecReport};
use crate::synth::{generate, Class, GenerateOptions, Manifest};
use crate::BenchError;
use faer::Mat;
use mesh_fem::graph::EdgeGraph;
use rayon::prelude::*;
use shape_retrieval::descriptor::{Descriptor, FeatureDetector};
use shape_retrieval::features::{descriptor_distance, repeatability, FeatureSet};
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::model::DescriptorSettings;
use shape_retrieval::RetrievalError;
use std::path::{Path, PathBuf};

mod methods;
mod report;
mod tosca;

pub use methods::{methods, Method, VocabularySource};

pub use report::{markdown, verdicts};
pub use tosca::{tosca_eval, tosca_markdown, ToscaEval};

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
        Descriptor::Dhk1 { times: hks.clone() },
        Descriptor::Dhk2 { times: hks },
        Descriptor::Dhk3 { times: dhk3 },
        Descriptor::default(),
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
    let (retrieval, n_clean, n_outside) = table_5(opts, &files, &nulls, &nulls_wanted, shapes, &plain, &hks_times)?;
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

/// Table 5: every retrieval method of the subset through the protocols, the shapes prepared
/// once per kind of preparation (the plain `shapes` first). Returns the reports and the sizes
/// of the clean and the outside collections.
#[allow(clippy::too_many_arguments)]
fn table_5(
    opts: &EvalOptions,
    files: &[ShapeFile],
    nulls: &[usize],
    nulls_wanted: &[String],
    shapes: Vec<protocol::BenchShape>,
    plain: &DescriptorSettings,
    hks_times: &[f64],
) -> Result<(Vec<MethodReport>, usize, usize), BenchError> {
    let (subset, meshes_dir, k) = (opts.subset, &opts.meshes_dir, opts.subset.eigenpairs());
    let clean_files: Vec<ShapeFile> = protocol::tosca_files(meshes_dir)?
        .into_iter()
        .filter(|f| subset == Subset::Default || nulls_wanted.contains(&f.family))
        .collect();
    let clean_families: Vec<String> = clean_files.iter().map(|f| f.family.clone()).collect();
    let clean = protocol::load_shapes(clean_files.clone(), plain, &opts.cache)?;
    let outside = match subset {
        Subset::Default => protocol::load_shapes(protocol::outside_files(meshes_dir)?, plain, &opts.cache)?,
        Subset::Small => Vec::new(),
    };
    // Methods that prepare the shapes alike (spike removal, denoising, smoothing) share one
    // set of prepared shapes and eigenbases; one set is held at a time, the plain one first.
    let methods = methods(subset, k, hks_times);
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
            Some(plain_sets) if group == plain => plain_sets,
            _ => (
                protocol::load_shapes(files.to_vec(), group, &opts.cache)?,
                protocol::load_shapes(clean_files.clone(), group, &opts.cache)?,
                match subset {
                    Subset::Default => protocol::load_shapes(protocol::outside_files(meshes_dir)?, group, &opts.cache)?,
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
                files,
                nulls,
                &mut g_clean,
                &clean_families,
                &mut g_outside,
                opts,
            )?);
        }
    }
    Ok((reports.into_iter().flatten().collect(), n_clean, n_outside))
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
