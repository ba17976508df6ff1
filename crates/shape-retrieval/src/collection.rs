//! A collection of shapes described for a vocabulary or an index, the way users index folders:
//! every shape described in parallel, each one reported as it is done, and a shape that cannot
//! be described either left out and reported with its reason ([`Tolerance::Skip`], the
//! default of `wfem retrieval build` and `wfem.RetrievalIndex.build`) or fatal
//! ([`Tolerance::Strict`]). The CLI and the Python package call these two functions; neither
//! re-implements the loop, and the strict constructors [`RetrievalIndex::build`] and
//! [`ShapeFeatures::compute_many`] are defined here as its strict case. A collection may mix
//! meshes and point clouds ([`AsShape`]).

use crate::model::{
    AsShape, BagSettings, DescriptorSettings, RetrievalIndex, RetrievalSettings, ShapeFeatures, ShapeRef,
    VocabularyModel,
};
use crate::RetrievalError;
use rayon::prelude::*;
use shifted_solve::SolveError;
use wfem_base::interrupt;
use wfem_heat::HeatError;

/// What a collection does with a shape that cannot be described.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tolerance {
    /// Leave it out and report it ([`Described::refused`]); fail only when no shape is left.
    #[default]
    Skip,
    /// All or nothing: the first failure (in input order) is the error.
    Strict,
}

/// A shape left out of a collection, with why.
#[derive(Debug)]
pub struct Refusal {
    /// The shape's name (e.g. its file).
    pub name: String,
    /// Why it could not be described.
    pub reason: RetrievalError,
}

/// The described shapes of a collection, in input order, and those left out.
#[derive(Debug)]
pub struct Described {
    /// The features of every usable shape, in input order.
    pub features: Vec<ShapeFeatures>,
    /// The shapes left out (only with [`Tolerance::Skip`]), in input order.
    pub refused: Vec<Refusal>,
}

/// Describes every shape in parallel (one eigensolve each), calling `done(name)` as each one
/// finishes (from the worker threads, in completion order).
///
/// # Errors
/// A bad descriptor or bag setting (before any shape is described); with
/// [`Tolerance::Strict`], the first shape that fails as [`RetrievalError::Shape`] (with
/// [`Tolerance::Skip`] every failure is a [`Refusal`], even when no shape is left).
pub fn describe_collection(
    shapes: &[(String, impl AsShape)],
    descriptor: &DescriptorSettings,
    bags: &BagSettings,
    tolerance: Tolerance,
    done: &(dyn Fn(&str) + Sync),
) -> Result<Described, RetrievalError> {
    descriptor.validate()?;
    bags.validate(descriptor.eigenpairs)?;
    let (features, refused) = each_shape(&borrowed(shapes), tolerance, done, &|name, shape| {
        ShapeFeatures::compute(name, &shape, descriptor, bags)
    })?;
    Ok(Described { features, refused })
}

/// The error when no shape of a collection could be used, naming each with its reason.
pub fn nothing_usable(refused: &[Refusal]) -> RetrievalError {
    RetrievalError::NothingUsable {
        shapes: refused.len(),
        reasons: refused
            .iter()
            .map(|r| format!("{}: {}", r.name, r.reason))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

/// [`RetrievalIndex::build`] over a collection: the usable shapes described
/// ([`describe_collection`]), the vocabulary trained on them unless one is given, and every
/// usable shape indexed. Returns the index and the shapes left out.
///
/// # Errors
/// Those of [`describe_collection`]; [`RetrievalError::NothingUsable`] when every shape was
/// refused; those of [`VocabularyModel::train`] and [`RetrievalIndex::insert`].
pub fn build_index(
    shapes: &[(String, impl AsShape)],
    settings: &RetrievalSettings,
    vocabulary: Option<VocabularyModel>,
    tolerance: Tolerance,
    done: &(dyn Fn(&str) + Sync),
) -> Result<(RetrievalIndex, Vec<Refusal>), RetrievalError> {
    let descriptor = vocabulary
        .as_ref()
        .map_or(&settings.descriptor, |v| v.descriptor())
        .clone();
    let described = describe_collection(shapes, &descriptor, &settings.bags, tolerance, done)?;
    if described.features.is_empty() && !described.refused.is_empty() {
        return Err(nothing_usable(&described.refused));
    }
    let vocabulary = match vocabulary {
        Some(v) => v,
        None => VocabularyModel::train(&descriptor, &settings.training, &described.features)?,
    };
    let mut index = RetrievalIndex::new(vocabulary, settings.bags.clone())?;
    for f in &described.features {
        index.insert(f)?;
    }
    Ok((index, described.refused))
}

/// The entries of shapes to append to an existing index ([`RetrievalIndex::describe`]: its
/// cleaning, descriptor and vocabulary), described in parallel with the same progress and
/// tolerance as [`describe_collection`]; entries in input order.
///
/// # Errors
/// With [`Tolerance::Strict`], the first shape that fails as [`RetrievalError::Shape`].
pub fn describe_entries(
    index: &RetrievalIndex,
    shapes: &[(String, impl AsShape)],
    tolerance: Tolerance,
    done: &(dyn Fn(&str) + Sync),
) -> Result<(Vec<crate::model::IndexEntry>, Vec<Refusal>), RetrievalError> {
    each_shape(&borrowed(shapes), tolerance, done, &|name, shape| {
        index.describe(name, &shape)
    })
}

// The strict constructors of the model types are the collection loop's strict case; they
// live here, above the model, so that the model does not depend on its collections.
impl RetrievalIndex {
    /// Builds an index in one go: describes `shapes` — meshes, point clouds or a mix
    /// ([`AsShape`]) — in parallel, trains the vocabulary on them unless one is given (training
    /// on the indexed shapes themselves is optimistic; see the module docs), and inserts every
    /// shape. A given vocabulary brings its own descriptor settings (Laplacian and cleaning
    /// included), which then replace `settings.descriptor`: its words only mean something for
    /// descriptors computed as its own were.
    ///
    /// # Errors
    /// Those of [`ShapeFeatures::compute_many`], [`VocabularyModel::train`], [`Self::insert`].
    pub fn build<S: AsShape>(
        shapes: &[(String, S)],
        settings: &RetrievalSettings,
        vocabulary: Option<VocabularyModel>,
    ) -> Result<Self, RetrievalError> {
        build_index(shapes, settings, vocabulary, Tolerance::Strict, &|_| ()).map(|(index, _)| index)
    }
}

impl ShapeFeatures {
    /// [`Self::compute`] for many shapes in parallel (one eigensolve per shape), in input order.
    ///
    /// # Errors
    /// The first failure, as [`RetrievalError::Shape`] naming the shape.
    pub fn compute_many<S: AsShape>(
        shapes: &[(String, S)],
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Vec<Self>, RetrievalError> {
        describe_collection(shapes, descriptor, bags, Tolerance::Strict, &|_| ()).map(|d| d.features)
    }
}

/// The shapes of a collection, borrowed: the generic entry points hand them to one loop.
fn borrowed(shapes: &[(String, impl AsShape)]) -> Vec<(&str, ShapeRef<'_>)> {
    shapes.iter().map(|(name, s)| (name.as_str(), s.as_shape())).collect()
}

/// `describe(name, shape)` for every shape in parallel, `done(name)` as each finishes; the
/// results in input order, split into kept values and refusals by `tolerance`.
fn each_shape<T: Send>(
    shapes: &[(&str, ShapeRef<'_>)],
    tolerance: Tolerance,
    done: &(dyn Fn(&str) + Sync),
    describe: &(dyn Fn(&str, ShapeRef<'_>) -> Result<T, RetrievalError> + Sync),
) -> Result<(Vec<T>, Vec<Refusal>), RetrievalError> {
    // The caller's interrupt reaches every worker; an interrupted collection stops before its
    // next shape.
    let interrupt = interrupt::current();
    let results: Vec<Result<T, RetrievalError>> = shapes
        .par_iter()
        .map(|&(name, shape)| {
            interrupt::within(interrupt.as_ref(), || {
                interrupt::checkpoint().map_err(|i| HeatError::from(SolveError::from(i)))?;
                let value = describe(name, shape);
                done(name);
                value
            })
        })
        .collect();
    if let Err(i) = interrupt::within(interrupt.as_ref(), interrupt::checkpoint) {
        return Err(HeatError::from(SolveError::from(i)).into());
    }
    let mut kept = Vec::with_capacity(shapes.len());
    let mut refused = Vec::new();
    for ((name, _), result) in shapes.iter().zip(results) {
        match result {
            Ok(value) => kept.push(value),
            Err(reason) if tolerance == Tolerance::Skip => refused.push(Refusal {
                name: name.to_string(),
                reason,
            }),
            Err(e) => {
                return Err(RetrievalError::Shape {
                    name: name.to_string(),
                    source: Box::new(e),
                })
            }
        }
    }
    Ok((kept, refused))
}
