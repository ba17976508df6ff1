//! Measuring: medians of repeated cold calls, power-law fits and the paper's Table 2.

#[allow(unused_imports)]
use super::*;

/// One measured quantity: median wall time over the repetitions and the largest peak heap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measurement {
    /// Median wall-clock seconds.
    pub seconds: f64,
    /// Largest peak of live heap bytes above the level at the start of a repetition.
    pub peak_bytes: usize,
    /// Number of repetitions.
    pub repetitions: usize,
}

/// Median of a non-empty list (mean of the middle two for even lengths).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.is_empty() {
        f64::NAN
    } else if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Runs `f` up to `repetitions` times (at least once; no new repetition after
/// `budget_seconds` in total) and returns the median time and the largest peak heap above the
/// level at the start of each call. The value returned by `f` is dropped after the clock stops.
pub fn measure<R>(
    repetitions: usize,
    budget_seconds: f64,
    mut f: impl FnMut() -> Result<R, BenchError>,
) -> Result<Measurement, BenchError> {
    let mut times = Vec::new();
    let mut peak = 0usize;
    let mut total = 0.0;
    while times.is_empty() || (times.len() < repetitions && total < budget_seconds) {
        let base = heap_reset_peak();
        let start = Instant::now();
        let out = f()?;
        let elapsed = start.elapsed().as_secs_f64();
        peak = peak.max(heap_peak().saturating_sub(base));
        drop(out);
        times.push(elapsed);
        total += elapsed;
    }
    Ok(Measurement {
        seconds: median(&times),
        peak_bytes: peak,
        repetitions: times.len(),
    })
}

/// Least-squares fit `log y = a + p log x`; returns the exponent p, or `None` with fewer than
/// two distinct positive points.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let m = logs.len() as f64;
    let (mx, my) = logs.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / m, b + y / m));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Log-log interpolation of a table `(x, y)` sorted by x; `None` outside its range.
pub fn interpolate_loglog(table: &[(f64, f64)], x: f64) -> Option<f64> {
    table.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        (x0 <= x && x <= x1).then(|| {
            let s = (x.ln() - x0.ln()) / (x1.ln() - x0.ln());
            (y0.ln() + s * (y1.ln() - y0.ln())).exp()
        })
    })
}

/// The paper's Table 2 (1.83 GHz Intel Core Duo, 1 GB RAM): n, seconds to build (L, B),
/// seconds for K_t f with the generalized Chebyshev method (r = 7, MINRES).
pub const PAPER_TABLE2: [(f64, f64, f64); 9] = [
    (1e3, 0.0734, 0.26),
    (5e3, 0.0821, 0.94),
    (20e3, 0.3438, 11.36),
    (40e3, 0.6067, 13.20),
    (80e3, 0.7044, 16.98),
    (100e3, 0.9781, 54.56),
    (200e3, 2.8119, 67.44),
    (400e3, 4.138, 98.36),
    (500e3, 5.5434, 112.22),
];

// ---------------------------------------------------------------------------------------------
// Report data
// ---------------------------------------------------------------------------------------------
