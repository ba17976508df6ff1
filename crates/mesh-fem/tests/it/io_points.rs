//! Point-cloud readers (`mesh_fem::io::load_points`, `load_shape`): every format from a file
//! written here by hand, the errors naming their line, and the mesh/cloud decision.

use mesh_fem::io::{load_points, load_shape, LoadOptions, Shape};
use mesh_fem::MeshError;
use std::path::PathBuf;

fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A version-1.0 NPY file of `values` with the given shape and dtype descriptor.
fn npy(descr: &str, shape: &str, fortran: bool, data: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

const POINTS: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.5], [0.0, 1.0, -2.0], [1.5, 1.25, 3.0]];

#[test]
fn every_point_format_reads_the_same_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let text: String = POINTS.iter().map(|p| format!("{} {} {}\n", p[0], p[1], p[2])).collect();
    let csv: String = POINTS.iter().map(|p| format!("{},{},{}\n", p[0], p[1], p[2])).collect();
    let le: Vec<u8> = POINTS.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let f32_be: Vec<u8> = POINTS
        .iter()
        .flatten()
        .flat_map(|&c| (c as f32).to_be_bytes())
        .collect();
    // Fortran order: the columns one after the other.
    let fortran: Vec<u8> = (0..3)
        .flat_map(|a| POINTS.iter().map(move |p| p[a]))
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let ply = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n{text}"
    );
    let files = [
        write(&dir, "a.xyz", format!("# comment\n{text}\n").as_bytes()),
        write(
            &dir,
            "b.pts",
            format!(
                "4\r\n{}",
                POINTS
                    .iter()
                    .map(|p| format!("{} {} {} 17 255 0 0\r\n", p[0], p[1], p[2]))
                    .collect::<String>()
            )
            .as_bytes(),
        ),
        write(&dir, "c.csv", format!("\u{feff}x,y,z\n{csv}").as_bytes()),
        write(&dir, "d.npy", &npy("<f8", "(4, 3)", false, &le)),
        write(&dir, "e.npy", &npy(">f4", "(4, 3)", false, &f32_be)),
        write(&dir, "f.npy", &npy("<f8", "(4, 3)", true, &fortran)),
        write(&dir, "g.ply", ply.as_bytes()),
    ];
    for path in &files {
        let cloud = load_points(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
        assert_eq!(cloud.positions(), &POINTS[..], "{path:?}");
        assert!(cloud.normals().is_none(), "{path:?}");
        assert!(matches!(load_shape(path, &LoadOptions::default()), Ok(Shape::Cloud(_))));
    }
}

#[test]
fn normals_are_read_from_six_columns_and_ply_nx_ny_nz() {
    let dir = tempfile::tempdir().unwrap();
    let rows: String = POINTS
        .iter()
        .map(|p| format!("{} {} {} 0 0 1\n", p[0], p[1], p[2]))
        .collect();
    let csv = rows.replace(' ', ",");
    let six: Vec<u8> = POINTS
        .iter()
        .flat_map(|p| [p[0], p[1], p[2], 0.0, 0.0, 1.0])
        .flat_map(|c| c.to_le_bytes())
        .collect();
    let ply = format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nproperty double nx\nproperty double ny\nproperty double nz\nend_header\n{rows}"
    );
    for path in [
        write(&dir, "a.xyz", rows.as_bytes()),
        write(&dir, "b.csv", csv.as_bytes()),
        write(&dir, "c.npy", &npy("<f8", "(4, 6)", false, &six)),
        write(&dir, "d.ply", ply.as_bytes()),
    ] {
        let cloud = load_points(&path).unwrap();
        assert_eq!(cloud.positions(), &POINTS[..]);
        assert_eq!(cloud.normals().unwrap(), &[[0.0, 0.0, 1.0]; 4][..], "{path:?}");
    }
    // A .pts file never reads colors as normals.
    let pts = write(&dir, "e.pts", rows.as_bytes());
    assert!(load_points(&pts).unwrap().normals().is_none());
}

#[test]
fn a_ply_with_faces_is_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let path = write(&dir, "m.ply", ply.as_bytes());
    assert!(matches!(load_shape(&path, &LoadOptions::default()), Ok(Shape::Mesh(m, _)) if m.n_faces() == 1));
    assert!(matches!(load_points(&path), Err(MeshError::Parse { .. })));
    let obj = write(&dir, "m.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(matches!(load_shape(&obj, &LoadOptions::default()), Ok(Shape::Mesh(..))));
}

#[test]
fn bad_point_files_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8]); 6] = [
        ("a.xyz", b"0 0 0\n1 0 0\n0 one 0\n"),
        ("b.xyz", b"0 0 0\n1 0 0 0 0 1\n0 1 0\n"),
        ("c.csv", b"0,0,0\n1,0\n0,1,0\n"),
        ("d.xyz", b"0 0 0\n1 0\n0 1 0\n"),
        ("e.npy", b"\x93NUMPY\x01\x00"),
        ("f.xyz", b"0 0 0 0\n"),
    ];
    for (name, bytes) in cases {
        let err = load_points(&write(&dir, name, bytes)).unwrap_err();
        assert!(matches!(err, MeshError::Parse { .. }), "{name}: {err}");
    }
    let err = load_points(&write(&dir, "g.xyz", b"0 0 0\n1 0 0\n0 1 0\n\n0 nan 0\n")).unwrap_err();
    assert!(matches!(err, MeshError::NonFinitePoint { point: 3, .. }), "{err}");
    let err = load_points(&write(&dir, "h.xyz", b"0 0 0\n1 0 0\n")).unwrap_err();
    assert!(matches!(err, MeshError::TooFewPoints { n_points: 2, .. }), "{err}");
    let two: Vec<u8> = [0.0f64; 8].iter().flat_map(|c| c.to_le_bytes()).collect();
    let err = load_points(&write(&dir, "i.npy", &npy("<f8", "(4, 2)", false, &two))).unwrap_err();
    assert!(err.to_string().contains("(n, 3)"), "{err}");
    let err = load_points(&write(&dir, "j.txt", b"0 0 0\n")).unwrap_err();
    assert!(matches!(err, MeshError::UnknownFormat { .. }), "{err}");
    // The line of the bad row is named.
    let err = load_points(&write(&dir, "k.xyz", b"0 0 0\n1 0 0\n0 one 0\n")).unwrap_err();
    assert!(matches!(err, MeshError::Parse { line: 3, .. }), "{err}");
}
