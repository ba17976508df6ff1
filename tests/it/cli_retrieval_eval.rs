//! `wfem retrieval eval` on a small generated labelled set: the measures it reports are checked
//! against rankings obtained independently (one `wfem retrieval query` per shape against the
//! index it saved) and measures computed here from their definitions; classes from folders,
//! file stems and a label file agree; a snapshot pins the text report.

use crate::common::{stderr, wfem};
use std::path::{Path, PathBuf};

/// Nine generated shapes in three class folders (sphere, torus, ellipsoid), each member a
/// different resolution or proportion.
fn labelled_set(dir: &Path) -> Vec<(PathBuf, &'static str)> {
    use mesh_fem::generate::{icosphere, torus};
    use mesh_fem::TriMesh;
    let stretch = |m: TriMesh, s: [f64; 3]| {
        TriMesh::new(
            m.positions()
                .iter()
                .map(|p| [s[0] * p[0], s[1] * p[1], s[2] * p[2]])
                .collect(),
            m.faces().to_vec(),
        )
        .unwrap()
    };
    let mut out = Vec::new();
    let mut put = |class: &'static str, i: usize, mesh: TriMesh| {
        let folder = dir.join(class);
        std::fs::create_dir_all(&folder).unwrap();
        let path = folder.join(format!("{class}{i}.off"));
        mesh_fem::io::write_mesh(&path, &mesh).unwrap();
        out.push((path, class));
    };
    for (i, level) in [2u32, 3, 2].into_iter().enumerate() {
        put(
            "sphere",
            i,
            stretch(icosphere(level), [1.0, 1.0, 1.0 + 0.05 * i as f64]),
        );
    }
    for (i, (minor, nu)) in [(0.4, 24), (0.38, 28), (0.42, 20)].into_iter().enumerate() {
        put("torus", i, torus(1.0, minor, nu, nu / 2));
    }
    for (i, (a, level)) in [(2.2, 2u32), (2.0, 3), (2.4, 2)].into_iter().enumerate() {
        put("ellipsoid", i, stretch(icosphere(level), [a, 1.0, 0.6]));
    }
    out
}

/// AP, NN, FT, ST, E (first 32) and normalised DCG of one relevance list, from their
/// definitions (PSB / SHREC).
fn measures(rel: &[bool]) -> [f64; 6] {
    let r = rel.iter().filter(|&&x| x).count() as f64;
    let hits = |k: usize| rel.iter().take(k).filter(|&&x| x).count() as f64;
    let mut ap = 0.0;
    for (k, &x) in rel.iter().enumerate() {
        if x {
            ap += hits(k + 1) / (k + 1) as f64;
        }
    }
    let k = rel.len().min(32);
    let (p, rc) = (hits(k) / k as f64, hits(k) / r);
    let e = if p + rc > 0.0 { 2.0 * p * rc / (p + rc) } else { 0.0 };
    let mut dcg = 0.0;
    for (k, &x) in rel.iter().enumerate() {
        if x {
            dcg += if k == 0 { 1.0 } else { 1.0 / ((k + 1) as f64).log2() };
        }
    }
    let ideal: f64 = 1.0 + (2..=r as usize).map(|j| 1.0 / (j as f64).log2()).sum::<f64>();
    let n = r as usize;
    [ap / r, hits(1), hits(n) / r, hits(2 * n) / r, e, dcg / ideal]
}

#[test]
fn retrieval_eval_reports_the_measures_of_its_rankings() {
    let dir = tempfile::tempdir().unwrap();
    let set = labelled_set(dir.path());
    let files: Vec<String> = set.iter().map(|(p, _)| p.to_str().unwrap().to_string()).collect();
    let (json, index) = (dir.path().join("report.json"), dir.path().join("index.json"));
    let small = ["--eigenpairs", "30", "--words", "6"];
    let mut args = vec!["retrieval", "eval"];
    args.extend(files.iter().map(String::as_str));
    args.extend(small);
    args.extend(["--json", json.to_str().unwrap(), "--index", index.to_str().unwrap()]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["shapes"], 9);
    assert_eq!(report["classes"], 3);

    // Rankings obtained independently: each shape queried against the saved index (one new
    // description each), itself dropped; measures from their definitions.
    let mut sum = [0.0; 6];
    for (q, (path, class)) in set.iter().enumerate() {
        let o = wfem(&["retrieval", "query", index.to_str().unwrap(), &files[q], "--top", "9"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let ranked: Vec<String> = String::from_utf8_lossy(&o.stdout)
            .lines()
            .map(|l| l.split('\t').nth(2).unwrap().to_string())
            .filter(|name| Path::new(name) != path.as_path())
            .collect();
        assert_eq!(ranked.len(), 8);
        let rel: Vec<bool> = ranked
            .iter()
            .map(|name| set.iter().any(|(p, c)| Path::new(name) == p.as_path() && c == class))
            .collect();
        let m = measures(&rel);
        let stored = &report["per_query"][q]["measures"];
        for (k, key) in ["map", "nn", "first_tier", "second_tier", "e_measure", "dcg"]
            .iter()
            .enumerate()
        {
            let got = stored[key].as_f64().unwrap();
            assert!((got - m[k]).abs() < 1e-12, "{} {key}: {got} vs {}", files[q], m[k]);
            sum[k] += m[k];
        }
    }
    for (k, key) in ["map", "nn", "first_tier", "second_tier", "e_measure", "dcg"]
        .iter()
        .enumerate()
    {
        let got = report["overall"][key].as_f64().unwrap();
        assert!(
            (got - sum[k] / 9.0).abs() < 1e-12,
            "overall {key}: {got} vs {}",
            sum[k] / 9.0
        );
    }

    // Classes from the file stems, and from a label file (paths relative to it), give the
    // same report.
    for how in ["stem", "labels"] {
        let labels = dir.path().join("labels.csv");
        let mut args = vec!["retrieval", "eval"];
        let listed;
        if how == "stem" {
            args.extend(files.iter().map(String::as_str));
            args.extend(["--class-from", "stem"]);
        } else {
            listed = set
                .iter()
                .map(|(p, c)| format!("{},{c}\n", p.strip_prefix(dir.path()).unwrap().display()))
                .collect::<String>();
            std::fs::write(&labels, format!("file,class\n{listed}")).unwrap();
            args.extend(["--labels", labels.to_str().unwrap()]);
        }
        args.extend(small);
        let o = wfem(&args);
        assert!(o.status.success(), "{how}: {}", stderr(&o));
        assert_eq!(String::from_utf8_lossy(&o.stdout), text, "{how}");
    }
    insta::assert_snapshot!("retrieval_eval_small", text);

    // Errors: a shape without a class, a label file naming no file, a file not in it.
    let o = wfem(&[
        "retrieval",
        "eval",
        "--labels",
        dir.path().join("none.csv").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    std::fs::write(dir.path().join("bad.csv"), "a.off\n").unwrap();
    let o = wfem(&[
        "retrieval",
        "eval",
        "--labels",
        dir.path().join("bad.csv").to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("bad.csv:1"), "{}", stderr(&o));
    let stray = dir.path().join("0042.off");
    mesh_fem::io::write_mesh(&stray, &mesh_fem::generate::icosphere(1)).unwrap();
    let o = wfem(&["retrieval", "eval", stray.to_str().unwrap(), "--class-from", "stem"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("0042.off"), "{}", stderr(&o));
    let labels = dir.path().join("labels.csv");
    let o = wfem(&[
        "retrieval",
        "eval",
        stray.to_str().unwrap(),
        "--labels",
        labels.to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("is not in"), "{}", stderr(&o));
}
