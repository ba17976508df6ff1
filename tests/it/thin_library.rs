//! Issues #15, #37: the library crates are thin. A user who depends on the facade `wfem` or on
//! any library crate compiles no CLI dependency; the store alone compiles no heat stack.

use std::process::Command;

/// Every package in the normal-dependency tree of `package` with the given feature flags.
fn dependency_tree(package: &str, extra: &[&str]) -> Vec<String> {
    let out = Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--offline",
            "--locked",
            "-e",
            "normal",
            "--prefix",
            "none",
            "-p",
            package,
        ])
        .args(extra)
        .output()
        .expect("cargo tree runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

#[test]
fn the_library_crates_pull_no_cli_dependency() {
    const CLI_ONLY: [&str; 4] = ["clap", "indicatif", "png", "wfem-render"];
    for package in [
        "wfem",
        "wfem-base",
        "mesh-fem",
        "mesh-repair",
        "shifted-solve",
        "wfem-heat",
        "shape-retrieval",
        "retrieval-store",
    ] {
        let tree = dependency_tree(package, &[]);
        assert!(tree.iter().any(|p| p == package), "{package}: {tree:?}");
        for dep in CLI_ONLY {
            assert!(!tree.iter().any(|p| p == dep), "{package} pulls {dep}");
        }
    }
    // The command-line package does build them (the check above is not vacuous).
    let full = dependency_tree("wfem-cli", &[]);
    assert!(full.iter().any(|p| p == "clap") && full.iter().any(|p| p == "wfem-render"));
}

#[test]
fn the_store_alone_compiles_no_heat_stack() {
    // retrieval-store without its `index` feature is a plain vector store.
    let tree = dependency_tree("retrieval-store", &[]);
    for dep in ["shape-retrieval", "wfem-heat", "shifted-solve", "mesh-fem", "faer"] {
        assert!(!tree.iter().any(|p| p == dep), "retrieval-store pulls {dep}: {tree:?}");
    }
    let indexed = dependency_tree("retrieval-store", &["--features", "index"]);
    assert!(indexed.iter().any(|p| p == "shape-retrieval"));
    // mesh-fem pulls nalgebra-sparse only with its feature.
    let plain = dependency_tree("mesh-fem", &[]);
    assert!(!plain.iter().any(|p| p == "nalgebra-sparse"), "{plain:?}");
    let with = dependency_tree("mesh-fem", &["--features", "nalgebra"]);
    assert!(with.iter().any(|p| p == "nalgebra-sparse"));
}
