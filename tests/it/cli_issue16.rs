//! Issue #16, the CLI path a new user meets: repairs from the command line, progress,
//! inaccurate methods, figure orientation and the metadata of outputs. (The hostile values of
//! every argument are in hostile.rs.)

use super::common::{read_npy, stderr, wfem};
use std::path::{Path, PathBuf};
use std::process::Command;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn csv_column(path: &Path) -> Vec<f64> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.parse().unwrap())
        .collect()
}

/// The sphere of level 1 with an unreferenced vertex inserted first: file vertex i + 1 is
/// sphere vertex i.
fn unreferenced_first(dir: &Path) -> (PathBuf, PathBuf) {
    let sphere = mesh_fem::generate::icosphere(1);
    let plain = dir.join("sphere.off");
    mesh_fem::io::write_mesh(&plain, &sphere).unwrap();
    let mut obj = String::from("v 5 5 5\n");
    for p in sphere.positions() {
        obj += &format!("v {:?} {:?} {:?}\n", p[0], p[1], p[2]);
    }
    for f in sphere.faces() {
        obj += &format!("f {} {} {}\n", f[0] + 2, f[1] + 2, f[2] + 2);
    }
    let unref = dir.join("unref.obj");
    std::fs::write(&unref, obj).unwrap();
    (plain, unref)
}

#[test]
fn issue_16_repair_from_the_cli_reports_and_keeps_the_file_numbering_of_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, unref) = unreferenced_first(dir.path());
    // Refused without --repair, with the flag named.
    let out = dir.path().join("k.csv");
    let o = wfem(&["heat", s(&unref), "--t", "0.1", "--source", "8", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("vertex 0 belongs to no face") && stderr(&o).contains("--repair unreferenced"),
        "{}",
        stderr(&o)
    );
    assert!(!stderr(&o).contains("the repair option"), "{}", stderr(&o));
    // With it: the repair and the renumbering are reported, --source 8 of the file is vertex 7
    // of the repaired mesh, and the result equals K_t e_7 on the clean sphere.
    let o = wfem(&[
        "heat",
        s(&unref),
        "--repair",
        "unreferenced",
        "--t",
        "0.1",
        "--source",
        "8",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("--repair unreferenced: dropped 1 unreferenced vertex"),
        "{err}"
    );
    assert!(err.contains("43 → 42 vertices"), "{err}");
    assert!(err.contains("warning: the vertex numbering changed"), "{err}");
    assert!(err.contains("vertex 8 of the file is vertex 7"), "{err}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("repaired mesh"));
    let repaired = csv_column(&out);
    let reference = dir.path().join("r.csv");
    let o = wfem(&["heat", s(&plain), "--t", "0.1", "--source", "7", "-o", s(&reference)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(repaired, csv_column(&reference));
    // A field with one value per vertex of the file is restricted to the kept vertices.
    let x: Vec<f64> = mesh_fem::generate::icosphere(1)
        .positions()
        .iter()
        .map(|p| p[0])
        .collect();
    let file_field = dir.path().join("file.csv");
    let text: String = std::iter::once(123.0)
        .chain(x.iter().copied())
        .map(|v| format!("{v:?}\n"))
        .collect();
    std::fs::write(&file_field, text).unwrap();
    let mesh_field = dir.path().join("mesh.csv");
    std::fs::write(&mesh_field, x.iter().map(|v| format!("{v:?}\n")).collect::<String>()).unwrap();
    let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    for (field, out) in [(&file_field, &a), (&mesh_field, &b)] {
        let o = wfem(&[
            "heat",
            s(&unref),
            "--repair",
            "all",
            "--t",
            "0.1",
            "--field",
            s(field),
            "-o",
            s(out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(csv_column(&a), csv_column(&b));
}

#[test]
fn issue_16_polygons_name_the_triangulate_flag() {
    let dir = tempfile::tempdir().unwrap();
    let quad = dir.path().join("quad.obj");
    std::fs::write(&quad, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let o = wfem(&["info", s(&quad)]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("pass --triangulate") && !err.contains("LoadOptions"),
        "{err}"
    );
}

#[test]
fn issue_16_the_original_stanford_bunny_works_with_repair_unreferenced() {
    let Ok(bunny) = wfem_corpus::mesh_path("common-3d-test-models/stanford-bunny.obj") else {
        eprintln!("skipped: the mesh corpus is not available");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.npy");
    let o = wfem(&[
        "heat",
        s(&bunny),
        "--t",
        "1e-4",
        "--source",
        "0",
        "--method",
        "fast",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--repair unreferenced"), "{}", stderr(&o));
    let o = wfem(&[
        "heat",
        s(&bunny),
        "--repair",
        "unreferenced",
        "--t",
        "1e-4",
        "--source",
        "0",
        "--method",
        "fast",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("dropped 1113 unreferenced vertices"),
        "{}",
        stderr(&o)
    );
    let meta: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("b.json")).unwrap()).unwrap();
    assert_eq!(meta["shape"], serde_json::json!([34834]));
    assert_eq!(meta["input"]["repair"]["file_vertices"], 35947);
    assert_eq!(
        meta["input"]["repair"]["file_vertex_of_row"].as_array().map(Vec::len),
        Some(34834)
    );
}

#[test]
fn issue_16_no_progress_off_a_terminal_unless_asked() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&mesh, &mesh_fem::generate::icosphere(2)).unwrap();
    let out = dir.path().join("k.npy");
    let args = ["heat", s(&mesh), "--t", "0.1", "0.2", "--source", "3", "-o", s(&out)];
    let o = wfem(&args);
    assert!(o.status.success());
    assert_eq!(stderr(&o), "", "progress written to a pipe");
    let mut always = vec!["--progress", "always"];
    always.extend(args);
    let o = wfem(&always);
    let err = stderr(&o);
    for step in [
        "reading s.off … done",
        "assembling L, B, D … done",
        "symbolic analysis … done",
        "K_t: t = 0.1 [",
        "K_t: t = 0.2 [",
        "writing",
    ] {
        assert!(err.contains(step), "{step:?} missing from:\n{err}");
    }
}

/// On a terminal the steps are drawn as indicatif spinners and a bar over the times (run
/// under `script`, which gives the child a pseudo-terminal; skipped where it is missing).
#[cfg(unix)]
#[test]
fn issue_16_progress_bars_on_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&mesh, &mesh_fem::generate::icosphere(2)).unwrap();
    let out = dir.path().join("k.npy");
    let cmd = format!(
        "{} heat {} --t 0.1 0.2 --source 3 -o {}",
        env!("CARGO_BIN_EXE_wfem"),
        s(&mesh),
        s(&out)
    );
    let Ok(o) = Command::new("script").args(["-qec", &cmd, "/dev/null"]).output() else {
        eprintln!("skipped: `script` is not available");
        return;
    };
    if !o.status.success() {
        eprintln!("skipped: `script` failed: {}", stderr(&o));
        return;
    }
    let tty = String::from_utf8_lossy(&o.stdout);
    for part in ["assembling L, B, D [00:00:0", "K_t: t = 0.1 [", "/2 [", "wrote"] {
        assert!(tty.contains(part), "{part:?} not drawn:\n{tty}");
    }
}

#[test]
fn issue_16_approximate_methods_report_their_error_and_need_allow_inaccurate() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&mesh, &mesh_fem::generate::icosphere(2)).unwrap();
    let out = dir.path().join("k.npy");
    let run = |method: &str, t: &str, allow: bool| {
        let mut args = vec![
            "heat",
            s(&mesh),
            "--t",
            t,
            "--source",
            "3",
            "--method",
            method,
            "-o",
            s(&out),
        ];
        if allow {
            args.push("--allow-inaccurate");
        }
        wfem(&args)
    };
    for method in ["taylor", "backward-euler"] {
        let o = run(method, "0.1", false);
        assert_eq!(o.status.code(), Some(1), "{method}");
        let err = stderr(&o);
        assert!(err.contains(&format!("--method {method} is off by")), "{err}");
        // The estimate is the real distance to the exact answer (dense, small mesh).
        let o = run(method, "0.1", true);
        assert!(o.status.success(), "{}", stderr(&o));
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("k.json")).unwrap()).unwrap();
        let estimate = meta["estimated_relative_error"][0].as_f64().unwrap();
        assert!(estimate > 1e-2, "{method}: {estimate}");
        let approx = read_npy(&out).unwrap().1;
        let exact_path = dir.path().join("exact.npy");
        let o = wfem(&[
            "heat",
            s(&mesh),
            "--t",
            "0.1",
            "--source",
            "3",
            "--method",
            "dense",
            "-o",
            s(&exact_path),
        ]);
        assert!(o.status.success());
        let exact = read_npy(&exact_path).unwrap().1;
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = approx.iter().zip(&exact).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale;
        assert!(
            (err - estimate).abs() < 1e-6 * err,
            "{method}: estimate {estimate} vs {err}"
        );
    }
    // At a tiny t the first-order methods are accurate: accepted, with the estimate printed.
    let o = run("taylor", "1e-9", false);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("estimated relative error"), "{}", stderr(&o));
}

#[test]
fn issue_16_spectral_with_too_many_eigenpairs_points_to_an_exact_method() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&mesh, &mesh_fem::generate::icosphere(4)).unwrap(); // 2562 vertices
    let out = dir.path().join("k.npy");
    let o = wfem(&[
        "heat",
        s(&mesh),
        "--t",
        "0.1",
        "--source",
        "3",
        "--method",
        "spectral",
        "--eigenpairs",
        "2562",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("--eigenpairs 2562") && err.contains("1..=256") && err.contains("--method dense"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn issue_16_npy_outputs_carry_their_metadata_and_figures_have_short_names() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("s.off");
    mesh_fem::io::write_mesh(&mesh, &mesh_fem::generate::icosphere(2)).unwrap();
    let out = dir.path().join("k.npy");
    let t2 = format!("{:?}", 0.1 * 0.1 + 0.0); // 0.010000000000000002
    let o = wfem(&[
        "heat",
        s(&mesh),
        "--t",
        &t2,
        "0.5",
        "--source",
        "3",
        "--kernel",
        "lumped",
        "--method",
        "fast",
        "-o",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.path().join("k.json")).unwrap()).unwrap();
    assert_eq!(meta["times"], serde_json::json!([0.010000000000000002, 0.5]));
    assert_eq!(meta["columns"], serde_json::json!(["t=0.01", "t=0.5"]));
    assert_eq!(meta["shape"], serde_json::json!([162, 2]));
    assert_eq!(meta["mass"], "barycentric");
    assert_eq!(meta["method"]["name"], "fast");
    assert_eq!(meta["source_vertex"], 3);
    assert_eq!(meta["command"], "heat");
    let png = dir.path().join("k.png");
    let o = wfem(&["heat", s(&mesh), "--t", &t2, "0.5", "--source", "3", "-o", s(&png)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.path().join("k-t0.01.png").is_file() && dir.path().join("k-t0.5.png").is_file());
}

/// The TOSCA cat is z-up: `--up auto` (the default) says so and `--up` overrides it.
#[test]
fn issue_16_figures_of_the_tosca_cat_are_upright() {
    let Ok(cat) = wfem_corpus::mesh_path("tosca-bcicp-5k/TOSCA_Isometric/cat0.off") else {
        eprintln!("skipped: the mesh corpus is not available");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("cat.png");
    let args = [
        "heat",
        s(&cat),
        "--t",
        "50",
        "--source",
        "0",
        "--method",
        "fast",
        "-o",
        s(&png),
    ];
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("up is +z"), "{}", stderr(&o));
    let o = wfem(&[&args[..], &["--up", "y"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("up is"), "{}", stderr(&o));
    for (rel, up) in [
        ("common-3d-test-models/stanford-bunny.obj", "+y"),
        ("common-3d-test-models/spot.obj", "+y"),
        ("common-3d-test-models/horse.ply", "+z"),
        ("tosca-bcicp-5k/TOSCA_Isometric/david0.off", "+z"),
    ] {
        let Ok(path) = wfem_corpus::mesh_path(rel) else {
            continue;
        };
        let o = wfem(&[
            "heat",
            s(&path),
            "--repair",
            "unreferenced",
            "--t",
            "1",
            "--source",
            "0",
            "--method",
            "fast",
            "-o",
            s(&png),
        ]);
        assert!(o.status.success(), "{rel}: {}", stderr(&o));
        assert!(stderr(&o).contains(&format!("up is {up}")), "{rel}: {}", stderr(&o));
    }
}
