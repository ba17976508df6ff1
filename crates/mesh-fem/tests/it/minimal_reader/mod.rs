//! A deliberately minimal OBJ (`v`/`f`) and OFF reader for the validate/stats/mtx tests,
//! independent of `mesh_fem::io` (written in parallel). Polygons are fan-triangulated, as in
//! the corpus table `SOURCES.md`.
#![allow(dead_code)]

use mesh_fem::TriMesh;
use std::path::PathBuf;

/// The corpus folder through the one corpus helper (`WFEM_MESHES` overrides it). The corpus
/// is required: `.ci/run` checks that it is there, so a missing folder is a failure, not a skip.
pub fn corpus_dir() -> Option<PathBuf> {
    Some(wfem_corpus::meshes_dir().expect("the mesh corpus ../shared/data/meshes is required (or set WFEM_MESHES)"))
}

/// Positions and fan-triangulated faces of an OBJ or OFF file.
pub fn read_parts(path: &std::path::Path) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut positions = Vec::new();
    let mut polygons: Vec<Vec<u32>> = Vec::new();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext.eq_ignore_ascii_case("obj") {
        for line in text.lines() {
            let mut w = line.split_whitespace();
            match w.next() {
                Some("v") => {
                    let c: Vec<f64> = w.take(3).map(|x| x.parse().unwrap()).collect();
                    positions.push([c[0], c[1], c[2]]);
                }
                Some("f") => polygons.push(
                    w.map(|x| {
                        let i: i64 = x.split('/').next().unwrap().parse().unwrap();
                        if i < 0 {
                            (positions.len() as i64 + i) as u32
                        } else {
                            (i - 1) as u32
                        }
                    })
                    .collect(),
                ),
                _ => {}
            }
        }
    } else if ext.eq_ignore_ascii_case("off") {
        let mut tokens = text
            .lines()
            .map(|l| l.split('#').next().unwrap())
            .flat_map(|l| l.split_whitespace())
            .peekable();
        let head = tokens.next().unwrap();
        assert!(head.ends_with("OFF"), "not an OFF file");
        let nv: usize = tokens.next().unwrap().parse().unwrap();
        let nf: usize = tokens.next().unwrap().parse().unwrap();
        let _ne = tokens.next();
        for _ in 0..nv {
            let c: Vec<f64> = (0..3).map(|_| tokens.next().unwrap().parse().unwrap()).collect();
            positions.push([c[0], c[1], c[2]]);
        }
        for _ in 0..nf {
            let k: usize = tokens.next().unwrap().parse().unwrap();
            polygons.push((0..k).map(|_| tokens.next().unwrap().parse().unwrap()).collect());
            // Optional per-face colours are not used by the corpus files we read.
        }
    } else {
        panic!("minimal reader: unsupported extension {ext}");
    }
    let mut faces = Vec::new();
    for p in polygons {
        for k in 1..p.len() - 1 {
            faces.push([p[0], p[k], p[k + 1]]);
        }
    }
    (positions, faces)
}

/// Reads a mesh file relative to the corpus folder.
pub fn read_corpus(rel: &str) -> Option<TriMesh> {
    let dir = corpus_dir()?;
    let (p, f) = read_parts(&dir.join(rel));
    Some(TriMesh::new(p, f).expect("corpus meshes have finite coordinates and valid indices"))
}
