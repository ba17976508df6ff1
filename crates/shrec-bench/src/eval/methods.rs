//! The retrieval methods of the report: the default recipe, Shape Google SG1/SG2 as in the
//! paper, and the ablations of the robustness ideas.

use super::Subset;
use shape_retrieval::bof::Assignment;
use shape_retrieval::descriptor::Descriptor;
use shape_retrieval::distance::BagDistance;
use shape_retrieval::hks::TimeSampling;
use shape_retrieval::model::{
    BagSettings, DescriptorSettings, GlobalSignature, RetrievalSettings, TrainingParams, VertexWeights,
};

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
    let shape_google = |descriptor: Descriptor| {
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
            shape_google(Descriptor::Dhk1 {
                times: TimeSampling::Explicit(hks_times.to_vec()),
            }),
            VocabularySource::NullShapes,
            false,
        ),
        method(
            "SG2 (ours)",
            "Shape Google: DHK2 (wFEM kernel, Eq. (6)) at 6 global times, L1, no z-scoring",
            shape_google(Descriptor::Dhk2 {
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
            shape_google(Descriptor::dhk3_default()),
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
