//! Evaluation of a labelled collection: every shape queries all the others and the standard
//! retrieval measures are averaged overall, per class, with the most confused class pairs.
//!
//! For a query q of class c, the other N − 1 shapes are ranked by increasing distance (the
//! query itself excluded; ties go to the lower index). With `rel(k) = 1` if the k-th ranked
//! shape has class c and `R = |c| − 1` the number of relevant shapes (queries with R = 0 have
//! no measure and are left out of every mean), the measures of the Princeton Shape Benchmark and
//! the SHREC tracks are:
//!
//! * **average precision** `AP = (1/R) Σ_k P(k)·rel(k)`, `P(k) = (Σ_{j≤k} rel(j))/k`
//!   ([`crate::retrieval::average_precision`]); its mean over queries is the **mAP**;
//! * **nearest neighbour** `NN = rel(1)`;
//! * **first tier** `FT = (Σ_{k≤R} rel(k))/R` and **second tier** `ST = (Σ_{k≤2R} rel(k))/R`
//!   (the recall at R and at 2R retrieved shapes);
//! * **E-measure** over the first `K = min(32, N − 1)` retrieved shapes: with
//!   `P = (Σ_{k≤K} rel(k))/K` and `Rc = (Σ_{k≤K} rel(k))/R`, `E = 2·P·Rc/(P + Rc)` (0 when
//!   nothing relevant is among them);
//! * **discounted cumulative gain**, normalised by its ideal value:
//!   `DCG = (rel(1) + Σ_{k≥2} rel(k)/log₂k) / (1 + Σ_{j=2}^{R} 1/log₂j)`, in [0, 1].
//!
//! Overall values are means over the queries; a class's values are the means over its queries.
//! The **confusion** of class a with class b is the share of the first-tier places of a's
//! queries (R per query) taken by shapes of class b.
//!
//! [`evaluate_collection`] builds an index of labelled meshes and evaluates it; every shape is
//! ranked from the signature **stored** in the index ([`evaluate_index`]: leave-one-out, no
//! second description). Without a vocabulary trained on other shapes, the words are fit to the
//! very shapes that are then retrieved, which is optimistic; the report says which was used.

use crate::model::{RetrievalIndex, RetrievalSettings, VocabularyModel};
use crate::retrieval::average_precision;
use crate::{check, RetrievalError};
use faer::MatRef;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use wfem_base::Choice as _;

/// The E-measure looks at this many retrieved shapes (PSB, SHREC).
pub const E_MEASURE_CUTOFF: usize = 32;

/// How many confused class pairs a report keeps.
pub const CONFUSIONS_KEPT: usize = 10;

/// The retrieval measures of one query or a mean of them (each in [0, 1]; see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Measures {
    /// Average precision (its mean over queries: mAP).
    pub map: f64,
    /// Nearest neighbour: is the first result relevant.
    pub nn: f64,
    /// First tier: recall within the first R results.
    pub first_tier: f64,
    /// Second tier: recall within the first 2R results.
    pub second_tier: f64,
    /// E-measure of the first 32 results.
    pub e_measure: f64,
    /// Normalised discounted cumulative gain.
    pub dcg: f64,
}

impl Measures {
    /// The measures of one ranked relevance list (`relevance[k]` for rank k + 1, the query
    /// excluded); `None` if nothing is relevant (R = 0).
    pub fn of_ranking(relevance: &[bool]) -> Option<Self> {
        let r = relevance.iter().filter(|&&x| x).count();
        let map = average_precision(relevance)?;
        let hits = |k: usize| relevance.iter().take(k).filter(|&&x| x).count() as f64;
        let k = E_MEASURE_CUTOFF.min(relevance.len());
        let (p, rc) = (hits(k) / k as f64, hits(k) / r as f64);
        let e_measure = if p + rc > 0.0 { 2.0 * p * rc / (p + rc) } else { 0.0 };
        let gain = |k: usize| if k == 0 { 1.0 } else { 1.0 / ((k + 1) as f64).log2() };
        let dcg: f64 = relevance
            .iter()
            .enumerate()
            .filter(|(_, &x)| x)
            .map(|(k, _)| gain(k))
            .sum();
        let ideal: f64 = (0..r).map(gain).sum();
        Some(Self {
            map,
            nn: hits(1),
            first_tier: hits(r) / r as f64,
            second_tier: hits(2 * r) / r as f64,
            e_measure,
            dcg: dcg / ideal,
        })
    }

    /// The mean of several (`None` for none).
    pub fn mean<'a>(all: impl IntoIterator<Item = &'a Measures>) -> Option<Self> {
        let mut sum = Measures::default();
        let mut n = 0usize;
        for m in all {
            sum.map += m.map;
            sum.nn += m.nn;
            sum.first_tier += m.first_tier;
            sum.second_tier += m.second_tier;
            sum.e_measure += m.e_measure;
            sum.dcg += m.dcg;
            n += 1;
        }
        (n > 0).then(|| {
            let n = n as f64;
            Measures {
                map: sum.map / n,
                nn: sum.nn / n,
                first_tier: sum.first_tier / n,
                second_tier: sum.second_tier / n,
                e_measure: sum.e_measure / n,
                dcg: sum.dcg / n,
            }
        })
    }
}

/// The measures of one class.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassMeasures {
    /// The class.
    pub class: String,
    /// Its number of shapes.
    pub shapes: usize,
    /// Means over its queries.
    pub measures: Measures,
}

/// One query's outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QueryReport {
    /// The shape.
    pub name: String,
    /// Its class.
    pub class: String,
    /// Its measures (`None` if it is alone in its class).
    pub measures: Option<Measures>,
    /// The first result.
    pub nearest: Option<String>,
}

/// The old name of [`QueryReport`] (one word per meaning: results are reports).
#[deprecated(note = "renamed QueryReport")]
pub type QueryOutcome = QueryReport;

/// Class `query` confused with class `retrieved`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Confusion {
    /// The queries' class.
    pub query: String,
    /// The class that took their first-tier places.
    pub retrieved: String,
    /// The share of the first-tier places of `query`'s queries taken by `retrieved`.
    pub share: f64,
}

/// The evaluation of a labelled collection (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// Number of shapes.
    pub shapes: usize,
    /// Number of classes.
    pub classes: usize,
    /// Number of queries with a measure (shapes whose class has another member).
    pub queries: usize,
    /// Means over those queries.
    pub overall: Measures,
    /// Per class, by class name.
    pub per_class: Vec<ClassMeasures>,
    /// The most confused pairs (at most [`CONFUSIONS_KEPT`]), largest share first.
    pub confusions: Vec<Confusion>,
    /// Where the vocabulary was trained (free text, e.g. "the indexed shapes (optimistic)").
    pub vocabulary: String,
    /// Every query.
    pub per_query: Vec<QueryReport>,
}

impl EvalReport {
    /// The classes by increasing mAP.
    pub fn worst_classes(&self) -> Vec<&ClassMeasures> {
        let mut v: Vec<&ClassMeasures> = self.per_class.iter().collect();
        v.sort_by(|a, b| a.measures.map.total_cmp(&b.measures.map).then(a.class.cmp(&b.class)));
        v
    }

    /// A plain-text report: the overall measures, every class, the confused pairs.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let row = |m: &Measures| {
            format!(
                "{:.4}  {:.4}  {:.4}  {:.4}  {:.4}  {:.4}",
                m.map, m.nn, m.first_tier, m.second_tier, m.e_measure, m.dcg
            )
        };
        let width = self
            .per_class
            .iter()
            .map(|c| c.class.chars().count())
            .max()
            .unwrap_or(0)
            .max(7);
        let _ = writeln!(
            s,
            "{} shapes, {} classes, {} queries (leave-one-out); vocabulary: {}",
            self.shapes, self.classes, self.queries, self.vocabulary
        );
        let _ = writeln!(
            s,
            "{:<width$}  shapes  mAP     NN      FT      ST      E       DCG",
            "class"
        );
        let _ = writeln!(s, "{:<width$}  {:>6}  {}", "overall", self.shapes, row(&self.overall));
        for c in &self.per_class {
            let _ = writeln!(s, "{:<width$}  {:>6}  {}", c.class, c.shapes, row(&c.measures));
        }
        if !self.confusions.is_empty() {
            let _ = writeln!(s, "most confused (share of the query class's first-tier places):");
            for c in &self.confusions {
                let _ = writeln!(s, "  {} → {}: {:.3}", c.query, c.retrieved, c.share);
            }
        }
        if self.vocabulary.contains("optimistic") {
            let _ = writeln!(
                s,
                "note: the words were fit to shapes that are also evaluated, which flatters every \
                 measure; a vocabulary trained on other shapes gives the honest number"
            );
        }
        s
    }
}

/// Evaluates rankings: `rank(q)` lists every other item (not q) by increasing distance.
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] if names and classes differ in length or a ranking
/// does not hold every other item once, [`RetrievalError::NothingToAverage`] if no class has
/// two members, and those of `rank`.
pub fn evaluate_rankings(
    names: &[String],
    classes: &[String],
    vocabulary: &str,
    rank: impl Fn(usize) -> Result<Vec<usize>, RetrievalError> + Sync,
) -> Result<EvalReport, RetrievalError> {
    let n = names.len();
    check::non_empty("labelled shapes", n)?;
    check::same("classes vs shapes", n, classes.len())?;
    let rankings: Vec<Vec<usize>> = (0..n)
        .into_par_iter()
        .map(|q| {
            let order = rank(q)?;
            let mut seen = vec![false; n];
            seen[q] = true;
            let complete =
                order.len() == n - 1 && order.iter().all(|&j| j < n && !std::mem::replace(&mut seen[j], true));
            if complete {
                Ok(order)
            } else {
                Err(RetrievalError::DimensionMismatch {
                    what: "ranking vs the other shapes",
                    expected: n - 1,
                    actual: order.len(),
                })
            }
        })
        .collect::<Result<_, _>>()?;
    let mut sizes: BTreeMap<&str, usize> = BTreeMap::new();
    for c in classes {
        *sizes.entry(c).or_default() += 1;
    }
    let per_query: Vec<QueryReport> = (0..n)
        .map(|q| {
            let relevance: Vec<bool> = rankings[q].iter().map(|&j| classes[j] == classes[q]).collect();
            QueryReport {
                name: names[q].clone(),
                class: classes[q].clone(),
                measures: Measures::of_ranking(&relevance),
                nearest: rankings[q].first().map(|&j| names[j].clone()),
            }
        })
        .collect();
    let overall = Measures::mean(per_query.iter().filter_map(|o| o.measures.as_ref())).ok_or(
        RetrievalError::NothingToAverage {
            what: "no class has two shapes",
        },
    )?;
    let per_class = sizes
        .iter()
        .filter_map(|(&class, &shapes)| {
            let m = Measures::mean(
                per_query
                    .iter()
                    .filter(|o| o.class == class)
                    .filter_map(|o| o.measures.as_ref()),
            )?;
            Some(ClassMeasures {
                class: class.to_string(),
                shapes,
                measures: m,
            })
        })
        .collect();
    // First-tier places of each query class taken by each other class.
    let mut taken: BTreeMap<(&str, &str), usize> = BTreeMap::new();
    for q in 0..n {
        let r = sizes[classes[q].as_str()] - 1;
        for &j in rankings[q].iter().take(r) {
            if classes[j] != classes[q] {
                *taken.entry((&classes[q], &classes[j])).or_default() += 1;
            }
        }
    }
    let mut confusions: Vec<Confusion> = taken
        .into_iter()
        .map(|((a, b), count)| {
            let places = sizes[a] * (sizes[a] - 1);
            Confusion {
                query: a.to_string(),
                retrieved: b.to_string(),
                share: count as f64 / places as f64,
            }
        })
        .collect();
    confusions.sort_by(|a, b| b.share.total_cmp(&a.share).then(a.query.cmp(&b.query)));
    confusions.truncate(CONFUSIONS_KEPT);
    Ok(EvalReport {
        shapes: n,
        classes: sizes.len(),
        queries: per_query.iter().filter(|o| o.measures.is_some()).count(),
        overall,
        per_class,
        confusions,
        vocabulary: vocabulary.to_string(),
        per_query,
    })
}

/// Evaluates a square distance matrix (row q = distances from shape q; ties → lower index).
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] for a non-square matrix or wrong label counts,
/// [`RetrievalError::NonFinite`], and those of [`evaluate_rankings`].
pub fn evaluate_distances(
    names: &[String],
    classes: &[String],
    distances: MatRef<'_, f64>,
    vocabulary: &str,
) -> Result<EvalReport, RetrievalError> {
    check::same("distance matrix rows vs shapes", names.len(), distances.nrows())?;
    check::same("distance matrix columns vs rows", distances.nrows(), distances.ncols())?;
    check::finite_mat("distances", distances)?;
    evaluate_rankings(names, classes, vocabulary, |q| {
        let row: Vec<f64> = (0..distances.ncols()).map(|j| distances[(q, j)]).collect();
        crate::retrieval::rank(&row, q)
    })
}

/// Evaluates an index: every entry queries the others **from its stored signature** (one O(N)
/// scan per query, nothing described again); `classes[i]` labels entry i.
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] if the labels do not match the entries, and those of
/// [`RetrievalIndex::rank`] and [`evaluate_rankings`].
pub fn evaluate_index(
    index: &RetrievalIndex,
    classes: &[String],
    vocabulary: &str,
) -> Result<EvalReport, RetrievalError> {
    let entries = index.entries();
    check::same("classes vs index entries", entries.len(), classes.len())?;
    let names: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    evaluate_rankings(&names, classes, vocabulary, |q| {
        Ok(index
            .rank(&entries[q].signature)?
            .into_iter()
            .map(|r| r.entry)
            .filter(|&j| j != q)
            .collect())
    })
}

/// Where the index's vocabulary was trained, for a report: "trained on N other shapes" when
/// none of its training shapes is indexed (an honest evaluation), otherwise how many of them
/// are (optimistic: the words were fit to the shapes then retrieved). Shapes are matched by
/// name.
pub fn vocabulary_source(index: &RetrievalIndex) -> String {
    let trained = &index.vocabulary().info().shapes;
    let indexed: std::collections::HashSet<&str> = index.entries().iter().map(|e| e.name.as_str()).collect();
    let inside = trained.iter().filter(|s| indexed.contains(s.as_str())).count();
    if inside == 0 {
        format!("trained on {} other shapes", trained.len())
    } else if inside == trained.len() && inside == indexed.len() {
        "trained on the indexed shapes (optimistic)".to_string()
    } else {
        format!(
            "trained on {} shapes, {inside} of them indexed (optimistic)",
            trained.len()
        )
    }
}

/// What [`evaluate_collection`] returns: the index it built and its evaluation.
#[derive(Clone, Debug)]
pub struct CollectionEvaluation {
    /// The index of the labelled shapes (e.g. to save it).
    pub index: RetrievalIndex,
    /// The evaluation.
    pub report: EvalReport,
}

/// Builds an index of labelled shapes — meshes, point clouds or both ([`crate::model::AsShape`]) —
/// ([`RetrievalIndex::build`]: trained on them unless a
/// vocabulary is given) and evaluates it ([`evaluate_index`]). The one call behind
/// `wfem retrieval eval`.
///
/// # Errors
/// [`RetrievalError::DimensionMismatch`] if classes and shapes differ in number, and those of
/// [`RetrievalIndex::build`] and [`evaluate_index`].
pub fn evaluate_collection(
    shapes: &[(String, impl crate::model::AsShape)],
    classes: &[String],
    settings: &RetrievalSettings,
    vocabulary: Option<VocabularyModel>,
) -> Result<CollectionEvaluation, RetrievalError> {
    check::same("classes vs shapes", shapes.len(), classes.len())?;
    let index = RetrievalIndex::build(shapes, settings, vocabulary)?;
    let report = evaluate_index(&index, classes, &vocabulary_source(&index))?;
    Ok(CollectionEvaluation { index, report })
}

/// How a shape's class is read from its file path when no label file is given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClassRule {
    /// The name of the folder holding the file (`chairs/chair_07.off` → `chairs`).
    #[default]
    Folder,
    /// The file name without its extension and digits, trailing `_`, `-`, `.` and spaces
    /// removed (`cat10.off` → `cat`, `david_3.obj` → `david`).
    Stem,
}

wfem_base::registry! {
    ClassRule as "class rule" {
        ClassRule::Folder = ClassRule::Folder => "folder" ["parent"]:
            "the folder holding the file (default)",
        ClassRule::Stem = ClassRule::Stem => "stem" ["name"]:
            "the file name without extension and digits (cat10.off → cat)",
    }
}

impl ClassRule {
    /// The class of the file at `path`.
    ///
    /// # Errors
    /// [`RetrievalError::Labels`] if the path has no such part (no folder, or a name of digits).
    pub fn class_of(&self, path: &Path) -> Result<String, RetrievalError> {
        let class = match self {
            ClassRule::Folder => path
                .parent()
                .and_then(|p| p.file_name())
                .map(|s| s.to_string_lossy().into_owned()),
            ClassRule::Stem => path.file_stem().map(|s| {
                let letters: String = s.to_string_lossy().chars().filter(|c| !c.is_ascii_digit()).collect();
                letters.trim_end_matches(['_', '-', '.', ' ']).to_string()
            }),
        };
        match class {
            Some(c) if !c.is_empty() => Ok(c),
            _ => Err(RetrievalError::Labels {
                location: path.display().to_string(),
                reason: format!("no class by the {} rule", self.name()),
            }),
        }
    }
}

/// Parses a label file as spreadsheet programs write it: one `file,class` pair per line; a
/// UTF-8 byte-order mark, CRLF line ends, blank lines and lines starting with `#` are skipped;
/// fields may be quoted (`"a, b.off",cat`, `""` for a quote inside); an optional header line
/// (`file,class`, `path,label`, `name,category` in any case) is skipped; fields are trimmed.
/// `source` names the file in errors.
///
/// # Errors
/// [`RetrievalError::Labels`] naming the line for a line without two non-empty fields, an
/// unclosed quote, a file listed twice, or a file without any pair.
pub fn parse_labels(text: &str, source: &str) -> Result<Vec<(String, String)>, RetrievalError> {
    let bad = |line: usize, reason: &str| RetrievalError::Labels {
        location: format!("{source}:{line}"),
        reason: reason.to_string(),
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out: Vec<(String, String)> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut first = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields = csv_fields(line).ok_or_else(|| bad(i + 1, "a quoted field is not closed"))?;
        let header = first && fields.len() == 2 && is_header(&fields[0], &fields[1]);
        first = false;
        if header {
            continue;
        }
        match fields.as_slice() {
            [file, class] if !file.is_empty() && !class.is_empty() => {
                if !seen.insert(file.clone()) {
                    return Err(bad(i + 1, "this file is listed twice"));
                }
                out.push((file.clone(), class.clone()));
            }
            _ => return Err(bad(i + 1, "expected `file,class`")),
        }
    }
    if out.is_empty() {
        return Err(RetrievalError::Labels {
            location: source.to_string(),
            reason: "no `file,class` line".into(),
        });
    }
    Ok(out)
}

/// Whether a first line names the columns rather than a shape.
fn is_header(file: &str, class: &str) -> bool {
    let (f, c) = (file.to_ascii_lowercase(), class.to_ascii_lowercase());
    ["file", "path", "name", "mesh", "shape", "filename"].contains(&f.as_str())
        && ["class", "label", "category", "family"].contains(&c.as_str())
}

/// The comma-separated fields of one line, trimmed, with RFC 4180 quoting (`"a, b",c`, `""`
/// for a quote inside quotes); `None` for an unclosed quote.
fn csv_fields(line: &str) -> Option<Vec<String>> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if quoted {
            if c != '"' {
                field.push(c);
            } else if chars.peek() == Some(&'"') {
                chars.next();
                field.push('"');
            } else {
                quoted = false;
            }
        } else if c == '"' && field.trim().is_empty() {
            field.clear();
            quoted = true;
        } else if c == ',' {
            fields.push(field.trim().to_string());
            field.clear();
        } else {
            field.push(c);
        }
    }
    if quoted {
        return None;
    }
    fields.push(field.trim().to_string());
    Some(fields)
}

/// Reads a label file ([`parse_labels`]) and resolves each file against the label file's
/// folder (absolute paths are kept).
///
/// # Errors
/// [`RetrievalError::Storage`] if the file cannot be read (regular files only) or is not
/// UTF-8, and those of [`parse_labels`].
pub fn read_label_file(path: &Path) -> Result<Vec<(std::path::PathBuf, String)>, RetrievalError> {
    let storage = |reason: String| RetrievalError::Storage {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = mesh_fem::io::read_regular_file(path).map_err(|e| storage(e.to_string()))?;
    let text = String::from_utf8(bytes).map_err(|_| storage("not UTF-8 text".into()))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    Ok(parse_labels(&text, &path.display().to_string())?
        .into_iter()
        .map(|(file, class)| (dir.join(file), class))
        .collect())
}
