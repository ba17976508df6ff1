//! Issue #16: every subcommand driven with hostile values of every argument — diffusion times,
//! degrees, eigenpairs, scales, k, levels, persistence, fields, indexes, output paths, special
//! files (FIFOs, directories, devices), empty files, huge numbers, NaN/∞ strings, negative
//! numbers. Each call must end, under a timeout, in a typed error (exit 1 with one line
//! `wfem: error: …`, or clap's exit 2) or in a correct result (exit 0, outputs of the right
//! shape without NaN). No panic, no hang, no library names in messages, inputs never modified.
//!
//! Huge diffusion times (up to the largest double) were wrong in wfem-heat when this table was
//! written (the rational method refused t = f64::MAX, dense gave NaN and the fast path failed at
//! 1e300, the HKS at 1e300 was 0); the lead fixed them in wfem-heat, and the tests at the end
//! check the t → ∞ limits exactly.

use super::common::{read_csv, read_npy};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Generous: the slowest row takes well under a second; a hang is what this catches.
const TIMEOUT: Duration = Duration::from_secs(120);

/// What a row must give.
#[derive(Clone, Debug)]
enum Want {
    /// Exit 1, one line `wfem: error: …` containing every fragment.
    Typed(&'static [&'static str]),
    /// Exit 2 from clap (`error: …` and a usage hint).
    Clap,
    /// Exit 0 and these checks.
    Ok(&'static [Check]),
}

/// A check of a successful row; paths are relative to the row's output folder.
#[derive(Clone, Debug)]
enum Check {
    /// Standard output contains the text.
    Stdout(&'static str),
    /// Standard error contains the text.
    Stderr(&'static str),
    /// A CSV field file with a header and `rows` × `cols` finite values.
    Csv(&'static str, usize, usize),
    /// An NPY file of float64 with shape (rows,) (cols = 1) or (rows, cols), finite values,
    /// and its `.json` sidecar naming `cols` columns.
    Npy(&'static str, usize, usize),
    /// A file exists and is not empty.
    File(&'static str),
    /// Every value of a CSV column equals this (to 1e-9 relative).
    CsvConst(&'static str, f64),
}

struct Row {
    args: String,
    want: Want,
}

fn row(args: &str, want: Want) -> Row {
    Row {
        args: args.to_string(),
        want,
    }
}

/// The result of one call.
struct Outcome {
    code: Option<i32>,
    stdout: String,
    stderr: String,
    timed_out: bool,
}

/// Runs the binary with a timeout (killed when it expires).
fn run(args: &[String], cwd: &Path) -> Outcome {
    let mut child = Command::new(env!("CARGO_BIN_EXE_wfem"))
        .args(args)
        .current_dir(cwd)
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the wfem binary runs");
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let (code, timed_out) = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break (status.code(), false);
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            break (None, true);
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Outcome {
        code,
        stdout: reader.join().unwrap_or_default(),
        stderr: err_reader.join().unwrap_or_default(),
        timed_out,
    }
}

/// Splits a row's arguments on spaces and fills in `{d}` (fixtures) and `{o}` (the row's own
/// output folder).
fn expand(args: &str, d: &Path, o: &Path) -> Vec<String> {
    args.split(' ')
        .filter(|a| !a.is_empty())
        .map(|a| {
            a.replace("{d}", d.to_str().unwrap())
                .replace("{o}", o.to_str().unwrap())
                .replace("{MAX}", "1.7976931348623157e308")
                .replace("{U64}", "18446744073709551615")
        })
        .collect()
}

fn check(c: &Check, o: &Path, out: &Outcome) -> Result<(), String> {
    match c {
        Check::Stdout(s) if !out.stdout.contains(s) => Err(format!("stdout lacks {s:?}")),
        Check::Stderr(s) if !out.stderr.contains(s) => Err(format!("stderr lacks {s:?}")),
        Check::Stdout(_) | Check::Stderr(_) => Ok(()),
        Check::File(f) => match std::fs::metadata(o.join(f)) {
            Ok(m) if m.is_file() && m.len() > 0 => Ok(()),
            _ => Err(format!("{f} missing or empty")),
        },
        Check::Csv(f, rows, cols) => {
            let (header, data) = read_csv(&o.join(f))?;
            if header.len() != *cols || data.len() != *rows || data.iter().any(|r| r.len() != *cols) {
                return Err(format!(
                    "{f}: {} × {} (header {}), expected {rows} × {cols}",
                    data.len(),
                    data.first().map_or(0, Vec::len),
                    header.len()
                ));
            }
            if data.iter().flatten().any(|v| !v.is_finite()) {
                return Err(format!("{f}: non-finite value"));
            }
            Ok(())
        }
        Check::CsvConst(f, value) => {
            let (_, data) = read_csv(&o.join(f))?;
            let bad = data.iter().flatten().find(|v| (*v - value).abs() > 1e-9 * value.abs());
            match bad {
                Some(v) => Err(format!("{f}: {v} ≠ {value}")),
                None => Ok(()),
            }
        }
        Check::Npy(f, rows, cols) => {
            let (shape, data) = read_npy(&o.join(f))?;
            let want = if *cols == 1 { vec![*rows] } else { vec![*rows, *cols] };
            if shape != want || data.len() != rows * cols {
                return Err(format!(
                    "{f}: shape {shape:?} ({} values), expected {want:?}",
                    data.len()
                ));
            }
            if data.iter().any(|v| !v.is_finite()) {
                return Err(format!("{f}: non-finite value"));
            }
            let sidecar = o.join(Path::new(f).with_extension("json"));
            let meta: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&sidecar).map_err(|e| format!("{}: {e}", sidecar.display()))?)
                    .map_err(|e| e.to_string())?;
            if meta["columns"].as_array().map(Vec::len) != Some(*cols) {
                return Err(format!("{}: columns {}", sidecar.display(), meta["columns"]));
            }
            Ok(())
        }
    }
}

/// Everything wrong with one row's outcome.
fn judge(r: &Row, o: &Path, out: &Outcome) -> Vec<String> {
    let mut bad = Vec::new();
    if out.timed_out {
        bad.push(format!("hang: no exit after {TIMEOUT:?}"));
        return bad;
    }
    for marker in ["panicked", "stack backtrace", "RUST_BACKTRACE"] {
        if out.stderr.contains(marker) {
            bad.push(format!("panic text {marker:?} in stderr"));
        }
    }
    // Library names (LoadOptions::…, RepairOptions::…) never reach a user of the CLI.
    if out.stderr.contains("Options::") || out.stderr.contains("TriMesh::") || out.stdout.contains("Options::") {
        bad.push("a library name in a message".into());
    }
    match &r.want {
        Want::Typed(fragments) => {
            if out.code != Some(1) {
                bad.push(format!("exit {:?}, expected 1", out.code));
            }
            let lines: Vec<&str> = out.stderr.lines().filter(|l| l.starts_with("wfem: error:")).collect();
            if lines.len() != 1 || !out.stderr.lines().last().is_some_and(|l| l.starts_with("wfem: error:")) {
                bad.push("not exactly one final `wfem: error:` line".into());
            }
            for f in *fragments {
                if !lines.iter().any(|l| l.contains(f)) {
                    bad.push(format!("message lacks {f:?}"));
                }
            }
        }
        Want::Clap => {
            if out.code != Some(2) || !out.stderr.starts_with("error:") {
                bad.push(format!("exit {:?}, expected clap's 2", out.code));
            }
        }
        Want::Ok(checks) => {
            if out.code != Some(0) {
                bad.push(format!("exit {:?}, expected 0", out.code));
            } else {
                bad.extend(checks.iter().filter_map(|c| check(c, o, out).err()));
            }
        }
    }
    bad
}

/// Fixture files in `d`.
struct Fixture {
    _dir: tempfile::TempDir,
    d: PathBuf,
}

/// Vertices of the small test sphere (icosphere level 1).
const N: usize = 42;

fn write(d: &Path, name: &str, text: impl AsRef<[u8]>) {
    std::fs::write(d.join(name), text).unwrap();
}

fn mkfifo(path: &Path) -> bool {
    Command::new("mkfifo").arg(path).status().is_ok_and(|s| s.success())
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_path_buf();
    let sphere = mesh_fem::generate::icosphere(1);
    assert_eq!(sphere.n_vertices(), N);
    mesh_fem::io::write_mesh(&d.join("sphere.off"), &sphere).unwrap();
    mesh_fem::io::write_mesh(&d.join("sphere.ply"), &sphere).unwrap();
    mesh_fem::io::write_mesh(&d.join("small.off"), &mesh_fem::generate::icosphere(0)).unwrap();
    // The sphere with an unreferenced vertex first (renumbering: file vertex i + 1 is mesh
    // vertex i).
    let mut obj = String::from("v 9 9 9\n");
    for p in sphere.positions() {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in sphere.faces() {
        obj += &format!("f {} {} {}\n", f[0] + 2, f[1] + 2, f[2] + 2);
    }
    write(&d, "unref.obj", &obj);
    // A triangle soup: every face with its own three vertices.
    let mut soup = String::new();
    for (k, f) in sphere.faces().iter().enumerate() {
        for &v in f {
            let p = sphere.positions()[v as usize];
            soup += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        soup += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    write(&d, "soup.obj", &soup);
    // A cube of quads.
    write(
        &d,
        "quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
    );
    write(&d, "empty.off", "");
    write(&d, "garbage.off", "OFF\nthis is not a mesh\n");
    // Fields on the sphere.
    let x: Vec<f64> = sphere.positions().iter().map(|p| p[0]).collect();
    let lines = |v: &[f64]| v.iter().map(|a| format!("{a}\n")).collect::<String>();
    write(&d, "f.csv", lines(&x));
    write(
        &d,
        "bom.csv",
        [b"\xef\xbb\xbf".as_slice(), lines(&x).as_bytes()].concat(),
    );
    write(&d, "big.csv", lines(&vec![1e308; N]));
    write(&d, "max.csv", lines(&vec![f64::MAX; N]));
    write(&d, "tiny.csv", lines(&vec![1e-310; N]));
    write(&d, "short.csv", lines(&x[..N - 1]));
    write(&d, "long.csv", lines(&vec![1.0; N + 1]));
    write(&d, "nan.csv", "nan\n".repeat(N));
    write(&d, "inf.csv", "1\n".repeat(N - 1) + "inf\n");
    write(&d, "text.csv", "a\nb\nc\n");
    write(&d, "empty.csv", "");
    let unref_x: Vec<f64> = std::iter::once(9.0).chain(x.iter().copied()).collect();
    write(&d, "unref_f.csv", lines(&unref_x));
    mesh_fem::io::write_field(&d.join("f.npy"), &sphere, &[("x", &x)], None).unwrap();
    // Special files.
    for name in ["dir.off", "dir.csv", "dir.json", "outdir.npy", "outdir.png"] {
        std::fs::create_dir(d.join(name)).unwrap();
    }
    for name in ["fifo.off", "fifo.csv", "fifo.json", "fifo_out.npy"] {
        assert!(mkfifo(&d.join(name)), "mkfifo is needed for this test");
    }
    std::fs::create_dir_all(d.join("ops_blocked/lumped_mass.mtx")).unwrap();
    std::fs::create_dir_all(d.join("demo_blocked/report.md")).unwrap();
    write(&d, "plain", "x");
    // A retrieval index built by the CLI, and hand-edited ones.
    let built = run(
        &expand(
            "retrieval build {d}/sphere.off {d}/small.off --out {d}/index.json --words 4 --spatial off",
            &d,
            &d,
        ),
        &d,
    );
    assert_eq!(built.code, Some(0), "{}", built.stderr);
    let index: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("index.json")).unwrap()).unwrap();
    let mut big = index.clone();
    for e in big["entries"].as_array_mut().unwrap() {
        e["bag"] = serde_json::json!(vec![1e308; 4]);
    }
    write(&d, "big_index.json", big.to_string());
    // The index format nests the vocabulary (settings, z-score statistics, words, σ).
    let mut sigma = index.clone();
    sigma["vocabulary"]["sigma"] = serde_json::json!(-1.0);
    write(&d, "sigma_index.json", sigma.to_string());
    let mut eigs = index.clone();
    eigs["vocabulary"]["descriptor"]["eigenpairs"] = serde_json::json!(u64::MAX);
    write(&d, "eigs_index.json", eigs.to_string());
    let mut words = index.clone();
    words["vocabulary"]["words"][0] = serde_json::json!([1.0]);
    write(&d, "words_index.json", words.to_string());
    let mut times = index.clone();
    times["vocabulary"]["descriptor"]["descriptor"]["tau_step"] = serde_json::json!(-1.0);
    write(&d, "times_index.json", times.to_string());
    let mut zscore = index;
    zscore["vocabulary"]["standardizer"]["std"][0] = serde_json::json!(0.0);
    write(&d, "zscore_index.json", zscore.to_string());
    write(&d, "garbage.json", "{not json");
    write(&d, "empty.json", "");
    Fixture { _dir: dir, d }
}

/// Hash of every regular file under `d` (inputs must never change).
fn snapshot(d: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    for entry in std::fs::read_dir(d).unwrap() {
        let p = entry.unwrap().path();
        if std::fs::symlink_metadata(&p).unwrap().is_file() {
            out.insert(p.clone(), std::fs::read(&p).unwrap());
        }
    }
    out
}

use Check::*;
use Want::{Clap, Typed};

const fn ok(checks: &'static [Check]) -> Want {
    Want::Ok(checks)
}

fn info_rows() -> Vec<Row> {
    vec![
        row("info {d}/sphere.off", ok(&[Stdout("vertices              42")])),
        row("info {d}/sphere.off --json", ok(&[Stdout("\"usable\": true")])),
        row("info {d}/missing.off", Typed(&["missing.off"])),
        row("info {d}/empty.off", Typed(&["empty.off"])),
        row("info {d}/garbage.off", Typed(&["garbage.off"])),
        row("info {d}/fifo.off", Typed(&["FIFO", "not a regular file"])),
        row("info {d}/dir.off", Typed(&["directory"])),
        row("info /dev/null", Typed(&["unknown mesh format"])),
        row("info {d}/plain", Typed(&["unknown mesh format"])),
        // Not usable, but info reports it (and names the flag that fixes it).
        row(
            "info {d}/unref.obj",
            ok(&[Stdout("--repair unreferenced"), Stdout("NOT usable")]),
        ),
        row(
            "info {d}/unref.obj --repair unreferenced",
            ok(&[
                Stdout("vertices              42"),
                Stderr("dropped 1 unreferenced vertex"),
            ]),
        ),
        row("info {d}/quad.obj", Typed(&["--triangulate"])),
        row(
            "info {d}/quad.obj --triangulate",
            ok(&[Stdout("faces                 12")]),
        ),
        row(
            "info {d}/soup.obj --repair weld",
            ok(&[
                Stdout("vertices              42"),
                Stderr("merged 198 duplicate vertices"),
            ]),
        ),
        row(
            "info {d}/soup.obj --repair all",
            ok(&[Stdout("vertices              42"), Stdout("usable")]),
        ),
        row("info {d}/sphere.off --repair bogus", Clap),
        row(
            "info {d}/sphere.off --repair weld --weld-tolerance -1",
            Typed(&["--weld-tolerance"]),
        ),
        row(
            "info {d}/sphere.off --repair weld --weld-tolerance nan",
            Typed(&["--weld-tolerance"]),
        ),
        row(
            "info {d}/sphere.off --repair weld --weld-tolerance inf",
            Typed(&["--weld-tolerance"]),
        ),
        row(
            "info {d}/sphere.off --weld-tolerance 0.1",
            Typed(&["--repair duplicate-vertices"]),
        ),
        row(
            "info {d}/sphere.off --repair weld --weld-tolerance 1e300",
            ok(&[Stdout("vertices")]),
        ),
        row("info", Clap),
        row("info {d}/sphere.off --progress sometimes", Clap),
    ]
}

fn operators_rows() -> Vec<Row> {
    vec![
        row(
            "operators {d}/sphere.off --out {o}/ops",
            ok(&[
                File("ops/stiffness.mtx"),
                File("ops/mass.mtx"),
                File("ops/lumped_mass.mtx"),
            ]),
        ),
        row(
            "operators {d}/sphere.off --out {o}/a/b/c",
            ok(&[File("a/b/c/mass.mtx")]),
        ),
        row(
            "operators {d}/sphere.off --out {d}/plain",
            Typed(&["plain", "not a folder"]),
        ),
        row("operators {d}/sphere.off --out {d}/plain/sub", Typed(&["plain"])),
        row(
            "operators {d}/sphere.off --out {d}/ops_blocked",
            Typed(&["lumped_mass.mtx", "directory"]),
        ),
        row(
            "operators {d}/unref.obj --out {o}/ops",
            Typed(&["vertex 0", "--repair unreferenced"]),
        ),
        row(
            "operators {d}/unref.obj --repair unreferenced --out {o}/ops",
            ok(&[File("ops/mass.mtx"), Stdout("for the repaired mesh")]),
        ),
        row("operators {d}/fifo.off --out {o}/ops", Typed(&["FIFO"])),
        row("operators {d}/sphere.off --out {o}/ops --lumped bogus", Clap),
    ]
}

fn heat_rows() -> Vec<Row> {
    let heat = |extra: &str, want: Want| row(&format!("heat {{d}}/sphere.off {extra}"), want);
    vec![
        // Diffusion times.
        heat("--t 0.1 --source 3 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat("--t 0.01 0.1 1 --source 3 -o {o}/k.npy", ok(&[Npy("k.npy", N, 3)])),
        heat("--t 1e-300 --source 3 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat(
            "--t 1e-9 --source 3 --method fast -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat("--t 1e6 --source 3 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat(
            "--t {MAX} --source 3 --kernel lumped -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        heat(
            "--t {MAX} --source 3 --kernel linear -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        heat(
            "--t {MAX} --source 3 --method spectral -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        heat(
            "--t 1e-300 {MAX} --source 3 -o {o}/k.png",
            ok(&[File("k-t1e-300.png"), File("k-t1.7976931348623157e308.png")]),
        ),
        heat("--t 0 --source 3 -o {o}/k.csv", Typed(&["--t 0", "finite t > 0"])),
        heat("--t -1 --source 3 -o {o}/k.csv", Typed(&["--t -1"])),
        heat("--t -0 --source 3 -o {o}/k.csv", Typed(&["--t"])),
        heat("--t nan --source 3 -o {o}/k.csv", Typed(&["--t NaN"])),
        heat("--t NaN --source 3 -o {o}/k.csv", Typed(&["--t NaN"])),
        heat("--t inf --source 3 -o {o}/k.csv", Typed(&["--t inf"])),
        heat("--t -inf --source 3 -o {o}/k.csv", Clap),
        heat("--t 1e999 --source 3 -o {o}/k.csv", Typed(&["--t inf"])),
        heat("--t abc --source 3 -o {o}/k.csv", Clap),
        heat(
            "--t 0.1 0.1 --source 3 -o {o}/k.png",
            Typed(&["--t 0.1 is given twice"]),
        ),
        heat("--t 0.1 0.1 --source 3 -o {o}/k.npy", Typed(&["given twice"])),
        heat("--source 3 -o {o}/k.csv", Clap),
        // Sources and fields.
        heat("--t 0.1 --source 41 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat("--t 0.1 --source 42 -o {o}/k.csv", Typed(&["--source 42", "0..=41"])),
        heat(
            "--t 0.1 --source 4294967295 -o {o}/k.csv",
            Typed(&["--source 4294967295"]),
        ),
        heat("--t 0.1 --source 4294967296 -o {o}/k.csv", Clap),
        heat("--t 0.1 --source -1 -o {o}/k.csv", Clap),
        heat("--t 0.1 -o {o}/k.csv", Typed(&["--source", "--field"])),
        heat("--t 0.1 --source 1 --field {d}/f.csv -o {o}/k.csv", Clap),
        heat("--t 0.1 --field {d}/f.csv -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat("--t 0.1 --field {d}/f.npy -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat("--t 0.1 --field {d}/bom.csv -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat(
            "--t 0.1 --field {d}/big.csv -o {o}/k.csv",
            ok(&[CsvConst("k.csv", 1e308)]),
        ),
        heat(
            "--t 0.1 --field {d}/max.csv --method fast -o {o}/k.csv",
            ok(&[CsvConst("k.csv", f64::MAX)]),
        ),
        heat(
            "--t 0.1 --field {d}/tiny.csv -o {o}/k.csv",
            ok(&[CsvConst("k.csv", 1e-310)]),
        ),
        heat(
            "--t 0.1 --field {d}/short.csv -o {o}/k.csv",
            Typed(&["41 values", "42 vertices"]),
        ),
        heat("--t 0.1 --field {d}/long.csv -o {o}/k.csv", Typed(&["43 values"])),
        heat("--t 0.1 --field {d}/nan.csv -o {o}/k.csv", Typed(&["NaN"])),
        heat("--t 0.1 --field {d}/inf.csv -o {o}/k.csv", Typed(&["inf", "vertex 41"])),
        heat("--t 0.1 --field {d}/text.csv -o {o}/k.csv", Typed(&["text.csv"])),
        heat("--t 0.1 --field {d}/empty.csv -o {o}/k.csv", Typed(&["0 values"])),
        heat("--t 0.1 --field {d}/fifo.csv -o {o}/k.csv", Typed(&["FIFO"])),
        heat("--t 0.1 --field {d}/dir.csv -o {o}/k.csv", Typed(&["directory"])),
        heat("--t 0.1 --field /dev/zero -o {o}/k.csv", Clap),
        heat("--t 0.1 --field {d}/dir.csv/../f.txt -o {o}/k.csv", Clap),
        heat("--t 0.1 --field {d}/missing.csv -o {o}/k.csv", Typed(&["missing.csv"])),
        heat("--t 0.1 --field {d}/sphere.off -o {o}/k.csv", Clap),
        // Methods and the options that go with them.
        heat(
            "--t 0.1 --source 3 --method dense -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --method fast -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral --eigenpairs 42 -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1), Stderr("estimated relative error")]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 1e-4 --source 3 --method spectral --eigenpairs 5 -o {o}/k.csv",
            Typed(&["--method spectral is off by", "--allow-inaccurate"]),
        ),
        heat(
            "--t 1e-4 --source 3 --method spectral --eigenpairs 5 --allow-inaccurate -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1), Stderr("written anyway")]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral --eigenpairs 0 -o {o}/k.csv",
            Typed(&["--eigenpairs 0", "1..=42"]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral --eigenpairs 43 -o {o}/k.csv",
            Typed(&["--eigenpairs 43"]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral --eigenpairs {U64} -o {o}/k.csv",
            Typed(&["--eigenpairs 18446744073709551615"]),
        ),
        heat(
            "--t 0.1 --source 3 --method spectral --eigenpairs -5 -o {o}/k.csv",
            Clap,
        ),
        heat(
            "--t 0.1 --source 3 --method taylor -o {o}/k.csv",
            Typed(&["--method taylor is off by"]),
        ),
        heat(
            "--t 0.1 --source 3 --method taylor --allow-inaccurate -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 1e-9 --source 3 --method taylor -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --method backward-euler -o {o}/k.csv",
            Typed(&["--method backward-euler is off by"]),
        ),
        heat(
            "--t 0.1 --source 3 --method backward-euler --allow-inaccurate -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --method rational --allow-inaccurate -o {o}/k.csv",
            Typed(&["--allow-inaccurate applies to"]),
        ),
        heat(
            "--t 0.1 --source 3 --method fast --eigenpairs 10 -o {o}/k.csv",
            Typed(&["--eigenpairs applies to --method spectral"]),
        ),
        heat(
            "--t 0.1 --source 3 --eigenpairs 10 -o {o}/k.csv",
            Typed(&["--eigenpairs applies to --method spectral"]),
        ),
        heat(
            "--t 0.1 --source 3 --method fast --backend lu -o {o}/k.csv",
            Typed(&["--backend applies to --method rational"]),
        ),
        heat(
            "--t 0.1 --source 3 --method dense --degree 8 -o {o}/k.csv",
            Typed(&["--degree applies to --method rational"]),
        ),
        heat("--t 0.1 --source 3 --method bogus -o {o}/k.csv", Clap),
        heat("--t 0.1 --source 3 --degree 16 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat("--t 0.1 --source 3 --degree 2 -o {o}/k.csv", ok(&[Csv("k.csv", N, 1)])),
        heat(
            "--t 0.1 --source 3 --degree 0 -o {o}/k.csv",
            Typed(&["--degree 0", "one of"]),
        ),
        heat("--t 0.1 --source 3 --degree 9 -o {o}/k.csv", Typed(&["--degree 9"])),
        heat("--t 0.1 --source 3 --degree 17 -o {o}/k.csv", Typed(&["--degree 17"])),
        heat("--t 0.1 --source 3 --degree {U64} -o {o}/k.csv", Typed(&["--degree"])),
        heat("--t 0.1 --source 3 --degree -2 -o {o}/k.csv", Clap),
        heat(
            "--t 0.1 --source 3 --backend lu -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --backend minres -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --backend multishift -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --kernel lumped -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat(
            "--t 0.1 --source 3 --kernel linear -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        heat("--t 0.1 --source 3 --kernel bogus -o {o}/k.csv", Clap),
        // Output paths.
        heat("--t 0.1 --source 3 -o {o}/k.ply", ok(&[File("k.ply")])),
        heat(
            "--t 0.01 0.1 --source 3 -o {o}/k.png",
            ok(&[File("k-t0.01.png"), File("k-t0.1.png")]),
        ),
        heat("--t 0.1 --source 3 --up -z -o {o}/k.png", ok(&[File("k.png")])),
        heat("--t 0.1 --source 3 --up x -o {o}/k.png", ok(&[File("k.png")])),
        heat("--t 0.1 --source 3 --up w -o {o}/k.png", Clap),
        heat("--t 0.1 --source 3 -o {o}/k.txt", Clap),
        heat("--t 0.1 --source 3 -o {o}/k.obj", Clap),
        heat("--t 0.1 --source 3 -o {o}/k", Clap),
        heat("--t 0.1 --source 3 -o {o}/.png", Clap),
        heat(
            "--t 0.1 --source 3 -o {o}/nodir/k.npy",
            Typed(&["nodir", "does not exist"]),
        ),
        heat(
            "--t 0.1 --source 3 -o {d}/plain/k.npy",
            Typed(&["plain", "not a folder"]),
        ),
        heat(
            "--t 0.1 --source 3 -o {d}/outdir.npy",
            Typed(&["outdir.npy", "directory"]),
        ),
        heat(
            "--t 0.1 --source 3 -o {d}/outdir.png",
            Typed(&["outdir.png", "directory"]),
        ),
        heat(
            "--t 0.1 --source 3 -o {d}/fifo_out.npy",
            Typed(&["fifo_out.npy", "not a regular file"]),
        ),
        heat(
            "--t 0.1 --field {d}/f.csv -o {d}/f.csv",
            Typed(&["f.csv", "input file"]),
        ),
        row(
            "heat {d}/sphere.ply --t 0.1 --source 3 -o {d}/sphere.ply",
            Typed(&["sphere.ply", "input file"]),
        ),
        heat(
            "--t 0.1 --field {d}/f.npy -o {d}/f.npy",
            Typed(&["f.npy", "input file"]),
        ),
        // 65 figures are refused before any work; 1001 times too.
        row(
            &format!(
                "heat {{d}}/sphere.off --source 3 -o {{o}}/k.png --t {}",
                (1..=65).map(|i| format!("{i}e-3")).collect::<Vec<_>>().join(" ")
            ),
            Typed(&["-o 65", "1..=64"]),
        ),
        row(
            &format!(
                "heat {{d}}/sphere.off --source 3 -o {{o}}/k.npy --t {}",
                (1..=1001).map(|i| format!("{i}e-3")).collect::<Vec<_>>().join(" ")
            ),
            Typed(&["--t with 1001 values"]),
        ),
        // Meshes.
        row(
            "heat {d}/unref.obj --t 0.1 --source 3 -o {o}/k.csv",
            Typed(&["--repair unreferenced"]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --source 3 -o {o}/k.csv",
            ok(&[
                Csv("k.csv", N, 1),
                Stderr("vertex numbering changed"),
                Stderr("vertex 3 of the file is vertex 2"),
            ]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --source 0 -o {o}/k.csv",
            Typed(&["--source 0", "dropped"]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --field {d}/unref_f.csv -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --field {d}/f.csv -o {o}/k.npy",
            ok(&[Npy("k.npy", N, 1)]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --field {d}/long.csv -o {o}/k.npy",
            // 43 values: one per vertex of the file, which has 43.
            ok(&[Npy("k.npy", N, 1)]),
        ),
        row(
            "heat {d}/unref.obj --repair unreferenced --t 0.1 --field {d}/short.csv -o {o}/k.npy",
            Typed(&["41 values", "43", "42"]),
        ),
        row(
            "heat {d}/soup.obj --repair weld --t 0.1 --source 3 -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1)]),
        ),
        row(
            "heat {d}/quad.obj --t 0.1 --source 0 -o {o}/k.csv",
            Typed(&["--triangulate"]),
        ),
        row(
            "heat {d}/quad.obj --triangulate --t 0.1 --source 0 -o {o}/k.csv",
            ok(&[Csv("k.csv", 8, 1)]),
        ),
        row("heat {d}/fifo.off --t 0.1 --source 0 -o {o}/k.csv", Typed(&["FIFO"])),
        row(
            "heat {d}/dir.off --t 0.1 --source 0 -o {o}/k.csv",
            Typed(&["directory"]),
        ),
        row(
            "heat {d}/empty.off --t 0.1 --source 0 -o {o}/k.csv",
            Typed(&["empty.off"]),
        ),
    ]
}

fn distance_rows() -> Vec<Row> {
    let dist = |extra: &str, want: Want| row(&format!("distance {{d}}/sphere.off {extra}"), want);
    vec![
        dist("--t 0.1 --from 3 -o {o}/d.npy", ok(&[Npy("d.npy", N, 1)])),
        dist("--t 0.1 --from 3 --kind linear -o {o}/d.csv", ok(&[Csv("d.csv", N, 1)])),
        dist("--t 0.1 --from 3 -o {o}/d.png", ok(&[File("d.png")])),
        dist("--t 1e300 --from 3 -o {o}/d.npy", ok(&[Npy("d.npy", N, 1)])),
        dist("--t 0 --from 3 -o {o}/d.npy", Typed(&["--t 0"])),
        dist("--t -1 --from 3 -o {o}/d.npy", Typed(&["--t -1"])),
        dist("--t nan --from 3 -o {o}/d.npy", Typed(&["--t NaN"])),
        dist("--t inf --from 3 -o {o}/d.npy", Typed(&["--t inf"])),
        dist("--t 0.1 --from 42 -o {o}/d.npy", Typed(&["--from 42"])),
        dist("--t 0.1 --from {U64} -o {o}/d.npy", Clap),
        dist("--t 0.1 --from -1 -o {o}/d.npy", Clap),
        dist("--t 0.1 --from 3 --degree 0 -o {o}/d.npy", Typed(&["--degree 0"])),
        dist("--t 0.1 --from 3 --degree 8 -o {o}/d.npy", ok(&[Npy("d.npy", N, 1)])),
        dist("--t 0.1 --from 3 --kind bogus -o {o}/d.npy", Clap),
        dist("--t 0.1 --from 3 -o {o}/nodir/d.npy", Typed(&["does not exist"])),
        dist("--t 0.1 --from 3 -o {d}/outdir.npy", Typed(&["directory"])),
        row(
            "distance {d}/unref.obj --t 0.1 --from 3 -o {o}/d.npy",
            Typed(&["--repair unreferenced"]),
        ),
        row(
            "distance {d}/unref.obj --repair unreferenced --t 0.1 --from 3 -o {o}/d.npy",
            ok(&[Npy("d.npy", N, 1)]),
        ),
        row("distance {d}/fifo.off --t 0.1 --from 3 -o {o}/d.npy", Typed(&["FIFO"])),
    ]
}

fn approx_rows() -> Vec<Row> {
    let approx = |extra: &str, want: Want| row(&format!("approx {{d}}/sphere.off {extra}"), want);
    vec![
        approx(
            "--field {d}/f.csv --persistence 0.1 -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21), Stdout("Linf error")]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --num-times 3 -o {o}/a.npy",
            ok(&[Npy("a.npy", N, 7)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 -o {o}/a.png",
            ok(&[File("a-f.png"), File("a-glob.png"), File("a-loc.png")]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0 -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 5 -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.5 --absolute -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --coefficients interpolate -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        // A field of 1e308 is decomposed at a scale 2^−e and scaled back, so even the
        // least-squares rule stays finite: written, with the warning that it is far from f
        // (the proportional rule and the anchored default are written too).
        approx(
            "--field {d}/big.csv --persistence 0.1 --coefficients least-squares -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx("--field {d}/big.csv -o {o}/a.csv", ok(&[Csv("a.csv", N, 21)])),
        // The library's defaults without options; --absolute needs a value.
        approx("--field {d}/f.csv -o {o}/a.csv", ok(&[Csv("a.csv", N, 21)])),
        approx(
            "--field {d}/f.csv --absolute -o {o}/a.csv",
            Typed(&["--absolute needs --persistence"]),
        ),
        approx("--field {d}/f.csv --coefficients magic -o {o}/a.csv", Clap),
        approx(
            "--field {d}/big.csv --persistence 0.1 --coefficients feature-values -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence -1 -o {o}/a.csv",
            Typed(&["--persistence -1"]),
        ),
        approx(
            "--field {d}/f.csv --persistence nan -o {o}/a.csv",
            Typed(&["--persistence NaN"]),
        ),
        approx(
            "--field {d}/f.csv --persistence inf -o {o}/a.csv",
            Typed(&["--persistence inf"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --num-times 0 -o {o}/a.csv",
            Typed(&["--num-times 0", "1..=100"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --num-times 101 -o {o}/a.csv",
            Typed(&["--num-times 101"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --num-times 1000000 -o {o}/a.csv",
            Typed(&["--num-times 1000000"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --num-times {U64} -o {o}/a.csv",
            Typed(&["--num-times 18446744073709551615"]),
        ),
        approx("--field {d}/f.csv --persistence 0.1 --num-times -1 -o {o}/a.csv", Clap),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k 0 -o {o}/a.csv",
            Typed(&["--k 0", "2..=42"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k 1 -o {o}/a.csv",
            Typed(&["--k 1"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k 2 -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k 42 -o {o}/a.csv",
            ok(&[Csv("a.csv", N, 21)]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k 43 -o {o}/a.csv",
            Typed(&["--k 43"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 --k {U64} -o {o}/a.csv",
            Typed(&["--k"]),
        ),
        approx(
            "--field {d}/short.csv --persistence 0.1 -o {o}/a.csv",
            Typed(&["41 values"]),
        ),
        approx("--field {d}/nan.csv --persistence 0.1 -o {o}/a.csv", Typed(&["NaN"])),
        approx("--field {d}/fifo.csv --persistence 0.1 -o {o}/a.csv", Typed(&["FIFO"])),
        approx(
            "--field {d}/dir.csv --persistence 0.1 -o {o}/a.csv",
            Typed(&["directory"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 -o {d}/f.csv",
            Typed(&["input file"]),
        ),
        approx(
            "--field {d}/f.csv --persistence 0.1 -o {o}/nodir/a.csv",
            Typed(&["does not exist"]),
        ),
        approx("--persistence 0.1 -o {o}/a.csv", Clap),
        row(
            "approx {d}/unref.obj --repair unreferenced --field {d}/unref_f.csv --persistence 0.1 -o {o}/a.npy",
            ok(&[Npy("a.npy", N, 21)]),
        ),
    ]
}

fn hks_rows() -> Vec<Row> {
    let hks = |extra: &str, want: Want| row(&format!("hks {{d}}/sphere.off {extra}"), want);
    vec![
        hks("-o {o}/h.npy", ok(&[Npy("h.npy", N, 16)])),
        hks("--num-times 1 -o {o}/h.csv", ok(&[Csv("h.csv", N, 1)])),
        hks("--num-times 1000 -o {o}/h.npy", ok(&[Npy("h.npy", N, 1000)])),
        hks("--times 0.1 1 10 -o {o}/h.csv", ok(&[Csv("h.csv", N, 3)])),
        hks(
            "--times 0.1 1 -o {o}/h.png",
            ok(&[File("h-t0.1.png"), File("h-t1.0.png")]),
        ),
        hks("--num-times 3 -o {o}/h.png", ok(&[Stdout("h-t")])),
        hks("--kernel lumped --scales 4 -o {o}/h.npy", ok(&[Npy("h.npy", N, 4)])),
        hks("--eigenpairs 42 --num-times 4 -o {o}/h.npy", ok(&[Npy("h.npy", N, 4)])),
        hks("--eigenpairs 2 --num-times 4 -o {o}/h.npy", ok(&[Npy("h.npy", N, 4)])),
        hks("--num-times 0 -o {o}/h.npy", Typed(&["--num-times 0", "1..=1000"])),
        hks("--num-times 1001 -o {o}/h.npy", Typed(&["--num-times 1001"])),
        hks("--num-times 1000000 -o {o}/h.npy", Typed(&["--num-times 1000000"])),
        hks(
            "--num-times {U64} -o {o}/h.npy",
            Typed(&["--num-times 18446744073709551615"]),
        ),
        hks("--num-times -1 -o {o}/h.npy", Clap),
        hks("--num-times 65 -o {o}/h.png", Typed(&["-o 65", "1..=64"])),
        hks("--times 1e-300 {MAX} -o {o}/h.npy", ok(&[Npy("h.npy", N, 2)])),
        hks("--times 0 -o {o}/h.npy", Typed(&["--times 0"])),
        hks("--times -1 -o {o}/h.npy", Typed(&["--times -1"])),
        hks("--times nan -o {o}/h.npy", Typed(&["--times NaN"])),
        hks("--times inf -o {o}/h.npy", Typed(&["--times inf"])),
        hks("--times 1 1 -o {o}/h.npy", Typed(&["given twice"])),
        hks("--times 1 --num-times 3 -o {o}/h.npy", Clap),
        hks("--eigenpairs 0 -o {o}/h.npy", Typed(&["--eigenpairs 0", "1..=42"])),
        hks("--eigenpairs 43 -o {o}/h.npy", Typed(&["--eigenpairs 43"])),
        hks(
            "--eigenpairs 100000000000 -o {o}/h.npy",
            Typed(&["--eigenpairs 100000000000"]),
        ),
        hks("--eigenpairs {U64} -o {o}/h.npy", Typed(&["--eigenpairs"])),
        hks("--eigenpairs -3 -o {o}/h.npy", Clap),
        hks("--kernel linear -o {o}/h.npy", ok(&[Npy("h.npy", N, 16)])),
        hks("-o {o}/nodir/h.npy", Typed(&["does not exist"])),
        hks("-o {d}/outdir.npy", Typed(&["directory"])),
        hks("-o {d}/fifo_out.npy", Typed(&["not a regular file"])),
        row("hks {d}/fifo.off -o {o}/h.npy", Typed(&["FIFO"])),
        row("hks {d}/unref.obj -o {o}/h.npy", Typed(&["--repair unreferenced"])),
        row(
            "hks {d}/unref.obj --repair unreferenced -o {o}/h.npy",
            ok(&[Npy("h.npy", N, 16)]),
        ),
        // The spectrum of the same sphere (a table of m rows, not per vertex).
        row("spectrum {d}/sphere.off -m 5 -o {o}/s.npy", ok(&[Npy("s.npy", 5, 2)])),
        row("spectrum {d}/sphere.off -m 41 -o {o}/s.csv", ok(&[File("s.csv")])),
        row(
            "spectrum {d}/sphere.off -m 0 -o {o}/s.csv",
            Typed(&["--eigenvalues 0", "1..=41"]),
        ),
        row(
            "spectrum {d}/sphere.off -m 42 -o {o}/s.csv",
            Typed(&["--eigenvalues 42"]),
        ),
        row(
            "spectrum {d}/sphere.off -m {U64} -o {o}/s.csv",
            Typed(&["--eigenvalues"]),
        ),
        row("spectrum {d}/sphere.off -m -1 -o {o}/s.csv", Clap),
        row("spectrum {d}/sphere.off --kind nope -o {o}/s.csv", Clap),
        row(
            "spectrum {d}/sphere.off -o {o}/s.png",
            Typed(&["a spectrum is a table"]),
        ),
        row("spectrum {d}/sphere.off -o {o}/nodir/s.npy", Typed(&["does not exist"])),
        row("spectrum {d}/fifo.off -o {o}/s.npy", Typed(&["FIFO"])),
    ]
}

fn demo_rows() -> Vec<Row> {
    vec![
        row(
            "demo --out {o}/demo --level 1",
            ok(&[
                File("demo/basis.ply"),
                File("demo/report.md"),
                File("demo/basis_t0.25.png"),
            ]),
        ),
        row(
            "demo --out {o}/demo --level 1 --eigenpairs 10 --quiet",
            ok(&[File("demo/report.md")]),
        ),
        row("demo --out {o}/demo --level 9", Typed(&["--level 9", "0..=8"])),
        row("demo --out {o}/demo --level 12", Typed(&["--level 12"])),
        row("demo --out {o}/demo --level 4294967295", Typed(&["--level 4294967295"])),
        row("demo --out {o}/demo --level 4294967296", Clap),
        row("demo --out {o}/demo --level -1", Clap),
        row(
            "demo --out {o}/demo --level 1 --eigenpairs 0",
            Typed(&["--eigenpairs 0"]),
        ),
        row(
            "demo --out {o}/demo --level 1 --eigenpairs 43",
            Typed(&["--eigenpairs 43"]),
        ),
        row(
            "demo --out {o}/demo --level 1 --eigenpairs {U64}",
            Typed(&["--eigenpairs"]),
        ),
        row(
            "demo --out {o}/demo --level 5 --eigenpairs 2000",
            Typed(&["--eigenpairs 2000", "n/10"]),
        ),
        row("demo --out {d}/plain --level 1", Typed(&["plain", "not a folder"])),
        row(
            "demo --out {d}/demo_blocked --level 1",
            Typed(&["report.md", "directory"]),
        ),
    ]
}

fn retrieval_rows() -> Vec<Row> {
    vec![
        row(
            "retrieval build {d}/sphere.off {d}/small.off --out {o}/i.json --words 4",
            ok(&[File("i.json"), Stdout("indexed 2 files")]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/i.json --words 0",
            Typed(&["--words 0"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/i.json --words {U64}",
            Typed(&["--words"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/i.json --words 1000",
            Typed(&["too few"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/i.json --eigenpairs 0",
            Typed(&["--eigenpairs 0"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/i.json --eigenpairs {U64}",
            Typed(&["--eigenpairs"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {d}/sphere.off",
            Typed(&["input file"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {o}/nodir/i.json",
            Typed(&["does not exist"]),
        ),
        row(
            "retrieval build {d}/sphere.off --out {d}/dir.json",
            Typed(&["directory"]),
        ),
        row("retrieval build {d}/fifo.off --out {o}/i.json", Typed(&["FIFO"])),
        row(
            "retrieval build {d}/unref.obj --out {o}/i.json",
            Typed(&["--repair unreferenced"]),
        ),
        row("retrieval build --out {o}/i.json", Clap),
        row(
            "retrieval query {d}/index.json {d}/sphere.off",
            ok(&[Stdout("sphere.off")]),
        ),
        row("retrieval query {d}/index.json {d}/sphere.off --top 0", ok(&[])),
        row(
            "retrieval query {d}/index.json {d}/sphere.off --top {U64}",
            ok(&[Stdout("small.off")]),
        ),
        row("retrieval query {d}/index.json {d}/sphere.off --top -1", Clap),
        row(
            "retrieval query {d}/index.json {d}/unref.obj --repair unreferenced",
            ok(&[Stdout("sphere.off")]),
        ),
        row("retrieval query {d}/index.json {d}/fifo.off", Typed(&["FIFO"])),
        row("retrieval query {d}/fifo.json {d}/sphere.off", Typed(&["FIFO"])),
        row("retrieval query {d}/dir.json {d}/sphere.off", Typed(&["directory"])),
        row(
            "retrieval query {d}/missing.json {d}/sphere.off",
            Typed(&["missing.json"]),
        ),
        row(
            "retrieval query {d}/empty.json {d}/sphere.off",
            Typed(&["not a wfem-retrieval-index file"]),
        ),
        row(
            "retrieval query {d}/garbage.json {d}/sphere.off",
            Typed(&["not a wfem-retrieval-index file"]),
        ),
        row(
            "retrieval query {d}/big_index.json {d}/sphere.off",
            Typed(&["invalid index", "bag value 1e308"]),
        ),
        row("retrieval query {d}/sigma_index.json {d}/sphere.off", Typed(&["sigma"])),
        row(
            "retrieval query {d}/eigs_index.json {d}/sphere.off",
            Typed(&["eigenpairs"]),
        ),
        row(
            "retrieval query {d}/words_index.json {d}/sphere.off",
            Typed(&["word 0"]),
        ),
        row(
            "retrieval query {d}/times_index.json {d}/sphere.off",
            Typed(&["tau_step"]),
        ),
        row(
            "retrieval query {d}/zscore_index.json {d}/sphere.off",
            Typed(&["z-score statistics"]),
        ),
        row(
            "retrieval query {d}/f.csv {d}/sphere.off",
            Typed(&["is not a wfem index"]),
        ),
        row("retrieval bogus", Clap),
    ]
}

fn global_rows() -> Vec<Row> {
    vec![
        row("bogus", Clap),
        row("--progress never info {d}/sphere.off", ok(&[Stdout("vertices")])),
        row(
            "--progress always heat {d}/sphere.off --t 0.1 --source 3 -o {o}/k.csv",
            ok(&[Csv("k.csv", N, 1), Stderr("assembling L, B, D"), Stderr("K_t: t = 0.1")]),
        ),
        row(
            "heat {d}/sphere.off --t 0.1 --source 3 -o {o}/k.csv --progress bogus",
            Clap,
        ),
    ]
}

/// Runs the rows on a few threads, each row in its own output folder, and returns the
/// failures.
fn run_table(name: &str, rows: Vec<Row>) {
    let fixture = fixture();
    let d = fixture.d.clone();
    let before = snapshot(&d);
    let outputs = tempfile::tempdir().unwrap();
    let jobs: Vec<(usize, Row)> = rows.into_iter().enumerate().collect();
    let queue = std::sync::Mutex::new(jobs.iter());
    let results = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..3 {
            s.spawn(|| loop {
                let Some((i, r)) = queue.lock().unwrap().next() else {
                    break;
                };
                let o = outputs.path().join(format!("row{i}"));
                std::fs::create_dir_all(&o).unwrap();
                let args = expand(&r.args, &d, &o);
                let out = run(&args, &o);
                let bad = judge(r, &o, &out);
                let typed = matches!(r.want, Want::Typed(_) | Want::Clap);
                results
                    .lock()
                    .unwrap()
                    .push((i, r.args.clone(), typed, bad, out.stderr));
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by_key(|r| r.0);
    let failures: Vec<String> = results
        .iter()
        .filter(|r| !r.3.is_empty())
        .map(|(_, args, _, bad, stderr)| {
            format!("wfem {args}\n    {}\n    stderr: {}", bad.join("; "), stderr.trim_end())
        })
        .collect();
    let typed = results.iter().filter(|r| r.2).count();
    eprintln!(
        "hostile table {name}: {} rows, {typed} typed errors, {} correct results, {} failures",
        results.len(),
        results.len() - typed,
        failures.len()
    );
    assert!(
        failures.is_empty(),
        "{} of {} rows failed:\n{}",
        failures.len(),
        results.len(),
        failures.join("\n")
    );
    assert_eq!(snapshot(&d), before, "an input file changed");
}

#[cfg(unix)]
#[test]
fn hostile_info_and_operators() {
    let mut rows = info_rows();
    rows.extend(operators_rows());
    rows.extend(global_rows());
    run_table("info/operators/global", rows);
}

#[cfg(unix)]
#[test]
fn hostile_heat() {
    run_table("heat", heat_rows());
}

#[cfg(unix)]
#[test]
fn hostile_distance_approx_hks() {
    let mut rows = distance_rows();
    rows.extend(approx_rows());
    rows.extend(hks_rows());
    run_table("distance/approx/hks", rows);
}

#[cfg(unix)]
#[test]
fn hostile_demo_and_retrieval() {
    let mut rows = demo_rows();
    rows.extend(retrieval_rows());
    run_table("demo/retrieval", rows);
}

// ---------------------------------------------------------------------------------------------
// Huge times: K_t f and the HKS at their t → ∞ limits.

/// K_t f at t → ∞ is the B-weighted mean of f on each component: for e_i on the sphere,
/// (1ᵀB e_i / area)·1.
fn limit_of_source(i: usize) -> f64 {
    let mesh = mesh_fem::generate::icosphere(1);
    let ops = mesh_fem::assemble(&mesh, &Default::default()).unwrap();
    let ones = faer::Mat::<f64>::from_fn(N, 1, |_, _| 1.0);
    let b1 = &ops.mass * &ones;
    let area: f64 = (0..N).map(|k| b1[(k, 0)]).sum();
    b1[(i, 0)] / area
}

/// Runs `heat … --source 3 -o k.csv` with `args` and checks that K_t e_3 is its t → ∞ limit.
fn heat_limit(args: &str) {
    let fixture = fixture();
    let o = tempfile::tempdir().unwrap();
    let full = format!("heat {{d}}/sphere.off --source 3 -o {{o}}/k.csv {args}");
    let out = run(&expand(&full, &fixture.d, o.path()), o.path());
    assert_eq!(out.code, Some(0), "wfem {full}: {}", out.stderr);
    let (_, data) = read_csv(&o.path().join("k.csv")).unwrap();
    let limit = limit_of_source(3);
    for r in data {
        assert!((r[0] - limit).abs() < 1e-9 * limit, "{} vs the limit {limit}", r[0]);
    }
}

/// Every method and kernel reaches the mean at t = f64::MAX, and the exact methods at 1e300
/// (before the fix: "shifted matrix tL − zB is numerically singular", NaN from dense, a failed
/// Cholesky in the fast path).
#[test]
fn issue_16_heat_at_huge_times_is_the_mean() {
    for args in [
        "--t {MAX}",
        "--t {MAX} --method fast",
        "--t {MAX} --method dense",
        "--t {MAX} --backend lu",
        "--t {MAX} --backend minres",
        "--t {MAX} --backend multishift",
        "--t 1e300 --method dense",
        "--t 1e300 --method fast",
    ] {
        heat_limit(args);
    }
}

/// The HKS at t = 1e300 is its limit 1/area (the constant eigenfunction squared; it was 0).
#[test]
fn issue_16_hks_at_a_huge_time_is_one_over_the_area() {
    let fixture = fixture();
    let o = tempfile::tempdir().unwrap();
    let out = run(
        &expand("hks {d}/sphere.off --times 1e300 -o {o}/h.csv", &fixture.d, o.path()),
        o.path(),
    );
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let (_, data) = read_csv(&o.path().join("h.csv")).unwrap();
    let area = mesh_fem::generate::icosphere(1).area();
    for r in data {
        assert!((r[0] - 1.0 / area).abs() < 1e-6 / area, "{} vs {}", r[0], 1.0 / area);
    }
}
