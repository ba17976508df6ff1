//! [`ShapeFeatures`] (what a shape contributes: descriptors, weights, global signature,
//! eigenpairs) and [`VocabularyModel`] (z-score statistics and words trained on them).

use super::{AsShape, BagSettings, DescriptorSettings, TrainingParams};
use crate::bof::{Assignment, Vocabulary, VocabularyParams};
use crate::check;
use crate::descriptor::ShapeDescriptors;
use crate::spatial::ShapeSpectrum;
use crate::standardize::Standardizer;
use crate::RetrievalError;
use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

/// The dense descriptors of one shape with what its bag needs: the vertex weights and the
/// global signature. Computed once per shape ([`ShapeFeatures::compute`]) and reused for
/// training, indexing and querying.
#[derive(Clone, Debug)]
pub struct ShapeFeatures {
    /// A name for reports (e.g. the file).
    pub name: String,
    /// m × d dense descriptors (not z-scored), one row per own vertex of the shape (m = n
    /// unless holes were filled).
    pub descriptors: Mat<f64>,
    /// m vertex weights.
    pub weights: Vec<f64>,
    /// The global signature (empty without fusion).
    pub global: Vec<f64>,
    /// The eigenpairs of the described vertices, for spatial bags (`None` without them).
    pub spectrum: Option<ShapeSpectrum>,
}

impl ShapeFeatures {
    /// Describes one shape, a mesh or a point cloud ([`AsShape`]): cleaning and operators
    /// ([`DescriptorSettings::shape`]), one eigensolve, the dense descriptor, the weights and
    /// the global signature.
    ///
    /// # Errors
    /// [`RetrievalError::Mesh`] from assembly, and those of [`Descriptor::compute`](crate::descriptor::Descriptor::compute),
    /// [`VertexWeights::compute`](super::VertexWeights::compute), [`GlobalSignature::compute`](super::GlobalSignature::compute).
    pub fn compute(
        name: &str,
        shape: &impl AsShape,
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Self, RetrievalError> {
        let mut shape = descriptor.shape(shape)?;
        Self::from_shape(name, &mut shape, descriptor, bags)
    }

    /// As [`Self::compute`] on prepared operators (and possibly cached eigenbases).
    ///
    /// # Errors
    /// Those of [`Self::compute`].
    pub fn from_shape(
        name: &str,
        shape: &mut ShapeDescriptors,
        descriptor: &DescriptorSettings,
        bags: &BagSettings,
    ) -> Result<Self, RetrievalError> {
        bags.validate(descriptor.eigenpairs)?;
        let descriptors = descriptor.descriptor.compute(shape)?;
        let weights = bags.weights.compute(shape)?;
        let global = match &bags.global {
            Some(g) => g.compute(shape)?,
            None => Vec::new(),
        };
        let mut features = Self::new(name, shape, descriptors, weights, global)?;
        if bags.spatial.is_some() {
            features.attach_spectrum(shape)?;
        }
        Ok(features)
    }

    /// Keeps the wFEM eigenpairs of `shape` (restricted to its described vertices), which
    /// spatial bags need.
    ///
    /// # Errors
    /// Those of the eigensolver; [`RetrievalError::DimensionMismatch`] if `shape` is not the
    /// one described.
    pub fn attach_spectrum(&mut self, shape: &mut ShapeDescriptors) -> Result<(), RetrievalError> {
        let m = shape.described_vertices();
        check::same("described vertices vs features", self.weights.len(), m)?;
        let area = shape.area();
        let basis = shape.eigenbasis(false)?;
        self.spectrum = Some(ShapeSpectrum {
            values: basis.values.clone(),
            vectors: basis.vectors.subrows(0, m).to_owned(),
            area,
        });
        Ok(())
    }

    /// Assembles the features of `shape` from their parts, keeping the rows of the shape's own
    /// vertices only ([`ShapeDescriptors::described_vertices`]: the vertices of filled holes
    /// take part in the operators, not in the bags). `descriptors` has a row per vertex of the
    /// prepared mesh (or per own vertex), `weights` one per own vertex, as
    /// [`VertexWeights::compute`](super::VertexWeights::compute) gives them.
    ///
    /// # Errors
    /// [`RetrievalError::DimensionMismatch`] if the sizes do not match the shape.
    pub fn new(
        name: &str,
        shape: &ShapeDescriptors,
        descriptors: Mat<f64>,
        weights: Vec<f64>,
        global: Vec<f64>,
    ) -> Result<Self, RetrievalError> {
        let m = shape.described_vertices();
        check::same("vertex weights vs described vertices", m, weights.len())?;
        let descriptors = if descriptors.nrows() == m {
            descriptors
        } else {
            check::same(
                "descriptor rows vs vertices",
                shape.mesh().n_vertices(),
                descriptors.nrows(),
            )?;
            descriptors.subrows(0, m).to_owned()
        };
        Ok(Self {
            name: name.to_string(),
            descriptors,
            weights,
            global,
            spectrum: None,
        })
    }
}

/// Where a vocabulary was trained: for provenance and for the "optimistic" warning.
#[derive(Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainingReport {
    /// Names of the training shapes.
    pub shapes: Vec<String>,
    /// Number of pooled descriptors k-means ran on.
    pub descriptors: usize,
}

/// The old name of [`TrainingReport`] (one word per meaning: results are reports).
#[deprecated(note = "renamed TrainingReport")]
pub type TrainingInfo = TrainingReport;

/// A trained vocabulary with everything needed to use it on new shapes: the descriptor settings,
/// the z-score statistics and the words. Its own artifact (`wfem retrieval vocab`).
#[derive(Clone, Debug)]
pub struct VocabularyModel {
    descriptor: DescriptorSettings,
    training: TrainingParams,
    standardizer: Option<Standardizer>,
    vocabulary: Vocabulary,
    info: TrainingReport,
    /// The word groups of spatial bags ([`crate::spatial::word_groups`]) for the last G asked
    /// for: a pure function of the words, computed once per model instead of once per shape.
    groups: std::sync::OnceLock<(usize, Vec<u32>)>,
}

impl VocabularyModel {
    /// Trains on the descriptors of `shapes`: pool them, fit the z-score statistics (if
    /// `params.standardize`) on the pool, then k-means on a seeded subsample of at most
    /// `max_training_points` z-scored rows; σ = the median nearest-word distance.
    ///
    /// # Errors
    /// [`RetrievalError::Empty`] without shapes, [`RetrievalError::DimensionMismatch`] if the
    /// descriptors disagree with the settings, and those of [`Standardizer::fit`] and
    /// [`Vocabulary::train`].
    pub fn train(
        descriptor: &DescriptorSettings,
        params: &TrainingParams,
        shapes: &[ShapeFeatures],
    ) -> Result<Self, RetrievalError> {
        descriptor.validate()?;
        check::non_empty("training shapes", shapes.len())?;
        let d = descriptor.descriptor.dimension();
        for s in shapes {
            check::same("training descriptor dimension", d, s.descriptors.ncols())?;
        }
        let rows: usize = shapes.iter().map(|s| s.descriptors.nrows()).sum();
        let mut pooled = Mat::<f64>::zeros(rows, d);
        let mut r0 = 0;
        for s in shapes {
            pooled
                .as_mut()
                .submatrix_mut(r0, 0, s.descriptors.nrows(), d)
                .copy_from(s.descriptors.as_ref());
            r0 += s.descriptors.nrows();
        }
        let standardizer = if params.standardize {
            let mut z = Standardizer::fit(pooled.as_ref())?;
            if let Some(w) = descriptor.descriptor.dimension_weights() {
                z = z.weighted(&w)?;
            }
            pooled = z.apply(pooled.as_ref())?;
            Some(z)
        } else {
            None
        };
        let vocabulary = Vocabulary::train(
            pooled.as_ref(),
            &VocabularyParams {
                size: params.words,
                max_iter: params.max_iter,
                seed: params.seed,
                sigma: None,
                max_training_points: Some(params.max_training_points),
            },
        )?;
        Ok(Self {
            descriptor: descriptor.clone(),
            training: *params,
            standardizer,
            vocabulary,
            info: TrainingReport {
                shapes: shapes.iter().map(|s| s.name.clone()).collect(),
                descriptors: rows.min(params.max_training_points),
            },
            groups: std::sync::OnceLock::new(),
        })
    }

    /// Reassembles a model from its parts (e.g. read from storage), checking consistency.
    ///
    /// # Errors
    /// [`RetrievalError::InvalidModel`] if the settings are invalid or the dimensions of the
    /// statistics and words disagree with the descriptor.
    pub fn from_parts(
        descriptor: DescriptorSettings,
        training: TrainingParams,
        standardizer: Option<Standardizer>,
        vocabulary: Vocabulary,
        info: TrainingReport,
    ) -> Result<Self, RetrievalError> {
        let invalid = |reason: String| RetrievalError::InvalidModel {
            what: "vocabulary",
            reason,
        };
        descriptor.validate().map_err(|e| invalid(e.to_string()))?;
        let d = descriptor.descriptor.dimension();
        if vocabulary.words().ncols() != d {
            return Err(invalid(format!(
                "words have dimension {} but the {} descriptor has {d}",
                vocabulary.words().ncols(),
                descriptor.descriptor.label()
            )));
        }
        if let Some(z) = &standardizer {
            if z.dimension() != d {
                return Err(invalid(format!(
                    "z-score statistics have dimension {} but the descriptor has {d}",
                    z.dimension()
                )));
            }
        }
        if training.words != vocabulary.size() {
            return Err(invalid(format!(
                "{} words stored, {} recorded as trained",
                vocabulary.size(),
                training.words
            )));
        }
        Ok(Self {
            descriptor,
            training,
            standardizer,
            vocabulary,
            info,
            groups: std::sync::OnceLock::new(),
        })
    }

    /// The descriptor settings the words were trained for.
    pub fn descriptor(&self) -> &DescriptorSettings {
        &self.descriptor
    }

    /// The training parameters.
    pub fn training(&self) -> &TrainingParams {
        &self.training
    }

    /// The z-score statistics (`None` if trained without standardisation).
    pub fn standardizer(&self) -> Option<&Standardizer> {
        self.standardizer.as_ref()
    }

    /// The words and σ.
    pub fn vocabulary(&self) -> &Vocabulary {
        &self.vocabulary
    }

    /// Where it was trained.
    pub fn info(&self) -> &TrainingReport {
        &self.info
    }

    /// The normalised bag `Θᵀw / 1ᵀΘᵀw` of descriptors (n × d) with vertex weights w (length n)
    /// and the given assignment Θ (for the normalised assignment the denominator is Σw).
    ///
    /// # Errors
    /// Those of [`Standardizer::apply`] and [`Vocabulary::bag_of_features`];
    /// [`RetrievalError::InvalidModel`] if the weights sum to zero.
    pub fn bag(
        &self,
        descriptors: MatRef<'_, f64>,
        weights: &[f64],
        assignment: Assignment,
    ) -> Result<Vec<f64>, RetrievalError> {
        // Θᵀw without forming Θ (n × V: 60 MB for 15K vertices and 512 words).
        let bag = self.standardized(descriptors, |d| {
            self.vocabulary.weighted_assignment(d, weights, assignment)
        })?;
        check::unit_sum("bag", "the vertex weights sum", bag)
    }

    /// `f` of the descriptors z-scored by the model's standardizer (as given without one).
    fn standardized<R>(
        &self,
        descriptors: MatRef<'_, f64>,
        f: impl FnOnce(MatRef<'_, f64>) -> Result<R, RetrievalError>,
    ) -> Result<R, RetrievalError> {
        match &self.standardizer {
            Some(z) => f(z.apply(descriptors)?.as_ref()),
            None => f(descriptors),
        }
    }

    /// The assignment Θ (n × V) of descriptors (n × d, not z-scored) to the words.
    ///
    /// # Errors
    /// Those of [`Standardizer::apply`] and [`Vocabulary::soft_assignment`].
    pub fn assignment(&self, descriptors: MatRef<'_, f64>, assignment: Assignment) -> Result<Mat<f64>, RetrievalError> {
        self.standardized(descriptors, |d| match assignment {
            Assignment::Normalized => self.vocabulary.soft_assignment(d),
            Assignment::Kernel => self.vocabulary.kernel_assignment(d),
        })
    }

    /// The bag of a shape under `bags`: the normalised bag, followed by the spatial histogram
    /// when `bags.spatial` is on (each half of the mass; see [`crate::spatial`]).
    ///
    /// # Errors
    /// Those of [`Self::assignment`] and [`SpatialBag::histogram`](crate::spatial::SpatialBag::histogram);
    /// [`RetrievalError::InvalidModel`] if the weights sum to zero or the features lack the
    /// eigenpairs a spatial bag needs.
    pub fn shape_bag(&self, features: &ShapeFeatures, bags: &BagSettings) -> Result<Vec<f64>, RetrievalError> {
        let Some(spatial) = &bags.spatial else {
            return self.bag(features.descriptors.as_ref(), &features.weights, bags.assignment);
        };
        // Spatial bags need Θ itself: the plain bag is taken from the same Θ.
        let theta = self.assignment(features.descriptors.as_ref(), bags.assignment)?;
        check::same("vertex weights vs descriptors", theta.nrows(), features.weights.len())?;
        check::finite_slice("vertex weights", &features.weights)?;
        let bag: Vec<f64> = (0..theta.ncols())
            .map(|c| theta.col(c).iter().zip(&features.weights).map(|(t, a)| t * a).sum())
            .collect();
        let bag = check::unit_sum("bag", "the vertex weights sum", bag)?;
        let spectrum = features.spectrum.as_ref().ok_or_else(|| RetrievalError::InvalidModel {
            what: "features",
            reason: format!(
                "{}: spatial bags need the eigenpairs (ShapeFeatures::attach_spectrum)",
                features.name
            ),
        })?;
        // Between groups of words when asked for (spatial::grouped), else between the words.
        let classes = spatial.classes(self.vocabulary.size());
        let theta = if classes < self.vocabulary.size() {
            crate::spatial::grouped(theta.as_ref(), &self.word_groups(classes)?, classes)?
        } else {
            theta
        };
        let flow = spatial.histogram(theta.as_ref(), &features.weights, spectrum)?;
        Ok(bag.iter().chain(&flow).map(|x| 0.5 * x).collect())
    }

    /// The G word groups of spatial bags ([`crate::spatial::word_groups`]), computed once.
    fn word_groups(&self, classes: usize) -> Result<std::borrow::Cow<'_, [u32]>, RetrievalError> {
        if let Some((g, groups)) = self.groups.get() {
            if *g == classes {
                return Ok(std::borrow::Cow::Borrowed(groups));
            }
        }
        let groups = crate::spatial::word_groups(self.vocabulary.words(), classes)?;
        // The first G asked for is kept (a model serves one index, with one G); another G is
        // computed on every call.
        let _ = self.groups.set((classes, groups.clone()));
        Ok(std::borrow::Cow::Owned(groups))
    }
}
