//! `cargo xtask wheel`: the `wfem` Python package as one wheel for every CPython ≥ 3.10 of
//! this platform (abi3, pyo3's `abi3-py310`), built by maturin in the **release** profile —
//! the route for users, installed in seconds with `pip install target/wheels/wfem-*.whl`.
//!
//! maturin comes from a small venv of its own under the target directory (`wheel-venv/`,
//! the version pinned in `crates/wfem-py/requirements-test.txt`), so nothing else is installed.

use crate::test_all::{bin, ensure_venv, target_dir, workspace_root, StepError};
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

/// The maturin pin of the test requirements (`maturin==X.Y.Z`).
fn maturin_pin(requirements: &str) -> Option<&str> {
    requirements.lines().map(str::trim).find(|l| l.starts_with("maturin=="))
}

/// Builds the release wheel into `<target>/wheels` and returns its path.
///
/// # Errors
/// A missing Python or venv module (with the fix), a failing pip or maturin.
pub fn build() -> Result<PathBuf, StepError> {
    let root = workspace_root();
    let target = target_dir(&root);
    let venv = target.join("wheel-venv");
    let python = ensure_venv(&venv)?;
    let maturin = bin(&venv, "maturin");
    if !maturin.exists() {
        let requirements = std::fs::read_to_string(root.join("crates/wfem-py/requirements-test.txt"))
            .map_err(|e| StepError(format!("requirements-test.txt: {e}")))?;
        let pin = maturin_pin(&requirements).unwrap_or("maturin>=1.9.4,<2").to_string();
        step(
            "pip install maturin",
            Command::new(&python)
                .args(["-m", "pip", "install", "--disable-pip-version-check", "--no-input"])
                .arg(&pin),
        )?;
    }
    let out = target.join("wheels");
    let _ = std::fs::remove_dir_all(&out);
    let start = Instant::now();
    step(
        "maturin build --release",
        Command::new(&maturin)
            .args(["build", "--release", "--locked", "--manifest-path"])
            .arg(root.join("crates/wfem-py/Cargo.toml"))
            .arg("--out")
            .arg(&out)
            .env("CARGO_TARGET_DIR", &target),
    )?;
    let wheel = std::fs::read_dir(&out)
        .map_err(|e| StepError(format!("{}: {e}", out.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .ok_or_else(|| StepError(format!("maturin wrote no wheel into {}", out.display())))?;
    eprintln!("==> wheel built in {:.0} s", start.elapsed().as_secs_f64());
    Ok(wheel)
}

fn step(name: &str, cmd: &mut Command) -> Result<(), StepError> {
    eprintln!("==> {name}: {cmd:?}");
    match cmd.status() {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(StepError(format!("{name} failed ({s})"))),
        Err(e) => Err(StepError(format!("{name}: cannot run {:?}: {e}", cmd.get_program()))),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_maturin_pin_is_read_from_the_test_requirements() {
        let text = "# comment\nnumpy==2.0\nmaturin==1.16.0\n";
        assert_eq!(super::maturin_pin(text), Some("maturin==1.16.0"));
        assert_eq!(super::maturin_pin("numpy==2.0\n"), None);
    }
}
