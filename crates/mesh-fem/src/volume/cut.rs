//! A planar cut through a tetrahedral mesh, for pictures of the interior: the part of the
//! boundary on the kept side of the plane (its triangles clipped at the plane) and the section
//! of every tetrahedron the plane crosses, as one triangle mesh whose vertices are the kept
//! vertices and points on crossing edges. A per-vertex field of the volume gives the cut's
//! field by linear interpolation along those edges — the P1 field itself, exactly.

use super::TetMesh;
use crate::vec3::{dot, sub};
use crate::{MeshError, TriMesh};
use std::collections::HashMap;

/// The cut surface and, for each of its vertices, the volume vertices it interpolates.
#[derive(Clone, Debug)]
pub struct Cut {
    /// The clipped boundary and the section, as one mesh.
    pub mesh: TriMesh,
    /// Vertex i of `mesh` is (1 − w)·f[a] + w·f[b] for its entry (a, b, w).
    pub sources: Vec<(u32, u32, f64)>,
}

impl Cut {
    /// The cut's values of a per-vertex field of the volume.
    pub fn values(&self, f: &[f64]) -> Vec<f64> {
        self.sources
            .iter()
            .map(|&(a, b, w)| (1.0 - w) * f[a as usize] + w * f[b as usize])
            .collect()
    }
}

/// The vertices of the cut, made once per volume vertex or crossing edge.
struct Points<'a> {
    positions: &'a [[f64; 3]],
    side: Vec<f64>,
    index: HashMap<(u32, u32), u32>,
    out: Vec<[f64; 3]>,
    sources: Vec<(u32, u32, f64)>,
}

impl Points<'_> {
    /// Vertex `v` of the volume.
    fn vertex(&mut self, v: u32) -> u32 {
        self.edge(v, v)
    }

    /// The point of edge (a, b) on the plane (or vertex a when a == b).
    fn edge(&mut self, a: u32, b: u32) -> u32 {
        let key = (a.min(b), a.max(b));
        if let Some(&i) = self.index.get(&key) {
            return i;
        }
        let (a, b) = key;
        let (sa, sb) = (self.side[a as usize], self.side[b as usize]);
        let w = if a == b || sa == sb {
            0.0
        } else {
            (sa / (sa - sb)).clamp(0.0, 1.0)
        };
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let p = [0, 1, 2].map(|k| (1.0 - w) * pa[k] + w * pb[k]);
        let i = self.out.len() as u32;
        self.out.push(p);
        self.sources.push((a, b, w));
        self.index.insert(key, i);
        i
    }

    /// A polygon (a cycle of volume vertices) clipped to the kept side: its corners as cut
    /// vertices (Sutherland–Hodgman against one plane).
    fn clip(&mut self, polygon: &[u32]) -> Vec<u32> {
        let mut out = Vec::new();
        for (k, &a) in polygon.iter().enumerate() {
            let b = polygon[(k + 1) % polygon.len()];
            let (ka, kb) = (self.side[a as usize] <= 0.0, self.side[b as usize] <= 0.0);
            if ka {
                out.push(self.vertex(a));
            }
            if ka != kb {
                out.push(self.edge(a, b));
            }
        }
        out.dedup();
        if out.len() > 1 && out.first() == out.last() {
            out.pop();
        }
        out
    }
}

/// The cut of `mesh` by the plane {p : p·normal = offset}, keeping the side p·normal ≤ offset
/// (look at it from `+normal`).
///
/// # Errors
/// [`MeshError::Empty`] when the kept side holds nothing (the plane misses the volume's side).
pub fn cut(mesh: &TetMesh, normal: [f64; 3], offset: f64) -> Result<Cut, MeshError> {
    let positions = mesh.positions();
    let mut points = Points {
        positions,
        side: positions.iter().map(|p| dot(*p, normal) - offset).collect(),
        index: HashMap::new(),
        out: Vec::new(),
        sources: Vec::new(),
    };
    let mut faces = Vec::new();
    let fan = |faces: &mut Vec<[u32; 3]>, poly: &[u32]| {
        for k in 1..poly.len().saturating_sub(1) {
            faces.push([poly[0], poly[k], poly[k + 1]]);
        }
    };
    for f in super::boundary_faces(mesh) {
        let poly = points.clip(&f);
        fan(&mut faces, &poly);
    }
    for t in mesh.tets() {
        let below: Vec<u32> = t.iter().copied().filter(|&v| points.side[v as usize] <= 0.0).collect();
        if below.is_empty() || below.len() == 4 {
            continue;
        }
        let above: Vec<u32> = t.iter().copied().filter(|&v| points.side[v as usize] > 0.0).collect();
        let mut section: Vec<u32> = Vec::new();
        for &a in &below {
            for &b in &above {
                section.push(points.edge(a, b));
            }
        }
        // Order the section's 3 or 4 points around their centroid, facing +normal.
        let c = section.iter().fold([0.0; 3], |s, &i| {
            let p = points.out[i as usize];
            [s[0] + p[0], s[1] + p[1], s[2] + p[2]]
        });
        let c = c.map(|x| x / section.len() as f64);
        let (u, v) = tangent_basis(normal);
        section.sort_by(|&i, &j| {
            let angle = |i: u32| {
                let d = sub(points.out[i as usize], c);
                dot(d, v).atan2(dot(d, u))
            };
            angle(i).total_cmp(&angle(j))
        });
        section.dedup();
        fan(&mut faces, &section);
    }
    let mesh = TriMesh::new(points.out, faces)?;
    Ok(Cut {
        mesh,
        sources: points.sources,
    })
}

/// Two unit vectors spanning the plane orthogonal to `n`, (u, v, n) right-handed.
fn tangent_basis(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    use crate::vec3::{cross, norm};
    let l = norm(n);
    let n = n.map(|x| x / l);
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let u = cross(helper, n);
    let lu = norm(u);
    let u = u.map(|x| x / lu);
    (u, cross(n, u))
}
