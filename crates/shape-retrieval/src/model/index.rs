//! [`RetrievalIndex`]: the vocabulary, the bag settings and one [`IndexEntry`] per shape;
//! queries rank the entries by the fused distance.

use super::{AsShape, BagSettings, ShapeFeatures, VocabularyModel};
use crate::check;
use crate::RetrievalError;

/// The number of results a query returns unless told otherwise (the library's and Python's
/// `k`; the command line shows fewer, `wfem retrieval query --top`).
pub const DEFAULT_RESULTS: usize = 10;

/// The retrieval signature of one shape: its normalised bag and its global signature.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeSignature {
    /// The bag (length V, non-negative, sums to 1).
    pub bag: Vec<f64>,
    /// The global signature (length m; empty without fusion).
    pub global: Vec<f64>,
}

/// One indexed shape.
#[derive(Clone, Debug, PartialEq)]
pub struct IndexEntry {
    /// Its name (the file as given to `build`).
    pub name: String,
    /// Its signature.
    pub signature: ShapeSignature,
}

/// One result of a query: the entry and its distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ranked {
    /// Position of the entry in the index.
    pub entry: usize,
    /// Its distance to the query (≥ 0).
    pub distance: f64,
}

/// A retrieval index: vocabulary, bag settings, and the signature of every indexed shape.
#[derive(Clone, Debug)]
pub struct RetrievalIndex {
    vocabulary: VocabularyModel,
    bags: BagSettings,
    entries: Vec<IndexEntry>,
}

impl RetrievalIndex {
    /// An empty index.
    ///
    /// # Errors
    /// Those of [`BagSettings::validate`].
    pub fn new(vocabulary: VocabularyModel, bags: BagSettings) -> Result<Self, RetrievalError> {
        bags.validate(vocabulary.descriptor().eigenpairs)?;
        Ok(Self {
            vocabulary,
            bags,
            entries: Vec::new(),
        })
    }

    /// Reassembles an index from stored parts, validating every entry: bag length V, bag values
    /// finite, in [0, 1] and summing to 1 (±1e−6), global signatures finite of length m.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] naming the entry and the value.
    pub fn from_parts(
        vocabulary: VocabularyModel,
        bags: BagSettings,
        entries: Vec<IndexEntry>,
    ) -> Result<Self, RetrievalError> {
        let mut index = Self::new(vocabulary, bags).map_err(|e| RetrievalError::InvalidModel {
            what: "index",
            reason: e.to_string(),
        })?;
        for e in entries {
            index.push_checked(e)?;
        }
        Ok(index)
    }

    fn push_checked(&mut self, entry: IndexEntry) -> Result<(), RetrievalError> {
        let invalid = |reason: String| RetrievalError::InvalidModel { what: "index", reason };
        let (i, name) = (self.entries.len(), &entry.name);
        let v = self.bags.bag_len(self.vocabulary.vocabulary().size());
        let bag = &entry.signature.bag;
        if bag.len() != v {
            return Err(invalid(format!(
                "entry {i} ({name}): bag has {} bins, the settings {v}",
                bag.len()
            )));
        }
        if let Some((j, x)) = bag
            .iter()
            .enumerate()
            .find(|(_, x)| !(x.is_finite() && (0.0..=1.0).contains(*x)))
        {
            return Err(invalid(format!(
                "entry {i} ({name}): bag value {x:e} at word {j} is not in [0, 1]"
            )));
        }
        let sum: f64 = bag.iter().sum();
        if (sum - 1.0).abs() > 1e-6 {
            return Err(invalid(format!("entry {i} ({name}): bag sums to {sum}, not 1")));
        }
        let m = self.bags.global.map_or(0, |g| g.len());
        let global = &entry.signature.global;
        if global.len() != m {
            return Err(invalid(format!(
                "entry {i} ({name}): global signature has {} values, the settings {m}",
                global.len()
            )));
        }
        // Every global signature of a real shape is within a few hundred of 0 (ln(λA), λA/4πi,
        // histogram bins); this also keeps every sum finite.
        if let Some((j, x)) = global.iter().enumerate().find(|(_, x)| x.is_nan() || x.abs() >= 1e3) {
            return Err(invalid(format!(
                "entry {i} ({name}): global value {x:e} at {j} is not finite or not below 1e3"
            )));
        }
        self.entries.push(entry);
        Ok(())
    }

    /// The vocabulary model.
    pub fn vocabulary(&self) -> &VocabularyModel {
        &self.vocabulary
    }

    /// The bag settings.
    pub fn bags(&self) -> &BagSettings {
        &self.bags
    }

    /// The indexed shapes.
    pub fn entries(&self) -> &[IndexEntry] {
        &self.entries
    }

    /// The entry named `name` ([`resolve_name`]).
    ///
    /// # Errors
    /// [`RetrievalError::UnknownShape`].
    pub fn find(&self, name: &str) -> Result<usize, RetrievalError> {
        resolve_name(self.entries.iter().map(|e| e.name.as_str()), name)
    }

    /// Every entry by increasing distance to entry `entry`'s stored signature, itself left
    /// out: a query by an indexed shape, nothing described again.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if there is no such entry.
    pub fn rank_entry(&self, entry: usize) -> Result<Vec<Ranked>, RetrievalError> {
        let Some(e) = self.entries.get(entry) else {
            return Err(RetrievalError::DimensionMismatch {
                what: "entry index vs entries",
                expected: self.entries.len(),
                actual: entry,
            });
        };
        let mut ranked = self.rank(&e.signature)?;
        ranked.retain(|r| r.entry != entry);
        Ok(ranked)
    }

    /// Computes the features of a shape (a mesh or a point cloud) with the index's settings
    /// (one eigensolve): a query is always described as the indexed shapes were, with the
    /// recorded Laplacian and cleaning.
    ///
    /// # Errors
    /// Those of [`ShapeFeatures::compute`].
    pub fn features(&self, name: &str, shape: &impl AsShape) -> Result<ShapeFeatures, RetrievalError> {
        ShapeFeatures::compute(name, shape, self.vocabulary.descriptor(), &self.bags)
    }

    /// The signature of a described shape.
    ///
    /// # Errors
    /// Those of [`VocabularyModel::bag`]; [`RetrievalError::DimensionMismatch`] if the global
    /// signature does not match the settings.
    pub fn signature(&self, features: &ShapeFeatures) -> Result<ShapeSignature, RetrievalError> {
        let bag = self.vocabulary.shape_bag(features, &self.bags)?;
        let m = self.bags.global.map_or(0, |g| g.len());
        check::same("global signature length", m, features.global.len())?;
        check::finite_slice("global signature", &features.global)?;
        Ok(ShapeSignature {
            bag,
            global: features.global.clone(),
        })
    }

    /// The entry of a shape (a mesh or a point cloud) with the index's settings:
    /// [`Self::features`] (one eigensolve) and [`Self::signature`] — what an append stores and a
    /// query compares.
    ///
    /// # Errors
    /// Those of [`Self::features`] and [`Self::signature`].
    pub fn describe(&self, name: &str, shape: &impl AsShape) -> Result<IndexEntry, RetrievalError> {
        let features = self.features(name, shape)?;
        Ok(IndexEntry {
            name: name.to_string(),
            signature: self.signature(&features)?,
        })
    }

    /// Adds a described shape.
    ///
    /// # Errors
    /// Those of [`Self::signature`].
    pub fn insert(&mut self, features: &ShapeFeatures) -> Result<(), RetrievalError> {
        let signature = self.signature(features)?;
        self.push_checked(IndexEntry {
            name: features.name.clone(),
            signature,
        })
    }

    /// The fused distance between two signatures (see the module docs).
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`], [`RetrievalError::NonFinite`],
    /// [`RetrievalError::NegativeBin`].
    pub fn distance(&self, a: &ShapeSignature, b: &ShapeSignature) -> Result<f64, RetrievalError> {
        let bag = self.bags.distance.between(&a.bag, &b.bag)?;
        check::same("global signature lengths", a.global.len(), b.global.len())?;
        check::finite_slice("global signature", &a.global)?;
        check::finite_slice("global signature", &b.global)?;
        Ok(self.fused(bag, &a.global, &b.global))
    }

    fn fused(&self, bag: f64, a: &[f64], b: &[f64]) -> f64 {
        match &self.bags.global {
            Some(g) if g.weight > 0.0 => bag + g.weight * g.distance(a, b),
            _ => bag,
        }
    }

    /// The distance of a validated query ([`Self::distance`] checked it against one entry) to
    /// a stored signature given as its bag followed by its global signature (`row`, V + m
    /// values), without checks: the inner loop of a scan over an external store.
    pub fn row_distance(&self, query: &ShapeSignature, row: &[f64]) -> f64 {
        let v = query.bag.len().min(row.len());
        let (bag, global) = row.split_at(v);
        self.fused(self.bags.distance.unchecked(&query.bag, bag), &query.global, global)
    }

    /// Every entry by increasing distance to the query signature (ties → lower entry index):
    /// one O(N·V) scan.
    ///
    /// # Errors
    /// Those of [`Self::distance`] (for the query only: entries were validated on insertion).
    pub fn rank(&self, query: &ShapeSignature) -> Result<Vec<Ranked>, RetrievalError> {
        if let Some(first) = self.entries.first() {
            // Validates the query once; the scan below then uses the unchecked formulas.
            self.distance(query, &first.signature)?;
        }
        let mut ranked: Vec<Ranked> = self
            .entries
            .iter()
            .enumerate()
            .map(|(entry, e)| Ranked {
                entry,
                distance: self.fused(
                    self.bags.distance.unchecked(&query.bag, &e.signature.bag),
                    &query.global,
                    &e.signature.global,
                ),
            })
            .collect();
        ranked.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.entry.cmp(&b.entry)));
        Ok(ranked)
    }
}

/// Which of `names` (in order) a user means by `wanted`: the one named exactly so; otherwise
/// the only one whose file name (`dir/cat0.off` → `cat0.off`) or file stem (`cat0`) it is.
///
/// # Errors
/// [`RetrievalError::UnknownShape`] when none matches or several do (named in the message).
pub fn resolve_name<'a>(names: impl Iterator<Item = &'a str>, wanted: &str) -> Result<usize, RetrievalError> {
    let names: Vec<&str> = names.collect();
    let exact: Vec<usize> = (0..names.len()).filter(|&i| names[i] == wanted).collect();
    if exact.len() > 1 {
        return Err(RetrievalError::UnknownShape {
            name: wanted.to_string(),
            reason: format!(
                "{} indexed shapes are named {wanted:?} (the index repeats the name): query with the file instead",
                exact.len()
            ),
        });
    }
    let matches = if exact.is_empty() {
        let path = |i: usize| std::path::Path::new(names[i]).to_path_buf();
        (0..names.len())
            .filter(|&i| {
                let p = path(i);
                p.file_name().is_some_and(|f| f == wanted) || p.file_stem().is_some_and(|f| f == wanted)
            })
            .collect()
    } else {
        exact
    };
    match matches.as_slice() {
        [one] => Ok(*one),
        [] => Err(RetrievalError::UnknownShape {
            name: wanted.to_string(),
            reason: format!(
                "no indexed shape is named {wanted:?} (of {} shapes{}); give a name as `build` stored it, its file name or its stem",
                names.len(),
                names
                    .first()
                    .map_or(String::new(), |n| format!(", e.g. {n:?}"))
            ),
        }),
        several => Err(RetrievalError::UnknownShape {
            name: wanted.to_string(),
            reason: format!(
                "{wanted:?} names {} indexed shapes ({}); give the whole name",
                several.len(),
                several
                    .iter()
                    .take(5)
                    .map(|&i| format!("{:?}", names[i]))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }),
    }
}

#[cfg(test)]
mod name_tests {
    use super::resolve_name;
    use crate::RetrievalError;

    #[test]
    fn names_resolve_exactly_then_by_file_name_or_stem() {
        let names = ["data/cat0.off", "data/cat1.off", "other/cat1.ply", "dog"];
        let find = |w: &str| resolve_name(names.iter().copied(), w);
        assert_eq!(find("data/cat0.off").unwrap(), 0);
        assert_eq!(find("cat0.off").unwrap(), 0);
        assert_eq!(find("cat0").unwrap(), 0);
        assert_eq!(find("cat1.ply").unwrap(), 2);
        assert_eq!(find("dog").unwrap(), 3);
        match find("cat1") {
            Err(RetrievalError::UnknownShape { reason, .. }) => {
                assert!(reason.contains("names 2 indexed shapes"), "{reason}");
                assert!(
                    reason.contains("data/cat1.off") && reason.contains("other/cat1.ply"),
                    "{reason}"
                );
            }
            other => panic!("{other:?}"),
        }
        match find("horse") {
            Err(RetrievalError::UnknownShape { reason, .. }) => assert!(reason.contains("of 4 shapes"), "{reason}"),
            other => panic!("{other:?}"),
        }
        assert!(resolve_name(std::iter::empty(), "x").is_err());
        match resolve_name(["a/x.off", "a/x.off"].into_iter(), "a/x.off") {
            Err(RetrievalError::UnknownShape { reason, .. }) => {
                assert!(reason.contains("repeats the name"), "{reason}")
            }
            other => panic!("{other:?}"),
        }
    }
}
