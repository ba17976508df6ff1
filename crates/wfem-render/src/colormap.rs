//! Perceptually uniform colormaps: Viridis (sequential) and Moreland's Coolwarm (diverging).

use std::sync::OnceLock;

/// A map from a normalised scalar t ∈ [0, 1] to an sRGB colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Colormap {
    /// Matplotlib's sequential Viridis (van der Walt & Smith, CC0): dark blue → green → yellow,
    /// CIE L* strictly increasing. The default, for unsigned fields such as K_t e_i.
    #[default]
    Viridis,
    /// Moreland's diverging Cool-to-Warm map (blue (59,76,192) → grey-white → red (180,4,38)),
    /// interpolated in his Msh colour space. For signed fields; pair it with a range symmetric
    /// about zero, e.g. `range: Some((-m, m))`, so that white marks zero.
    Coolwarm,
}

impl Colormap {
    /// The sRGB colour of t; t is clamped to [0, 1] and NaN maps to t = 0.
    pub fn map(&self, t: f64) -> [u8; 3] {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let rgb = match self {
            Colormap::Viridis => viridis(t),
            Colormap::Coolwarm => {
                let lut = coolwarm_lut();
                let x = t * (COOLWARM_SAMPLES - 1) as f64;
                let i = (x.floor() as usize).min(COOLWARM_SAMPLES - 2);
                let w = x - i as f64;
                let (a, b) = (lut[i], lut[i + 1]);
                [
                    a[0] + w * (b[0] - a[0]),
                    a[1] + w * (b[1] - a[1]),
                    a[2] + w * (b[2] - a[2]),
                ]
            }
        };
        rgb.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
    }

    /// A lookup table of `n ≥ 2` colours sampling t = k/(n−1), used by the renderer so that the
    /// per-pixel cost of the colormap is one index.
    pub(crate) fn table(&self, n: usize) -> Vec<[u8; 3]> {
        let n = n.max(2);
        (0..n).map(|k| self.map(k as f64 / (n - 1) as f64)).collect()
    }
}

/// Viridis as the degree-6 polynomial least-squares fit of matplotlib's 256-entry table
/// (fit published by Matt Zucker, CC0); per-channel error within ≈ 5/255 sRGB steps (largest
/// at the yellow end), which is invisible, and it keeps the monotone lightness of the original.
fn viridis(t: f64) -> [f64; 3] {
    const C: [[f64; 3]; 7] = [
        [
            0.277_727_327_223_417_7,
            0.005_407_344_544_966_578,
            0.334_099_805_335_306_1,
        ],
        [0.105_093_043_108_577_4, 1.404_613_529_898_575, 1.384_590_162_594_685],
        [
            -0.330_861_828_725_556_3,
            0.214_847_559_468_213,
            0.095_095_163_028_236_59,
        ],
        [-4.634_230_498_983_486, -5.799_100_973_351_585, -19.332_440_956_279_87],
        [6.228_269_936_347_081, 14.179_933_366_805_09, 56.690_552_600_681_05],
        [4.776_384_997_670_288, -13.745_145_377_746_01, -65.353_032_633_372_34],
        [-5.435_455_855_934_631, 4.645_852_612_178_535, 26.312_435_249_583_2],
    ];
    let mut out = [0.0; 3];
    for (ch, o) in out.iter_mut().enumerate() {
        // Horner evaluation, highest degree first.
        *o = C.iter().rev().fold(0.0, |acc, c| acc * t + c[ch]);
    }
    out
}

const COOLWARM_SAMPLES: usize = 257;

/// Moreland's Cool-to-Warm map sampled at 257 points (the midpoint t = 1/2 is a sample).
fn coolwarm_lut() -> &'static [[f64; 3]] {
    static LUT: OnceLock<Vec<[f64; 3]>> = OnceLock::new();
    LUT.get_or_init(|| {
        let cool = [59.0 / 255.0, 76.0 / 255.0, 192.0 / 255.0];
        let warm = [180.0 / 255.0, 4.0 / 255.0, 38.0 / 255.0];
        (0..COOLWARM_SAMPLES)
            .map(|k| msh_interpolate(cool, warm, k as f64 / (COOLWARM_SAMPLES - 1) as f64))
            .collect()
    })
}

// --- Colour science for Moreland's diverging maps ("Diverging Color Maps for Scientific
// Visualization", ISVC 2009): sRGB → linear → XYZ (D65) → CIELAB → Msh, where
// M = |Lab|, s = acos(L/M) (saturation), h = atan2(b, a) (hue).

const WHITE_D65: [f64; 3] = [0.950_47, 1.0, 1.088_83];

fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn lab_f(t: f64) -> f64 {
    const D: f64 = 6.0 / 29.0;
    if t > D * D * D {
        t.cbrt()
    } else {
        t / (3.0 * D * D) + 4.0 / 29.0
    }
}

fn lab_f_inv(t: f64) -> f64 {
    const D: f64 = 6.0 / 29.0;
    if t > D {
        t * t * t
    } else {
        3.0 * D * D * (t - 4.0 / 29.0)
    }
}

/// sRGB (components in [0, 1]) to CIELAB with the D65 white point.
pub(crate) fn srgb_to_lab(rgb: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(srgb_to_linear);
    let x = 0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175_0 * b;
    let z = 0.019_333_9 * r + 0.119_192_0 * g + 0.950_304_1 * b;
    let (fx, fy, fz) = (
        lab_f(x / WHITE_D65[0]),
        lab_f(y / WHITE_D65[1]),
        lab_f(z / WHITE_D65[2]),
    );
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

fn lab_to_srgb(lab: [f64; 3]) -> [f64; 3] {
    let fy = (lab[0] + 16.0) / 116.0;
    let fx = fy + lab[1] / 500.0;
    let fz = fy - lab[2] / 200.0;
    let x = WHITE_D65[0] * lab_f_inv(fx);
    let y = WHITE_D65[1] * lab_f_inv(fy);
    let z = WHITE_D65[2] * lab_f_inv(fz);
    let r = 3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z;
    let g = -0.969_266_0 * x + 1.876_010_8 * y + 0.041_556_0 * z;
    let b = 0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z;
    [r, g, b].map(linear_to_srgb)
}

fn lab_to_msh(lab: [f64; 3]) -> [f64; 3] {
    let m = (lab[0] * lab[0] + lab[1] * lab[1] + lab[2] * lab[2]).sqrt();
    let s = if m > 0.0 {
        (lab[0] / m).clamp(-1.0, 1.0).acos()
    } else {
        0.0
    };
    let h = lab[2].atan2(lab[1]);
    [m, s, h]
}

fn msh_to_lab(msh: [f64; 3]) -> [f64; 3] {
    let [m, s, h] = msh;
    [m * s.cos(), m * s.sin() * h.cos(), m * s.sin() * h.sin()]
}

/// Moreland's hue spin when interpolating from a saturated to an unsaturated colour.
fn adjust_hue(msh: [f64; 3], m_unsat: f64) -> f64 {
    let [m, s, h] = msh;
    if m >= m_unsat {
        return h;
    }
    let spin = s * (m_unsat * m_unsat - m * m).sqrt() / (m * s.sin());
    if h > -std::f64::consts::FRAC_PI_3 {
        h + spin
    } else {
        h - spin
    }
}

fn msh_interpolate(rgb1: [f64; 3], rgb2: [f64; 3], x: f64) -> [f64; 3] {
    let mut a = lab_to_msh(srgb_to_lab(rgb1));
    let mut b = lab_to_msh(srgb_to_lab(rgb2));
    let mut x = x;
    // Distinct saturated end colours: pass through an unsaturated (white) midpoint.
    if a[1] > 0.05 && b[1] > 0.05 && (a[2] - b[2]).abs() > std::f64::consts::FRAC_PI_3 {
        let m_mid = a[0].max(b[0]).max(88.0);
        if x < 0.5 {
            b = [m_mid, 0.0, 0.0];
            x *= 2.0;
        } else {
            a = [m_mid, 0.0, 0.0];
            x = 2.0 * x - 1.0;
        }
    }
    if a[1] < 0.05 && b[1] > 0.05 {
        a[2] = adjust_hue(b, a[0]);
    } else if b[1] < 0.05 && a[1] > 0.05 {
        b[2] = adjust_hue(a, b[0]);
    }
    let msh = [0, 1, 2].map(|k| (1.0 - x) * a[k] + x * b[k]);
    lab_to_srgb(msh_to_lab(msh))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lab_roundtrip() {
        for rgb in [[0.2, 0.5, 0.9], [1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [0.7, 0.1, 0.3]] {
            let back = lab_to_srgb(srgb_to_lab(rgb));
            for k in 0..3 {
                assert!((back[k] - rgb[k]).abs() < 1e-6, "{rgb:?} -> {back:?}");
            }
        }
        // White has L* = 100 and no chroma.
        let w = srgb_to_lab([1.0; 3]);
        assert!((w[0] - 100.0).abs() < 1e-3 && w[1].abs() < 1e-2 && w[2].abs() < 1e-2);
    }

    #[test]
    fn coolwarm_midpoint_is_moreland_grey() {
        // Moreland's table gives (221, 221, 221) at the centre of the Cool-to-Warm map.
        let mid = Colormap::Coolwarm.map(0.5);
        for c in mid {
            assert!((c as i32 - 221).abs() <= 2, "{mid:?}");
        }
    }
}
