//! Issue #15: the `wfem` library is thin. A user who depends on it with
//! `default-features = false` (or on the four library crates) compiles no CLI dependency.

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
fn the_library_without_default_features_pulls_no_cli_dependency() {
    const CLI_ONLY: [&str; 4] = ["clap", "indicatif", "png", "wfem-render"];
    for (package, extra) in [
        ("wfem", &["--no-default-features"][..]),
        ("mesh-fem", &[][..]),
        ("shifted-solve", &[][..]),
        ("wfem-heat", &[][..]),
        ("shape-retrieval", &[][..]),
    ] {
        let tree = dependency_tree(package, extra);
        assert!(tree.iter().any(|p| p == package), "{package}: {tree:?}");
        for dep in CLI_ONLY {
            assert!(!tree.iter().any(|p| p == dep), "{package} {extra:?} pulls {dep}");
        }
    }
    // The default features do build the CLI (the check above is not vacuous).
    let full = dependency_tree("wfem", &[]);
    assert!(full.iter().any(|p| p == "clap") && full.iter().any(|p| p == "wfem-render"));
}
