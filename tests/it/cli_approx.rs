//! End-to-end tests of `wfem approx` (feature-driven approximation, paper Sect. 4.2).

use std::path::Path;
use std::process::Command;
use wfem_base::Choice;

fn wfem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .output()
        .expect("the wfem binary runs")
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}
fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A level-3 icosphere and a noisy smooth field on it, written as OFF and CSV.
fn setup(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf, Vec<f64>) {
    let mesh = mesh_fem::generate::icosphere(3);
    let path = dir.join("sphere.off");
    mesh_fem::io::write_mesh(&path, &mesh).expect("write test mesh");
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let f: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|p| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            p[0] + 0.5 * p[1] * p[2] + 0.3 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        })
        .collect();
    let field = dir.join("f.csv");
    let text: String = f.iter().map(|v| format!("{v:.17e}\n")).collect();
    std::fs::write(&field, text).unwrap();
    (path, field, f)
}

#[test]
fn approx_has_help() {
    let o = wfem(&["approx", "--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("--persistence"));
}

/// The CSV output holds f, then f_glob and f_loc for every scale, with f_glob + f_loc = f,
/// and the report lists one row per scale with the L∞ error of that row's f_loc. The field is
/// noisy (about 3.5 % of its range): the default adds the GCV scale t* to the four asked for,
/// marks it and reports the noise estimate; `--noise keep` gives the four scales alone.
#[test]
fn approx_writes_components_and_prints_the_report() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, field, f) = setup(dir.path());
    let out = dir.path().join("approx.csv");
    for (rule, n_scales) in [(None, 5), (Some("keep"), 4)] {
        let mut args = vec![
            "approx",
            mesh.to_str().unwrap(),
            "--field",
            field.to_str().unwrap(),
            "--persistence",
            "0.25",
            "--scales",
            "4",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(rule) = rule {
            args.extend(["--noise", rule]);
        }
        let o = wfem(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = stdout(&o);
        assert!(text.contains("642 vertices"), "{text}");
        assert!(text.contains("Linf error"), "{text}");
        let rows: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.trim_end_matches(" *"))
            .filter(|l| l.split_whitespace().count() == 6 && l.split_whitespace().all(|w| w.parse::<f64>().is_ok()))
            .map(|l| l.split_whitespace().map(String::from).collect())
            .collect();
        assert_eq!(rows.len(), n_scales, "{text}");
        let marked: Vec<&str> = text.lines().filter(|l| l.ends_with(" *")).collect();
        match rule {
            None => {
                assert_eq!(marked.len(), 1, "{text}");
                assert!(
                    text.contains("noise: σ̂ = ") && text.contains("GCV scale t* = "),
                    "{text}"
                );
            }
            Some(_) => {
                assert!(marked.is_empty(), "{text}");
                assert!(text.contains("noise: not estimated (--noise keep)"), "{text}");
            }
        }
        // The CSV has one column per field: f, f_glob_t<t> (one per scale), f_loc_t<t>, each
        // named with its t.
        let csv = std::fs::read_to_string(&out).unwrap();
        let lines: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
        let header: Vec<&str> = lines[0].split(',').collect();
        assert_eq!(header.len(), 1 + 2 * n_scales, "header {}", lines[0]);
        assert!(
            header[1].starts_with("f_glob_t") && header[1 + n_scales].starts_with("f_loc_t"),
            "header {}",
            lines[0]
        );
        for (s, row) in rows.iter().enumerate() {
            // The t in the name is the t of the report's row (4 significant digits).
            let named: f64 = header[1 + s]["f_glob_t".len()..].parse().unwrap();
            let printed: f64 = row[1].parse().unwrap();
            assert!((named - printed).abs() <= 1e-3 * printed, "{named} vs {printed}");
        }
        let data: Vec<Vec<f64>> = lines[1..]
            .iter()
            .map(|l| l.split(',').map(|x| x.trim().parse::<f64>().unwrap()).collect())
            .collect();
        assert_eq!(data.len(), 642);
        for (i, row) in data.iter().enumerate() {
            assert!((row[0] - f[i]).abs() < 1e-12);
            for s in 0..n_scales {
                assert!(
                    (row[1 + s] + row[1 + n_scales + s] - f[i]).abs() < 1e-9,
                    "vertex {i} scale {s}"
                );
            }
        }
        for (s, row) in rows.iter().enumerate() {
            let linf = data.iter().fold(0.0f64, |m, r| m.max(r[1 + n_scales + s].abs()));
            let printed: f64 = row[2].parse().unwrap();
            assert!((printed - linf).abs() <= 1e-5 * linf, "scale {s}: {printed} vs {linf}");
        }
    }
}

#[test]
fn approx_png_writes_three_figures() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, field, _) = setup(dir.path());
    let out = dir.path().join("approx.png");
    let o = wfem(&[
        "approx",
        mesh.to_str().unwrap(),
        "--field",
        field.to_str().unwrap(),
        "--persistence",
        "0.25",
        "--scales",
        "2",
        "--coefficients",
        "interpolate",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let pngs: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "png"))
        .collect();
    assert_eq!(pngs.len(), 3, "{}", stdout(&o));
    for p in pngs {
        let bytes = std::fs::read(p.path()).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
}

#[test]
fn approx_rejects_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, field, _) = setup(dir.path());
    let out = dir.path().join("o.npy");
    let o = wfem(&[
        "approx",
        mesh.to_str().unwrap(),
        "--field",
        field.to_str().unwrap(),
        "--persistence",
        "-1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("persistence"), "{}", stderr(&o));
    let short = dir.path().join("short.csv");
    std::fs::write(&short, "1\n2\n3\n").unwrap();
    let o = wfem(&[
        "approx",
        mesh.to_str().unwrap(),
        "--field",
        short.to_str().unwrap(),
        "--persistence",
        "0.1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).starts_with("wfem: error:"), "{}", stderr(&o));
}

/// Issue #24: `wfem approx MESH --field F -o OUT` with no other option runs the library's
/// default decomposition (the same numbers as `feature_approximation` with
/// `ApproxParams::default()`) and meets the paper's 2 % at the finest scale on the
/// benchmark's small cases (docs/APPROX-RESULTS.md); the sidecar records the scales, the
/// anchors and the coefficients; a noisy field is denoised (issue #40), or warned about with
/// `--noise keep`.
#[test]
fn issue_24_defaults_on_the_benchmark_small_cases() {
    use shrec_bench::approx_eval::{load_case, noise, BenchField, SMALL_CASES};
    use wfem_heat::approx::{feature_approximation, ApproxParams};
    let meshes = wfem_corpus::meshes_dir().expect("the mesh corpus is required (or set WFEM_MESHES)");
    let dir = tempfile::tempdir().unwrap();
    for case in SMALL_CASES {
        let (mesh, kernel, lambda_k) = load_case(&meshes, &case).unwrap();
        let fields: &[BenchField] = if case.mesh.contains("398") {
            &BenchField::ALL
        } else {
            &[BenchField::Coordinate]
        };
        for field in fields {
            let f = field.values(&mesh, &kernel, lambda_k).unwrap();
            let csv = dir.path().join("f.csv");
            std::fs::write(&csv, f.iter().map(|v| format!("{v:.17e}\n")).collect::<String>()).unwrap();
            let out = dir.path().join("a.npy");
            let path = meshes.join(case.mesh);
            let o = wfem(&[
                "approx",
                path.to_str().unwrap(),
                "--field",
                csv.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ]);
            assert!(o.status.success(), "{}: {}", case.name, stderr(&o));
            assert!(!stderr(&o).contains("warning"), "{}: {}", case.name, stderr(&o));
            let meta: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.path().join("a.json")).unwrap()).unwrap();
            let record = &meta["approximation"];
            let library = feature_approximation(&mesh, &kernel, &f, &ApproxParams::default()).unwrap();
            assert_eq!(record["coefficients"], library.coefficients.name());
            assert_eq!(record["sampling"], library.sampling.name());
            assert_eq!(record["anchors"], serde_json::json!(library.anchors));
            let scales = record["scales"].as_array().unwrap();
            assert_eq!(scales.len(), library.scales.len());
            for (s, l) in scales.iter().zip(&library.scales) {
                assert!((s["t"].as_f64().unwrap() - l.t).abs() <= 1e-12 * l.t);
                assert_eq!(s["anchors"], serde_json::json!(l.anchors));
                let c: Vec<f64> = serde_json::from_value(s["coefficients"].clone()).unwrap();
                assert_eq!(c.len(), l.coefficients.len());
                for (a, b) in c.iter().zip(&l.coefficients) {
                    assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{}: {a} vs {b}", case.name);
                }
                let e = s["relative_linf_error"].as_f64().unwrap();
                assert!((e - l.relative_linf_error).abs() <= 1e-9, "{} {field:?}", case.name);
                if l.anchors.len() == library.anchors.len() {
                    assert!(s["anchor_error"].as_f64().unwrap() < 1e-6, "{} {field:?}", case.name);
                }
            }
            let finest = scales[0]["relative_linf_error"].as_f64().unwrap();
            assert!(finest < 0.02, "{} {field:?}: {finest}", case.name);
        }
        // Issue #40: the noisy coordinate (5 % of the range) is denoised without options, as
        // the library does: t* among the scales, marked; σ̂ and t* in the report and the sidecar.
        let z: Vec<f64> = mesh.positions().iter().map(|p| p[2]).collect();
        let range = z.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - z.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let noisy: Vec<f64> = z.iter().zip(noise(z.len(), range, 0.05)).map(|(a, b)| a + b).collect();
        let csv = dir.path().join("noisy.csv");
        std::fs::write(&csv, noisy.iter().map(|v| format!("{v:.17e}\n")).collect::<String>()).unwrap();
        let out = dir.path().join("n.npy");
        let path = meshes.join(case.mesh);
        let run = |extra: &[&str]| {
            let mut args = vec![
                "approx",
                path.to_str().unwrap(),
                "--field",
                csv.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ];
            args.extend_from_slice(extra);
            wfem(&args)
        };
        let o = run(&[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(!stderr(&o).contains("warning"), "{}: {}", case.name, stderr(&o));
        assert!(stdout(&o).contains("noise: σ̂ = "), "{}", stdout(&o));
        let library = feature_approximation(&mesh, &kernel, &noisy, &ApproxParams::default()).unwrap();
        let chosen = library.chosen.expect("5 % noise is denoised");
        let estimate = library.noise.as_ref().unwrap();
        assert!(
            (estimate.noise - 0.05 * range).abs() < 0.15 * 0.05 * range,
            "{}",
            estimate.noise
        );
        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("n.json")).unwrap()).unwrap();
        let record = &meta["approximation"];
        assert_eq!(record["chosen"], serde_json::json!(chosen));
        assert_eq!(record["noise_rule"], "auto");
        let sigma = record["noise"]["sigma"].as_f64().unwrap();
        assert!((sigma - estimate.noise).abs() <= 1e-9 * estimate.noise);
        let t = record["scales"][chosen]["t"].as_f64().unwrap();
        assert!((t - estimate.t).abs() <= 1e-12 * t && (record["noise"]["t"].as_f64().unwrap() - t).abs() <= 1e-12 * t);
        // Taken as clean, the noisy anchors are warned about, naming the noise rule.
        let o = run(&["--noise", "keep"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("wfem: warning:") && err.contains("--persistence") && err.contains("--noise auto"),
            "{}: {err}",
            case.name
        );
    }
}
