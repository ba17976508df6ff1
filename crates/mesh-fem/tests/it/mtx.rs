//! Matrix Market I/O: libigl's reference files, bit-exact round trips, malformed input with
//! line numbers, atomic writes, and the nalgebra-sparse conversions.

use crate::minimal_reader;

use faer::sparse::{SparseColMat, Triplet};
use mesh_fem::generate::{bumpy, icosphere};
#[cfg(feature = "nalgebra")]
use mesh_fem::mtx::{from_nalgebra_csc, to_nalgebra_csc, to_nalgebra_csr};
use mesh_fem::mtx::{read_matrix_market, write_matrix_market, write_operators};
use mesh_fem::stats::stats;
use mesh_fem::{assemble, AssemblyParams, MeshError, TriMesh};
use std::collections::BTreeMap;
use std::path::Path;

/// All stored entries as a map (row, col) → value (duplicates summed).
fn entries(m: &SparseColMat<usize, f64>) -> BTreeMap<(usize, usize), f64> {
    let mut out = BTreeMap::new();
    let r = m.as_ref();
    for j in 0..m.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            *out.entry((i, j)).or_insert(0.0) += v;
        }
    }
    out
}

fn from_triplets(nrows: usize, ncols: usize, t: &[(usize, usize, f64)]) -> SparseColMat<usize, f64> {
    let t: Vec<_> = t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(nrows, ncols, &t).unwrap()
}

#[test]
fn libigl_reference_files_read_and_match_assembly() {
    let Some(reference) = wfem_corpus::reference_dir() else {
        eprintln!("../shared/reference is not present: the libigl cross-check does not run");
        return;
    };
    for name in ["irregular_sphere_L4", "grid_70x70", "ellipsoid_L4"] {
        let (p, f) = minimal_reader::read_parts(&reference.join(format!("{name}.obj")));
        let mesh = TriMesh::new(p, f).unwrap();
        let s = stats(&mesh);
        let n = mesh.n_vertices();
        let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
        for (kind, ours) in [
            ("stiffness", &ops.stiffness),
            ("mass", &ops.mass),
            ("lumped_mass", &ops.lumped_mass()),
        ] {
            let m = read_matrix_market(reference.join(format!("{name}_{kind}.mtx"))).unwrap();
            assert_eq!((m.nrows(), m.ncols()), (n, n), "{name} {kind}");
            let e = entries(&m);
            // The pattern of L and B is the vertex–edge graph plus the diagonal; D is diagonal.
            let expected_nnz = if kind == "lumped_mass" { n } else { n + 2 * s.n_edges };
            assert_eq!(e.len(), expected_nnz, "{name} {kind}");
            for (&(i, j), &v) in &e {
                assert_eq!(e.get(&(j, i)), Some(&v), "{name} {kind} not symmetric at ({i}, {j})");
            }
            // Entry by entry against our assembly (libigl agrees to ~1e-15 relative).
            let ours = entries(ours);
            let scale = e.values().fold(0.0f64, |a, v| a.max(v.abs()));
            for (&(i, j), &v) in &e {
                let w = ours.get(&(i, j)).copied().unwrap_or(0.0);
                assert!((v - w).abs() <= 1e-12 * scale, "{name} {kind} ({i}, {j}): {v} vs {w}");
            }
            for (&(i, j), &w) in &ours {
                if !e.contains_key(&(i, j)) {
                    assert!(
                        w.abs() <= 1e-12 * scale,
                        "{name} {kind}: ({i}, {j}) = {w} missing in file"
                    );
                }
            }
        }
        let l = read_matrix_market(reference.join(format!("{name}_stiffness.mtx"))).unwrap();
        let mut row_sum = vec![0.0; n];
        let mut diag_positive = true;
        for (&(i, j), &v) in &entries(&l) {
            row_sum[i] += v;
            diag_positive &= i != j || v > 0.0;
        }
        assert!(diag_positive, "{name}: L has positive diagonal");
        assert!(row_sum.iter().all(|r| r.abs() < 1e-10), "{name}: L·1 = 0");
        let b = read_matrix_market(reference.join(format!("{name}_mass.mtx"))).unwrap();
        assert!(
            (entries(&b).values().sum::<f64>() - s.area).abs() < 1e-12 * s.area,
            "{name}: 1ᵀB1 = area"
        );
    }
}

#[test]
fn operators_round_trip_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    // bumpy(5): ≈ 41K lines per matrix, more than one parallel formatting task of the writer,
    // so the lines of several tasks must come back in order.
    let ops = assemble(&bumpy(5), &AssemblyParams::default()).unwrap();
    assert!(ops.stiffness.compute_nnz() / 2 > 1 << 14);
    write_operators(dir.path(), &ops).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    // Atomic writes leave no temporary files behind.
    assert_eq!(names, ["lumped_mass.mtx", "mass.mtx", "stiffness.mtx"]);
    for (file, m) in [("stiffness.mtx", &ops.stiffness), ("mass.mtx", &ops.mass)] {
        let back = read_matrix_market(dir.path().join(file)).unwrap();
        assert_eq!(entries(&back), entries(m), "{file}");
    }
    let d = entries(&read_matrix_market(dir.path().join("lumped_mass.mtx")).unwrap());
    assert_eq!(d.len(), ops.n());
    for (i, &v) in ops.lumped_diagonal.iter().enumerate() {
        assert_eq!(d[&(i, i)].to_bits(), v.to_bits());
    }
    let text = std::fs::read_to_string(dir.path().join("stiffness.mtx")).unwrap();
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
}

#[test]
fn general_matrix_round_trips_extreme_values() {
    let t = [
        (0, 0, 1.0),
        (2, 0, -0.1),
        (1, 1, 0.0), // an explicit zero is kept
        (0, 2, 1e300),
        (3, 2, -5e-324),
        (1, 3, std::f64::consts::PI),
        (2, 3, 1.0 / 3.0),
    ];
    let m = from_triplets(4, 5, &t);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("general.mtx");
    write_matrix_market(&path, &m, false).unwrap();
    let back = read_matrix_market(&path).unwrap();
    assert_eq!((back.nrows(), back.ncols()), (4, 5));
    let (a, b) = (entries(&m), entries(&back));
    assert_eq!(a.len(), b.len());
    for (k, v) in &a {
        assert_eq!(b[k].to_bits(), v.to_bits(), "{k:?}");
    }
    // Overwriting an existing file works and stays atomic.
    write_matrix_market(&path, &from_triplets(1, 1, &[(0, 0, 2.0)]), true).unwrap();
    assert_eq!(entries(&read_matrix_market(&path).unwrap())[&(0, 0)], 2.0);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn symmetric_write_checks_symmetry() {
    let dir = tempfile::tempdir().unwrap();
    let m = from_triplets(3, 3, &[(0, 0, 1.0), (1, 0, 2.0), (0, 1, 2.5)]);
    match write_matrix_market(dir.path().join("a.mtx"), &m, true) {
        Err(MeshError::MatrixMarket { message, .. }) => assert!(message.contains("not symmetric"), "{message}"),
        other => panic!("{other:?}"),
    }
    let m = from_triplets(2, 3, &[(0, 0, 1.0)]);
    assert!(matches!(
        write_matrix_market(dir.path().join("b.mtx"), &m, true),
        Err(MeshError::MatrixMarket { .. })
    ));
    let m = from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, f64::NAN)]);
    match write_matrix_market(dir.path().join("nan.mtx"), &m, false) {
        Err(MeshError::MatrixMarket { message, .. }) => assert!(message.contains("(1, 1) is NaN"), "{message}"),
        other => panic!("{other:?}"),
    }
    // Nothing was left behind by the failed writes.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // Writing into a folder that does not exist is an I/O error naming the path.
    let e = write_matrix_market(
        dir.path().join("no/such/dir/c.mtx"),
        &from_triplets(1, 1, &[(0, 0, 1.0)]),
        false,
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::Io { .. }), "{e}");
}

fn read_str(text: &str) -> Result<SparseColMat<usize, f64>, MeshError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.mtx");
    std::fs::write(&path, text).unwrap();
    read_matrix_market(&path)
}

#[test]
fn other_fields_and_symmetries_are_read() {
    let m = read_str("%%MatrixMarket matrix coordinate pattern general\n% comment\n\n2 2 2\n1 2\n2 1\n").unwrap();
    assert_eq!(entries(&m), BTreeMap::from([((0, 1), 1.0), ((1, 0), 1.0)]));
    let m = read_str("%%MatrixMarket matrix coordinate integer symmetric\n3 3 3\n1 1 4\n3 1 -2\n3 3 7\n").unwrap();
    assert_eq!(
        entries(&m),
        BTreeMap::from([((0, 0), 4.0), ((2, 0), -2.0), ((0, 2), -2.0), ((2, 2), 7.0)])
    );
    let m = read_str("%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n2 1 1.5\n").unwrap();
    assert_eq!(entries(&m), BTreeMap::from([((1, 0), 1.5), ((0, 1), -1.5)]));
    // Duplicates are summed; the header is case-insensitive.
    let m = read_str("%%MatrixMarket MATRIX Coordinate Real General\n1 1 2\n1 1 1\n1 1 2\n").unwrap();
    assert_eq!(entries(&m), BTreeMap::from([((0, 0), 3.0)]));
}

#[test]
fn malformed_files_name_the_line() {
    let h = "%%MatrixMarket matrix coordinate real general\n";
    let cases: Vec<(String, usize, &str)> = vec![
        (format!("{h}2 2\n"), 2, "rows cols entries"),
        (format!("{h}2 x 1\n1 1 1\n"), 2, "bad size line"),
        (format!("{h}% c\n2 2 2\n1 1 1.0\n3 1 2.0\n"), 5, "row index 3"),
        (format!("{h}2 2 1\n1 0 1.0\n"), 3, "column index 0"),
        (format!("{h}2 2 1\n1 1 abc\n"), 3, "bad value"),
        (format!("{h}2 2 1\n1 1 NaN\n"), 3, "non-finite"),
        (format!("{h}2 2 1\n1 1\n"), 3, "missing value"),
        (format!("{h}2 2 1\n1 1 1 1\n"), 3, "too many fields"),
        (format!("{h}2 2 1\n1 1 1\n2 2 1\n"), 4, "more entries"),
        (
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 2 1.0\n".to_string(),
            3,
            "above the diagonal",
        ),
        (
            "%%MatrixMarket matrix coordinate real symmetric\n2 3 1\n1 1 1.0\n".to_string(),
            2,
            "square",
        ),
        ("%%NotMatrixMarket\n1 1 1\n1 1 1\n".to_string(), 1, "header"),
        // A corrupt size line must not make the reader allocate absurd amounts of memory.
        (format!("{h}10 1000000000000 1\n1 1 1\n"), 2, "refusing to allocate"),
    ];
    for (text, line, needle) in cases {
        match read_str(&text) {
            Err(MeshError::MatrixMarketLine { line: l, message, .. }) => {
                assert_eq!(l, line, "{text:?}: {message}");
                assert!(message.contains(needle), "{text:?}: {message}");
            }
            other => panic!("{text:?}: {other:?}"),
        }
    }
    for (text, needle) in [
        (format!("{h}2 2 3\n1 1 1\n"), "announces 3 entries"),
        (
            format!("{h}2 2 1000000000000000000\n1 1 1\n"),
            "announces 1000000000000000000 entries",
        ),
        (
            "%%MatrixMarket matrix array real general\n1 1\n1\n".to_string(),
            "coordinate",
        ),
        (
            "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n".to_string(),
            "complex",
        ),
        (String::new(), "empty"),
    ] {
        match read_str(&text) {
            Err(MeshError::MatrixMarket { message, .. }) => assert!(message.contains(needle), "{text:?}: {message}"),
            other => panic!("{text:?}: {other:?}"),
        }
    }
    let e = read_matrix_market("/nonexistent/file.mtx").unwrap_err();
    assert!(matches!(e, MeshError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/file.mtx"));
}

#[cfg(feature = "nalgebra")]
#[test]
fn nalgebra_conversions_round_trip_and_agree_on_products() {
    let ops = assemble(&icosphere(2), &AssemblyParams::default()).unwrap();
    let l = &ops.stiffness;
    let csc = to_nalgebra_csc(l);
    assert_eq!(
        (csc.nrows(), csc.ncols(), csc.nnz()),
        (l.nrows(), l.ncols(), entries(l).len())
    );
    let back = from_nalgebra_csc(&csc);
    assert_eq!(entries(&back), entries(l));
    // y = L x through CSR versus a product over the faer entries.
    let csr = to_nalgebra_csr(l);
    let n = l.nrows();
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut y_faer = vec![0.0; n];
    for (&(i, j), &v) in &entries(l) {
        y_faer[i] += v * x[j];
    }
    for (i, row) in csr.row_iter().enumerate() {
        let y: f64 = row
            .col_indices()
            .iter()
            .zip(row.values())
            .map(|(&j, &v)| v * x[j])
            .sum();
        assert!((y - y_faer[i]).abs() < 1e-12, "row {i}");
    }
    // A rectangular, unsorted-input matrix converts too.
    let m = from_triplets(3, 2, &[(2, 1, 1.0), (0, 1, 2.0), (1, 0, 3.0)]);
    assert_eq!(entries(&from_nalgebra_csc(&to_nalgebra_csc(&m))), entries(&m));
}

/// Entries of a Matrix Market file as read by nalgebra-sparse's own (independent) reader.
fn nalgebra_entries(path: &Path) -> BTreeMap<(usize, usize), f64> {
    let coo: nalgebra_sparse::CooMatrix<f64> = nalgebra_sparse::io::load_coo_from_matrix_market_file(path).unwrap();
    let mut out = BTreeMap::new();
    for (i, j, &v) in coo.triplet_iter() {
        *out.entry((i, j)).or_insert(0.0) += v;
    }
    out
}

#[test]
fn reader_and_writer_agree_with_nalgebra_sparse() {
    // Files written by mesh-fem read identically with nalgebra-sparse's reader.
    let dir = tempfile::tempdir().unwrap();
    let ops = assemble(&bumpy(1), &AssemblyParams::default()).unwrap();
    write_operators(dir.path(), &ops).unwrap();
    let general = dir.path().join("general.mtx");
    write_matrix_market(&general, &ops.stiffness, false).unwrap();
    for (file, m) in [
        ("stiffness.mtx", &ops.stiffness),
        ("mass.mtx", &ops.mass),
        ("general.mtx", &ops.stiffness),
    ] {
        assert_eq!(nalgebra_entries(&dir.path().join(file)), entries(m), "{file}");
    }
    // libigl's reference files read identically with both readers.
    if let Some(reference) = wfem_corpus::reference_dir() {
        for name in [
            "grid_70x70_stiffness.mtx",
            "ellipsoid_L4_mass.mtx",
            "irregular_sphere_L4_lumped_mass.mtx",
        ] {
            let path = reference.join(name);
            assert_eq!(
                entries(&read_matrix_market(&path).unwrap()),
                nalgebra_entries(&path),
                "{name}"
            );
        }
    }
}
