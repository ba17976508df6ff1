//! The CLI on tetrahedral meshes (issue #39): `info`, `heat`, `geodesic`, `operators` read a
//! volume file; its operators are the tetrahedra's; bad flags for a volume are refused.

use crate::common::{read_npy, stderr, wfem};
use std::fmt::Write as _;

/// The generated unit cube of 6n³ tetrahedra as MEDIT text (1-based indices).
fn write_cube(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
    let cube = mesh_fem::generate::tet_cube(n);
    let mut text = String::from("MeshVersionFormatted 1\nDimension 3\nVertices\n");
    writeln!(text, "{}", cube.n_vertices()).unwrap();
    for p in cube.positions() {
        writeln!(text, "{} {} {} 0", p[0], p[1], p[2]).unwrap();
    }
    writeln!(text, "Tetrahedra\n{}", cube.n_tets()).unwrap();
    for t in cube.tets() {
        writeln!(text, "{} {} {} {} 0", t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1).unwrap();
    }
    text.push_str("End\n");
    let path = dir.join("cube.mesh");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn info_heat_and_geodesic_read_a_volume() {
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 6);
    let path = cube.to_str().unwrap();
    let n = 7 * 7 * 7;

    let o = wfem(&["info", path, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["n_tets"], 6 * 216);
    assert_eq!(info["n_vertices"], n);
    assert!((info["total_volume"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(info["boundary_euler"], 2);
    assert_eq!(info["n_boundary_components"], 1);
    assert_eq!(info["boundary_genus"], 0);
    assert!(info["worst_tet"].as_u64().unwrap() < 6 * 216);
    let o = wfem(&["info", path]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("boundary topology:    1 component, genus 0"), "{text}");
    assert!(text.contains("the worst: tetrahedron"), "{text}");

    // Heat from the centre: conserved (1ᵀB K_t e = 1ᵀB e), symmetric about the centre.
    let centre = n / 2;
    let heat = dir.path().join("u.npy");
    let o = wfem(&[
        "heat",
        path,
        "--source",
        &centre.to_string(),
        "--t",
        "0.01",
        "-o",
        heat.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (shape, u) = read_npy(&heat).unwrap();
    assert_eq!(shape[0], n);
    // 1ᵀB f = Σ D_ii f_i (D holds the row sums of B).
    let fem = mesh_fem::volume::assemble_volume(&mesh_fem::generate::tet_cube(6), &Default::default()).unwrap();
    let d = &fem.lumped_diagonal;
    let bu: f64 = u.iter().zip(d).map(|(x, m)| x * m).sum();
    assert!((bu - d[centre]).abs() < 1e-12 * d[centre], "{bu} vs {}", d[centre]);
    assert!(u.iter().all(|v| v.is_finite()));

    // Geodesics through the solid default to the heat method and are nearly Euclidean.
    let geo = dir.path().join("g.npy");
    let o = wfem(&[
        "geodesic",
        path,
        "--from",
        &centre.to_string(),
        "-o",
        geo.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, d) = read_npy(&geo).unwrap();
    let cube = mesh_fem::generate::tet_cube(6);
    let c = cube.positions()[centre];
    let mut err = 0.0;
    for (v, p) in cube.positions().iter().enumerate() {
        if v != centre {
            let exact = mesh_fem::vec3::norm(mesh_fem::vec3::sub(*p, c));
            err += (d[v] - exact).abs() / exact;
        }
    }
    assert!(
        err / (n - 1) as f64 > 0.0 && err / ((n - 1) as f64) < 0.08,
        "mean relative error {}",
        err / (n - 1) as f64
    );
}

#[test]
fn flags_for_surfaces_are_refused_on_a_volume() {
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 2);
    let path = cube.to_str().unwrap();
    let out = dir.path().join("x.npy");
    for (args, expected) in [
        (
            vec!["heat", path, "--t", "0.1", "--source", "0", "--laplacian", "robust"],
            "linear FEM",
        ),
        (
            vec!["heat", path, "--t", "0.1", "--source", "0", "--triangulate"],
            "--triangulate",
        ),
        (
            vec!["heat", path, "--t", "0.1", "--source", "0", "--repair", "weld"],
            "orient, degenerate and unreferenced",
        ),
        (
            vec!["geodesic", path, "--from", "0", "--method", "fast-marching"],
            "heat method",
        ),
    ] {
        let mut a = args.clone();
        a.extend(["-o", out.to_str().unwrap()]);
        let o = wfem(&a);
        assert!(!o.status.success(), "{args:?}");
        assert!(stderr(&o).contains(expected), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    }
    assert!(!out.exists());
}

#[test]
fn a_volume_figure_shows_a_cut_and_a_bad_plane_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 3);
    let path = cube.to_str().unwrap();
    let png = dir.path().join("h.png");
    let o = wfem(&[
        "heat",
        path,
        "--source",
        "0",
        "--t",
        "0.05",
        "--cut",
        "x=0.4",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("cut at x=0.4"), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    // PNG header: width and height (big endian) at bytes 16..24; the cut row makes it taller than wide / 2.
    let (w, h) = (
        u32::from_be_bytes(bytes[16..20].try_into().unwrap()),
        u32::from_be_bytes(bytes[20..24].try_into().unwrap()),
    );
    assert!(h * 3 > w, "{w} × {h}: no second row");
    for (plane, expected) in [
        ("w=1", "not a plane"),
        ("x=nan", "not a plane"),
        ("x=-5", "leaves nothing"),
    ] {
        let out = dir.path().join("bad.png");
        let o = wfem(&[
            "heat",
            path,
            "--source",
            "0",
            "--t",
            "0.05",
            "--cut",
            plane,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{plane}");
        assert!(stderr(&o).contains(expected), "{plane}: {}", stderr(&o));
        assert!(!out.exists());
    }
}

#[test]
fn a_time_that_overflows_in_its_unit_is_named_as_given() {
    // Issue #41: `--t 1e308 --time-unit area` was reported as "--t inf".
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 2);
    let out = dir.path().join("x.npy");
    let o = wfem(&[
        "heat",
        cube.to_str().unwrap(),
        "--source",
        "0",
        "--t",
        "1e308",
        "--time-unit",
        "area",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("--t 100000000") || e.contains("--t 1e308"), "{e}");
    assert!(e.contains("overflows") && !e.contains("inf"), "{e}");
}

#[test]
fn retrieval_says_a_volume_is_not_a_surface() {
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 2);
    let index = dir.path().join("i.sqlite");
    let o = wfem(&[
        "retrieval",
        "build",
        cube.to_str().unwrap(),
        "--out",
        index.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("is a tetrahedral mesh"), "{}", stderr(&o));
    assert!(!index.exists());
}

/// `wfem spectrum`: the Shape-DNA of a solid with the 3-D Weyl normalisation (issue #39), the
/// eigenvalues those of the library, and the same command on a surface with the 2-D one.
#[test]
fn spectrum_writes_the_shape_dna_of_a_solid_and_of_a_surface() {
    use shape_retrieval::global::{operators_signature, GlobalKind, Measure};
    use wfem_base::Choice;
    let dir = tempfile::tempdir().unwrap();
    let cube = write_cube(dir.path(), 4);
    let csv = dir.path().join("dna.csv");
    let o = wfem(&[
        "spectrum",
        cube.to_str().unwrap(),
        "-m",
        "8",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(format!("eigenvalue,{}", GlobalKind::WeylShapeDna.name()).as_str())
    );
    let rows: Vec<[f64; 2]> = lines
        .map(|l| {
            let (a, b) = l.split_once(',').unwrap();
            [a.parse().unwrap(), b.parse().unwrap()]
        })
        .collect();
    assert_eq!(rows.len(), 8);
    let fem = mesh_fem::volume::assemble_volume(&mesh_fem::generate::tet_cube(4), &Default::default()).unwrap();
    let ops = wfem_heat::Operators::new(&fem, mesh_fem::Mass::Consistent).unwrap();
    let sig = operators_signature(&ops, GlobalKind::WeylShapeDna, 8, Measure::Volume(1.0)).unwrap();
    for (i, row) in rows.iter().enumerate() {
        assert!((row[0] - sig.eigenvalues[i + 1]).abs() < 1e-9 * row[0], "λ_{}", i + 1);
        let weyl = (6.0 * std::f64::consts::PI.powi(2) * (i + 1) as f64).powf(2.0 / 3.0);
        assert!((row[1] - row[0] / weyl).abs() < 1e-9, "g_{}", i + 1);
    }
    // The sidecar of an .npy output names the measure; a histogram kind is written alone.
    let npy = dir.path().join("dna.npy");
    let o = wfem(&[
        "spectrum",
        cube.to_str().unwrap(),
        "--kind",
        GlobalKind::Biharmonic.name(),
        "-o",
        npy.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (shape, _) = read_npy(&npy).unwrap();
    assert_eq!(shape, vec![shape_retrieval::global::BIHARMONIC_BINS]);
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("dna.json")).unwrap()).unwrap();
    assert_eq!(meta["dimension"], 3);
    assert!((meta["volume"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    // A surface: λ_i A/(4π i) with A its area.
    let sphere = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&sphere, &mesh_fem::generate::icosphere(2)).unwrap();
    let out = dir.path().join("s.npy");
    let o = wfem(&[
        "spectrum",
        sphere.to_str().unwrap(),
        "-m",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (shape, v) = read_npy(&out).unwrap();
    assert_eq!(shape, vec![3, 2]);
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    let area = meta["area"].as_f64().unwrap();
    assert_eq!(meta["dimension"], 2);
    for i in 0..3 {
        let (lambda, g) = (v[2 * i], v[2 * i + 1]);
        // λ₁₋₃ of the unit sphere are 2 = l(l + 1), l = 1.
        assert!((lambda - 2.0).abs() < 0.05, "{lambda}");
        assert!((g - lambda * area / (4.0 * std::f64::consts::PI * (i + 1) as f64)).abs() < 1e-12);
    }
    // Bad requests: a format that holds a mesh, too many eigenvalues; nothing is written.
    let ply = dir.path().join("x.ply");
    let o = wfem(&["spectrum", cube.to_str().unwrap(), "-o", ply.to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains(".csv"), "{}", stderr(&o));
    let o = wfem(&[
        "spectrum",
        cube.to_str().unwrap(),
        "-m",
        "125",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("--eigenvalues"),
        "{}",
        stderr(&o)
    );
    assert!(!ply.exists());
}
