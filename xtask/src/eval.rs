//! `cargo xtask shrec-eval`: the paper's Sect. 5 experiment (Tables 3–5) end to end on the
//! synthetic SHREC'10-style data of [`crate::shrec`].
//!
//! For every null shape X and every transformed shape Y of it (class × strength):
//!
//! 1. **Features** SHK1/SHK2 ([`shape_retrieval::FeatureDetector`]) on X and Y and their
//!    repeatability `(rep(Y, X) + rep(X, Y))/2` within R = 5 % of the diameter of X
//!    ([`shape_retrieval::repeatability`]).
//!    *Approximation:* geodesic distances are edge-graph (Dijkstra) distances
//!    ([`mesh_fem::transform::EdgeGraph::distances`]), which overestimate surface geodesics by a
//!    few per cent, and the diameter is the double-sweep lower bound of the edge-graph diameter
//!    (farthest vertex from vertex 0, then farthest from that one). The X → Y map is the inverse
//!    of the ground truth (null vertices without a preimage, e.g. removed by sampling, are
//!    ignored).
//! 2. **Robustness** of the dense descriptors DHK1, DHK2, DHK3 and SI-HKS: the average relative
//!    L2 distance `‖f_X(x) − f_Y(y)‖/‖f_X(x)‖` over all ground-truth pairs
//!    ([`shape_retrieval::descriptor_distance`]), Table 4 style.
//! 3. **Retrieval** with Shape Google bags of features: a 48-word vocabulary (seeded k-means)
//!    trained on the null shapes' descriptors, bags normalised to sum 1 (area-weighted:
//!    Voronoi areas for SG1, `B·1` for SG2 and SG3), L1 distances, and the mAP of the queries of
//!    each class × strength against the whole collection (relevant = the same null shape),
//!    Table 5 style. SG1 = HKS of the lumped kernel (DHK1), SG2 = HKS of the wFEM kernel (DHK2),
//!    SG3 = SI-HKS.
//!
//! Times are global (chosen once from the first null shape's spectrum), so the scale-covariant
//! DHK1/DHK2 are *expected* to fail on the `scale` class, while DHK3 and SI-HKS should not.

use crate::shrec::{generate, Class, GenerateOptions, Manifest, ShrecError};
use faer::Mat;
use mesh_fem::transform::EdgeGraph;
use mesh_fem::TriMesh;
use rayon::prelude::*;
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::{
    descriptor_distance, evaluate, pairwise_l1, repeatability, vertex_areas, Descriptor, DescriptorParams,
    FeatureDetector, FeatureSet, RetrievalError, ShapeDescriptors, SihksParams, Vocabulary, VocabularyParams,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Errors of the evaluation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EvalError {
    /// Data generation or reading failed.
    #[error(transparent)]
    Shrec(#[from] ShrecError),
    /// A mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] mesh_fem::MeshError),
    /// A descriptor or metric failed on a named shape.
    #[error("{shape}: {source}")]
    Retrieval {
        /// The shape file.
        shape: String,
        /// The failure.
        source: RetrievalError,
    },
    /// A bad ground-truth file or manifest.
    #[error("{0}")]
    Data(String),
}

/// Which part of the benchmark to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Subset {
    /// The 8 default TOSCA shapes × 9 synthetic classes × strengths 1–5, k = 100 (360 shapes;
    /// measured ≈ 3 min per 4 shapes with the release build on a shared 2-core machine).
    Default,
    /// 2 shapes × 4 classes × strengths 1 and 5, k = 24 (the xtask test).
    Small,
}

impl Subset {
    /// Base shapes.
    pub fn shapes(self) -> Vec<String> {
        let names: &[&str] = match self {
            Subset::Default => &crate::shrec::DEFAULT_SHAPES,
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

    fn name(self) -> &'static str {
        match self {
            Subset::Default => "default",
            Subset::Small => "small",
        }
    }
}

/// Options of [`run`].
#[derive(Clone, Debug)]
pub struct EvalOptions {
    /// Folder of the generated data (reused if its `manifest.json` covers the subset).
    pub data_dir: PathBuf,
    /// Corpus folder for generation (default: `mesh_fem::corpus`).
    pub meshes_dir: Option<PathBuf>,
    /// The subset.
    pub subset: Subset,
    /// Seed of the generator and of k-means.
    pub seed: u64,
}

/// Number of HKS times of DHK1–DHK3 (Shape Google uses 6 scales).
const NUM_TIMES: usize = 6;
/// Vocabulary size (Shape Google).
const WORDS: usize = 48;
/// Repeatability radius as a fraction of the diameter (SHREC'10).
const RADIUS_FRACTION: f64 = 0.05;
/// Dense descriptors of the robustness table.
const DENSE: [Descriptor; 4] = Descriptor::ALL;
/// Descriptors of SG1, SG2, SG3.
const BAGS: [Descriptor; 3] = [Descriptor::Dhk1, Descriptor::Dhk2, Descriptor::SiHks];

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

/// The three tables.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalReport {
    /// Subset name.
    pub subset: String,
    /// Number of null shapes and of transformed shapes.
    pub n_null: usize,
    /// Number of transformed shapes.
    pub n_transformed: usize,
    /// Eigenpairs k.
    pub eigenpairs: usize,
    /// Mean number of SHK1 and SHK2 features per shape.
    pub mean_features: [f64; 2],
    /// Repeatability, columns SHK1, SHK2.
    pub repeatability: Vec<Row>,
    /// Robustness (relative L2 distance), columns DHK1, DHK2, DHK3, SI-HKS.
    pub robustness: Vec<Row>,
    /// mAP, columns SG1, SG2, SG3.
    pub retrieval: Vec<Row>,
}

struct Loaded {
    base: usize,
    class: Option<Class>,
    strength: u8,
    file: String,
    mesh: TriMesh,
    ground_truth: Vec<i64>,
}

fn read_gt(path: &Path, n: usize) -> Result<Vec<i64>, EvalError> {
    let text = std::fs::read_to_string(path).map_err(|e| EvalError::Data(format!("{}: {e}", path.display())))?;
    let gt: Vec<i64> = text
        .lines()
        .map(|l| l.trim().parse::<i64>())
        .collect::<Result<_, _>>()
        .map_err(|e| EvalError::Data(format!("{}: {e}", path.display())))?;
    if gt.len() != n {
        return Err(EvalError::Data(format!(
            "{}: {} lines for {n} vertices",
            path.display(),
            gt.len()
        )));
    }
    Ok(gt)
}

/// Loads the manifest if it covers the subset, else generates the data.
fn data(opts: &EvalOptions) -> Result<Manifest, EvalError> {
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
    let meshes_dir = match &opts.meshes_dir {
        Some(d) => d.clone(),
        None => mesh_fem::corpus::meshes_dir()?,
    };
    Ok(generate(&GenerateOptions {
        meshes_dir,
        out_dir: opts.data_dir.clone(),
        shapes,
        classes,
        strengths,
        seed: opts.seed,
    })?)
}

/// Double-sweep lower bound of the edge-graph diameter.
fn diameter(graph: &EdgeGraph) -> Result<f64, EvalError> {
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
fn feature_balls(graph: &EdgeGraph, features: &[u32], radius: f64) -> Result<Vec<(u32, Vec<f64>)>, EvalError> {
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

struct Analysed {
    dense: Vec<Mat<f64>>,
    bags: Vec<Vec<f64>>,
    features: [Vec<u32>; 2],
    weights_lumped: Vec<f64>,
    weights_wfem: Vec<f64>,
}

fn analyse(
    mesh: &TriMesh,
    params: &DescriptorParams,
    dhk3_times: &TimeSampling,
    file: &str,
) -> Result<Analysed, EvalError> {
    let wrap = |source| EvalError::Retrieval {
        shape: file.to_string(),
        source,
    };
    let mut s = ShapeDescriptors::new(mesh, params).map_err(wrap)?;
    let mut dense = Vec::new();
    for d in DENSE {
        if d == Descriptor::Dhk3 {
            s.set_times(dhk3_times.clone());
            dense.push(s.dense(d).map_err(wrap)?);
            s.set_times(params.times.clone());
        } else {
            dense.push(s.dense(d).map_err(wrap)?);
        }
    }
    let features = [
        s.features(FeatureDetector::Shk1).map_err(wrap)?,
        s.features(FeatureDetector::Shk2).map_err(wrap)?,
    ];
    Ok(Analysed {
        dense,
        bags: Vec::new(),
        features,
        weights_lumped: s.operators().lumped_diagonal.clone(),
        weights_wfem: vertex_areas(s.operators().mass.as_ref()),
    })
}

fn bag_column(d: Descriptor) -> usize {
    DENSE.iter().position(|&x| x == d).unwrap_or(0)
}

fn make_bags(a: &mut Analysed, vocabularies: &[Vocabulary], file: &str) -> Result<(), EvalError> {
    let mut bags = Vec::new();
    for (v, &d) in vocabularies.iter().zip(&BAGS) {
        let weights = if d == Descriptor::Dhk1 {
            &a.weights_lumped
        } else {
            &a.weights_wfem
        };
        let mut bag = v
            .bag_of_features(a.dense[bag_column(d)].as_ref(), weights)
            .map_err(|source| EvalError::Retrieval {
                shape: file.to_string(),
                source,
            })?;
        let total: f64 = bag.iter().sum();
        bag.iter_mut().for_each(|x| *x /= total);
        bags.push(bag);
    }
    a.bags = bags;
    Ok(())
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Runs the evaluation (see the module docs).
///
/// # Errors
/// The first failure, naming the shape.
pub fn run(opts: &EvalOptions) -> Result<EvalReport, EvalError> {
    let manifest = data(opts)?;
    let subset = opts.subset;
    let (shapes, classes, strengths) = (subset.shapes(), subset.classes(), subset.strengths());
    let mut loaded = Vec::new();
    for s in &shapes {
        let stem = format!("{s}0");
        let b = manifest
            .bases
            .iter()
            .find(|b| b.shape == stem)
            .ok_or_else(|| EvalError::Data(format!("manifest has no base {stem}")))?;
        let base = loaded.len();
        let mut push = |class: Option<Class>, strength: u8, mesh: &str, gt: &str| -> Result<(), EvalError> {
            let (m, _) = mesh_fem::io::load(&opts.data_dir.join(mesh), &Default::default())?;
            let ground_truth = read_gt(&opts.data_dir.join(gt), m.n_vertices())?;
            loaded.push(Loaded {
                base,
                class,
                strength,
                file: mesh.to_string(),
                mesh: m,
                ground_truth,
            });
            Ok(())
        };
        push(None, 0, &b.mesh, &b.ground_truth)?;
        for o in manifest
            .outputs
            .iter()
            .filter(|o| o.shape == stem && classes.contains(&o.class) && strengths.contains(&o.strength))
        {
            push(Some(o.class), o.strength, &o.mesh, &o.ground_truth)?;
        }
    }
    // Null shapes: indices of `loaded` with class None. Their base index is the null's index.
    let nulls: Vec<usize> = (0..loaded.len()).filter(|&i| loaded[i].class.is_none()).collect();

    // Global times from the first null shape's spectrum.
    let k = subset.eigenpairs();
    let mut params = DescriptorParams {
        eigenpairs: k,
        ..Default::default()
    };
    let reference = ShapeDescriptors::new(&loaded[nulls[0]].mesh, &params)
        .and_then(|mut s| s.eigenbasis(false).map(|b| b.values.clone()))
        .map_err(|source| EvalError::Retrieval {
            shape: loaded[nulls[0]].file.clone(),
            source,
        })?;
    let lambda_max = reference.last().copied().unwrap_or(1.0);
    let lambda_2 = reference.get(1).copied().unwrap_or(lambda_max);
    let c = 4.0 * std::f64::consts::LN_10;
    let times = log_spaced(c / lambda_max, c / lambda_2, NUM_TIMES);
    params.times = TimeSampling::Explicit(times);
    // DHK3 uses times in units of 1/λ_max: the same range on the reference shape.
    let dhk3_times = TimeSampling::Explicit(log_spaced(c, c * lambda_max / lambda_2, NUM_TIMES));
    // SI-HKS window: from 1/(64 λ_max) (flat, with room for a 4× shrink) to 2^10/λ_2.
    let t0 = 1.0 / (64.0 * lambda_max);
    let tau_max = (1024.0 / lambda_2 / t0).log2().ceil();
    params.sihks = SihksParams {
        time_unit: t0,
        tau_min: 0.0,
        tau_max,
        tau_step: 0.25,
        ..Default::default()
    };

    // Descriptors of every shape, in parallel.
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut analysed: Vec<Analysed> = loaded
        .par_iter()
        .map(|l| {
            let a = analyse(&l.mesh, &params, &dhk3_times, &l.file)?;
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d % 10 == 0 || d == loaded.len() {
                eprintln!("shrec-eval: descriptors of {d}/{} shapes", loaded.len());
            }
            Ok(a)
        })
        .collect::<Result<_, EvalError>>()?;

    // Vocabularies on the null shapes' descriptors.
    let vocabularies: Vec<Vocabulary> = BAGS
        .iter()
        .map(|&d| {
            let col = bag_column(d);
            let blocks: Vec<&Mat<f64>> = nulls.iter().map(|&i| &analysed[i].dense[col]).collect();
            let rows: usize = blocks.iter().map(|m| m.nrows()).sum();
            let dim = blocks[0].ncols();
            let mut pooled = Mat::<f64>::zeros(rows, dim);
            let mut r0 = 0;
            for m in blocks {
                for i in 0..m.nrows() {
                    for j in 0..dim {
                        pooled[(r0 + i, j)] = m[(i, j)];
                    }
                }
                r0 += m.nrows();
            }
            Vocabulary::train(
                pooled.as_ref(),
                &VocabularyParams {
                    size: WORDS,
                    seed: opts.seed,
                    max_training_points: Some(20_000),
                    ..Default::default()
                },
            )
            .map_err(|source| EvalError::Retrieval {
                shape: format!("vocabulary {}", d.name()),
                source,
            })
        })
        .collect::<Result<_, _>>()?;
    analysed
        .par_iter_mut()
        .zip(&loaded)
        .try_for_each(|(a, l)| make_bags(a, &vocabularies, &l.file))?;

    // Per null: graph, diameter, balls around its features.
    struct NullGeo {
        radius: f64,
        balls: [Vec<(u32, Vec<f64>)>; 2],
    }
    let geo: Vec<NullGeo> = nulls
        .iter()
        .map(|&i| {
            let graph = EdgeGraph::new(&loaded[i].mesh);
            let radius = RADIUS_FRACTION * diameter(&graph)?;
            let balls = [
                feature_balls(&graph, &analysed[i].features[0], radius)?,
                feature_balls(&graph, &analysed[i].features[1], radius)?,
            ];
            Ok(NullGeo { radius, balls })
        })
        .collect::<Result<_, EvalError>>()?;

    // Per transformed shape: repeatability (2) and robustness (4).
    let transformed: Vec<usize> = (0..loaded.len()).filter(|&i| loaded[i].class.is_some()).collect();
    let per_shape: Vec<(Vec<Option<f64>>, Vec<f64>)> = transformed
        .par_iter()
        .map(|&i| {
            let l = &loaded[i];
            let ni = nulls.iter().position(|&n| n == l.base).unwrap_or(0);
            let null = &loaded[l.base];
            let y_to_x: Vec<Option<u32>> = l.ground_truth.iter().map(|&g| (g >= 0).then_some(g as u32)).collect();
            let mut x_to_y: Vec<Option<u32>> = vec![None; null.mesh.n_vertices()];
            for (y, x) in y_to_x.iter().enumerate() {
                if let Some(x) = x {
                    x_to_y[*x as usize].get_or_insert(y as u32);
                }
            }
            let graph_y = EdgeGraph::new(&l.mesh);
            let wrap = |source| EvalError::Retrieval {
                shape: l.file.clone(),
                source,
            };
            let mut reps = Vec::new();
            for det in 0..2 {
                let balls_y = feature_balls(&graph_y, &analysed[i].features[det], geo[ni].radius)?;
                let r = repeatability(
                    FeatureSet {
                        features: &analysed[l.base].features[det],
                        n_vertices: null.mesh.n_vertices(),
                        correspondence: &x_to_y,
                    },
                    FeatureSet {
                        features: &analysed[i].features[det],
                        n_vertices: l.mesh.n_vertices(),
                        correspondence: &y_to_x,
                    },
                    geo[ni].radius,
                    &oracle(&geo[ni].balls[det]),
                    &oracle(&balls_y),
                );
                reps.push(match r {
                    Ok(r) => Some(r.overall),
                    Err(RetrievalError::NothingToAverage { .. }) => None,
                    Err(e) => return Err(wrap(e)),
                });
            }
            let pairs: Vec<(u32, u32)> = y_to_x
                .iter()
                .enumerate()
                .filter_map(|(y, x)| x.map(|x| (x, y as u32)))
                .collect();
            let robust = (0..DENSE.len())
                .map(|c| {
                    descriptor_distance(
                        analysed[l.base].dense[c].as_ref(),
                        analysed[i].dense[c].as_ref(),
                        &pairs,
                    )
                })
                .collect::<Result<Vec<_>, _>>()
                .map_err(wrap)?;
            Ok((reps, robust))
        })
        .collect::<Result<_, EvalError>>()?;

    // Retrieval: one distance matrix per bag type over the whole collection.
    let labels: Vec<u32> = loaded.iter().map(|l| l.base as u32).collect();
    let mut ap: Vec<Vec<Option<f64>>> = Vec::new();
    for b in 0..BAGS.len() {
        let bags: Vec<Vec<f64>> = analysed.iter().map(|a| a.bags[b].clone()).collect();
        let d = pairwise_l1(&bags).map_err(|source| EvalError::Retrieval {
            shape: "collection".into(),
            source,
        })?;
        let r = evaluate(d.as_ref(), &labels).map_err(|source| EvalError::Retrieval {
            shape: "collection".into(),
            source,
        })?;
        ap.push(r.average_precision);
    }

    // Tables.
    let mut repeatability_rows = Vec::new();
    let mut robustness_rows = Vec::new();
    let mut retrieval_rows = Vec::new();
    for &c in &classes {
        for &s in &strengths {
            let members: Vec<usize> = (0..transformed.len())
                .filter(|&j| loaded[transformed[j]].class == Some(c) && loaded[transformed[j]].strength == s)
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
                values: (0..DENSE.len()).map(|d| col(&|j| Some(per_shape[j].1[d]))).collect(),
            });
            retrieval_rows.push(Row {
                class: c.name().into(),
                strength: s,
                values: (0..BAGS.len()).map(|b| col(&|j| ap[b][transformed[j]])).collect(),
            });
        }
    }
    let n_features = |d: usize| mean(&analysed.iter().map(|a| a.features[d].len() as f64).collect::<Vec<_>>());
    Ok(EvalReport {
        subset: subset.name().into(),
        n_null: nulls.len(),
        n_transformed: transformed.len(),
        eigenpairs: k,
        mean_features: [n_features(0).unwrap_or(0.0), n_features(1).unwrap_or(0.0)],
        repeatability: repeatability_rows,
        robustness: robustness_rows,
        retrieval: retrieval_rows,
    })
}

fn log_spaced(a: f64, b: f64, num: usize) -> Vec<f64> {
    let (la, lb) = (a.ln(), b.ln());
    (0..num)
        .map(|j| (la + (lb - la) * j as f64 / (num - 1).max(1) as f64).exp())
        .collect()
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".into(), |v| format!("{v:.digits$}"))
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
    for class in ["sampling", "topology", "localscale"] {
        if let (Some(l), Some(w)) = (
            class_mean(&report.robustness, class, 0),
            class_mean(&report.robustness, class, 1),
        ) {
            let holds = w <= l * 1.001;
            out.push(format!(
                "{class}: DHK2 (wFEM) {:.4} vs DHK1 (lumped) {:.4} mean relative distance → claim \"wFEM at least as robust\" {}",
                w,
                l,
                if holds { "HOLDS" } else { "DOES NOT HOLD" }
            ));
        }
    }
    if report.robustness.iter().any(|r| r.class == "scale") {
        let means: Vec<Option<f64>> = (0..4).map(|c| class_mean(&report.robustness, "scale", c)).collect();
        let best = (0..4)
            .filter_map(|c| means[c].map(|v| (c, v)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((c, v)) = best {
            let holds = c >= 2;
            out.push(format!(
                "scale (robustness): lowest distance {} = {:.4} → claim \"scale-invariant descriptor best on scale\" {}",
                DENSE[c].name(),
                v,
                if holds { "HOLDS" } else { "DOES NOT HOLD" }
            ));
        }
        let maps: Vec<Option<f64>> = (0..3).map(|c| class_mean(&report.retrieval, "scale", c)).collect();
        if let (Some(a), Some(b), Some(si)) = (maps[0], maps[1], maps[2]) {
            let holds = si >= a.max(b) - 1e-12;
            out.push(format!(
                "scale (retrieval): SG3 (SI-HKS) mAP {:.3} vs SG1 {:.3}, SG2 {:.3} → claim \"SI-HKS best on scale\" {}",
                si,
                a,
                b,
                if holds { "HOLDS" } else { "DOES NOT HOLD" }
            ));
        }
    }
    out
}

/// The markdown report.
pub fn markdown(report: &EvalReport) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# SHREC'10-style evaluation of wFEM heat kernel descriptors\n");
    let _ = writeln!(
        out,
        "Generated by `cargo xtask shrec-eval --subset {}` (see `xtask/src/eval.rs` for the protocol). \
         {} null shapes, {} transformed shapes, k = {} eigenpairs, {} HKS times, {} words. \
         Mean feature count per shape: SHK1 {:.1}, SHK2 {:.1}.\n",
        report.subset,
        report.n_null,
        report.n_transformed,
        report.eigenpairs,
        NUM_TIMES,
        WORDS,
        report.mean_features[0],
        report.mean_features[1]
    );
    let _ = writeln!(
        out,
        "Geodesic distances and the diameter are edge-graph (Dijkstra) approximations; R = 5 % of \
         the double-sweep edge-graph diameter of the null shape.\n"
    );
    let _ = writeln!(out, "## Claims of the paper on these data\n");
    for v in verdicts(report) {
        let _ = writeln!(out, "* {v}");
    }
    let _ = writeln!(out, "\n## Feature repeatability (higher is better; Table 3/4 style)\n");
    table(&mut out, &["SHK1", "SHK2"], &report.repeatability, 3);
    let _ = writeln!(
        out,
        "\n## Descriptor robustness: mean ‖f_X(x) − f_Y(y)‖/‖f_X(x)‖ at corresponding points (lower is better; Table 4 style)\n"
    );
    table(&mut out, &["DHK1", "DHK2", "DHK3", "SI-HKS"], &report.robustness, 4);
    let _ = writeln!(
        out,
        "\n## Retrieval mAP, Shape Google bags of features (higher is better; Table 5 style)\n"
    );
    table(
        &mut out,
        &["SG1 (lumped)", "SG2 (wFEM)", "SG3 (SI-HKS)"],
        &report.retrieval,
        3,
    );
    out
}
