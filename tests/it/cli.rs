//! End-to-end tests of the `wfem` binary on generated meshes written to temporary folders.

use std::path::Path;
use std::process::Command;

fn wfem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .output()
        .expect("the wfem binary runs")
}

fn write_icosphere(dir: &Path, level: u32) -> std::path::PathBuf {
    let path = dir.join("sphere.off");
    mesh_fem::io::write_mesh(&path, &mesh_fem::generate::icosphere(level)).expect("write test mesh");
    path
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}
fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn every_subcommand_has_help() {
    for sub in ["info", "operators", "heat", "demo"] {
        let o = wfem(&[sub, "--help"]);
        assert!(o.status.success(), "{sub} --help failed: {}", stderr(&o));
        assert!(stdout(&o).contains("Usage"), "{sub} --help prints no usage");
    }
}

#[test]
fn info_reports_statistics_as_text_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 2);
    let o = wfem(&["info", mesh.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("vertices              162"), "{text}");
    assert!(text.contains("Euler characteristic  2"), "{text}");
    let o = wfem(&["info", mesh.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["stats"]["n_vertices"], 162);
    assert_eq!(v["stats"]["genus"], 0);
    assert_eq!(v["usable"], true);
}

#[test]
fn errors_print_one_line_and_exit_nonzero() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.off");
    let o = wfem(&["info", missing.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.starts_with("wfem: error:"), "{err}");

    let unknown = dir.path().join("mesh.abc");
    std::fs::write(&unknown, "1 2 3\n").unwrap();
    let o = wfem(&["info", unknown.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("unknown mesh format"), "{}", stderr(&o));
    // .xyz is a point cloud (issue #27); one point is too few.
    let cloud = dir.path().join("mesh.xyz");
    std::fs::write(&cloud, "1 2 3\n").unwrap();
    let o = wfem(&["info", cloud.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("at least 3"), "{}", stderr(&o));
}

#[test]
fn operators_writes_three_matrix_market_files_that_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 2);
    let out = dir.path().join("ops");
    let o = wfem(&["operators", mesh.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let l = mesh_fem::mtx::read_matrix_market(out.join("stiffness.mtx")).unwrap();
    let b = mesh_fem::mtx::read_matrix_market(out.join("mass.mtx")).unwrap();
    let d = mesh_fem::mtx::read_matrix_market(out.join("lumped_mass.mtx")).unwrap();
    let ops = mesh_fem::assemble(&mesh_fem::generate::icosphere(2), &Default::default()).unwrap();
    // Round trip is exact (17 significant digits), so compare entry by entry.
    for (read, ours) in [(&l, &ops.stiffness), (&b, &ops.mass)] {
        let a = read.to_dense();
        let c = ours.to_dense();
        assert_eq!(a.nrows(), 162);
        for j in 0..162 {
            for i in 0..162 {
                assert_eq!(a[(i, j)], c[(i, j)]);
            }
        }
    }
    assert_eq!(d.compute_nnz(), 162);
}

#[test]
fn heat_writes_every_format_and_never_touches_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 2);
    let before = std::fs::read(&mesh).unwrap();
    for ext in ["ply", "npy", "csv", "png"] {
        let out = dir.path().join(format!("k.{ext}"));
        let o = wfem(&[
            "heat",
            mesh.to_str().unwrap(),
            "--t",
            "0.1",
            "--source",
            "3",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        assert!(out.exists(), "{ext} not written");
    }
    // The CSV holds K_t e_3: mass-conserving, 1ᵀB K_t e_3 = 1ᵀB e_3.
    let g = mesh_fem::io::read_field(&dir.path().join("k.csv"), 162).unwrap();
    let ops = mesh_fem::assemble(&mesh_fem::generate::icosphere(2), &Default::default()).unwrap();
    let ones = faer::Mat::<f64>::from_fn(162, 1, |_, _| 1.0);
    let b1 = &ops.mass * &ones;
    let mass: f64 = (0..162).map(|i| b1[(i, 0)] * g[i]).sum();
    assert!(
        (mass - b1[(3, 0)]).abs() < 1e-12 * b1[(3, 0)],
        "mass {mass} vs {}",
        b1[(3, 0)]
    );
    assert_eq!(std::fs::read(&mesh).unwrap(), before, "the input mesh was modified");

    // Writing over the input is refused (an .off input is not even an output format; a .ply
    // input is, and is still refused).
    let o = wfem(&[
        "heat",
        mesh.to_str().unwrap(),
        "--t",
        "0.1",
        "--source",
        "0",
        "-o",
        mesh.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("output format is chosen by the extension"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read(&mesh).unwrap(), before);
    let ply = dir.path().join("sphere.ply");
    mesh_fem::io::write_mesh(&ply, &mesh_fem::generate::icosphere(2)).unwrap();
    let ply_before = std::fs::read(&ply).unwrap();
    let o = wfem(&[
        "heat",
        ply.to_str().unwrap(),
        "--t",
        "0.1",
        "--source",
        "0",
        "-o",
        ply.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("never writes over its input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&ply).unwrap(), ply_before);
}

#[test]
fn heat_with_several_times_and_a_field_file() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 2);
    let field = dir.path().join("f.csv");
    let m = mesh_fem::generate::icosphere(2);
    let values: String = m.positions().iter().map(|p| format!("{}\n", p[0])).collect();
    std::fs::write(&field, values).unwrap();
    let out = dir.path().join("k.npy");
    let o = wfem(&[
        "heat",
        mesh.to_str().unwrap(),
        "--t",
        "0.01",
        "0.1",
        "1",
        "--field",
        field.to_str().unwrap(),
        "--method",
        "dense",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    // 3 columns × 162 rows of f64 after the header.
    assert!(bytes.len() > 3 * 162 * 8);
    // Bad inputs: a non-finite t and a wrong source index are typed errors.
    let o = wfem(&[
        "heat",
        mesh.to_str().unwrap(),
        "--t",
        "-1",
        "--source",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--t -1 is out of range"), "{}", stderr(&o));
    let o = wfem(&[
        "heat",
        mesh.to_str().unwrap(),
        "--t",
        "1",
        "--source",
        "999",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("999"), "{}", stderr(&o));
}

#[test]
fn demo_writes_ply_png_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = wfem(&[
        "demo",
        "--out",
        out.to_str().unwrap(),
        "--level",
        "2",
        "--eigenpairs",
        "40",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("basis.ply").exists());
    assert!(out.join("report.md").exists());
    let pngs = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "png"))
        .count();
    // Four K_t e_i figures, then f, f_glob, f_loc and f_glob at four persistences (Fig. 12–13),
    // then the volume's two (boundary above, cut below).
    assert_eq!(pngs, 4 + 7 + 2);
    let vtu = std::fs::read_to_string(out.join("volume.vtu")).unwrap();
    assert!(
        vtu.contains("NumberOfPoints=\"5137\" NumberOfCells=\"28160\""),
        "{}",
        &vtu[..300]
    );
    assert!(vtu.contains("Name=\"heat_t0.05\""));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| 0.25 |"), "{report}");
    assert!(report.contains("## Feature-driven approximation"), "{report}");
    assert!(
        report.contains("![f_glob](approx_glob.png)") && report.contains("| 40 % |"),
        "{report}"
    );
    // The volume's heat is conserved to rounding (the last column of its table).
    let volume = &report[report.find("## A volume").expect("a volume section")..];
    let lost: Vec<f64> = volume
        .lines()
        .filter(|l| l.starts_with("| 0."))
        .map(|l| l.trim_end_matches(" |").rsplit("| ").next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(lost.len(), 2, "{volume}");
    assert!(lost.iter().all(|&x| x < 1e-12), "{volume}");
}

/// `--backend` selects how the rational method solves its shifted systems; every backend gives
/// the same K_t e_i (to the accuracy of the iterative ones).
#[test]
fn heat_backends_agree() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 3);
    let run = |backend: &str| -> Vec<f64> {
        let out = dir.path().join(format!("k_{backend}.csv"));
        let o = wfem(&[
            "heat",
            mesh.to_str().unwrap(),
            "--t",
            "0.05",
            "--source",
            "7",
            "--backend",
            backend,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{backend}: {}", stderr(&o));
        std::fs::read_to_string(&out)
            .unwrap()
            .lines()
            .filter_map(|l| l.split(',').next_back()?.trim().parse::<f64>().ok())
            .collect()
    };
    let reference = run("ldlt");
    assert_eq!(reference.len(), 642);
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for backend in ["lu", "minres", "multishift"] {
        let g = run(backend);
        assert_eq!(g.len(), reference.len(), "{backend}");
        let err = g.iter().zip(&reference).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale;
        assert!(err < 1e-10, "{backend}: {err:e}");
    }
    let o = wfem(&[
        "heat",
        mesh.to_str().unwrap(),
        "--t",
        "1",
        "--source",
        "0",
        "--backend",
        "cg",
        "-o",
        "x.csv",
    ]);
    assert!(!o.status.success());
}

/// Issue #37, point 4: a renamed flag's old spelling still works for one release, with a
/// warning that names the new one; the new spelling gives no warning.
#[test]
fn old_spellings_work_and_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_icosphere(dir.path(), 2);
    let out = dir.path().join("h.npy");
    let (mesh, out) = (mesh.to_str().unwrap(), out.to_str().unwrap());
    let old = wfem(&[
        "hks", mesh, "--eigs", "20", "--scales", "4", "--method", "spectral", "-o", out,
    ]);
    assert!(old.status.success(), "{}", stderr(&old));
    let err = stderr(&old);
    assert!(err.contains("--eigs is the old spelling of --eigenpairs"), "{err}");
    assert!(err.contains("--scales is the old spelling of --num-times"), "{err}");
    let new = wfem(&[
        "hks",
        mesh,
        "--eigenpairs",
        "20",
        "--num-times",
        "4",
        "--method",
        "spectral",
        "-o",
        out,
    ]);
    assert!(new.status.success(), "{}", stderr(&new));
    assert!(!stderr(&new).contains("old spelling"), "{}", stderr(&new));
    // A visible alias (`--out` of `-o`) is not an old spelling.
    let visible = wfem(&["hks", mesh, "--eigenpairs", "20", "--times", "0.1", "--out", out]);
    assert!(!stderr(&visible).contains("old spelling"), "{}", stderr(&visible));
}
