//! The orientation of the standard views: which way is up and which side faces the viewer,
//! given explicitly ([`UpAxis`]) or found from the principal axes of the mesh ([`Frame::auto`]);
//! and the orthonormal camera frame of a [`View`] that the triangle and splat rasterisers share.

use mesh_fem::TriMesh;

use crate::vec3::{cross, dot, normalized, V3};
use crate::View;

/// `a / |a|`, or `a` itself when it cannot be normalised.
fn unit(a: V3) -> V3 {
    normalized(a).unwrap_or(a)
}

/// Which coordinate axis points up in the mesh's own frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpAxis {
    /// +x.
    X,
    /// +y (the usual convention of OBJ/PLY datasets: bunny, armadillo, spot).
    #[default]
    Y,
    /// +z (TOSCA, CAD and many generated meshes).
    Z,
    /// −x.
    NegX,
    /// −y.
    NegY,
    /// −z.
    NegZ,
}

/// Which way is up in the figures: an axis, or [`Up::Auto`], chosen from the mesh's extents
/// ([`Frame::auto`]); the registry of `--up`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Up {
    /// From the extents of the mesh (its second moments along x, y, z): +z for a shape thin
    /// along y (a person in a TOSCA-style z-up file) or thin along x and longer in y than in z
    /// (a standing quadruped), +y otherwise.
    #[default]
    Auto,
    /// The given axis.
    Axis(UpAxis),
}

wfem_base::registry! {
    Up as "up direction" {
        Up::Auto = Up::Auto => "auto":
            "from the extents of the mesh: +z for a person thin along y or a quadruped standing along y (TOSCA), +y otherwise (default)",
        Up::Axis(UpAxis::X) = Up::Axis(UpAxis::X) => "x" ["+x"]: "+x",
        Up::Axis(UpAxis::Y) = Up::Axis(UpAxis::Y) => "y" ["+y"]: "+y (most OBJ/PLY scans: bunny, armadillo, spot)",
        Up::Axis(UpAxis::Z) = Up::Axis(UpAxis::Z) => "z" ["+z"]: "+z (TOSCA, CAD)",
        Up::Axis(UpAxis::NegX) = Up::Axis(UpAxis::NegX) => "-x": "−x",
        Up::Axis(UpAxis::NegY) = Up::Axis(UpAxis::NegY) => "-y": "−y",
        Up::Axis(UpAxis::NegZ) = Up::Axis(UpAxis::NegZ) => "-z": "−z",
    }
}

impl Up {
    /// The frame of the standard views for `mesh`.
    pub fn frame(self, mesh: &mesh_fem::TriMesh) -> Frame {
        match self {
            Up::Auto => Frame::auto(mesh),
            Up::Axis(axis) => Frame::from_up(axis),
        }
    }
}

/// "+z", "-y", or the rounded vector for a direction off the axes (for messages naming the up
/// direction a figure uses).
pub fn direction_label(v: [f64; 3]) -> String {
    match v.map(|c| c.round() as i64) {
        [1, 0, 0] if v[0] == 1.0 => "+x".into(),
        [-1, 0, 0] if v[0] == -1.0 => "-x".into(),
        [0, 1, 0] if v[1] == 1.0 => "+y".into(),
        [0, -1, 0] if v[1] == -1.0 => "-y".into(),
        [0, 0, 1] if v[2] == 1.0 => "+z".into(),
        [0, 0, -1] if v[2] == -1.0 => "-z".into(),
        _ => format!("({:.2}, {:.2}, {:.2})", v[0], v[1], v[2]),
    }
}

/// A right-handed orthonormal frame of the figures: `up` is screen-up in the front view,
/// `front` points from the mesh towards the viewer of the front view, and
/// `right = up × front` is screen-right there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Screen-right of the front view.
    pub right: [f64; 3],
    /// Up.
    pub up: [f64; 3],
    /// Towards the viewer of the front view.
    pub front: [f64; 3],
}

impl Frame {
    /// The frame with `up` and `front` (made orthonormal; `front` must not be parallel to
    /// `up`).
    pub fn new(up: [f64; 3], front: [f64; 3]) -> Self {
        let up = unit(up);
        let front = unit(sub_projection(front, up));
        Self {
            right: cross(up, front),
            up,
            front,
        }
    }

    /// The frame of a coordinate up axis. +y keeps the front at +z; +z is the y-up frame
    /// turned by +90° about x (front at −y); the others turn +y onto their axis the same way.
    pub fn from_up(up: UpAxis) -> Self {
        let (u, f) = match up {
            UpAxis::Y => ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            UpAxis::Z => ([0.0, 0.0, 1.0], [0.0, -1.0, 0.0]),
            UpAxis::X => ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
            UpAxis::NegY => ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
            UpAxis::NegZ => ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            UpAxis::NegX => ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        };
        Self::new(u, f)
    }

    /// Maps a direction given in the y-up frame (x right, y up, z front) into this frame.
    pub fn map(&self, v: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (k, o) in out.iter_mut().enumerate() {
            *o = v[0] * self.right[k] + v[1] * self.up[k] + v[2] * self.front[k];
        }
        out
    }

    /// Orients the figures from the extents of the mesh: the area-weighted standard deviations
    /// sx, sy, sz of its surface along x, y and z (its second moments: mesh files are almost
    /// always modelled or scanned axis-aligned, with +y or +z up).
    ///
    /// * **Up** is +y, the most common convention (bunny, armadillo, spot, Homer), unless the
    ///   extents say +z: y is clearly the thinnest axis (sy < 0.6·min(sx, sz): a person
    ///   standing in a z-up file, thin front to back, like TOSCA's David, Michael, Victoria),
    ///   or x is the thinnest and z clearly shorter than y (sz < 0.8·sy: a quadruped standing
    ///   along y in a z-up file, like TOSCA's cat, dog, horse and wolf — an animal is longer
    ///   than it is tall).
    /// * **Front** is the thinnest axis, so the front view shows the broad side of the shape
    ///   (a cat's flank, a person's front): on the side the frame of the up axis faces
    ///   ([`Frame::from_up`]: +z for y-up, −y for z-up) when that is the thin axis, else on
    ///   its positive side.
    /// * A nearly isotropic shape (every deviation within 15 %: a sphere, a cube) keeps the
    ///   y-up frame.
    ///
    /// No rule on extents is always right (a TOSCA animal rearing up is as tall as it is long);
    /// the CLI prints the choice and `--up` overrides it.
    pub fn auto(mesh: &TriMesh) -> Self {
        auto_frame(mesh).unwrap_or_else(|| Self::from_up(UpAxis::Y))
    }
}

fn sub_projection(a: V3, onto_unit: V3) -> V3 {
    let d = dot(a, onto_unit);
    [
        a[0] - d * onto_unit[0],
        a[1] - d * onto_unit[1],
        a[2] - d * onto_unit[2],
    ]
}

/// Area-weighted standard deviations of the surface along x, y and z (triangles by their
/// centroids, so the result does not depend on how densely a region is sampled).
fn deviations(mesh: &TriMesh) -> Option<V3> {
    let positions = mesh.positions();
    let mut area = 0.0;
    let mut first = [0.0; 3];
    let mut second = [0.0; 3];
    for face in mesh.faces() {
        let [p, q, r] = face.map(|v| positions[v as usize]);
        let n = cross(
            [q[0] - p[0], q[1] - p[1], q[2] - p[2]],
            [r[0] - p[0], r[1] - p[1], r[2] - p[2]],
        );
        let w = 0.5 * dot(n, n).sqrt();
        if !w.is_finite() {
            continue;
        }
        area += w;
        for k in 0..3 {
            let c = (p[k] + q[k] + r[k]) / 3.0;
            first[k] += w * c;
            second[k] += w * c * c;
        }
    }
    if !(area > 0.0 && area.is_finite()) {
        return None;
    }
    let sd = [0, 1, 2].map(|k| {
        let mean = first[k] / area;
        (second[k] / area - mean * mean).max(0.0).sqrt()
    });
    sd.iter().all(|s| s.is_finite()).then_some(sd)
}

fn auto_frame(mesh: &TriMesh) -> Option<Frame> {
    let [sx, sy, sz] = deviations(mesh)?;
    let (lo, hi) = (sx.min(sy).min(sz), sx.max(sy).max(sz));
    // hi is finite and ≥ 0 (deviations() checked it).
    if hi <= 0.0 || lo > hi / 1.15 {
        return None; // nearly isotropic: no preferred axis
    }
    let person_z_up = sy < 0.6 * sx.min(sz);
    let animal_z_up = sx <= sy && sx <= sz && sz < 0.8 * sy;
    let up = if person_z_up || animal_z_up {
        UpAxis::Z
    } else {
        UpAxis::Y
    };
    let default = Frame::from_up(up);
    let thin = if sx <= sy && sx <= sz {
        0
    } else if sy <= sz {
        1
    } else {
        2
    };
    let mut front = [0.0; 3];
    front[thin] = if default.front[thin] != 0.0 {
        default.front[thin]
    } else {
        1.0
    };
    // The thin axis is up itself only for a flat y-up shape (a terrain): keep the y-up frame.
    if default.up[thin] != 0.0 {
        return Some(default);
    }
    Some(Frame::new(default.up, front))
}

/// Orthonormal camera frame: `right`, `up` span the screen, `dir` points towards the viewer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Camera {
    pub(crate) right: V3,
    pub(crate) up: V3,
    pub(crate) dir: V3,
}

impl Camera {
    /// `None` if the direction is zero/non-finite or (nearly) parallel to `up`.
    pub(crate) fn new(view: &View) -> Option<Self> {
        let dir = normalized(view.direction)?;
        let up = normalized(view.up)?;
        let r = cross(up, dir);
        if dot(r, r) < 1e-12 {
            return None;
        }
        let right = normalized(r)?;
        let up = cross(dir, right);
        Some(Self { right, up, dir })
    }

    pub(crate) fn project(&self, p: V3) -> (f64, f64, f64) {
        (dot(p, self.right), dot(p, self.up), dot(p, self.dir))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box_mesh(ext: [f64; 3]) -> TriMesh {
        let (p, f) = mesh_fem::generate::icosphere(2).into_parts();
        let p = p
            .into_iter()
            .map(|q| [q[0] * ext[0], q[1] * ext[1], q[2] * ext[2]])
            .collect();
        TriMesh::new(p, f).unwrap()
    }

    #[test]
    fn auto_picks_y_or_z_from_the_extents() {
        // Isotropic: y-up frame.
        assert_eq!(Frame::auto(&box_mesh([1.0, 1.0, 1.0])), Frame::from_up(UpAxis::Y));
        // A standing quadruped along y in a z-up file (thin x, long y, medium z): z up, flank in front.
        let cat = Frame::auto(&box_mesh([0.3, 2.0, 1.0]));
        assert_eq!((cat.up, cat.front), ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]));
        // A person thin along y in a z-up file: z up, front −y.
        assert_eq!(Frame::auto(&box_mesh([1.5, 0.3, 1.7])), Frame::from_up(UpAxis::Z));
        // A y-up scan thinnest along z (bunny-like): the y-up frame.
        assert_eq!(Frame::auto(&box_mesh([1.0, 1.0, 0.7])), Frame::from_up(UpAxis::Y));
        // A cow-like shape thin along x with y ≈ z (spot): y up, flank (+x) in front.
        let spot = Frame::auto(&box_mesh([0.5, 1.0, 1.05]));
        assert_eq!((spot.up, spot.front), ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0]));
    }

    #[test]
    fn coordinate_frames_are_right_handed_and_map_y_up() {
        for up in [
            UpAxis::X,
            UpAxis::Y,
            UpAxis::Z,
            UpAxis::NegX,
            UpAxis::NegY,
            UpAxis::NegZ,
        ] {
            let f = Frame::from_up(up);
            assert_eq!(cross(f.up, f.front), f.right, "{up:?}");
            assert_eq!(f.map([0.0, 1.0, 0.0]), f.up);
            assert_eq!(dot(f.up, f.front), 0.0);
        }
        assert_eq!(Frame::from_up(UpAxis::Z).front, [0.0, -1.0, 0.0]);
    }
}
