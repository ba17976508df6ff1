//! The legend: a vertical colour bar (maximum on top) with tick labels and iso-level marks.

use super::font::{draw_text, text_height, text_width};
use super::{Rect, RenderParams, RgbImage};

const TEXT: [u8; 3] = [25, 25, 25];
const FRAME: [u8; 3] = [60, 60, 60];

/// Bar rectangle and the total width of the legend column, which starts at x = `x0`.
pub(crate) fn bar_rect(x0: u32, top: u32, height: u32, fs: u32, range: (f64, f64)) -> (Rect, u32) {
    let pad = 6 * fs;
    let bar_w = 8 * fs;
    let bar_h = ((height as f64 * 0.72) as u32).clamp(1, height.max(1));
    let label_w = labels(range, bar_h, fs)
        .iter()
        .map(|(_, s)| text_width(s, fs))
        .max()
        .unwrap_or(0);
    let bar = Rect {
        x: x0 + pad + 2 * fs,
        y: top + height.saturating_sub(bar_h) / 2,
        width: bar_w,
        height: bar_h,
    };
    (bar, pad + 2 * fs + bar_w + 6 * fs + label_w + pad)
}

/// Draws the bar, its frame, the iso-level marks on its left and the labelled ticks on its right.
pub(crate) fn draw(img: &mut RgbImage, bar: Rect, range: (f64, f64), params: &RenderParams, fs: u32) {
    let (lo, hi) = range;
    let constant = hi <= lo;
    let (x0, y0) = (bar.x as i64, bar.y as i64);
    let (bw, bh) = (bar.width as i64, bar.height as i64);
    for row in 0..bh {
        // Top row is t = 1 (the maximum); a constant field shows the middle colour.
        let t = if constant {
            0.5
        } else {
            1.0 - row as f64 / (bh - 1).max(1) as f64
        };
        img.fill_rect(x0, y0 + row, x0 + bw, y0 + row + 1, params.colormap.map(t));
    }
    let f = fs as i64;
    // Frame, one font pixel wide, outside the bar.
    img.fill_rect(x0 - f, y0 - f, x0 + bw + f, y0, FRAME);
    img.fill_rect(x0 - f, y0 + bh, x0 + bw + f, y0 + bh + f, FRAME);
    img.fill_rect(x0 - f, y0, x0, y0 + bh, FRAME);
    img.fill_rect(x0 + bw, y0, x0 + bw + f, y0 + bh, FRAME);

    let y_of = |v: f64| -> i64 {
        if constant {
            y0 + bh / 2
        } else {
            y0 + ((hi - v) / (hi - lo) * (bh - 1) as f64).round() as i64
        }
    };
    // Iso-levels as short marks left of the bar, matching the lines on the surface.
    if !constant && params.n_isolines > 0 {
        let step = (hi - lo) / (params.n_isolines + 1) as f64;
        for k in 1..=params.n_isolines {
            let y = y_of(lo + k as f64 * step);
            img.fill_rect(x0 - 4 * f, y, x0 - f, y + 1, TEXT);
        }
    }
    let th = text_height(fs) as i64;
    for (v, label) in labels(range, bar.height, fs) {
        let y = y_of(v);
        img.fill_rect(x0 + bw + f, y, x0 + bw + 3 * f, y + f.max(1), FRAME);
        let ty = (y - th / 2).min(img.height as i64 - th).max(0);
        // A gap of 3 font pixels keeps the tick from reading as a minus sign.
        draw_text(img, x0 + bw + 6 * f, ty, &label, fs, TEXT);
    }
}

/// Tick values and labels: the two ends of the range, plus "nice" values (1, 2, 2.5, 5 × 10^k)
/// in between that do not collide with the end labels.
pub(crate) fn labels(range: (f64, f64), bar_h: u32, fs: u32) -> Vec<(f64, String)> {
    let (lo, hi) = range;
    if hi <= lo {
        return vec![(lo, format_value(lo, lo.abs().max(1e-300) * 1e-3, lo.abs()))];
    }
    let magnitude = lo.abs().max(hi.abs());
    let end_prec = 10f64.powf(magnitude.log10().floor() - 2.0);
    let mut out = vec![
        (hi, format_value(hi, end_prec, magnitude)),
        (lo, format_value(lo, end_prec, magnitude)),
    ];
    let step = nice_step((hi - lo) / 5.0);
    let min_gap = (text_height(fs) + 3 * fs) as f64 * (hi - lo) / bar_h.max(1) as f64;
    let mut k = (lo / step).ceil();
    while k * step < hi {
        let v = k * step;
        if v - lo > min_gap && hi - v > min_gap {
            out.push((v, format_value(v, step, magnitude)));
        }
        k += 1.0;
        if out.len() > 20 {
            break; // cannot happen with a nice step of range/5; a guard against rounding
        }
    }
    out
}

/// The smallest of 1, 2, 2.5, 5 × 10^k that is ≥ x.
fn nice_step(x: f64) -> f64 {
    let e = x.log10().floor();
    let base = 10f64.powf(e);
    let m = x / base;
    // The tolerance keeps exact inputs such as 0.2 (= 2 × 10⁻¹ up to rounding) on their step.
    let tol = 1e-9;
    let nice = if m <= 1.0 + tol {
        1.0
    } else if m <= 2.0 + tol {
        2.0
    } else if m <= 2.5 + tol {
        2.5
    } else if m <= 5.0 + tol {
        5.0
    } else {
        10.0
    };
    nice * base
}

/// Formats v with resolution `prec` (the smallest difference that matters); fixed notation for
/// magnitudes (of the whole range) in [1e-3, 1e5), scientific otherwise; trailing zeros trimmed.
pub(crate) fn format_value(v: f64, prec: f64, magnitude: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_finite() { "0".into() } else { format!("{v}") };
    }
    let prec = if prec > 0.0 && prec.is_finite() {
        prec
    } else {
        v.abs() * 1e-3
    };
    // Digits of the step: 2.5 × 10^k needs one more than 10^k.
    let prec_exp =
        prec.log10().floor() as i32 - i32::from((prec / 10f64.powi(prec.log10().floor() as i32) - 2.5).abs() < 1e-9);
    let s = if (1e-3..1e5).contains(&magnitude) {
        let decimals = (-prec_exp).clamp(0, 8) as usize;
        trim_zeros(format!("{v:.decimals$}"))
    } else {
        let exp = v.abs().log10().floor() as i32;
        let digits = (exp - prec_exp).clamp(0, 4) as usize;
        let s = format!("{v:.digits$e}");
        match s.split_once('e') {
            Some((mant, e)) => format!("{}e{e}", trim_zeros(mant.to_string())),
            None => s,
        }
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_fixed_and_scientific() {
        assert_eq!(format_value(0.5, 0.1, 1.0), "0.5");
        assert_eq!(format_value(1.0, 0.01, 1.0), "1");
        assert_eq!(format_value(-0.25, 0.25, 1.0), "-0.25");
        assert_eq!(format_value(1.5e-5, 1e-6, 2e-5), "1.5e-5");
        assert_eq!(format_value(2e6, 1e5, 2e6), "2e6");
        assert_eq!(format_value(-1e-9, 1e-3, 1.0), "0");
        assert_eq!(format_value(0.0, 0.1, 1.0), "0");
    }

    #[test]
    fn nice_steps() {
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(0.2), 0.2);
        assert_eq!(nice_step(0.22), 0.25);
        assert_eq!(nice_step(7.0), 10.0);
    }

    #[test]
    fn labels_include_both_ends_and_interior_ticks() {
        let l = labels((-1.0, 1.0), 300, 1);
        assert_eq!(l[0], (1.0, "1".to_string()));
        assert_eq!(l[1], (-1.0, "-1".to_string()));
        let interior: Vec<&str> = l[2..].iter().map(|(_, s)| s.as_str()).collect();
        assert_eq!(interior, ["-0.5", "0", "0.5"]);
        assert_eq!(labels((3.0, 3.0), 300, 1).len(), 1);
    }
}
