//! Bounds on every size a caller chooses (numbers of times, scales, eigenpairs, output
//! columns), defined once for the library, the command line and Python: each is checked
//! before anything is allocated, so a huge or mistyped number is a typed error naming the
//! parameter, never an abort, a panic on a failed allocation or an unbounded run. The CLI
//! names the same bounds by their flags (`src/cli/limits.rs`).

use crate::HeatError;

/// Diffusion times per call (`heat --t`, `hks --times`/`--num-times`, Python's `times`/
/// `num_times`): each costs one solve or one n-vector, and every output holds n × T values.
pub const MAX_TIMES: usize = 1000;

/// Scales of the feature-driven approximation (each one K_t application and two n-vectors;
/// paper: 5–10).
pub const MAX_APPROX_SCALES: usize = 100;

/// Memory budget of the partial eigensolver (its Krylov basis and projected matrix).
pub const EIGENSOLVER_MEMORY: u64 = 4 << 30;

/// Memory budget of one n × T output array.
pub const OUTPUT_MEMORY: u64 = 2 << 30;

/// Meshes with at most this many vertices may ask for any number of eigenpairs up to n.
pub const SMALL_MESH: usize = 1000;

/// Above [`SMALL_MESH`], the spectral method takes at most n / `SPECTRAL_FRACTION` eigenpairs
/// (beyond, the shift-invert Lanczos costs more than an exact method).
pub const SPECTRAL_FRACTION: usize = 10;

fn out_of_range(name: &'static str, reason: String) -> HeatError {
    HeatError::InvalidParameter { name, reason }
}

/// `value` in `lo..=hi`.
///
/// # Errors
/// [`HeatError::InvalidParameter`] naming `name`, the value and the range.
pub fn count(name: &'static str, value: usize, lo: usize, hi: usize) -> Result<usize, HeatError> {
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(out_of_range(name, format!("{value} is not in {lo}..={hi}")))
    }
}

/// A number of diffusion times: 1..=[`MAX_TIMES`].
///
/// # Errors
/// [`HeatError::InvalidParameter`].
pub fn times(name: &'static str, count: usize) -> Result<usize, HeatError> {
    self::count(name, count, 1, MAX_TIMES)
}

/// `count` output columns of n values each fit [`OUTPUT_MEMORY`].
///
/// # Errors
/// [`HeatError::InvalidParameter`] with the largest count allowed on this mesh.
pub fn columns(name: &'static str, count: usize, n: usize) -> Result<(), HeatError> {
    let bytes = (count as u128).saturating_mul(n as u128).saturating_mul(8);
    if bytes > u128::from(OUTPUT_MEMORY) {
        let max = (OUTPUT_MEMORY / (n.max(1) as u64).saturating_mul(8)).max(1);
        return Err(out_of_range(
            name,
            format!(
                "{count} columns of {n} values need {:.1} GB; at most {max} on this mesh",
                bytes as f64 / 1e9
            ),
        ));
    }
    Ok(())
}

/// Memory in bytes of [`crate::spectral::Eigenbasis::partial`] for k pairs of an n-vertex mesh: the
/// basis V and MV (n × d each) and the projected matrix (d × d), d = min(n, max(6k, k + 200)).
pub fn partial_eigensolver_bytes(n: usize, k: usize) -> u64 {
    let (n, k) = (n as u64, k as u64);
    let d = k.saturating_mul(6).max(k.saturating_add(200)).min(n);
    n.saturating_mul(d)
        .saturating_mul(2)
        .saturating_add(d.saturating_mul(d))
        .saturating_mul(8)
}

/// The largest k ≤ `k` whose eigensolver fits [`EIGENSOLVER_MEMORY`] on n vertices (≥ 1).
pub fn max_eigenpairs(n: usize, k: usize) -> usize {
    (1..=k.min(n))
        .rev()
        .step_by((k.min(n) / 64).max(1))
        .find(|&k| partial_eigensolver_bytes(n, k) <= EIGENSOLVER_MEMORY)
        .unwrap_or(1)
}

/// A number of eigenpairs k of an n-vertex mesh for the partial eigensolver: in 1..=n and
/// within [`EIGENSOLVER_MEMORY`].
///
/// # Errors
/// [`HeatError::InvalidParameter`] naming `name`.
pub fn eigenpairs(name: &'static str, k: usize, n: usize) -> Result<usize, HeatError> {
    count(name, k, 1, n)?;
    let bytes = partial_eigensolver_bytes(n, k);
    if bytes > EIGENSOLVER_MEMORY {
        return Err(out_of_range(
            name,
            format!(
                "{k} eigenpairs of {n} vertices need about {:.1} GB for the eigensolver; at most {} on this mesh",
                bytes as f64 / 1e9,
                max_eigenpairs(n, k)
            ),
        ));
    }
    Ok(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_outside_the_bounds_are_refused() {
        assert_eq!(partial_eigensolver_bytes(100, 100), 8 * (2 * 100 * 100 + 100 * 100));
        assert!(eigenpairs("k", 200, 48_485).is_ok());
        assert!(eigenpairs("k", 5000, 48_485).is_err());
        assert!(eigenpairs("k", usize::MAX, 10).is_err());
        assert!(eigenpairs("k", 0, 10).is_err());
        assert!(times("num_times", MAX_TIMES).is_ok());
        assert!(times("num_times", 1_000_000_000).is_err());
        assert!(columns("num_times", 1000, 100_000).is_ok());
        let e = columns("num_times", usize::MAX, usize::MAX).unwrap_err().to_string();
        assert!(e.contains("num_times"), "{e}");
    }
}
