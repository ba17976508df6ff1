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
    let basis = wfem_heat::spectral::Eigenbasis::dense(&ops.stiffness, &ops.mass).unwrap();
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

/// Issue #25: a time past the time at infinity (the bunny's case: area 0.057, `--t 0.1`)
/// gives a warning naming the sensible range instead of a silent blank result; the same time
/// in units of the area (`--time-unit area`) is t = τ·A and is recorded in the sidecar.
#[test]
fn meaningless_times_are_warned_and_units_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = dir.path().join("small.off");
    let mesh = mesh_fem::generate::icosphere(3).with_area(0.057).unwrap();
    mesh_fem::io::write_mesh(&mesh_path, &mesh).unwrap();
    let m = mesh_path.to_str().unwrap();
    let out = dir.path().join("d.npy");
    let o = wfem(&["distance", m, "--t", "0.1", "--from", "0", "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning: --t: t = 0.1 is past the time at infinity"),
        "{err}"
    );
    assert!(err.contains("sensible times for this mesh are about"), "{err}");
    // The result is indeed blank.
    let d = mesh_fem::io::read_field(&out, mesh.n_vertices()).unwrap();
    assert!(
        d.iter().all(|&x| x < 1e-6),
        "{:?}",
        d.iter().fold(0.0f64, |a, &b| a.max(b))
    );
    // A sensible time: no warning.
    let o = wfem(&["distance", m, "--t", "1e-3", "--from", "0", "-o", out.to_str().unwrap()]);
    assert!(o.status.success() && !stderr(&o).contains("warning"), "{}", stderr(&o));
    // In area units: τ = 1e-3/A gives the same distances, and the sidecar says so.
    let area = mesh.area();
    let tau = 1e-3 / area;
    let out2 = dir.path().join("d2.npy");
    let o = wfem(&[
        "distance",
        m,
        "--t",
        &tau.to_string(),
        "--time-unit",
        "area",
        "--from",
        "0",
        "-o",
        out2.to_str().unwrap(),
    ]);
    assert!(o.status.success() && !stderr(&o).contains("warning"), "{}", stderr(&o));
    let (a, b) = (
        mesh_fem::io::read_field(&out, mesh.n_vertices()).unwrap(),
        mesh_fem::io::read_field(&out2, mesh.n_vertices()).unwrap(),
    );
    let scale = a.iter().fold(0.0f64, |m, &x| m.max(x));
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-9 * scale));
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("d2.json")).unwrap()).unwrap();
    assert_eq!(sidecar["time_unit"]["name"], "area");
    assert!((sidecar["time_unit"]["value"].as_f64().unwrap() - area).abs() <= 1e-12 * area);
    assert!((sidecar["times"][0].as_f64().unwrap() - 1e-3).abs() <= 1e-15);
    // Too small: the result equals the input.
    let o = wfem(&[
        "distance",
        m,
        "--t",
        "1e-20",
        "--from",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("is too small for this mesh"), "{}", stderr(&o));
}
