//! [`Descriptor`]: a dense descriptor with its parameters — the registry of descriptors (one
//! line per descriptor: name, aliases, help, default parameters) and the one place a
//! descriptor is computed ([`Descriptor::compute`]).
//!
//! **Adding a descriptor** = a variant with its parameters, its line in the `registry!`, its arm
//! in [`Descriptor::compute`] (and in the small `match`es below that say which options it
//! takes). The CLI (`retrieval --descriptor`), Python (`wfem.descriptors`, `RetrievalIndex`) and
//! index files take its name, help and defaults from here.

use crate::descriptor::ShapeDescriptors;
use crate::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use crate::sihks::{scale_invariant_hks, SihksParams, TimeUnit};
use crate::{check, RetrievalError};
use faer::Mat;
use serde::{Deserialize, Serialize};
use wfem_heat::KernelDiagonal;

/// A dense (per-vertex) descriptor with its parameters (paper, Sect. 5).
///
/// Every variant is computed from the k smallest eigenpairs of its kernel (see
/// [`crate::descriptor`]); the HKS variants are `h(x, t) = Σ_k e^{−λ_k t} φ_k(x)²` (the kernel
/// value k_t(x, x) of Eq. (6), resp. Eq. (7) for DHK1). Parsing a name
/// ([`wfem_base::Choice::parse`]) gives the descriptor with its default parameters (those of
/// retrieval); [`Descriptor::with_options`] changes them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Descriptor {
    /// SI-HKS of the wFEM kernel with times `t = t₀·α^τ` (by default t₀ = A, the surface area:
    /// exactly scale invariant; [`crate::sihks`], [`TimeUnit::Area`]).
    SiHks {
        /// Base α of the time sampling (> 1).
        alpha: f64,
        /// First τ.
        tau_min: f64,
        /// Last τ.
        tau_max: f64,
        /// Step Δτ.
        tau_step: f64,
        /// Number K of Fourier magnitudes kept.
        frequencies: usize,
        /// The time unit t₀ (absent in files: the area).
        #[serde(default = "area_unit", skip_serializing_if = "is_area_unit")]
        time_unit: TimeUnit,
        /// Which diagonal of the kernel is sampled (absent in files: the kernel value).
        #[serde(default, skip_serializing_if = "is_kernel_value", with = "wfem_base::serde_name")]
        convention: KernelDiagonal,
    },
    /// Log-HKS of the wFEM kernel on the shape rescaled to unit area, `ln(A·h(x, A·τ_j))` at the
    /// given dimensionless times τ_j ([`SpectrumNormalization::UnitArea`]); exactly scale
    /// invariant. (`A·h ≥ A·φ₀² = 1`, so the logarithm is defined and ≥ 0.)
    AreaHks {
        /// Times in units of the area (none by default: they must be given).
        times: Vec<f64>,
    },
    /// DHK1: HKS of the lumped (Voronoi-cot) kernel, Eq. (7), at absolute times.
    Dhk1 {
        /// Times in the squared length unit of the meshes (or automatic per shape).
        times: TimeSampling,
    },
    /// DHK2: HKS of the wFEM kernel, Eq. (6), at absolute times.
    Dhk2 {
        /// Times in the squared length unit of the meshes (or automatic per shape).
        times: TimeSampling,
    },
    /// DHK3: HKS of the wFEM kernel with eigenvalues divided by λ_max of the k computed ones
    /// (the paper's scale-invariant dense descriptor, Sect. 5).
    Dhk3 {
        /// Times in units of 1/λ_max (or automatic per shape).
        times: TimeSampling,
    },
    /// The wave kernel signature of the wFEM spectrum at N energies ([`crate::wks`]): the
    /// energies of pyFM and geomfum, per shape from its own spectrum (scale invariant up to the
    /// truncation: λ → λ/α² shifts every log-energy by the same amount).
    Wks {
        /// Number N of energies.
        energies: usize,
    },
    /// Several descriptors side by side (per vertex: the columns of the first part, then of the
    /// next), e.g. SI-HKS and WKS (`si-hks+wks`). In bags each part weighs alike: after the
    /// per-dimension z-scoring, a part of dimension d_p is scaled by 1/√d_p
    /// ([`Descriptor::dimension_weights`]), so that five SI-HKS magnitudes are not drowned by a
    /// hundred WKS energies. Parts are computed from the one eigenbasis of the shape.
    Combined {
        /// The parts (at least two; none itself combined).
        parts: Vec<Descriptor>,
    },
}

wfem_base::registry! {
    Descriptor as "descriptor" {
        Descriptor::SiHks { .. } = Descriptor::default() => "si-hks" ["sihks"]:
            "scale-invariant HKS of the wFEM kernel, times in units of the surface area (default)",
        Descriptor::AreaHks { .. } = Descriptor::AreaHks { times: Vec::new() } => "area-hks":
            "log-HKS of the wFEM kernel on the shape rescaled to unit area",
        Descriptor::Dhk1 { .. } = Descriptor::Dhk1 { times: TimeSampling::default() } => "dhk1":
            "HKS of the lumped Voronoi-cot kernel (Eq. (7)) at absolute times",
        Descriptor::Dhk2 { .. } = Descriptor::Dhk2 { times: TimeSampling::default() } => "dhk2":
            "HKS of the wFEM kernel (Eq. (6)) at absolute times",
        Descriptor::Dhk3 { .. } = Descriptor::dhk3_default() => "dhk3":
            "HKS of the wFEM kernel with eigenvalues divided by λ_max (the paper's scale-invariant DHK3)",
        Descriptor::Wks { .. } = Descriptor::wks_default() => "wks" ["wave-kernel-signature"]:
            "wave kernel signature (Aubry et al. 2011) of the wFEM spectrum, pyFM's energies",
        Descriptor::Combined { .. } = Descriptor::sihks_wks_default() => "si-hks+wks" ["hks+wks"]:
            "SI-HKS and WKS side by side, each part weighing alike in the bags",
    }
}

/// The SI-HKS of the retrieval default ([`Descriptor::default`]): area time unit, α = 2,
/// τ ∈ [−12, 1] in steps of 1/8 (105 samples), K = 5 Fourier magnitudes, kernel values.
///
/// Narrower and lower than [`SihksParams::default`] (τ ∈ [−10, 2], K = 8): on TOSCA-76
/// (`cargo xtask tosca-eval`, 48 words, χ²) that window gives mAP 0.986 (david 0.91); this one
/// 0.998 with the vocabulary trained on the 76 and 0.999 with one trained outside them, when it
/// was chosen (with today's cleaning and capped weights: 0.9972 and 0.9978,
/// docs/SHREC-RESULTS.md). The small times resolve the humans' fingers and faces; frequencies
/// ≥ 5 mostly carried noise. At τ = −12 the 100th mode has tλ ≈ 4π·100·2⁻¹² ≈ 0.3 (Weyl), so
/// the first samples see the truncation of the spectrum: the descriptor depends (mildly) on k,
/// which is recorded with it.
pub const RETRIEVAL_SIHKS: SihksParams = SihksParams {
    alpha: 2.0,
    tau_min: -12.0,
    tau_max: 1.0,
    tau_step: 1.0 / 8.0,
    time_unit: TimeUnit::Area(1.0),
    num_frequencies: 5,
    convention: KernelDiagonal::KernelValue,
};

fn area_unit() -> TimeUnit {
    TimeUnit::Area(1.0)
}

fn is_area_unit(unit: &TimeUnit) -> bool {
    *unit == area_unit()
}

fn is_kernel_value(convention: &KernelDiagonal) -> bool {
    *convention == KernelDiagonal::KernelValue
}

/// The retrieval default: SI-HKS of the wFEM kernel (Eq. (6)) with [`RETRIEVAL_SIHKS`].
impl Default for Descriptor {
    fn default() -> Self {
        Self::sihks(&RETRIEVAL_SIHKS)
    }
}

/// Options a caller may give beside a descriptor's name (command-line flags, keyword
/// arguments): each belongs to some descriptors, and [`Descriptor::with_options`] refuses it for
/// the others. The field names are the options' names in messages (`tau_min` is the CLI's
/// `--tau-min`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DescriptorOptions {
    /// Times (DHK1–DHK3: explicit or automatic; area-HKS: explicit only).
    pub times: Option<TimeSampling>,
    /// SI-HKS: base α of the time sampling.
    pub alpha: Option<f64>,
    /// SI-HKS: first τ.
    pub tau_min: Option<f64>,
    /// SI-HKS: last τ.
    pub tau_max: Option<f64>,
    /// SI-HKS: step Δτ.
    pub tau_step: Option<f64>,
    /// SI-HKS: number K of Fourier magnitudes.
    pub frequencies: Option<usize>,
    /// SI-HKS: the time unit t₀.
    pub time_unit: Option<TimeUnit>,
    /// SI-HKS: which diagonal of the kernel is sampled.
    pub convention: Option<KernelDiagonal>,
    /// WKS: number N of energies.
    pub energies: Option<usize>,
}

impl DescriptorOptions {
    /// The SI-HKS options as a whole (every field of `p`).
    pub fn sihks(p: &SihksParams) -> Self {
        Self {
            alpha: Some(p.alpha),
            tau_min: Some(p.tau_min),
            tau_max: Some(p.tau_max),
            tau_step: Some(p.tau_step),
            frequencies: Some(p.num_frequencies),
            time_unit: Some(p.time_unit),
            convention: Some(p.convention),
            ..Self::default()
        }
    }

    /// The names of the options given, in field order.
    pub fn given(&self) -> Vec<&'static str> {
        let flags = [
            ("times", self.times.is_some()),
            ("alpha", self.alpha.is_some()),
            ("tau_min", self.tau_min.is_some()),
            ("tau_max", self.tau_max.is_some()),
            ("tau_step", self.tau_step.is_some()),
            ("frequencies", self.frequencies.is_some()),
            ("time_unit", self.time_unit.is_some()),
            ("convention", self.convention.is_some()),
            ("energies", self.energies.is_some()),
        ];
        flags
            .iter()
            .filter(|(_, given)| *given)
            .map(|(name, _)| *name)
            .collect()
    }
}

impl Descriptor {
    /// The four dense descriptors of the paper's Tables 3–4, in table order, with their default
    /// parameters.
    pub fn paper() -> [Descriptor; 4] {
        [
            Descriptor::Dhk1 {
                times: TimeSampling::default(),
            },
            Descriptor::Dhk2 {
                times: TimeSampling::default(),
            },
            Descriptor::Dhk3 {
                times: TimeSampling::default(),
            },
            Descriptor::default(),
        ]
    }

    /// How the paper writes it (`DHK1`, …, `SI-HKS`, `area-HKS`; parts joined by `+`), for
    /// tables and titles.
    pub fn label(&self) -> String {
        match self {
            Descriptor::Dhk1 { .. } => "DHK1".into(),
            Descriptor::Dhk2 { .. } => "DHK2".into(),
            Descriptor::Dhk3 { .. } => "DHK3".into(),
            Descriptor::SiHks { .. } => "SI-HKS".into(),
            Descriptor::AreaHks { .. } => "area-HKS".into(),
            Descriptor::Wks { .. } => "WKS".into(),
            Descriptor::Combined { parts } => parts.iter().map(Descriptor::label).collect::<Vec<_>>().join("+"),
        }
    }

    /// Whether it is computed from the spectrum of (L, D) (the lumped Voronoi mass) rather
    /// than (L, B).
    pub fn uses_lumped(&self) -> bool {
        matches!(self, Descriptor::Dhk1 { .. })
    }

    /// The options this descriptor takes ([`DescriptorOptions`] field names; a combined
    /// descriptor takes those of its parts).
    pub fn options(&self) -> Vec<&'static str> {
        match self {
            Descriptor::SiHks { .. } => vec![
                "alpha",
                "tau_min",
                "tau_max",
                "tau_step",
                "frequencies",
                "time_unit",
                "convention",
            ],
            Descriptor::AreaHks { .. }
            | Descriptor::Dhk1 { .. }
            | Descriptor::Dhk2 { .. }
            | Descriptor::Dhk3 { .. } => vec!["times"],
            Descriptor::Wks { .. } => vec!["energies"],
            Descriptor::Combined { parts } => {
                let mut all: Vec<&'static str> = Vec::new();
                for o in parts.iter().flat_map(Descriptor::options) {
                    if !all.contains(&o) {
                        all.push(o);
                    }
                }
                all
            }
        }
    }

    /// The weight of each dimension after z-scoring (`None`: all 1): for a combined descriptor
    /// 1/√d_p on the d_p dimensions of each part, so that every part contributes alike to the
    /// Euclidean distances of the vocabulary. Folded into the z-score deviations of the index
    /// ([`crate::standardize::Standardizer::weighted`]), so index files keep their form.
    pub fn dimension_weights(&self) -> Option<Vec<f64>> {
        match self {
            Descriptor::Combined { parts } => Some(
                parts
                    .iter()
                    .flat_map(|p| {
                        let d = p.dimension();
                        std::iter::repeat_n(1.0 / (d.max(1) as f64).sqrt(), d)
                    })
                    .collect(),
            ),
            _ => None,
        }
    }

    /// The descriptors that take `option` (their canonical names), for messages.
    fn owners(option: &str) -> Vec<&'static str> {
        <Descriptor as wfem_base::Choice>::entries()
            .iter()
            .filter_map(|e| <Descriptor as wfem_base::Choice>::from_canonical(e.name))
            .filter(|d| d.options().contains(&option))
            .map(|d| wfem_base::Choice::name(&d))
            .collect()
    }

    /// This descriptor with `options` applied.
    ///
    /// # Errors
    /// [`RetrievalError::MisplacedOption`] for an option that does not belong to this
    /// descriptor (it is refused, not ignored); [`RetrievalError::InvalidParameter`] for
    /// automatic times given to area-HKS. (Values are checked by [`Self::validate`].)
    pub fn with_options(self, options: &DescriptorOptions) -> Result<Self, RetrievalError> {
        let takes = self.options();
        if let Some(option) = options.given().into_iter().find(|o| !takes.contains(o)) {
            return Err(RetrievalError::MisplacedOption {
                option,
                descriptor: wfem_base::Choice::name(&self),
                owners: Self::owners(option),
            });
        }
        let times = |old: TimeSampling| options.times.clone().unwrap_or(old);
        Ok(match self {
            Descriptor::SiHks { .. } => {
                let p = self.sihks_params().unwrap_or_default();
                Self::sihks(&SihksParams {
                    alpha: options.alpha.unwrap_or(p.alpha),
                    tau_min: options.tau_min.unwrap_or(p.tau_min),
                    tau_max: options.tau_max.unwrap_or(p.tau_max),
                    tau_step: options.tau_step.unwrap_or(p.tau_step),
                    num_frequencies: options.frequencies.unwrap_or(p.num_frequencies),
                    time_unit: options.time_unit.unwrap_or(p.time_unit),
                    convention: options.convention.unwrap_or(p.convention),
                })
            }
            Descriptor::AreaHks { times: old } => match options.times.clone() {
                None => Descriptor::AreaHks { times: old },
                Some(TimeSampling::Explicit(times)) => Descriptor::AreaHks { times },
                Some(TimeSampling::Auto { num_times }) => {
                    return Err(RetrievalError::InvalidParameter {
                        name: "num_times",
                        value: num_times as f64,
                        reason: "area-hks takes explicit times in units of the area, not automatic ones",
                    })
                }
            },
            Descriptor::Dhk1 { times: old } => Descriptor::Dhk1 { times: times(old) },
            Descriptor::Dhk2 { times: old } => Descriptor::Dhk2 { times: times(old) },
            Descriptor::Dhk3 { times: old } => Descriptor::Dhk3 { times: times(old) },
            Descriptor::Wks { energies } => Descriptor::Wks {
                energies: options.energies.unwrap_or(energies),
            },
            Descriptor::Combined { parts } => {
                // Each option goes to the parts that take it.
                let mut out = Vec::with_capacity(parts.len());
                for part in parts {
                    let takes = part.options();
                    let mine = DescriptorOptions {
                        times: options.times.clone().filter(|_| takes.contains(&"times")),
                        alpha: options.alpha.filter(|_| takes.contains(&"alpha")),
                        tau_min: options.tau_min.filter(|_| takes.contains(&"tau_min")),
                        tau_max: options.tau_max.filter(|_| takes.contains(&"tau_max")),
                        tau_step: options.tau_step.filter(|_| takes.contains(&"tau_step")),
                        frequencies: options.frequencies.filter(|_| takes.contains(&"frequencies")),
                        time_unit: options.time_unit.filter(|_| takes.contains(&"time_unit")),
                        convention: options.convention.filter(|_| takes.contains(&"convention")),
                        energies: options.energies.filter(|_| takes.contains(&"energies")),
                    };
                    out.push(part.with_options(&mine)?);
                }
                Descriptor::Combined { parts: out }
            }
        })
    }

    /// The descriptor for indexing a collection, with `options` applied: as
    /// [`Self::with_options`], but the descriptors whose times are absolute (DHK1, DHK2) or
    /// have no default (area-HKS) need them given, since automatic times adapt to each shape's
    /// spectrum and would not compare shapes.
    ///
    /// # Errors
    /// [`RetrievalError::MissingTimes`] and those of [`Self::with_options`] and
    /// [`Self::validate`].
    pub fn for_collection(self, options: &DescriptorOptions) -> Result<Self, RetrievalError> {
        let explicit = matches!(options.times, Some(TimeSampling::Explicit(_)));
        let needs_times = |d: &Descriptor| {
            matches!(
                d,
                Descriptor::AreaHks { .. } | Descriptor::Dhk1 { .. } | Descriptor::Dhk2 { .. }
            )
        };
        let needs = match &self {
            Descriptor::Combined { parts } => parts.iter().any(needs_times),
            other => needs_times(other),
        };
        if needs && !explicit {
            return Err(RetrievalError::MissingTimes {
                descriptor: wfem_base::Choice::name(&self),
            });
        }
        let out = self.with_options(options)?;
        out.validate()?;
        Ok(out)
    }

    /// SI-HKS with the given options.
    pub fn sihks(p: &SihksParams) -> Self {
        Descriptor::SiHks {
            alpha: p.alpha,
            tau_min: p.tau_min,
            tau_max: p.tau_max,
            tau_step: p.tau_step,
            frequencies: p.num_frequencies,
            time_unit: p.time_unit,
            convention: p.convention,
        }
    }

    /// The WKS at pyFM's N = [`crate::wks::DEFAULT_ENERGIES`] energies.
    pub fn wks_default() -> Self {
        Descriptor::Wks {
            energies: crate::wks::DEFAULT_ENERGIES,
        }
    }

    /// SI-HKS (retrieval's, [`RETRIEVAL_SIHKS`]) and the WKS at pyFM's energies side by side.
    pub fn sihks_wks_default() -> Self {
        Descriptor::Combined {
            parts: vec![Descriptor::default(), Descriptor::wks_default()],
        }
    }

    /// The paper's DHK3 at its CLI times `4 ln10 · 10^{0.4 j}`, j = 0 … 5 (units of 1/λ_max):
    /// six scales over two decades from the finest resolved one, as in Shape Google.
    pub fn dhk3_default() -> Self {
        Descriptor::Dhk3 {
            times: TimeSampling::Explicit(
                (0..6)
                    .map(|j| 4.0 * std::f64::consts::LN_10 * 10f64.powf(0.4 * j as f64))
                    .collect(),
            ),
        }
    }

    /// The SI-HKS options of an SI-HKS descriptor (`None` for the others).
    pub fn sihks_params(&self) -> Option<SihksParams> {
        match *self {
            Descriptor::SiHks {
                alpha,
                tau_min,
                tau_max,
                tau_step,
                frequencies,
                time_unit,
                convention,
            } => Some(SihksParams {
                alpha,
                tau_min,
                tau_max,
                tau_step,
                time_unit,
                num_frequencies: frequencies,
                convention,
            }),
            _ => None,
        }
    }

    /// The times of a descriptor sampled at times (`None` for SI-HKS and the WKS).
    fn times(&self) -> Option<TimeSampling> {
        match self {
            Descriptor::AreaHks { times } => Some(TimeSampling::Explicit(times.clone())),
            Descriptor::Dhk1 { times } | Descriptor::Dhk2 { times } | Descriptor::Dhk3 { times } => Some(times.clone()),
            Descriptor::SiHks { .. } | Descriptor::Wks { .. } | Descriptor::Combined { .. } => None,
        }
    }

    /// The descriptor dimension d (for automatic times, their number).
    pub fn dimension(&self) -> usize {
        match self {
            Descriptor::SiHks { frequencies, .. } => *frequencies,
            Descriptor::Wks { energies } => *energies,
            Descriptor::Combined { parts } => parts.iter().map(Descriptor::dimension).sum(),
            other => other.times().map_or(0, |t| t.len()),
        }
    }

    /// Checks the parameters (the same checks the computation makes, without a shape).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] / [`RetrievalError::Empty`] naming the parameter.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        match self {
            Descriptor::SiHks { frequencies, .. } => {
                let p = self.sihks_params().unwrap_or_default();
                let m = p.times(Some(1.0))?.len();
                if *frequencies == 0 || m < 3 || *frequencies > (m - 1) / 2 + 1 {
                    return Err(RetrievalError::InvalidParameter {
                        name: "frequencies",
                        value: *frequencies as f64,
                        reason: "must be in 1 ..= (number of τ samples − 1)/2 + 1, with at least 3 τ samples",
                    });
                }
                Ok(())
            }
            Descriptor::Wks { energies } => {
                check::non_empty("energies", *energies)?;
                wfem_heat::limits::times("energies", *energies)?;
                Ok(())
            }
            Descriptor::Combined { parts } => {
                if parts.len() < 2 || parts.iter().any(|p| matches!(p, Descriptor::Combined { .. })) {
                    return Err(RetrievalError::InvalidParameter {
                        name: "parts",
                        value: parts.len() as f64,
                        reason: "a combined descriptor needs at least two parts, none itself combined",
                    });
                }
                parts.iter().try_for_each(Descriptor::validate)
            }
            other => match other.times() {
                Some(TimeSampling::Explicit(t)) => {
                    check::non_empty("times", t.len())?;
                    t.iter().try_for_each(|&t| check::positive("time", t))
                }
                Some(TimeSampling::Auto { num_times }) => check::non_empty("times", num_times),
                None => Ok(()),
            },
        }
    }

    /// The descriptor (n × d) of one shape.
    ///
    /// # Errors
    /// The size limits of its times ([`TimeSampling::check_size`]), those of the eigensolver
    /// ([`ShapeDescriptors::eigenbasis`]), [`heat_kernel_signature`] and
    /// [`scale_invariant_hks`].
    pub fn compute(&self, shape: &mut ShapeDescriptors) -> Result<Mat<f64>, RetrievalError> {
        if let Descriptor::Combined { parts } = self {
            self.validate()?;
            let blocks = parts.iter().map(|p| p.compute(shape)).collect::<Result<Vec<_>, _>>()?;
            let n = blocks.first().map_or(0, |b| b.nrows());
            let mut out = Mat::<f64>::zeros(n, blocks.iter().map(|b| b.ncols()).sum());
            let mut c0 = 0;
            for b in &blocks {
                out.as_mut().submatrix_mut(0, c0, n, b.ncols()).copy_from(b.as_ref());
                c0 += b.ncols();
            }
            return Ok(out);
        }
        if let Some(times) = self.times() {
            // A huge T must not cost an eigensolve, let alone an allocation.
            times.check_size(shape.mesh().n_vertices().max(1))?;
        }
        let area = shape.area();
        let basis = shape.eigenbasis(self.uses_lumped())?;
        let spectrum = Spectrum::new(&basis.values, basis.vectors.as_ref())?.with_area(area)?;
        let hks = |times: TimeSampling, normalization| {
            heat_kernel_signature(
                &spectrum,
                &HksParams {
                    times,
                    normalization,
                    ..Default::default()
                },
            )
            .map(|h| h.values)
        };
        match self {
            Descriptor::SiHks { .. } => scale_invariant_hks(&spectrum, &self.sihks_params().unwrap_or_default()),
            Descriptor::AreaHks { times } => {
                let mut h = hks(
                    TimeSampling::Explicit(times.clone()),
                    SpectrumNormalization::UnitArea { area },
                )?;
                for j in 0..h.ncols() {
                    for i in 0..h.nrows() {
                        let v = h[(i, j)];
                        // NaN is not positive either.
                        if v.is_nan() || v <= 0.0 {
                            return Err(RetrievalError::NonPositiveSignature {
                                vertex: i,
                                time: times[j],
                                value: v,
                            });
                        }
                        h[(i, j)] = v.ln();
                    }
                }
                Ok(h)
            }
            Descriptor::Dhk1 { times } | Descriptor::Dhk2 { times } => hks(times.clone(), SpectrumNormalization::None),
            Descriptor::Dhk3 { times } => hks(times.clone(), SpectrumNormalization::MaxEigenvalue),
            Descriptor::Wks { energies } => Ok(crate::wks::wave_kernel_signature(&spectrum, *energies)?.values),
            // Computed part by part above; reaching here would be a nested combination.
            Descriptor::Combined { parts } => Err(RetrievalError::InvalidParameter {
                name: "parts",
                value: parts.len() as f64,
                reason: "a combined descriptor is computed part by part, none itself combined",
            }),
        }
    }
}

impl ShapeDescriptors {
    /// The dense descriptor (n × d) of this shape; see [`Descriptor::compute`].
    ///
    /// # Errors
    /// Those of [`Descriptor::compute`].
    pub fn dense(&mut self, descriptor: &Descriptor) -> Result<Mat<f64>, RetrievalError> {
        descriptor.compute(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wfem_base::Choice;

    #[test]
    fn the_registry_is_consistent_and_its_default_is_the_retrieval_default() {
        wfem_base::check_registry::<Descriptor>().unwrap();
        assert_eq!(Descriptor::default_name(), "si-hks");
        assert_eq!(Descriptor::parse("SIHKS").unwrap(), Descriptor::sihks(&RETRIEVAL_SIHKS));
        assert_eq!(Descriptor::parse("dhk3").unwrap(), Descriptor::dhk3_default());
        assert_eq!(
            Descriptor::parse("wks").unwrap().dimension(),
            crate::wks::DEFAULT_ENERGIES
        );
    }

    #[test]
    fn every_option_belongs_to_some_descriptor_and_is_refused_elsewhere() {
        let all = DescriptorOptions {
            times: Some(TimeSampling::Explicit(vec![1.0])),
            alpha: Some(2.0),
            tau_min: Some(-3.0),
            tau_max: Some(3.0),
            tau_step: Some(0.5),
            frequencies: Some(3),
            time_unit: Some(TimeUnit::Absolute(1.0)),
            convention: Some(KernelDiagonal::OperatorDiagonal),
            energies: Some(7),
        };
        for option in all.given() {
            assert!(!Descriptor::owners(option).is_empty(), "{option} has no owner");
        }
        let only_energies = DescriptorOptions {
            energies: Some(7),
            ..Default::default()
        };
        let err = Descriptor::default().with_options(&only_energies).unwrap_err();
        match err {
            RetrievalError::MisplacedOption {
                option,
                descriptor,
                owners,
            } => {
                assert_eq!(
                    (option, descriptor, owners),
                    ("energies", "si-hks", vec!["wks", "si-hks+wks"])
                );
            }
            other => panic!("{other:?}"),
        }
        let wks = Descriptor::wks_default().with_options(&only_energies).unwrap();
        assert_eq!(wks, Descriptor::Wks { energies: 7 });
    }

    #[test]
    fn options_change_only_what_they_name() {
        let tau = DescriptorOptions {
            tau_min: Some(-4.0),
            frequencies: Some(3),
            ..Default::default()
        };
        let p = Descriptor::default()
            .with_options(&tau)
            .unwrap()
            .sihks_params()
            .unwrap();
        assert_eq!((p.tau_min, p.num_frequencies), (-4.0, 3));
        assert_eq!((p.tau_max, p.tau_step, p.alpha), (1.0, 0.125, 2.0));
        let times = DescriptorOptions {
            times: Some(TimeSampling::Explicit(vec![0.5, 1.0])),
            ..Default::default()
        };
        for name in ["dhk1", "dhk2", "dhk3", "area-hks"] {
            let d = Descriptor::parse(name).unwrap().with_options(&times).unwrap();
            assert_eq!(d.dimension(), 2, "{name}");
        }
        let auto = DescriptorOptions {
            times: Some(TimeSampling::Auto { num_times: 4 }),
            ..Default::default()
        };
        assert!(matches!(
            Descriptor::parse("area-hks").unwrap().with_options(&auto),
            Err(RetrievalError::InvalidParameter { name: "num_times", .. })
        ));
    }

    #[test]
    fn a_collection_needs_the_times_of_absolute_descriptors() {
        for name in ["dhk1", "dhk2", "area-hks"] {
            let err = Descriptor::parse(name)
                .unwrap()
                .for_collection(&DescriptorOptions::default())
                .unwrap_err();
            assert!(matches!(err, RetrievalError::MissingTimes { descriptor } if descriptor == name));
        }
        for name in ["si-hks", "dhk3", "wks"] {
            let d = Descriptor::parse(name).unwrap();
            assert_eq!(d.clone().for_collection(&DescriptorOptions::default()).unwrap(), d);
        }
    }

    #[test]
    fn the_file_form_is_unchanged() {
        // Index files written before the registry carried the parameters read the same.
        let json = r#"{"kind":"si-hks","alpha":2.0,"tau_min":-12.0,"tau_max":1.0,"tau_step":0.125,"frequencies":5}"#;
        let d: Descriptor = serde_json::from_str(json).unwrap();
        assert_eq!(d, Descriptor::default());
        assert_eq!(serde_json::to_string(&d).unwrap(), json);
        let dhk2 = r#"{"kind":"dhk2","times":{"num_times":16}}"#;
        let d: Descriptor = serde_json::from_str(dhk2).unwrap();
        assert_eq!(d, Descriptor::parse("dhk2").unwrap());
    }
}
