//! The one seeded random generator of wfem: SplitMix64 (Steele, Lea & Flood, OOPSLA 2014).
//!
//! wfem has no `rand` dependency; every random choice (k-means++ seeding, training-set
//! subsampling, Lanczos start blocks, the synthetic SHREC'10 transformations) draws from this
//! generator, so that one seed gives the same bits on every platform and thread count.
//!
//! The state advances by the golden-ratio increment `0x9E37_79B9_7F4A_7C15` and every output is
//! finalised by Stafford's "Mix13" (`z ^= z >> 30; z *= 0xBF58…; z ^= z >> 27; z *= 0x94D0…;
//! z ^= z >> 31`). Statistically adequate for seeding and sampling, not for cryptography.
//!
//! ```
//! use mesh_fem::rng::SplitMix64;
//! let mut rng = SplitMix64::new(0);
//! // The first output of SplitMix64 seeded with 0 (reference value of the published algorithm).
//! assert_eq!(rng.next_u64(), 0xE220_A839_7B1D_CDAF);
//! ```

/// The SplitMix64 generator with a cached second Box–Muller normal.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
    spare_normal: Option<f64>,
}

impl SplitMix64 {
    /// A generator with the given seed (every seed, including 0, is valid).
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed,
            spare_normal: None,
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits (the top 53 bits of [`Self::next_u64`]).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in `0..n` by rejection (no modulo bias). `n = 0` returns 0.
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            return 0;
        }
        let n = n as u64;
        let zone = u64::MAX - u64::MAX % n;
        loop {
            let x = self.next_u64();
            if x < zone {
                return (x % n) as usize;
            }
        }
    }

    /// A standard normal by the Box–Muller transform; the second value of each pair is cached
    /// and returned by the next call.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        // u1 ∈ (0, 1], so ln u1 is finite.
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        self.spare_normal = Some(r * phi.sin());
        r * phi.cos()
    }

    /// A uniformly distributed unit vector in ℝ³ (a normalised standard normal triple).
    pub fn unit_vector(&mut self) -> [f64; 3] {
        loop {
            let v = [self.normal(), self.normal(), self.normal()];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 1e-9 {
                return v.map(|c| c / l);
            }
        }
    }

    /// A uniformly random permutation of `0..n` (Fisher–Yates, drawing with [`Self::below`]).
    pub fn permutation(&mut self, n: usize) -> Vec<u32> {
        let mut p: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            p.swap(i, self.below(i + 1));
        }
        p
    }
}
