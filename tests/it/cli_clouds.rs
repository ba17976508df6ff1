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
    // The sidecar records the Laplacian used: a cloud's is the robust one.
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("k.json")).unwrap()).unwrap();
    assert_eq!(sidecar["input"]["laplacian"], "robust", "{sidecar}");
    assert_eq!(sidecar["input"]["point_cloud"], true, "{sidecar}");
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

/// Writes an (n, 3) float64 array as `.npy` (format 1.0).
fn write_npy(path: &std::path::Path, points: &[[f64; 3]]) {
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, 3), }}",
        points.len()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for p in points {
        for c in p {
            bytes.extend(c.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Writes points as `.xyz` text.
fn write_xyz(path: &std::path::Path, points: &[[f64; 3]]) {
    let mut text = String::new();
    for p in points {
        writeln!(text, "{:?} {:?} {:?}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(path, text).unwrap();
}

/// n points uniform on a mesh's surface (the workspace's seeded generator).
fn sample(mesh: &mesh_fem::TriMesh, n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = wfem_heat::rng::SplitMix64::new(seed);
    mesh_fem::cloud::sample_surface(mesh, n, &mut || rng.next_f64())
        .unwrap()
        .positions()
        .to_vec()
}

#[test]
fn retrieval_indexes_meshes_and_point_clouds_together() {
    use mesh_fem::generate::{bumpy, torus};
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (t, b) = (torus(1.0, 0.4, 48, 24), bumpy(3));
    mesh_fem::io::write_mesh(std::path::Path::new(&p("torus.obj")), &t).unwrap();
    mesh_fem::io::write_mesh(std::path::Path::new(&p("bumpy.off")), &b).unwrap();
    write_npy(std::path::Path::new(&p("torus-cloud.npy")), &sample(&t, 1500, 1));
    write_xyz(std::path::Path::new(&p("bumpy-cloud.xyz")), &sample(&b, 1500, 2));
    let index = p("index.sqlite");
    let files = ["torus.obj", "bumpy.off", "torus-cloud.npy", "bumpy-cloud.xyz"].map(p);
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--out", &index, "--words", "6", "--eigs", "30"]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("indexed 4 files, 2 of them point clouds"), "{out}");

    // A new cloud of the torus finds a torus first (its mesh or its cloud).
    let query = p("query.xyz");
    write_xyz(std::path::Path::new(&query), &sample(&t, 1500, 3));
    let o = wfem(&["retrieval", "query", &index, &query, "--top", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let first = out.lines().next().unwrap_or_default();
    assert!(first.contains("torus"), "{out}");

    // The index records the cotangent L: a query asking for another one is refused, naming
    // both; asking for the recorded one is the same as not asking.
    let o = wfem(&["retrieval", "query", &index, &files[0], "--laplacian", "robust"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--laplacian robust") && err.contains("cotan"), "{err}");
    let o = wfem(&[
        "retrieval",
        "query",
        &index,
        &files[0],
        "--laplacian",
        "cotan",
        "--top",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("torus.obj"));

    // Clouds are appended like meshes.
    let more = p("more-torus.csv");
    let text: String = sample(&t, 1200, 4)
        .iter()
        .map(|q| format!("{},{},{}\n", q[0], q[1], q[2]))
        .collect();
    std::fs::write(&more, format!("x,y,z\n{text}")).unwrap();
    let o = wfem(&["retrieval", "add", &index, &more]);
    assert!(o.status.success(), "{}", stderr(&o));

    // A robust index records its Laplacian and takes the same mix.
    let robust = p("robust.sqlite");
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(String::as_str));
    args.extend([
        "--out",
        &robust,
        "--words",
        "6",
        "--eigs",
        "30",
        "--laplacian",
        "robust",
    ]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = wfem(&["retrieval", "query", &robust, &files[0], "--top", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
}
