//! Best uniform rational approximations r_n of e^{-x} on [0, ∞) ("CRAM"), paper Eq. (10)–(11).
//!
//! # Convention (x-plane, upper-half-plane poles)
//! Every table stores
//!
//! ```text
//! e^{-x} ≈ r_n(x) = c0 + 2 Re Σ_{j=1..⌊n/2⌋} c_j / (x − z_j)  [+ c_r / (x − z_r)  for odd n],
//! ```
//!
//! with every complex pole z_j in the upper half plane (its conjugate is the other member of the
//! pair) and, for odd n, one extra real negative pole z_r with real residue c_r.
//! Then `r_n(t B⁻¹L) f = c0 f + 2 Re Σ_j c_j (tL − z_j B)⁻¹ B f (+ c_r (tL − z_r B)⁻¹ B f)`.
//!
//! # Mapping to the paper and to the nuclear (Pusa) tables
//! The paper writes Eq. (11) as `exp(C) ≈ α0 I + Σ_{i=1..r} α_i (C − θ_i I)⁻¹` for C = −tB⁻¹L,
//! i.e. it approximates e^{z} on z ≤ 0 with poles θ_i and residues α_i (all r of them, both
//! members of each conjugate pair), and Eq. (13) reads `K_t f ≈ α0 f − Σ_i α_i (tL + θ_i B)⁻¹ B f`.
//! With x = −z the two conventions are related by
//! **z_j = −conj(θ_j), c_j = −conj(α_j), c0 = α0**; summing both members of a conjugate pair
//! gives the factor 2 Re, so only the ⌊n/2⌋ upper-half-plane poles need a solve.
//!
//! # Provenance
//! * Even n = 2…16: docs/NUMERICS.md §2.3 (20 significant digits), obtained from transmutagen's
//!   200-digit Remez cache (`ergs/transmutagen`, `transmutagen/data/CRAM_cache/{n}_200`) by
//!   120-digit root finding; n = 14, 16 agree with Pusa, NSE 169 (2011) 155–167 (corrected
//!   2012) under the mapping above.
//! * Odd n = 3, 5, 7: computed by `tools/odd_cram_tables.py` (mpmath, 60 digits) from the same
//!   transmutagen cache; the script verifies the 2n+2-point equioscillation of the error (which
//!   characterises the best approximation) to better than 1e−37 relative before printing.

// The constants keep all 20 published digits so they can be compared with their sources verbatim.
#![allow(clippy::excessive_precision)]

use crate::SolveError;
use faer::c64;

/// A best uniform rational approximation r_n of e^{-x} on [0, ∞) in partial-fraction form
/// (paper Eq. (10)–(11)); see the [module docs](self) for the sign convention.
#[derive(Debug, Clone, PartialEq)]
pub struct RationalApprox {
    /// Degree n of numerator and denominator (the paper's r).
    pub degree: usize,
    /// Constant term c0 = r_n(∞) (= ±E_n).
    pub c0: f64,
    /// Complex poles z_j with Im z_j > 0, one per conjugate pair.
    pub poles: &'static [c64],
    /// Residues c_j belonging to [`Self::poles`].
    pub residues: &'static [c64],
    /// For odd degree: the real negative pole and its residue `(z_r, c_r)`.
    pub real_pole: Option<(f64, f64)>,
    /// E_n = max_{x ≥ 0} |r_n(x) − e^{-x}| (exact arithmetic; in f64 the partial-fraction sum
    /// bottoms out near 2e−14, docs/NUMERICS.md §2.2).
    pub max_error: f64,
}

/// Default degree: n = 16 (8 complex solves). Its E_16 = 2.1e−16 is below the float64 floor of
/// the partial-fraction sum (≈2e−14, docs/NUMERICS.md §2.2), so 16 reaches the best accuracy attainable
/// in double precision; higher degrees only add solves and cancellation (Σ2|c_j| grows ~2.3× per
/// degree), while n = 14 would already cost an extra decade (E_14 = 1.8e−14).
pub const DEFAULT_DEGREE: usize = 16;

/// The paper's choice r = 7 (Sect. 3: "r := 7 provides an error lower than 10⁻⁷").
pub const PAPER_DEGREE: usize = 7;

const fn c(re: f64, im: f64) -> c64 {
    c64::new(re, im)
}

impl RationalApprox {
    /// The best uniform approximation of degree `degree`.
    ///
    /// Shipped degrees: 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16.
    ///
    /// # Errors
    /// [`SolveError::UnsupportedDegree`] for any other degree.
    pub fn cram(degree: usize) -> Result<&'static RationalApprox, SolveError> {
        TABLES
            .iter()
            .find(|a| a.degree == degree)
            .ok_or(SolveError::UnsupportedDegree {
                degree,
                available: SHIPPED_DEGREES,
            })
    }

    /// All shipped tables, by increasing degree.
    pub fn all() -> &'static [RationalApprox] {
        &TABLES
    }

    /// Evaluates r_n(x) = c0 + 2 Re Σ_j c_j/(x − z_j) (+ c_r/(x − z_r)) in double precision.
    pub fn eval(&self, x: f64) -> f64 {
        let mut acc = self.c0;
        for (z, r) in self.poles.iter().zip(self.residues) {
            acc += 2.0 * (*r / (c64::new(x, 0.0) - *z)).re;
        }
        if let Some((z, r)) = self.real_pole {
            acc += r / (x - z);
        }
        acc
    }

    /// Number of shifted solves per right-hand side: one per conjugate pair plus the real pole.
    pub fn n_solves(&self) -> usize {
        self.poles.len() + usize::from(self.real_pole.is_some())
    }

    /// Σ_j 2|c_j| (+|c_r|): the factor by which a relative solve error ε per pole is amplified
    /// in r_n(tB⁻¹L)f (docs/NUMERICS.md §2.2).
    pub fn error_amplification(&self) -> f64 {
        self.residues.iter().map(|r| 2.0 * r.norm()).sum::<f64>() + self.real_pole.map_or(0.0, |(_, r)| r.abs())
    }

    /// The paper's (θ_i, α_i) of Eq. (11)–(13) for all n poles (both members of each conjugate
    /// pair, then the real pole): θ = −conj(z), α = −conj(c).
    pub fn paper_poles(&self) -> Vec<(c64, c64)> {
        let mut out = Vec::with_capacity(self.degree);
        for (z, r) in self.poles.iter().zip(self.residues) {
            out.push((-z.conj(), -r.conj()));
            out.push((-*z, -*r));
        }
        if let Some((z, r)) = self.real_pole {
            out.push((c64::new(-z, 0.0), c64::new(-r, 0.0)));
        }
        out
    }
}

/// Degrees with a shipped table.
pub const SHIPPED_DEGREES: &[usize] = &[2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16];

static TABLES: [RationalApprox; 11] = [
    // docs/NUMERICS.md §2.3, n = 2.
    RationalApprox {
        degree: 2,
        c0: 7.3586701695805292800e-3,
        poles: &[c(-5.8479863263849061285e-1, 1.1855377812415785045)],
        residues: &[c(-1.6885872734712943005e-1, -8.0945019772077935048e-1)],
        real_pole: None,
        max_error: 7.3586701695805292800e-3,
    },
    // tools/odd_cram_tables.py, n = 3: equioscillation at 8 points to 2e-43.
    RationalApprox {
        degree: 3,
        c0: -7.9938063633568782881e-4,
        poles: &[c(-1.9820847875074079031e-1, 2.4107321029593380552)],
        residues: &[c(-6.9116392297431125592e-1, 4.3182218073431145642e-2)],
        real_pole: Some((-1.3688493230338539681, 1.4838485523029698992)),
        max_error: 7.9938063633568782881e-4,
    },
    // docs/NUMERICS.md §2.3, n = 4.
    RationalApprox {
        degree: 4,
        c0: 8.6522406952888523482e-5,
        poles: &[
            c(-1.5483932232971221744, 1.1918229466274256140),
            c(3.6784538618153983804e-1, 3.6581212986786673035),
        ],
        residues: &[
            c(6.1686779567832924168e-2, -1.9050409793030812954),
            c(-7.3395957163942207458e-2, 4.4999992247406271943e-1),
        ],
        real_pole: None,
        max_error: 8.6522406952888523482e-5,
    },
    // tools/odd_cram_tables.py, n = 5: equioscillation at 12 points to 1e-40.
    RationalApprox {
        degree: 5,
        c0: -9.3457131530266464768e-6,
        poles: &[
            c(-1.4405959942514724469, 2.3969835252938434535),
            c(1.0395056627937978944, 4.9213907336950271592),
        ],
        residues: &[
            c(-1.8723857791332469302, -3.7820630682407316096e-1),
            c(2.387886840880753345e-1, 1.0373867230367910467e-1),
        ],
        real_pole: Some((-2.1554154620085580192, 3.2718193944526842925)),
        max_error: 9.3457131530266464768e-6,
    },
    // docs/NUMERICS.md §2.3, n = 6.
    RationalApprox {
        degree: 6,
        c0: 1.0084543748996707079e-6,
        poles: &[
            c(-2.4006027476632035398, 1.1931292641501556043),
            c(-1.1585523628230171725, 3.6147724480383846068),
            c(1.7819885196256903191, 6.1965120962654247860),
        ],
        residues: &[
            c(5.7901301012950485516e-1, -4.2868875753470872956),
            c(-6.6300688564711040957e-1, 1.4514124962062375557),
            c(8.3581626491457074235e-2, -1.0642920552995280875e-1),
        ],
        real_pole: None,
        max_error: 1.0084543748996707079e-6,
    },
    // tools/odd_cram_tables.py, n = 7 (the paper's r = 7): equioscillation at 16 points to 1e-38.
    RationalApprox {
        degree: 7,
        c0: -1.0874974913752479609e-7,
        poles: &[
            c(-2.4231963513685187792, 2.3930293109369367756),
            c(-7.5760863371246975436e-1, 4.8436185091371495949),
            c(2.575726086391993882, 7.4809774314099503803),
        ],
        residues: &[
            c(-4.4566693870505470738, -1.5604498955857685362),
            c(9.0260521366982582153e-1, 7.4003615604162754851e-1),
            c(-3.9680465809293210908e-2, -5.247761625707437461e-2),
        ],
        real_pole: Some((-2.9410969231931400453, 7.1876259359111990987)),
        max_error: 1.0874974913752479609e-7,
    },
    // docs/NUMERICS.md §2.3, n = 8.
    RationalApprox {
        degree: 8,
        c0: 1.1722652116334907178e-8,
        poles: &[
            c(-3.2209452399451133668, 1.1936196046206519457),
            c(-2.2922491423048669926, 3.6007714934833810552),
            c(-2.6949098091275149029e-1, 6.0820325874935431647),
            c(3.4085395096636528123, 8.7730345535790393278),
        ],
        residues: &[
            c(1.8317717057715202914, -9.5256080740643358460),
            c(-2.4362407257817649368, 3.7167556135083240053),
            c(6.3258805131157439600e-1, -4.4392309694789681147e-1),
            c(-2.8129757023298988893e-2, 1.1577384208923706411e-2),
        ],
        real_pole: None,
        max_error: 1.1722652116334907178e-8,
    },
    // docs/NUMERICS.md §2.3, n = 10.
    RationalApprox {
        degree: 10,
        c0: 1.3611205233454477499e-10,
        poles: &[
            c(-4.0277324675187486643, 1.1938560664553323908),
            c(-3.2837528832313007331, 3.5943867723559030865),
            c(-1.7154060157689568146, 6.0389349254839190337),
            c(8.9440470160948065815e-1, 8.5827568986133875274),
            c(5.1611912720200760068, 1.1375156251916541201e1),
        ],
        residues: &[
            c(4.8183819908450345756, -2.1054597238399712507e1),
            c(-7.1171651040990542521, 8.8195331578731968199),
            c(2.5655849548411277781, -1.2163857061202029670),
            c(-2.7258698029640302865e-1, 1.4211727031631144164e-2),
            c(5.7849038580128854346e-3, 6.8585070894470128355e-4),
        ],
        real_pole: None,
        max_error: 1.3611205233454477499e-10,
    },
    // docs/NUMERICS.md §2.3, n = 12.
    RationalApprox {
        degree: 12,
        c0: 1.5794568370512387715e-12,
        poles: &[
            c(-4.8274934521610644815, 1.1939879912230829176),
            c(-4.2061242043183013345, 3.5909207588846161230),
            c(-2.9178685450793058124, 6.0173459240923723595),
            c(-8.5170709671550174357e-1, 8.5038328256346359240),
            c(2.2359682461306795080, 1.1109296232702840461e1),
            c(6.9986879086036170270, 1.3995916624970728270e1),
        ],
        residues: &[
            c(1.1799379956012233069e1, -4.6411635333526785749e1),
            c(-1.8785977421525417239e1, 2.0237285126063454092e1),
            c(8.2382559342348080565, -2.7961912623038074586),
            c(-1.3194115340711864577, -1.8352358287334646006e-1),
            c(6.8571494249760100694e-2, 3.8419082886648048812e-2),
            c(-8.1843349926244425124e-4, -5.8135358242612133592e-4),
        ],
        real_pole: None,
        max_error: 1.5794568370512387715e-12,
    },
    // docs/NUMERICS.md §2.3, n = 14 (= Pusa 2011/2012 CRAM-14 under z = −conj θ, c = −conj α).
    RationalApprox {
        degree: 14,
        c0: 1.8321743782540412752e-14,
        poles: &[
            c(-5.6231425727459771252, 1.1940690463439669732),
            c(-5.0893450605806245017, 3.5888240290270065157),
            c(-3.9933697105785685304, 6.0048316422350373162),
            c(-2.2697838292311127001, 8.4617379730402213968),
            c(2.0875863825013012194e-1, 1.0991260561901260918e1),
            c(3.7032750494234480610, 1.3656371871483268170e1),
            c(8.8977731864688888193, 1.6630982619902085304e1),
        ],
        residues: &[
            c(2.7875161940145646399e1, -1.0214733999056451427e2),
            c(-4.6933274488831293041e1, 4.5643649768827760758e1),
            c(2.3498232091082701235e1, -5.8083591297142075069),
            c(-4.8071120988325088739, -1.3209793837428724235),
            c(3.7636003878226968871e-1, 3.3518347029450103951e-1),
            c(-9.4390253107361688578e-3, -1.7184791958483017532e-2),
            c(7.1542880635890673042e-5, 1.4361043349541300136e-4),
        ],
        real_pole: None,
        max_error: 1.8321743782540412752e-14,
    },
    // docs/NUMERICS.md §2.3, n = 16 (= Pusa 2011/2012 CRAM-16 under z = −conj θ, c = −conj α).
    RationalApprox {
        degree: 16,
        c0: 2.1248537104952237488e-16,
        poles: &[
            c(-6.4161776990994341857, 1.1941223933701386699),
            c(-5.9481522689511774823, 3.5874573620183223162),
            c(-4.9931747377179964192, 5.9968817136039421951),
            c(-3.5091036084149180718, 8.4361989858843750942),
            c(-1.4193758971856659905, 1.0925363484496722585e1),
            c(1.4139284624888862117, 1.3497725698892745388e1),
            c(5.2649713434426468908, 1.6220221473167927305e1),
            c(1.0843917078696988026e1, 1.9277446167181652284e1),
        ],
        residues: &[
            c(6.4500878025539644564e1, -2.2459440762652096092e2),
            c(-1.1339775178483930464e2, 1.0194721704215856386e2),
            c(6.2518392463207919933e1, -1.1190391094283228881e1),
            c(-1.5059585270023467196e1, -5.7514052776421820767),
            c(1.4793007113558000013, 1.7686588323782937902),
            c(-4.1023136835410020949e-2, -1.5743466173455468195e-1),
            c(-2.1151742182466031443e-4, 4.3892969647380673895e-3),
            c(5.0901521865224928712e-7, -2.4220017652852287986e-5),
        ],
        real_pole: None,
        max_error: 2.1248537104952237488e-16,
    },
];
