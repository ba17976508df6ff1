//! The CLI on point clouds and with `--laplacian` (issue #27).

use crate::common::{read_npy, stderr, wfem};
use std::fmt::Write as _;

/// A point cloud on the unit sphere (a Fibonacci lattice), as `.xyz` text.
fn write_cloud(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
    let mut text = String::new();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        writeln!(text, "{} {} {}", r * phi.cos(), r * phi.sin(), z).unwrap();
    }
    let path = dir.join("cloud.xyz");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn heat_and_operators_read_a_point_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = write_cloud(dir.path(), 800);
    let out = dir.path().join("k.npy");
    let o = wfem(&[
        "heat",
        cloud.to_str().unwrap(),
        "--t",
        "0.05",
        "--source",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("point cloud of 800 points"), "{}", stderr(&o));
    let (shape, values) = read_npy(&out).unwrap();
    assert_eq!(shape[0], 800);
    assert!(values.iter().all(|v| v.is_finite()));
    let ops = dir.path().join("ops");
    let o = wfem(&["operators", cloud.to_str().unwrap(), "--out", ops.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(ops.join("mass.mtx").exists());
}

#[test]
fn laplacian_flag_takes_the_library_names_and_non_manifold_meshes_are_warned() {
    let dir = tempfile::tempdir().unwrap();
    // Three triangles on one edge: a non-manifold mesh.
    let mesh = dir.path().join("fins.obj");
    std::fs::write(
        &mesh,
        "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0.2\nv 0.5 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let out = dir.path().join("k.npy");
    let args = |lap: Option<&str>| {
        let mut a = vec![
            "heat",
            mesh.to_str().unwrap(),
            "--t",
            "0.01",
            "--source",
            "0",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(l) = lap {
            a.extend(["--laplacian", l]);
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |lap: Option<&str>| {
        let a = args(lap);
        wfem(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let o = run(None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--laplacian robust"), "{}", stderr(&o));
    for name in <mesh_fem::Laplacian as wfem_choice::Choice>::names() {
        let o = run(Some(name));
        assert!(o.status.success(), "{name}: {}", stderr(&o));
    }
    let o = run(Some("intrinsic"));
    assert!(!o.status.success());
    assert!(stderr(&o).contains("robust"), "{}", stderr(&o));
}
