//! The one seeded random-number helper of the workspace: SplitMix64 (Steele, Lea & Flood,
//! OOPSLA 2014). Tiny, fast, deterministic for a given seed and platform independent — good
//! enough for start vectors, k-means++ seeding and synthetic benchmark data, which is all the
//! workspace needs (no `rand` dependency).

/// SplitMix64 generator, with the second normal of each Box–Muller pair cached.
///
/// The state advances by the golden-ratio increment `0x9E37_79B9_7F4A_7C15` and every output
/// is finalised by Stafford's "Mix13". Statistically adequate for seeding and sampling, not for
/// cryptography.
///
/// ```
/// use wfem_base::rng::SplitMix64;
/// let mut a = SplitMix64::new(7);
/// let mut b = SplitMix64::new(7);
/// assert_eq!(a.next_u64(), b.next_u64()); // same seed, same stream
/// let u = a.next_f64();
/// assert!((0.0..1.0).contains(&u));
/// // The first output for seed 0 (reference value of the published algorithm).
/// assert_eq!(SplitMix64::new(0).next_u64(), 0xE220_A839_7B1D_CDAF);
/// ```
#[derive(Clone, Debug, PartialEq)]
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
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [−½, ½) (centred start vectors).
    pub fn next_centered(&mut self) -> f64 {
        self.next_f64() - 0.5
    }

    /// Uniform integer in `0..n` by rejection (no modulo bias). `n = 0` returns 0.
    pub fn next_below(&mut self, n: usize) -> usize {
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

    /// A standard normal variate by the Box–Muller transform; the second value of each pair
    /// is cached and returned by the next call.
    pub fn next_normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        // 1 − u ∈ (0, 1], so the logarithm is finite.
        let u1 = 1.0 - self.next_f64();
        let u2 = self.next_f64();
        let r = (-2.0 * u1.ln()).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u2;
        self.spare_normal = Some(r * phi.sin());
        r * phi.cos()
    }

    /// A uniformly distributed unit vector in ℝ³ (a normalised standard normal triple).
    pub fn unit_vector(&mut self) -> [f64; 3] {
        loop {
            let v = [self.next_normal(), self.next_normal(), self.next_normal()];
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 1e-9 {
                return v.map(|c| c / l);
            }
        }
    }

    /// A uniformly random permutation of `0..n` (Fisher–Yates, drawing with
    /// [`Self::next_below`]).
    pub fn permutation(&mut self, n: usize) -> Vec<u32> {
        let mut p: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            p.swap(i, self.next_below(i + 1));
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn matches_the_reference_splitmix64_stream() {
        // First outputs of SplitMix64 seeded with 1234567 (reference C implementation).
        let mut g = SplitMix64::new(1_234_567);
        assert_eq!(g.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(g.next_u64(), 3_203_168_211_198_807_973);
        assert_eq!(g.next_u64(), 9_817_491_932_198_370_423);
    }

    #[test]
    fn uniform_moments_and_range() {
        let mut g = SplitMix64::new(42);
        let n = 100_000;
        let xs: Vec<f64> = (0..n).map(|_| g.next_f64()).collect();
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 5e-3, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 2e-3, "{var}");
        let counts = (0..n).fold([0usize; 7], |mut c, _| {
            c[g.next_below(7)] += 1;
            c
        });
        assert!(counts
            .iter()
            .all(|&c| (c as f64 - n as f64 / 7.0).abs() < 0.05 * n as f64 / 7.0));
        let zs: Vec<f64> = (0..n).map(|_| g.next_normal()).collect();
        let zm = zs.iter().sum::<f64>() / n as f64;
        let zv = zs.iter().map(|z| (z - zm) * (z - zm)).sum::<f64>() / n as f64;
        assert!(zm.abs() < 0.02 && (zv - 1.0).abs() < 0.02, "{zm} {zv}");
    }
}
