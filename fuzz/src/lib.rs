//! Shared invariant checks of the wfem fuzz targets.
//!
//! Every target feeds arbitrary bytes to a reader. The reader must return either a typed
//! [`MeshError`] or a mesh for which the checks below hold; anything else (a panic, an
//! overflow, a hang, a huge allocation, a NaN) is a crash that libFuzzer records.

use mesh_fem::io::{LoadOptions, LoadReport, MeshFormat};
use mesh_fem::validate::validate;
use mesh_fem::{assemble, AssemblyParams, MeshError, TriMesh};
use std::path::Path;

/// The name readers put into error messages.
pub fn name_for(format: MeshFormat) -> &'static Path {
    Path::new(match format {
        MeshFormat::Obj => "fuzz.obj",
        MeshFormat::Ply => "fuzz.ply",
        MeshFormat::Off => "fuzz.off",
        MeshFormat::Stl => "fuzz.stl",
    })
}

/// An error must name its culprit: its message must not be empty, and a parse error must
/// carry the file name it was given.
pub fn check_error(e: &MeshError, name: &Path) {
    let msg = e.to_string();
    assert!(!msg.is_empty(), "error without a message: {e:?}");
    if let MeshError::Parse { path, .. } = e {
        assert_eq!(path, name, "parse error names another file: {e:?}");
    }
}

/// Invariants of a mesh returned by a reader: every face index < n_vertices, every
/// coordinate finite, at least one face and one vertex, and a validation report can be
/// built whose counts match the mesh.
pub fn check_mesh(mesh: &TriMesh, report: &LoadReport, format: MeshFormat) {
    assert_eq!(report.format, format);
    let n = mesh.n_vertices();
    assert!(n > 0 && mesh.n_faces() > 0, "reader returned an empty mesh");
    for (f, face) in mesh.faces().iter().enumerate() {
        for &i in face {
            assert!((i as usize) < n, "face {f} uses vertex {i} of {n}");
        }
    }
    for (v, p) in mesh.positions().iter().enumerate() {
        assert!(p.iter().all(|c| c.is_finite()), "vertex {v} is not finite: {p:?}");
    }
    let v = validate(mesh);
    assert_eq!(v.n_vertices, n);
    assert_eq!(v.n_faces, mesh.n_faces());
    // Building the summary walks every problem's Display impl.
    let _ = v.summary();
}

/// Reads `data` as `format` and checks the result (see [`check_mesh`] and [`check_error`]).
pub fn read_and_check(data: &[u8], format: MeshFormat) -> Option<TriMesh> {
    let name = name_for(format);
    for triangulate in [false, true] {
        let opts = LoadOptions::with_triangulation(triangulate);
        let read = match format {
            MeshFormat::Obj => mesh_fem::io::read_obj(data, name, &opts),
            MeshFormat::Ply => mesh_fem::io::read_ply(data, name, &opts),
            MeshFormat::Off => mesh_fem::io::read_off(data, name, &opts),
            MeshFormat::Stl => mesh_fem::io::read_stl(data, name, &opts),
        };
        match read {
            Ok((mesh, report)) => {
                check_mesh(&mesh, &report, format);
                if triangulate {
                    return Some(mesh);
                }
            }
            Err(e) => check_error(&e, name),
        }
    }
    None
}

/// The whole path: load → validate → (if usable) assemble, then check the operators:
/// all values finite, L and B symmetric, L·1 ≈ 0 relative to the row's absolute sum,
/// positive diagonal of L, B and D, and D's diagonal equal to the row sums of B (the
/// barycentric lumped mass, the paper's Eq. (7)).
pub fn pipeline(data: &[u8]) {
    let Some((&selector, file)) = data.split_first() else {
        return;
    };
    let format = match selector % 4 {
        0 => MeshFormat::Obj,
        1 => MeshFormat::Ply,
        2 => MeshFormat::Off,
        _ => MeshFormat::Stl,
    };
    let name = name_for(format);
    let opts = LoadOptions::with_triangulation(selector & 4 != 0);
    let (mesh, report) = match mesh_fem::io::load_bytes(file, format, name, &opts) {
        Ok(r) => r,
        Err(e) => return check_error(&e, name),
    };
    check_mesh(&mesh, &report, format);
    let usable = validate(&mesh).is_usable();
    match assemble(&mesh, &AssemblyParams::default()) {
        Ok(ops) => {
            assert!(usable, "assemble succeeded on a mesh validate calls unusable");
            check_operators(&mesh, &ops);
        }
        Err(e) => {
            assert!(!usable, "validate calls the mesh usable but assemble fails: {e}");
            check_error(&e, name);
        }
    }
}

/// Entry (i, j) of a CSC matrix, 0 if not stored.
fn entry(m: &faer::sparse::SparseColMat<usize, f64>, i: usize, j: usize) -> f64 {
    let s = m.symbolic();
    let range = s.col_range(j);
    let rows = &s.row_idx()[range.clone()];
    match rows.binary_search(&i) {
        Ok(k) => m.val()[range.start + k],
        Err(_) => 0.0,
    }
}

fn check_operators(mesh: &TriMesh, ops: &mesh_fem::FemOperators) {
    let n = mesh.n_vertices();
    assert_eq!(ops.n(), n);
    let lumped = ops.lumped_mass();
    for (what, m) in [("L", &ops.stiffness), ("B", &ops.mass), ("D", &lumped)] {
        assert_eq!((m.nrows(), m.ncols()), (n, n), "{what} has the wrong shape");
        assert!(m.val().iter().all(|v| v.is_finite()), "{what} has a non-finite entry");
    }
    assert!(
        ops.lumped_diagonal.iter().all(|d| d.is_finite() && *d > 0.0),
        "D is not positive"
    );
    let l = &ops.stiffness;
    let s = l.symbolic();
    let mut row_sum = vec![0.0f64; n];
    let mut row_abs = vec![0.0f64; n];
    let mut b_row_sum = vec![0.0f64; n];
    for j in 0..n {
        for p in s.col_range(j) {
            let i = s.row_idx()[p];
            let v = l.val()[p];
            row_sum[i] += v;
            row_abs[i] += v.abs();
            assert_eq!(v, entry(l, j, i), "L is not symmetric at ({i}, {j})");
            let b = ops.mass.val()[p];
            assert_eq!(b, entry(&ops.mass, j, i), "B is not symmetric at ({i}, {j})");
            b_row_sum[i] += b;
        }
    }
    for i in 0..n {
        let d = entry(l, i, i);
        assert!(d > 0.0, "L has a non-positive diagonal entry {d} at {i}");
        assert!(
            row_sum[i].abs() <= 1e-9 * row_abs[i],
            "L·1 = {} at row {i}, but Σ|L_ij| = {}",
            row_sum[i],
            row_abs[i]
        );
        let dd = ops.lumped_diagonal[i];
        assert!(
            (dd - b_row_sum[i]).abs() <= 1e-9 * dd,
            "D_ii = {dd} but Σ_j B_ij = {} at row {i}",
            b_row_sum[i]
        );
    }
}

/// Reads `data` as a one-file volume format and checks the result: a typed error naming the
/// file, or tetrahedra with indices in range and finite coordinates whose validation report
/// counts them, and — when no problem is fatal — operators that assemble with finite values.
pub fn read_volume_and_check(data: &[u8], format: mesh_fem::io::volume::VolumeFormat) {
    use mesh_fem::volume::{assemble_volume, validate_volume};
    let name = Path::new("fuzz.volume");
    match mesh_fem::io::volume::parse_volume(data, format, name) {
        Err(e) => assert!(!e.to_string().is_empty(), "error without a message: {e:?}"),
        Ok(read) => {
            let m = &read.mesh;
            let n = m.n_vertices();
            assert!(n > 0 && m.n_tets() > 0, "reader returned an empty volume");
            assert!(m.tets().iter().flatten().all(|&i| (i as usize) < n));
            assert!(m.positions().iter().flatten().all(|c| c.is_finite()));
            let report = validate_volume(m);
            assert_eq!((report.n_vertices, report.n_tets), (n, m.n_tets()));
            if report.clone().into_result().is_ok() {
                if let Ok(fem) = assemble_volume(m, &AssemblyParams::default()) {
                    assert!(fem.lumped_diagonal.iter().all(|d| d.is_finite() && *d > 0.0));
                }
            }
        }
    }
}
