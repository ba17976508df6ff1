//! Our OBJ reader against `tobj` as an independent oracle, on every OBJ file of the corpus.
//!
//! `tobj` renumbers vertices per group in order of first use (so vertex numbering cannot be
//! compared), but the triangles as position triples must be the same multiset. This also
//! checks that our fan triangulation matches tobj's.

use mesh_fem::io::{load, LoadOptions};
use rayon::prelude::*;
use wfem_corpus::all_mesh_files;

type Tri = [[u64; 3]; 3];

fn key(p: [f64; 3]) -> [u64; 3] {
    p.map(f64::to_bits)
}

#[test]
fn our_obj_triangles_equal_tobj_triangles_on_the_corpus() {
    let files: Vec<_> = all_mesh_files()
        .unwrap()
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .collect();
    assert!(files.len() >= 40, "only {} OBJ files", files.len());
    let tobj_opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    files.par_iter().for_each(|path| {
        let (mesh, _) = load(path, &LoadOptions::with_triangulation(true)).unwrap();
        let mut ours: Vec<Tri> = mesh
            .faces()
            .iter()
            .map(|f| f.map(|i| key(mesh.positions()[i as usize])))
            .collect();
        let (models, _) = tobj::load_obj(path, &tobj_opts).unwrap();
        let mut theirs: Vec<Tri> = Vec::new();
        for m in &models {
            let p = &m.mesh.positions;
            for t in m.mesh.indices.chunks_exact(3) {
                let corner = |i: u32| {
                    let i = i as usize;
                    key([p[3 * i], p[3 * i + 1], p[3 * i + 2]])
                };
                theirs.push([corner(t[0]), corner(t[1]), corner(t[2])]);
            }
        }
        ours.sort_unstable();
        theirs.sort_unstable();
        assert_eq!(ours.len(), theirs.len(), "{}", path.display());
        assert!(ours == theirs, "{}: triangles differ from tobj", path.display());
    });
}
