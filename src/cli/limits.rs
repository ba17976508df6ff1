//! Bounds on every size that comes from the command line, checked before anything is
//! allocated or computed: a typed error names the flag, the value and the allowed range.

use super::CliError;

/// PNG figures per run (one per field; each is a ≈1 MB image rendered from four views).
pub const MAX_FIGURES: usize = 64;

/// `demo --level`: level 8 has 655,362 vertices (the largest size of the benchmarks); level 9
/// would need ≈ 10 GB for the spectral part of the demo.
pub const MAX_DEMO_LEVEL: u32 = 8;

// The library's bounds (shared with Python), named here by their flags.
pub use wfem_heat::limits::{
    partial_eigensolver_bytes, EIGENSOLVER_MEMORY, MAX_APPROX_SCALES, MAX_TIMES, OUTPUT_MEMORY, SMALL_MESH,
    SPECTRAL_FRACTION,
};

fn out_of_range(flag: &'static str, value: impl ToString, allowed: String, why: impl Into<String>) -> CliError {
    CliError::OutOfRange {
        flag,
        value: value.to_string(),
        allowed,
        why: why.into(),
    }
}

/// `value` must lie in `lo..=hi`.
pub fn count(flag: &'static str, value: usize, lo: usize, hi: usize, why: &str) -> Result<usize, CliError> {
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(out_of_range(flag, value, format!("{lo}..={hi}"), why))
    }
}

/// A diffusion time: finite and > 0 (the largest double is allowed).
pub fn time(flag: &'static str, t: f64) -> Result<f64, CliError> {
    if t.is_finite() && t > 0.0 {
        Ok(t)
    } else {
        Err(out_of_range(flag, t, "finite t > 0".into(), "a diffusion time"))
    }
}

/// A list of diffusion times: at most [`MAX_TIMES`], each valid, none repeated.
pub fn times(flag: &'static str, ts: &[f64]) -> Result<(), CliError> {
    if ts.len() > MAX_TIMES {
        return Err(out_of_range(
            flag,
            format!("with {} values", ts.len()),
            format!("1..={MAX_TIMES} values"),
            "each value is one output column",
        ));
    }
    for (i, &t) in ts.iter().enumerate() {
        time(flag, t)?;
        if ts[..i].contains(&t) {
            return Err(CliError::Usage(format!(
                "{flag} {t} is given twice (two identical output columns)"
            )));
        }
    }
    Ok(())
}

/// `count` output columns of n values each must fit [`OUTPUT_MEMORY`].
pub fn columns(flag: &'static str, count: usize, n: usize) -> Result<(), CliError> {
    let bytes = 8 * count as u64 * n as u64;
    if bytes > OUTPUT_MEMORY {
        let max = (OUTPUT_MEMORY / (8 * n.max(1) as u64)).max(1);
        return Err(out_of_range(
            flag,
            count,
            format!("1..={max} on this {n}-vertex mesh"),
            format!("{count} columns of {n} values need {:.1} GB", bytes as f64 / 1e9),
        ));
    }
    Ok(())
}

/// The number of eigenpairs of a heat kernel signature: [`eigenpairs`], and at most
/// n / [`SPECTRAL_FRACTION`] where the partial eigensolver runs (above
/// [`wfem_heat::spectral::DENSE_MAX_VERTICES`] vertices; below, a large k uses the dense decomposition).
pub fn descriptor_eigenpairs(k: usize, n: usize) -> Result<usize, CliError> {
    let k = eigenpairs("--eigenpairs", k, n)?;
    let limit = n / SPECTRAL_FRACTION;
    if n > wfem_heat::spectral::DENSE_MAX_VERTICES && k > limit {
        return Err(out_of_range(
            "--eigenpairs",
            k,
            format!("1..={limit} (n/{SPECTRAL_FRACTION}) on this {n}-vertex mesh"),
            "the partial eigensolver slows down sharply beyond; the signature at the usual times needs 100–300",
        ));
    }
    Ok(k)
}

/// A number of eigenpairs k for an n-vertex mesh computed by the partial eigensolver: in
/// 1..=n and within [`EIGENSOLVER_MEMORY`].
pub fn eigenpairs(flag: &'static str, k: usize, n: usize) -> Result<usize, CliError> {
    count(flag, k, 1, n, &format!("the mesh has {n} vertices"))?;
    let bytes = partial_eigensolver_bytes(n, k);
    if bytes > EIGENSOLVER_MEMORY {
        let max = wfem_heat::limits::max_eigenpairs(n, k);
        return Err(out_of_range(
            flag,
            k,
            format!("1..={max} on this mesh"),
            format!(
                "{k} eigenpairs of {n} vertices need about {:.1} GB for the eigensolver",
                bytes as f64 / 1e9
            ),
        ));
    }
    Ok(k)
}

/// The number of eigenpairs of `--method spectral`: [`eigenpairs`], and at most
/// n / [`SPECTRAL_FRACTION`] above [`SMALL_MESH`] vertices.
pub fn spectral_eigenpairs(k: usize, n: usize) -> Result<usize, CliError> {
    let k = eigenpairs("--eigenpairs", k, n)?;
    let limit = n / SPECTRAL_FRACTION;
    if n > SMALL_MESH && k > limit {
        let exact = if n <= wfem_heat::spectral::DENSE_MAX_VERTICES {
            "--method dense (all eigenpairs, exact, O(n³)) or --method fast"
        } else {
            "--method fast or --method rational (exact, no eigenpairs)"
        };
        return Err(out_of_range(
            "--eigenpairs",
            k,
            format!("1..={limit} (n/{SPECTRAL_FRACTION}) on this {n}-vertex mesh"),
            format!("more eigenpairs cost more than an exact method; use {exact}"),
        ));
    }
    Ok(k)
}

pub use shape_retrieval::limits::{MAX_RETRIEVAL_EIGS, MAX_WORDS};

/// The sizes of `retrieval build` (the library's bounds, [`shape_retrieval::limits`], named
/// by their flags).
pub fn retrieval_sizes(eigs: usize, words: usize) -> Result<(), CliError> {
    count("--eigenpairs", eigs, 1, MAX_RETRIEVAL_EIGS, "eigenpairs per shape")?;
    count("--words", words, 1, MAX_WORDS, "vocabulary size")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigensolver_memory_grows_with_k_and_saturates_at_n() {
        assert_eq!(partial_eigensolver_bytes(100, 100), 8 * (2 * 100 * 100 + 100 * 100));
        assert!(partial_eigensolver_bytes(48_485, 200) < EIGENSOLVER_MEMORY);
        assert!(eigenpairs("--eigenpairs", 5000, 48_485).is_err());
        assert!(eigenpairs("--eigenpairs", usize::MAX, 10).is_err());
        assert!(eigenpairs("--eigenpairs", 0, 10).is_err());
    }

    #[test]
    fn spectral_refuses_a_large_fraction_of_a_large_mesh() {
        assert!(spectral_eigenpairs(6, 6).is_ok());
        assert!(spectral_eigenpairs(1000, 1000).is_ok());
        assert!(spectral_eigenpairs(500, 5000).is_ok());
        let e = spectral_eigenpairs(501, 5000).unwrap_err().to_string();
        assert!(e.contains("--eigenpairs 501") && e.contains("--method dense"), "{e}");
    }

    #[test]
    fn times_must_be_positive_finite_and_distinct() {
        assert!(times("--t", &[0.01, f64::MAX]).is_ok());
        for bad in [[0.0], [-1.0], [f64::NAN], [f64::INFINITY]] {
            assert!(times("--t", &bad).is_err());
        }
        let e = times("--t", &[0.01, 0.01]).unwrap_err().to_string();
        assert!(e.contains("given twice"), "{e}");
        assert!(times("--t", &vec![1.0; MAX_TIMES + 1]).is_err());
    }
}
