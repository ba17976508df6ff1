//! End-to-end test of `wfem distance` on a generated mesh in a temporary folder, checked
//! against the dense spectral formula.

use std::process::Command;

fn wfem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .output()
        .expect("the wfem binary runs")
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn distance_row_matches_the_dense_spectral_formula() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = dir.path().join("sphere.off");
    let mesh = mesh_fem::generate::icosphere(2);
    mesh_fem::io::write_mesh(&mesh_path, &mesh).unwrap();
    let before = std::fs::read(&mesh_path).unwrap();
    let m = mesh.n_vertices();
    let ops = mesh_fem::assemble(&mesh, &Default::default()).unwrap();
    let basis = wfem_heat::Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
    let (from, t) = (5usize, 0.02);
    for (kind, ext) in [("wfem", "csv"), ("linear", "npy"), ("wfem", "ply")] {
        let out = dir.path().join(format!("d-{kind}.{ext}"));
        let o = wfem(&[
            "distance",
            mesh_path.to_str().unwrap(),
            "--t",
            &t.to_string(),
            "--from",
            &from.to_string(),
            "--kind",
            kind,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{kind}: {}", stderr(&o));
        assert!(out.exists());
        if ext == "ply" {
            continue;
        }
        let d = mesh_fem::io::read_field(&out, m).unwrap();
        // Dense: wFEM Σ e^{−λt}((Bx)_i − (Bx)_j)², linear Σ e^{−2λt}(x_i − x_j)².
        let x = &basis.vectors;
        let bx = &ops.mass * x;
        let (w, s) = if kind == "wfem" { (&bx, 1.0) } else { (x, 2.0) };
        let exact: Vec<f64> = (0..m)
            .map(|j| {
                (0..m)
                    .map(|k| (-s * t * basis.values[k]).exp() * (w[(from, k)] - w[(j, k)]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let scale = exact.iter().fold(0.0f64, |a, &b| a.max(b));
        for j in 0..m {
            assert!(
                (d[j] - exact[j]).abs() < 1e-6 * scale,
                "{kind} j={j}: {} vs {}",
                d[j],
                exact[j]
            );
        }
        assert_eq!(d[from], 0.0);
    }
    assert_eq!(
        std::fs::read(&mesh_path).unwrap(),
        before,
        "the input mesh was modified"
    );
    // Bad input: a vertex out of range and a non-positive t are one-line errors.
    let out = dir.path().join("bad.csv");
    for args in [["--from", "100000", "--t", "0.1"], ["--from", "0", "--t", "-1"]] {
        let mut all = vec!["distance", mesh_path.to_str().unwrap()];
        all.extend_from_slice(&args);
        all.extend_from_slice(&["-o", out.to_str().unwrap()]);
        let o = wfem(&all);
        assert!(!o.status.success());
        assert!(stderr(&o).starts_with("wfem: error:"), "{}", stderr(&o));
    }
    assert!(!out.exists());
    // Never writes over the input.
    let o = wfem(&[
        "distance",
        mesh_path.to_str().unwrap(),
        "--t",
        "0.1",
        "--from",
        "0",
        "-o",
        mesh_path.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read(&mesh_path).unwrap(), before);
}
