//! `cargo test-all`: the whole test suite — Rust and Python — on a fresh machine.
//!
//! 1. `cargo test --workspace --locked --features mesh-fem/nalgebra` (every optional feature of
//!    a library crate that the workspace does not already turn on);
//!    then every library crate checked **alone** (`cargo check -p X --lib` with only its own
//!    default features, warnings refused): a crate that compiles only thanks to a feature another
//!    crate turns on, or has code dead without it, fails here (ARCHITECTURE.md, "each crate
//!    usable alone");
//! 2. a virtual environment under the target directory (`$CARGO_TARGET_DIR` or `target/`,
//!    `python-venv/`), created with `python3 -m venv` (or `$WFEM_PYTHON -m venv`); a missing
//!    `venv` module stops with the command that installs it;
//! 3. the pinned packages of `crates/wfem-py/requirements-test.txt` from PyPI, then those of
//!    `requirements-test-nodeps.txt` without their declared dependencies (geomfum, whose torch
//!    the tests do not use; each skipped while its file is unchanged);
//! 4. the extension built by maturin in the **dev** profile, the one `cargo test` just used, so
//!    the dependencies compiled for the tests are reused, and installed into the venv as a
//!    wheel (like a user's `pip install`);
//! 5. pytest on `crates/wfem-py/tests`;
//! 6. the wheel route of a new user: the same wheel with its declared dependencies (and the
//!    `batch` extra) in a venv of its own, running the Python README's quick start and both
//!    examples from a temporary folder.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug, Default)]
pub struct TestAllOptions {
    /// Skip `cargo test` (Python suite only).
    pub python_only: bool,
    /// Skip the Python suite.
    pub rust_only: bool,
    /// Extra arguments for pytest (e.g. `-k dask`).
    pub pytest_args: Vec<String>,
}

/// An error of a step, with what to do about it.
#[derive(Debug)]
pub struct StepError(pub String);

impl std::fmt::Display for StepError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for StepError {}

fn fail<T>(message: impl Into<String>) -> Result<T, StepError> {
    Err(StepError(message.into()))
}

/// The workspace root (xtask's parent directory).
pub fn workspace_root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).to_path_buf()
}

/// The cargo target directory: `$CARGO_TARGET_DIR` (relative to the workspace root when
/// relative, as cargo run from there reads it) or `<root>/target`.
pub fn target_dir(root: &Path) -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) if !dir.is_empty() => {
            let dir = PathBuf::from(dir);
            if dir.is_absolute() {
                dir
            } else {
                root.join(dir)
            }
        }
        _ => root.join("target"),
    }
}

fn run_step(name: &str, cmd: &mut Command) -> Result<(), StepError> {
    eprintln!("==> {name}: {cmd:?}");
    match cmd.status() {
        Ok(status) if status.success() => Ok(()),
        Ok(status) => fail(format!("{name} failed ({status})")),
        Err(e) => fail(format!("{name}: cannot run {:?}: {e}", cmd.get_program())),
    }
}

pub(crate) fn bin(venv: &Path, name: &str) -> PathBuf {
    if cfg!(windows) {
        venv.join("Scripts").join(format!("{name}.exe"))
    } else {
        venv.join("bin").join(name)
    }
}

/// Creates the venv if needed and returns its Python.
pub(crate) fn ensure_venv(venv: &Path) -> Result<PathBuf, StepError> {
    let python = bin(venv, "python");
    if python.exists() {
        return Ok(python);
    }
    let base = std::env::var("WFEM_PYTHON").unwrap_or_else(|_| "python3".into());
    let version = Command::new(&base)
        .args(["-c", "import sys; print('%d.%d' % sys.version_info[:2])"])
        .output();
    let version = match version {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout).trim().to_string(),
        _ => {
            return fail(format!(
                "no Python found ({base}): install CPython >= 3.10 (e.g. `apt install python3 python3-venv`) \
                 or set WFEM_PYTHON to its path"
            ))
        }
    };
    let ok = version
        .split_once('.')
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)))
        .is_some_and(|v| v >= (3, 10));
    if !ok {
        return fail(format!(
            "{base} is Python {version}; wfem needs >= 3.10 (set WFEM_PYTHON)"
        ));
    }
    eprintln!("==> creating {} with {base} ({version})", venv.display());
    let status = Command::new(&base).args(["-m", "venv"]).arg(venv).status();
    if !matches!(status, Ok(s) if s.success()) || !python.exists() {
        let _ = std::fs::remove_dir_all(venv);
        return fail(format!(
            "`{base} -m venv {}` failed: the Python venv module (with ensurepip) is missing.\n\
             Fix: `sudo apt install python{version}-venv` (Debian/Ubuntu; `python3-venv` for the default Python), \
             `sudo dnf install python3` (Fedora), or point WFEM_PYTHON at a Python that has it.",
            venv.display()
        ));
    }
    Ok(python)
}

/// Installs the pinned requirements unless the venv already has exactly this file (a stamp
/// `<file stem>.installed` in the venv remembers what was installed); `no_deps`: without the
/// packages' declared dependencies (`pip install --no-deps`).
pub(crate) fn ensure_requirements(
    python: &Path,
    venv: &Path,
    requirements: &Path,
    no_deps: bool,
) -> Result<(), StepError> {
    let wanted = std::fs::read(requirements).map_err(|e| StepError(format!("{}: {e}", requirements.display())))?;
    let stem = requirements
        .file_stem()
        .map_or("requirements".into(), |s| s.to_string_lossy());
    let stamp = venv.join(format!("{stem}.installed"));
    if std::fs::read(&stamp).ok().as_deref() == Some(&wanted[..]) {
        eprintln!("==> pinned Python packages already installed");
        return Ok(());
    }
    let mut pip = pip_install(python);
    if no_deps {
        pip.arg("--no-deps");
    }
    run_step("pip install", pip.arg("-r").arg(requirements))?;
    std::fs::write(&stamp, &wanted).map_err(|e| StepError(format!("{}: {e}", stamp.display())))
}

/// The wheel route of a new user, on the wheel the suite just built: a venv of its own with
/// only `pip install 'wfem-….whl[batch]'` (the declared dependencies and the `batch` extra, no
/// test packages), then, from a temporary folder, the Python README's quick start and both
/// examples (`smooth.py` on its default mesh, `retrieval.py` on twelve shapes of the corpus).
fn wheel_route(root: &Path, target: &Path, wheel: &Path) -> Result<(), StepError> {
    let venv = target.join("python-wheel-venv");
    let python = ensure_venv(&venv)?;
    let spec = format!("{}[batch]", wheel.display());
    run_step(
        "pip install the wheel with its dependencies",
        pip_install(&python).arg(&spec),
    )?;
    // The same version as last time is "already satisfied": put this build's wheel in.
    run_step(
        "pip install this build's wheel",
        pip_install(&python).args(["--force-reinstall", "--no-deps"]).arg(wheel),
    )?;
    let work = target.join("python-wheel-route");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).map_err(|e| StepError(format!("{}: {e}", work.display())))?;
    let readme = root.join("crates/wfem-py/README.md");
    let text = std::fs::read_to_string(&readme).map_err(|e| StepError(format!("{}: {e}", readme.display())))?;
    let quick = text
        .split_once("## Quick start")
        .and_then(|(_, rest)| rest.split_once("```python\n"))
        .and_then(|(_, rest)| rest.split_once("```"))
        .map(|(code, _)| code.to_string());
    let Some(quick) = quick else {
        return fail(format!(
            "{}: no ```python block under \"## Quick start\"",
            readme.display()
        ));
    };
    let script = work.join("quick_start.py");
    std::fs::write(&script, quick).map_err(|e| StepError(format!("{}: {e}", script.display())))?;
    run_step(
        "README quick start from the wheel",
        Command::new(&python).arg(&script).current_dir(&work),
    )?;
    let examples = root.join("crates/wfem-py/examples");
    run_step(
        "examples/smooth.py from the wheel",
        Command::new(&python).arg(examples.join("smooth.py")).current_dir(&work),
    )?;
    // Twelve shapes of four classes (the example's default folder is all 76).
    let corpus = wfem_corpus::meshes_dir().map_err(|e| StepError(e.to_string()))?;
    let tosca = corpus.join("tosca-bcicp-5k").join("TOSCA_Isometric");
    let folder = work.join("shapes");
    std::fs::create_dir_all(&folder).map_err(|e| StepError(format!("{}: {e}", folder.display())))?;
    let mut names: Vec<String> = std::fs::read_dir(&tosca)
        .map_err(|e| StepError(format!("{}: {e}", tosca.display())))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".off"))
        .collect();
    names.sort();
    for class in ["cat", "dog", "horse", "wolf"] {
        let poses = names.iter().filter(|n| {
            n.trim_end_matches(".off")
                .trim_end_matches(|c: char| c.is_ascii_digit())
                == class
        });
        for name in poses.take(3) {
            std::fs::copy(tosca.join(name), folder.join(name))
                .map_err(|e| StepError(format!("{}: {e}", tosca.join(name).display())))?;
        }
    }
    run_step(
        "examples/retrieval.py from the wheel",
        Command::new(&python)
            .arg(examples.join("retrieval.py"))
            .arg(&folder)
            .args(["--words", "16", "--index"])
            .arg(work.join("index.sqlite"))
            .current_dir(&work),
    )?;
    let _ = std::fs::remove_dir_all(&work);
    Ok(())
}

/// Builds the wheel (dev profile) and installs it into the venv; returns the wheel.
fn install_wfem(python: &Path, venv: &Path, root: &Path, target: &Path) -> Result<PathBuf, StepError> {
    let wheels = target.join("python-wheels");
    let _ = std::fs::remove_dir_all(&wheels);
    run_step(
        "maturin build (dev profile)",
        Command::new(bin(venv, "maturin"))
            .args([
                "build",
                "--profile",
                "dev",
                "--locked",
                "--auditwheel",
                "skip",
                "--manifest-path",
            ])
            .arg(root.join("crates/wfem-py/Cargo.toml"))
            .arg("--interpreter")
            .arg(python)
            .arg("--out")
            .arg(&wheels)
            .env("CARGO_TARGET_DIR", target),
    )?;
    let wheel = std::fs::read_dir(&wheels)
        .map_err(|e| StepError(format!("{}: {e}", wheels.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"));
    let Some(wheel) = wheel else {
        return fail(format!("maturin wrote no wheel into {}", wheels.display()));
    };
    run_step(
        "pip install wfem",
        pip_install(python).args(["--no-deps", "--force-reinstall"]).arg(&wheel),
    )?;
    Ok(wheel)
}

fn pip_install(python: &Path) -> Command {
    let mut cmd = Command::new(python);
    cmd.args(["-m", "pip", "install", "--disable-pip-version-check", "--no-input"]);
    cmd
}

/// Runs the suites; prints the time of each phase.
///
/// # Errors
/// Features of library crates that no other workspace crate turns on, enabled for the test run
/// so that their code is tested too.
pub const RUST_FEATURES: &str = "mesh-fem/nalgebra";

/// The workspace's library packages (every member with a `lib`, `cdylib` or `rlib` target),
/// from `cargo metadata`.
pub fn library_packages(cargo: &str, root: &Path) -> Result<Vec<String>, StepError> {
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--no-deps",
            "--format-version",
            "1",
            "--offline",
            "--locked",
        ])
        .current_dir(root)
        .output()
        .map_err(|e| StepError(format!("cargo metadata could not start: {e}")))?;
    if !out.status.success() {
        return fail(format!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let meta: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| StepError(format!("cargo metadata: {e}")))?;
    let mut names = Vec::new();
    for package in meta["packages"].as_array().into_iter().flatten() {
        let is_library = package["targets"].as_array().into_iter().flatten().any(|t| {
            t["kind"]
                .as_array()
                .into_iter()
                .flatten()
                .any(|k| matches!(k.as_str(), Some("lib" | "cdylib" | "rlib")))
        });
        if let (true, Some(name)) = (is_library, package["name"].as_str()) {
            names.push(name.to_string());
        }
    }
    names.sort();
    Ok(names)
}

/// `cargo check -p X --lib` for every library package, one at a time, so that each is compiled
/// with its own features only; any warning fails the step.
fn crates_alone(cargo: &str, root: &Path) -> Result<(), StepError> {
    let packages = library_packages(cargo, root)?;
    if packages.len() < 8 {
        return fail(format!("cargo metadata lists only {packages:?} as library packages"));
    }
    for package in &packages {
        eprintln!("==> cargo check -p {package} --lib (alone)");
        let out = Command::new(cargo)
            .args(["check", "--locked", "--lib", "--message-format", "short", "-p", package])
            .current_dir(root)
            .output()
            .map_err(|e| StepError(format!("cargo check could not start: {e}")))?;
        let stderr = String::from_utf8_lossy(&out.stderr);
        let warnings: Vec<&str> = stderr
            .lines()
            .filter(|l| l.contains(": warning: ") || l.contains(": error"))
            .collect();
        if !out.status.success() || !warnings.is_empty() {
            return fail(format!(
                "library crate {package} does not compile cleanly alone (cargo check -p {package} --lib):\n{}",
                if warnings.is_empty() {
                    stderr.to_string()
                } else {
                    warnings.join("\n")
                }
            ));
        }
    }
    Ok(())
}

/// The first failing step, with what to do about it.
pub fn run(opts: &TestAllOptions) -> Result<(), StepError> {
    let root = workspace_root();
    let target = target_dir(&root);
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut times = Vec::new();
    if !opts.python_only {
        let t = Instant::now();
        run_step(
            "Rust suite",
            Command::new(&cargo)
                .args(["test", "--workspace", "--locked", "--features", RUST_FEATURES])
                .current_dir(&root),
        )?;
        times.push(("Rust suite (cargo test --workspace --locked)", t.elapsed()));
        let t = Instant::now();
        crates_alone(&cargo, &root)?;
        times.push(("library crates checked alone", t.elapsed()));
    }
    if !opts.rust_only {
        let t = Instant::now();
        let venv = target.join("python-venv");
        let python = ensure_venv(&venv)?;
        ensure_requirements(
            &python,
            &venv,
            &root.join("crates/wfem-py/requirements-test.txt"),
            false,
        )?;
        ensure_requirements(
            &python,
            &venv,
            &root.join("crates/wfem-py/requirements-test-nodeps.txt"),
            true,
        )?;
        times.push(("Python environment", t.elapsed()));
        let t = Instant::now();
        let wheel = install_wfem(&python, &venv, &root, &target)?;
        times.push(("wfem extension (maturin, dev profile)", t.elapsed()));
        let t = Instant::now();
        let mut pytest = Command::new(&python);
        pytest
            .args(["-m", "pytest", "-q"])
            .arg(root.join("crates/wfem-py/tests"))
            .args(&opts.pytest_args)
            .current_dir(&root);
        // The CLI the Rust suite built, for the tests comparing its numbers with the package's.
        let cli = target
            .join("debug")
            .join(if cfg!(windows) { "wfem.exe" } else { "wfem" });
        if cli.is_file() && std::env::var_os("WFEM_CLI").is_none() {
            pytest.env("WFEM_CLI", &cli);
        }
        run_step("Python suite", &mut pytest)?;
        times.push(("Python suite (pytest)", t.elapsed()));
        let t = Instant::now();
        wheel_route(&root, &target, &wheel)?;
        times.push(("wheel route (fresh venv: quick start, both examples)", t.elapsed()));
    }
    eprintln!("==> all suites passed");
    for (name, d) in times {
        eprintln!("    {:>6.0} s  {name}", d.as_secs_f64());
    }
    Ok(())
}
