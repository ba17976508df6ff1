//! End-to-end tests of `wfem hks` against a dense generalized eigendecomposition.

use mesh_fem::{assemble, AssemblyParams, Lumping};
use std::path::Path;
use std::process::Command;
use wfem_heat::spectral::Eigenbasis;

fn wfem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .output()
        .expect("the wfem binary runs")
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Reads a little-endian float64 C-order NPY file: (shape, values).
fn read_npy(path: &Path) -> (Vec<usize>, Vec<f64>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(
        header.contains("'descr': '<f8'") && header.contains("'fortran_order': False"),
        "{header}"
    );
    let shape_text = header.split("'shape': (").nth(1).unwrap().split(')').next().unwrap();
    let shape: Vec<usize> = shape_text
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let values = bytes[10 + header_len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (shape, values)
}

/// `Σ_{k<K} e^{−λ_k t} φ_k(i)²`, row-major n × T.
fn reference(basis: &Eigenbasis, k: usize, times: &[f64]) -> Vec<f64> {
    let n = basis.vectors.nrows();
    let mut out = Vec::new();
    for i in 0..n {
        for &t in times {
            out.push(
                (0..k)
                    .map(|c| (-basis.values[c] * t).exp() * basis.vectors[(i, c)].powi(2))
                    .sum(),
            );
        }
    }
    out
}

fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// `--method spectral` is the truncated sum of Eq. (8) (what the peers compute); the default,
/// `--method auto`, is the full HKS — exact where truncation fails, spectral where its bound
/// holds — and `--method exact` the full HKS without eigenpairs; for both kernels, against the
/// dense decomposition with all n eigenpairs. The lumped kernel's D is `--lumped voronoi` here.
#[test]
fn hks_matches_dense_reference_for_both_kernels_and_methods() {
    let dir = tempfile::tempdir().unwrap();
    // 642 vertices: the block Lanczos path.
    let mesh = mesh_fem::generate::bumpy(3);
    let n = mesh.n_vertices();
    let path = dir.path().join("bumpy.off");
    mesh_fem::io::write_mesh(&path, &mesh).unwrap();
    let ops = assemble(
        &mesh,
        &AssemblyParams {
            lumping: Lumping::Voronoi,
            ..Default::default()
        },
    )
    .unwrap();
    let times = [0.001, 0.01, 0.1, 1.0];
    for (kernel, mass) in [("wfem", &ops.mass), ("lumped", &ops.lumped_mass())] {
        let dense = Eigenbasis::dense(&ops.stiffness, mass).unwrap();
        let truncated = reference(&dense, 30, &times);
        let full = reference(&dense, n, &times);
        // The truncated sum really is off at the small times (so the comparison means something).
        assert!(max_rel(&truncated[..], &full[..]) > 0.05);
        for (method, want, tol) in [
            ("spectral", &truncated, 1e-8),
            ("auto", &full, 1e-3),
            ("exact", &full, 1e-8),
        ] {
            let out = dir.path().join(format!("{kernel}-{method}.npy"));
            let mut args = vec![
                "hks",
                path.to_str().unwrap(),
                "--times",
                "0.001",
                "0.01",
                "0.1",
                "1",
                "--kernel",
                kernel,
                "--method",
                method,
                "-o",
                out.to_str().unwrap(),
            ];
            if method != "exact" {
                args.extend(["--eigenpairs", "30"]);
            }
            if kernel == "lumped" {
                args.extend(["--lumped", "voronoi"]);
            }
            let o = wfem(&args);
            assert!(o.status.success(), "{kernel} {method}: {}", stderr(&o));
            let (shape, values) = read_npy(&out);
            assert_eq!(shape, vec![n, times.len()]);
            let e = max_rel(&values, want);
            assert!(e < tol, "{kernel} {method}: {e:e}");
            // The sidecar says which method each time used.
            let sidecar = std::fs::read_to_string(out.with_extension("json")).unwrap();
            let sidecar: serde_json::Value = serde_json::from_str(&sidecar).unwrap();
            let used = sidecar["sources"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|s| s["method"] == "exact")
                .count();
            match method {
                "spectral" => assert_eq!(used, 0, "{sidecar}"),
                "exact" => assert_eq!(used, times.len(), "{sidecar}"),
                _ => assert!(used >= 1 && used < times.len(), "{sidecar}"),
            }
        }
    }
    // --lumped is for the lumped kernel only; --eigenpairs is not used by exact values at given times.
    let out = dir.path().join("x.npy");
    let o = wfem(&[
        "hks",
        path.to_str().unwrap(),
        "--times",
        "0.1",
        "--lumped",
        "voronoi",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--lumped applies to a lumped --mass"),
        "{}",
        stderr(&o)
    );
    let o = wfem(&[
        "hks",
        path.to_str().unwrap(),
        "--times",
        "0.1",
        "--method",
        "exact",
        "--eigenpairs",
        "5",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        stderr(&o).contains("--eigenpairs does not apply to --method exact"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

#[test]
fn hks_automatic_scales_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.off");
    mesh_fem::io::write_mesh(&path, &mesh_fem::generate::bumpy(2)).unwrap();
    let out = dir.path().join("hks.csv");
    let o = wfem(&[
        "hks",
        path.to_str().unwrap(),
        "--scales",
        "5",
        "--eigenpairs",
        "20",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap().split(',').count(), 5);
    assert_eq!(lines.count(), 162);
    // The HKS decreases in t at every vertex.
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
        assert!(v.windows(2).all(|w| w[1] < w[0]), "{line}");
    }
}

#[test]
fn hks_rejects_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.off");
    mesh_fem::io::write_mesh(&path, &mesh_fem::generate::icosphere(1)).unwrap();
    let out = dir.path().join("x.npy");
    for args in [
        vec!["--times", "-1"],
        vec!["--num-times", "0"],
        vec!["--eigenpairs", "0"],
    ] {
        let mut all = vec!["hks", path.to_str().unwrap()];
        all.extend(args.iter().copied());
        all.extend(["-o", out.to_str().unwrap()]);
        let o = wfem(&all);
        assert!(!o.status.success());
        assert!(stderr(&o).starts_with("wfem: error:"), "{}", stderr(&o));
        assert!(!out.exists());
    }
    // Never writes over the input.
    let before = std::fs::read(&path).unwrap();
    let o = wfem(&["hks", path.to_str().unwrap(), "-o", path.to_str().unwrap()]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read(&path).unwrap(), before);
}

#[test]
fn retrieval_build_then_query_finds_the_same_shape_first() {
    let dir = tempfile::tempdir().unwrap();
    let shapes = [
        ("bumpy.off", mesh_fem::generate::bumpy(2)),
        ("sphere.off", mesh_fem::generate::icosphere(2)),
        ("torus.off", mesh_fem::generate::torus(1.0, 0.4, 20, 10)),
    ];
    let mut files = Vec::new();
    for (name, mesh) in &shapes {
        let p = dir.path().join(name);
        mesh_fem::io::write_mesh(&p, mesh).unwrap();
        files.push(p.to_str().unwrap().to_string());
    }
    let index = dir.path().join("index.json");
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--out", index.to_str().unwrap(), "--eigenpairs", "30", "--words", "8"]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    // A rescaled copy of the bumpy sphere retrieves the bumpy sphere first (the default SI-HKS
    // in area units is exactly scale invariant), at distance ≈ 0.
    let query = dir.path().join("query.off");
    mesh_fem::io::write_mesh(&query, &mesh_fem::generate::bumpy(2).scaled(5.0).unwrap()).unwrap();
    let o = wfem(&[
        "retrieval",
        "query",
        index.to_str().unwrap(),
        query.to_str().unwrap(),
        "--top",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let first: Vec<&str> = text.lines().next().unwrap().split('\t').collect();
    assert_eq!(first[0], "1");
    assert!(first[2].ends_with("bumpy.off"), "{text}");
    assert!(first[1].parse::<f64>().unwrap() < 1e-6, "{text}");
    assert_eq!(text.lines().count(), 2);
    // A file that is not an index is refused.
    let o = wfem(&["retrieval", "query", files[0].as_str(), query.to_str().unwrap()]);
    assert!(!o.status.success());
}

/// The default index file is SQLite (retrieval-store): the same ranking as the JSON index
/// (distances equal up to the f32 storage), `add` appends without rebuilding, a JSON index
/// refuses `add`, and a SQLite file that is not an index is refused by name.
#[test]
fn retrieval_sqlite_index_ranks_like_json_and_takes_appends() {
    let dir = tempfile::tempdir().unwrap();
    let shapes = [
        ("bumpy.off", mesh_fem::generate::bumpy(2)),
        ("sphere.off", mesh_fem::generate::icosphere(2)),
        ("torus.off", mesh_fem::generate::torus(1.0, 0.4, 20, 10)),
    ];
    let mut files = Vec::new();
    for (name, mesh) in &shapes {
        let p = dir.path().join(name);
        mesh_fem::io::write_mesh(&p, mesh).unwrap();
        files.push(p.to_str().unwrap().to_string());
    }
    let query = dir.path().join("query.off");
    mesh_fem::io::write_mesh(&query, &mesh_fem::generate::bumpy(2).scaled(3.0).unwrap()).unwrap();
    let run = |args: &[&str]| {
        let o = wfem(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let build = |out: &Path, files: &[String]| {
        let mut args = vec!["retrieval", "build"];
        args.extend(files.iter().map(|s| s.as_str()));
        args.extend(["--out", out.to_str().unwrap(), "--eigenpairs", "30", "--words", "8"]);
        run(&args);
    };
    let parse = |text: &str| -> Vec<(String, f64)> {
        text.lines()
            .map(|l| {
                let c: Vec<&str> = l.split('\t').collect();
                (c[2].to_string(), c[1].parse().unwrap())
            })
            .collect()
    };
    let (sqlite, json) = (dir.path().join("index.sqlite"), dir.path().join("index.json"));
    build(&sqlite, &files[..2]);
    build(&json, &files[..2]);
    assert_eq!(&std::fs::read(&sqlite).unwrap()[..16], b"SQLite format 3\0");
    let q = |index: &Path| {
        parse(&run(&[
            "retrieval",
            "query",
            index.to_str().unwrap(),
            query.to_str().unwrap(),
            "--top",
            "3",
        ]))
    };
    let (a, b) = (q(&sqlite), q(&json));
    assert_eq!(a.len(), 2);
    for ((na, da), (nb, db)) in a.iter().zip(&b) {
        assert_eq!(na, nb);
        assert!((da - db).abs() < 1e-5, "{a:?} vs {b:?}");
    }
    assert!(a[0].0.ends_with("bumpy.off"));

    // Append the torus: the index now answers with three shapes; the first two keep their
    // distances (nothing was rebuilt).
    run(&["retrieval", "add", sqlite.to_str().unwrap(), files[2].as_str()]);
    let c = q(&sqlite);
    assert_eq!(c.len(), 3);
    assert!(c.iter().any(|(n, _)| n.ends_with("torus.off")));
    for (name, d) in &a {
        let (_, d2) = c.iter().find(|(n, _)| n == name).unwrap();
        assert_eq!(d, d2);
    }
    // Adding the same file again is refused, and the index is unchanged.
    let before = std::fs::read(&sqlite).unwrap();
    let o = wfem(&["retrieval", "add", sqlite.to_str().unwrap(), files[2].as_str()]);
    assert!(!o.status.success());
    assert_eq!(q(&sqlite), c);
    assert_eq!(std::fs::read(&sqlite).unwrap().len(), before.len());
    // A JSON index is written whole: add refuses it.
    let o = wfem(&["retrieval", "add", json.to_str().unwrap(), files[2].as_str()]);
    assert!(stderr(&o).contains("SQLite index"), "{}", stderr(&o));
    // A SQLite vector store without index settings is not an index.
    let other = dir.path().join("other.sqlite");
    retrieval_store::Store::create(&other, &retrieval_store::StoreParams::new(8), false).unwrap();
    let o = wfem(&["retrieval", "query", other.to_str().unwrap(), query.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not a wfem retrieval index"), "{}", stderr(&o));
}

#[test]
fn retrieval_cleaning_is_selectable_and_checked() {
    // `--despike off --fill-holes 1.5 --denoise 0.2` are recorded as such; bad values are usage
    // errors that say what the flag takes.
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (name, mesh) in [
        ("bumpy.off", mesh_fem::generate::bumpy(2)),
        ("torus.off", mesh_fem::generate::torus(1.0, 0.4, 20, 10)),
    ] {
        let p = dir.path().join(name);
        mesh_fem::io::write_mesh(&p, &mesh).unwrap();
        files.push(p.to_str().unwrap().to_string());
    }
    let vocab = dir.path().join("vocab.json");
    let run = |extra: &[&str]| {
        let mut args = vec!["retrieval", "vocab", "--words", "4"];
        args.extend(files.iter().map(|s| s.as_str()));
        args.extend(["--out", vocab.to_str().unwrap()]);
        args.extend(extra);
        wfem(&args)
    };
    let o = run(&["--despike", "off", "--fill-holes", "1.5", "--denoise", "0.2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&vocab).unwrap()).unwrap();
    // Written as null (a missing field would read as the default, on).
    assert!(v["descriptor"]["despiking"].is_null(), "{}", v["descriptor"]);
    assert_eq!(
        v["descriptor"]["denoising"],
        serde_json::json!({"roughness": 0.2, "max_coherence": 0.1})
    );
    assert_eq!(
        v["descriptor"]["hole_filling"],
        serde_json::json!({"max_perimeter": 1.5})
    );
    let o = run(&["--fill-holes", "off"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&vocab).unwrap()).unwrap();
    assert!(v["descriptor"]["hole_filling"].is_null(), "{}", v["descriptor"]);
    for (flag, value) in [
        ("--despike", "-1"),
        ("--despike", "nan"),
        ("--denoise", "0"),
        ("--denoise", "no"),
        ("--fill-holes", "-2"),
        ("--fill-holes", "inf"),
    ] {
        let o = run(&[&format!("{flag}={value}")]);
        assert!(!o.status.success(), "{flag} {value}");
        assert!(
            stderr(&o).contains("positive number or `off`"),
            "{flag} {value}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn retrieval_defaults_are_recorded_in_the_vocabulary_and_the_index() {
    // `vocab` and `build` with no option write the documented defaults (issue #13): SI-HKS of the
    // wFEM kernel, area time unit, τ ∈ [−12, 1] step 1/8, α = 2, K = 5, k = 100, the cotangent
    // Laplacian, isolated spikes put back (threshold 3), rough and incoherent shapes denoised to roughness 0.1,
    // holes up to 3√A closed, handles up to 0.35√A cut, z-scored, 512 words, soft assignment,
    // areas capped at 3 medians, plain bags, χ², no fusion; `build --vocab` reuses the
    // vocabulary as it was written. (Shapes large enough for 512 words: 2,000 descriptors.)
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for (name, mesh) in [
        ("bumpy.off", mesh_fem::generate::bumpy(3)),
        ("sphere.off", mesh_fem::generate::icosphere(3)),
        ("torus.off", mesh_fem::generate::torus(1.0, 0.4, 40, 20)),
    ] {
        let p = dir.path().join(name);
        mesh_fem::io::write_mesh(&p, &mesh).unwrap();
        files.push(p.to_str().unwrap().to_string());
    }
    let read = |p: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let vocab = dir.path().join("vocab.json");
    let mut args = vec!["retrieval", "vocab"];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--out", vocab.to_str().unwrap()]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = read(&vocab);
    assert_eq!(v["format"], "wfem-retrieval-vocabulary");
    assert_eq!(
        v["descriptor"],
        serde_json::json!({
            "eigenpairs": 100,
            "laplacian": "cotan",
            "descriptor": {"kind": "si-hks", "alpha": 2.0, "tau_min": -12.0, "tau_max": 1.0,
                           "tau_step": 0.125, "frequencies": 5},
            "despiking": {"threshold": 3.0},
            "denoising": {"roughness": 0.1, "max_coherence": 0.1},
            "hole_filling": {"max_perimeter": 3.0},
            "topology_repair": {"max_handle": 0.35},
            "refinement": {"vertices_per_eigenpair": 20.0}
        })
    );
    assert_eq!(v["training"]["words"], 512);
    assert_eq!(v["training"]["standardize"], true);
    assert_eq!(v["words"].as_array().unwrap().len(), 512);
    assert!(v["words"]
        .as_array()
        .unwrap()
        .iter()
        .all(|w| w.as_array().unwrap().len() == 5));
    assert_eq!(v["standardizer"]["mean"].as_array().unwrap().len(), 5);
    assert_eq!(v["standardizer"]["std"].as_array().unwrap().len(), 5);

    // build without --vocab: the same defaults, trained on the indexed shapes.
    let index = dir.path().join("index.json");
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(|s| s.as_str()));
    args.extend(["--out", index.to_str().unwrap()]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("optimistic"));
    let i = read(&index);
    assert_eq!(i["format"], "wfem-retrieval-index");
    assert_eq!(i["vocabulary"]["descriptor"], v["descriptor"]);
    assert_eq!(i["vocabulary"]["training"], v["training"]);
    assert_eq!(
        i["bags"],
        serde_json::json!({"weights": {"kind": "capped-area", "factor": 3.0}, "assignment": "normalized",
                           "distance": "chi-squared", "global": null})
    );
    assert_eq!(i["entries"].as_array().unwrap().len(), 3);
    for e in i["entries"].as_array().unwrap() {
        let bag: Vec<f64> = e["bag"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        // 512 words, no spatial histogram.
        assert_eq!(bag.len(), 512);
        assert!((bag.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
    // `--refine`: the factor or `off` is recorded; a factor that is not a positive number, or
    // above the library's bound, is refused.
    for (refine, expected) in [
        ("off", Ok(serde_json::Value::Null)),
        ("40", Ok(serde_json::json!({"vertices_per_eigenpair": 40.0}))),
        ("0", Err("positive number or `off`")),
        ("5000", Err("vertices per eigenpair")),
    ] {
        let out = dir.path().join(format!("refined-{refine}.json"));
        let mut args = vec!["retrieval", "vocab"];
        args.extend(files.iter().map(|s| s.as_str()));
        args.extend(["--out", out.to_str().unwrap(), "--refine", refine, "--words", "8"]);
        let o = wfem(&args);
        match expected {
            Ok(recorded) => {
                assert!(o.status.success(), "{}", stderr(&o));
                assert_eq!(read(&out)["descriptor"]["refinement"], recorded);
            }
            Err(message) => {
                assert!(!o.status.success());
                assert!(stderr(&o).contains(message), "{}", stderr(&o));
            }
        }
    }
    // `--area-cap off`: plain vertex areas; a cap that is not a positive number is refused.
    for (cap, expected) in [
        ("off", Some(serde_json::json!({"kind": "area"}))),
        ("2.5", Some(serde_json::json!({"kind": "capped-area", "factor": 2.5}))),
        ("0", None),
        ("nan", None),
    ] {
        let plain = dir.path().join("plain.json");
        let mut args = vec!["retrieval", "build"];
        args.extend(files.iter().map(|s| s.as_str()));
        args.extend(["--out", plain.to_str().unwrap(), "--area-cap", cap, "--force"]);
        let o = wfem(&args);
        match expected {
            Some(weights) => {
                assert!(o.status.success(), "{}", stderr(&o));
                assert_eq!(read(&plain)["bags"]["weights"], weights);
            }
            None => {
                assert!(!o.status.success());
                assert!(stderr(&o).contains("positive number or `off`"), "{}", stderr(&o));
            }
        }
    }

    // `--spatial C:G`: spatially sensitive bags between G groups of words (512 + G(G+1)/2 bins);
    // groups without a time, or not a whole number ≥ 1, are refused.
    for (spatial, expected) in [
        ("0.01:8", Some(serde_json::json!({"time": 0.01, "groups": 8}))),
        ("off:3", None),
        ("0.01:0", None),
        ("0.01:x", None),
    ] {
        let out = dir.path().join("spatial.json");
        let mut args = vec!["retrieval", "build"];
        args.extend(files.iter().map(|s| s.as_str()));
        args.extend(["--out", out.to_str().unwrap(), "--spatial", spatial, "--force"]);
        let o = wfem(&args);
        match expected {
            Some(bag) => {
                assert!(o.status.success(), "{}", stderr(&o));
                let i = read(&out);
                assert_eq!(i["bags"]["spatial"], bag);
                assert_eq!(i["entries"][0]["bag"].as_array().unwrap().len(), 512 + 8 * 9 / 2);
            }
            None => {
                assert!(!o.status.success());
                assert!(stderr(&o).contains("--spatial takes"), "{}", stderr(&o));
            }
        }
    }

    // build --vocab: the stored vocabulary verbatim, the chosen distance recorded.
    let reused = dir.path().join("reused.json");
    let mut args = vec!["retrieval", "build"];
    args.extend(files[..2].iter().map(|s| s.as_str()));
    args.extend([
        "--out",
        reused.to_str().unwrap(),
        "--vocab",
        vocab.to_str().unwrap(),
        "--distance",
        "l1",
    ]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = read(&reused);
    assert_eq!(r["vocabulary"], v);
    assert_eq!(r["bags"]["distance"], "l1");
    assert_eq!(r["entries"].as_array().unwrap().len(), 2);
    // One file is "1 file" (issue #25).
    let one = dir.path().join("one.json");
    let o = wfem(&[
        "retrieval",
        "build",
        files[0].as_str(),
        "--out",
        one.to_str().unwrap(),
        "--vocab",
        vocab.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("indexed 1 file ("),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // Descriptor options conflict with --vocab (the vocabulary fixes them).
    let o = wfem(&[
        "retrieval",
        "build",
        files[0].as_str(),
        "--out",
        dir.path().join("x.json").to_str().unwrap(),
        "--vocab",
        vocab.to_str().unwrap(),
        "--words",
        "8",
    ]);
    assert!(!o.status.success());
}

/// Issue #25: `heat` and `hks` read their times in a unit of the mesh (`--time-unit`), record
/// it, and warn past the time at infinity in the unit the times were given in.
#[test]
fn time_units_and_warnings_of_heat_and_hks() {
    let dir = tempfile::tempdir().unwrap();
    let mesh_path = dir.path().join("small.off");
    let mesh = mesh_fem::generate::icosphere(2).with_area(0.057).unwrap();
    mesh_fem::io::write_mesh(&mesh_path, &mesh).unwrap();
    let m = mesh_path.to_str().unwrap();
    let stats = mesh_fem::stats::stats(&mesh);
    let edge2 = stats.mean_edge_length * stats.mean_edge_length;
    let run = |args: &[&str]| {
        let o = crate::common::wfem(args);
        assert!(o.status.success(), "{}", crate::common::stderr(&o));
        crate::common::stderr(&o)
    };
    let json = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path().join(name)).unwrap()).unwrap()
    };
    let h = dir.path().join("h.npy");
    let err = run(&[
        "heat",
        m,
        "--t",
        "10",
        "2",
        "--time-unit",
        "edge",
        "--source",
        "3",
        "-o",
        h.to_str().unwrap(),
    ]);
    assert!(!err.contains("warning"), "{err}");
    let side = json("h.json");
    assert_eq!(side["time_unit"]["name"], "edge");
    assert!((side["times"][0].as_f64().unwrap() - 10.0 * edge2).abs() <= 1e-12 * edge2);
    assert!((side["times"][1].as_f64().unwrap() - 2.0 * edge2).abs() <= 1e-12 * edge2);
    // The same heat in absolute units: equal values.
    let h2 = dir.path().join("h2.npy");
    run(&[
        "heat",
        m,
        "--t",
        &(10.0 * edge2).to_string(),
        &(2.0 * edge2).to_string(),
        "--source",
        "3",
        "-o",
        h2.to_str().unwrap(),
    ]);
    let (a, b) = (
        crate::common::read_npy(&h).unwrap().1,
        crate::common::read_npy(&h2).unwrap().1,
    );
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-12));
    assert_eq!(json("h2.json")["time_unit"]["name"], "absolute");
    // Past infinity, in area units (the heat equation's one τ = 100 for every scaling).
    let err = run(&[
        "heat",
        m,
        "--t",
        "100",
        "--time-unit",
        "area",
        "--source",
        "3",
        "-o",
        h.to_str().unwrap(),
    ]);
    assert!(
        err.contains("--t: t = 100 is past the time at infinity") && err.contains("(--time-unit area)"),
        "{err}"
    );
    let k = dir.path().join("k.npy");
    let err = run(&[
        "hks",
        m,
        "--times",
        "10",
        "1e-3",
        "--time-unit",
        "area",
        "-o",
        k.to_str().unwrap(),
    ]);
    assert!(err.contains("--times: t = 10 is past the time at infinity"), "{err}");
    assert_eq!(err.matches("warning").count(), 1, "{err}");
    let side = json("k.json");
    assert_eq!(side["time_unit"]["given"], serde_json::json!([10.0, 1e-3]));
    assert!((side["times"][1].as_f64().unwrap() - 1e-3 * mesh.area()).abs() <= 1e-15);
}
