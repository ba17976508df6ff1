//! `wfem_base::rng::SplitMix64` against the published reference outputs and the moments of its
//! distributions.

use wfem_base::rng::SplitMix64;

#[test]
fn splitmix64_reference_values_and_normals() {
    // Reference outputs of Vigna's splitmix64.c for seed 0.
    let mut r = SplitMix64::new(0);
    assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
    assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    assert_eq!(r.next_u64(), 0x06C4_5D18_8009_454F);
    let mut r = SplitMix64::new(42);
    let m = 200_000;
    let z: Vec<f64> = (0..m).map(|_| r.next_normal()).collect();
    let mean = z.iter().sum::<f64>() / m as f64;
    let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / m as f64;
    let kurt = z.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / m as f64 / (var * var);
    assert!(mean.abs() < 0.01, "mean {mean}");
    assert!((var - 1.0).abs() < 0.01, "variance {var}");
    assert!((kurt - 3.0).abs() < 0.05, "kurtosis {kurt}");
    let u: Vec<usize> = (0..60_000).map(|_| r.next_below(6)).collect();
    for k in 0..6 {
        let c = u.iter().filter(|&&x| x == k).count();
        assert!((c as i64 - 10_000).abs() < 400, "bin {k}: {c}");
    }
    let p = r.permutation(100);
    let mut sorted = p.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, (0..100).collect::<Vec<u32>>());
}

#[test]
fn uniform_is_the_top_53_bits_and_unit_vectors_are_unit() {
    let (mut a, mut b) = (SplitMix64::new(7), SplitMix64::new(7));
    for _ in 0..100 {
        let u = a.next_f64();
        assert!((0.0..1.0).contains(&u));
        assert_eq!(u, (b.next_u64() >> 11) as f64 / (1u64 << 53) as f64);
    }
    let mut r = SplitMix64::new(3);
    let mut mean = [0.0; 3];
    for _ in 0..20_000 {
        let v = r.unit_vector();
        assert!(((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() - 1.0).abs() < 1e-12);
        (0..3).for_each(|k| mean[k] += v[k] / 20_000.0);
    }
    // Isotropy: the mean of uniform unit vectors is 0 (standard error ≈ 0.004 per component).
    assert!(mean.iter().all(|m| m.abs() < 0.02), "{mean:?}");
    assert_eq!(r.next_below(0), 0);
}
