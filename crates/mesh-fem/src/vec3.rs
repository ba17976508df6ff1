//! Small 3-vector helpers, the one copy of them in the workspace (mesh-fem's assembly and
//! validation, the renderer and the SHREC'10 synthesis use these).

/// a + b.
#[inline]
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a + s (b − a)`: the point at parameter s on the segment from a to b.
#[inline]
pub fn lerp(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [
        a[0] + s * (b[0] - a[0]),
        a[1] + s * (b[1] - a[1]),
        a[2] + s * (b[2] - a[2]),
    ]
}

/// a − b.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a · b.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a|.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The axis-aligned bounding box (lowest, highest corner) of `positions`; both corners are
/// the origin for no positions.
pub fn bounding_box(positions: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    if positions.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// The first of `points` with a NaN or infinite component, with its index.
pub(crate) fn first_non_finite(points: &[[f64; 3]]) -> Option<(usize, [f64; 3])> {
    points
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|c| !c.is_finite()))
        .map(|(i, &p)| (i, p))
}

/// An orthonormal tangent basis (x, y) with x × y = n (n a unit vector).
pub(crate) fn tangent_basis(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let test = if n[0].abs() > 0.9 {
        [0.0, 1.0, 0.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let x = cross(test, n);
    let len = norm(x);
    let x = x.map(|c| c / len);
    (x, cross(n, x))
}

/// Length of the bounding-box diagonal of `positions` (0 for none).
pub fn bbox_diagonal(positions: &[[f64; 3]]) -> f64 {
    let (lo, hi) = bounding_box(positions);
    norm(sub(hi, lo))
}
