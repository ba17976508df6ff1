//! [`DescriptorSpec`]: a dense descriptor with its parameters, and the one place it is computed.

use crate::descriptor::{Descriptor, DescriptorParams, ShapeDescriptors};
use crate::hks::{heat_kernel_signature, HksParams, Spectrum, SpectrumNormalization, TimeSampling};
use crate::sihks::{scale_invariant_hks, SihksParams, TimeUnit};
use crate::{check, RetrievalError};
use faer::Mat;
use serde::{Deserialize, Serialize};
use wfem_heat::KernelDiagonal;

/// A dense (per-vertex) descriptor with its parameters: the one place a descriptor is computed
/// ([`Self::compute`]); [`Descriptor`] names it without parameters ([`Self::kind`]).
///
/// Every variant is computed from the k smallest eigenpairs of its kernel (see
/// [`crate::descriptor`]); the HKS variants are `h(x, t) = Σ_k e^{−λ_k t} φ_k(x)²` (the kernel
/// value k_t(x, x) of Eq. (6), resp. Eq. (7) for DHK1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum DescriptorSpec {
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
        /// Times in units of the area.
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
}

fn area_unit() -> TimeUnit {
    TimeUnit::Area(1.0)
}

fn is_area_unit(unit: &TimeUnit) -> bool {
    *unit == area_unit()
}

fn is_kernel_value(convention: &KernelDiagonal) -> bool {
    *convention == KernelDiagonal::KernelValue
}

/// The retrieval default: SI-HKS of the wFEM kernel (Eq. (6)), area time unit, α = 2,
/// τ ∈ [−12, 1] in steps of 1/8 (105 samples), K = 5 Fourier magnitudes.
///
/// Narrower and lower than [`SihksParams::default`] (τ ∈ [−10, 2], K = 8): on TOSCA-76
/// (`cargo xtask tosca-eval`, 48 words, χ²) that window gives mAP 0.986 (david 0.91); this one
/// 0.998 with the vocabulary trained on the 76 and 0.999 with one trained outside them, when it
/// was chosen (with today's cleaning and capped weights: 0.9972 and 0.9978, docs/SHREC-RESULTS.md).
/// The small
/// times resolve the humans' fingers and faces; frequencies ≥ 5 mostly carried noise. At
/// τ = −12 the 100th mode has tλ ≈ 4π·100·2⁻¹² ≈ 0.3 (Weyl), so the first samples see the
/// truncation of the spectrum: the descriptor depends (mildly) on k, which is recorded with it.
impl ShapeDescriptors {
    /// The dense descriptor (n × T for the HKS variants, n × K for SI-HKS) with the times and
    /// SI-HKS options of this shape's [`DescriptorParams`]; see the module docs of
    /// [`crate::descriptor`]. (Defined here, beside the one dispatch it calls, so that the
    /// descriptor module does not depend on the model.)
    ///
    /// # Errors
    /// Those of [`DescriptorSpec::compute`].
    pub fn dense(&mut self, descriptor: Descriptor) -> Result<Mat<f64>, RetrievalError> {
        DescriptorSpec::with_params(descriptor, &self.params).compute(self)
    }
}

impl Default for DescriptorSpec {
    fn default() -> Self {
        Self::sihks(&SihksParams {
            tau_min: -12.0,
            tau_max: 1.0,
            num_frequencies: 5,
            ..SihksParams::default()
        })
    }
}

impl DescriptorSpec {
    /// The descriptor without its parameters.
    pub fn kind(&self) -> Descriptor {
        match self {
            DescriptorSpec::SiHks { .. } => Descriptor::SiHks,
            DescriptorSpec::AreaHks { .. } => Descriptor::AreaHks,
            DescriptorSpec::Dhk1 { .. } => Descriptor::Dhk1,
            DescriptorSpec::Dhk2 { .. } => Descriptor::Dhk2,
            DescriptorSpec::Dhk3 { .. } => Descriptor::Dhk3,
            DescriptorSpec::Wks { .. } => Descriptor::Wks,
        }
    }

    /// SI-HKS with the given options.
    pub fn sihks(p: &SihksParams) -> Self {
        DescriptorSpec::SiHks {
            alpha: p.alpha,
            tau_min: p.tau_min,
            tau_max: p.tau_max,
            tau_step: p.tau_step,
            frequencies: p.num_frequencies,
            time_unit: p.time_unit,
            convention: p.convention,
        }
    }

    /// A descriptor with the times and SI-HKS options of `params` (the parameters of
    /// [`crate::descriptor::ShapeDescriptors::dense`]; area-HKS takes its explicit times, or none).
    pub fn with_params(descriptor: Descriptor, params: &DescriptorParams) -> Self {
        let times = params.times.clone();
        match descriptor {
            Descriptor::SiHks => Self::sihks(&params.sihks),
            Descriptor::AreaHks => DescriptorSpec::AreaHks {
                times: match times {
                    TimeSampling::Explicit(t) => t,
                    TimeSampling::Auto { .. } => Vec::new(),
                },
            },
            Descriptor::Dhk1 => DescriptorSpec::Dhk1 { times },
            Descriptor::Dhk2 => DescriptorSpec::Dhk2 { times },
            Descriptor::Dhk3 => DescriptorSpec::Dhk3 { times },
            Descriptor::Wks => Self::wks_default(),
        }
    }

    /// The WKS at pyFM's N = [`crate::wks::DEFAULT_ENERGIES`] energies.
    pub fn wks_default() -> Self {
        DescriptorSpec::Wks {
            energies: crate::wks::DEFAULT_ENERGIES,
        }
    }

    /// The descriptor's defaults for retrieval, or `None` where it has none: the absolute
    /// times of DHK1/DHK2 and the area times of area-HKS depend on the collection.
    pub fn retrieval_default(descriptor: Descriptor) -> Option<Self> {
        match descriptor {
            Descriptor::SiHks => Some(Self::default()),
            Descriptor::Dhk3 => Some(Self::dhk3_default()),
            Descriptor::Wks => Some(Self::wks_default()),
            Descriptor::AreaHks | Descriptor::Dhk1 | Descriptor::Dhk2 => None,
        }
    }

    /// A descriptor at explicit times (SI-HKS, which samples its own times, and the WKS, which
    /// has energies, get their retrieval defaults).
    pub fn with_times(descriptor: Descriptor, times: Vec<f64>) -> Self {
        match descriptor {
            Descriptor::SiHks => Self::default(),
            Descriptor::Wks => Self::wks_default(),
            Descriptor::AreaHks => DescriptorSpec::AreaHks { times },
            Descriptor::Dhk1 => DescriptorSpec::Dhk1 {
                times: TimeSampling::Explicit(times),
            },
            Descriptor::Dhk2 => DescriptorSpec::Dhk2 {
                times: TimeSampling::Explicit(times),
            },
            Descriptor::Dhk3 => DescriptorSpec::Dhk3 {
                times: TimeSampling::Explicit(times),
            },
        }
    }

    /// The paper's DHK3 at its CLI times `4 ln10 · 10^{0.4 j}`, j = 0 … 5 (units of 1/λ_max):
    /// six scales over two decades from the finest resolved one, as in Shape Google.
    pub fn dhk3_default() -> Self {
        DescriptorSpec::Dhk3 {
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
            DescriptorSpec::SiHks {
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

    /// The descriptor dimension d (for automatic times, their number).
    pub fn dimension(&self) -> usize {
        match self {
            DescriptorSpec::SiHks { frequencies, .. } => *frequencies,
            DescriptorSpec::AreaHks { times } => times.len(),
            DescriptorSpec::Wks { energies } => *energies,
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } | DescriptorSpec::Dhk3 { times } => {
                match times {
                    TimeSampling::Explicit(t) => t.len(),
                    TimeSampling::Auto { num_times } => *num_times,
                }
            }
        }
    }

    /// Checks the parameters (the same checks the computation makes, without a shape).
    ///
    /// # Errors
    /// [`RetrievalError::InvalidParameter`] / [`RetrievalError::Empty`] naming the parameter.
    pub fn validate(&self) -> Result<(), RetrievalError> {
        let explicit = |times: &[f64]| {
            check::non_empty("times", times.len())?;
            times.iter().try_for_each(|&t| check::positive("time", t))
        };
        match self {
            DescriptorSpec::SiHks { frequencies, .. } => {
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
            DescriptorSpec::AreaHks { times } => explicit(times),
            DescriptorSpec::Wks { energies } => {
                check::non_empty("energies", *energies)?;
                wfem_heat::limits::times("energies", *energies)?;
                Ok(())
            }
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } | DescriptorSpec::Dhk3 { times } => {
                match times {
                    TimeSampling::Explicit(t) => explicit(t),
                    TimeSampling::Auto { num_times } => check::non_empty("times", *num_times),
                }
            }
        }
    }

    /// The descriptor (n × d) of one shape.
    ///
    /// # Errors
    /// Those of the eigensolver ([`ShapeDescriptors::eigenbasis`]), [`heat_kernel_signature`]
    /// and [`scale_invariant_hks`].
    pub fn compute(&self, shape: &mut ShapeDescriptors) -> Result<Mat<f64>, RetrievalError> {
        let area = shape.area();
        let basis = shape.eigenbasis(self.kind().uses_lumped())?;
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
            DescriptorSpec::SiHks { .. } => scale_invariant_hks(&spectrum, &self.sihks_params().unwrap_or_default()),
            DescriptorSpec::AreaHks { times } => {
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
            DescriptorSpec::Dhk1 { times } | DescriptorSpec::Dhk2 { times } => {
                hks(times.clone(), SpectrumNormalization::None)
            }
            DescriptorSpec::Dhk3 { times } => hks(times.clone(), SpectrumNormalization::MaxEigenvalue),
            DescriptorSpec::Wks { energies } => Ok(crate::wks::wave_kernel_signature(&spectrum, *energies)?.values),
        }
    }
}
