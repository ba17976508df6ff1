//! Signals never leave files (issue #41): SIGINT or SIGTERM at any moment of a run —
//! computing, writing its temporary files, renaming them — ends `wfem` with no temporary file
//! or probe left beside its outputs, and every output is its old file or its new one.
//!
//! Each command runs once to completion (the reference), then again many times, signalled at
//! a range of moments: as soon as one of its temporary files appears in the output folder
//! (the write phase; the folder is polled) and then after a few more microseconds or
//! milliseconds, and at fractions of the reference run's length. The issue's reproduction:
//! `retrieval build` left `.index.sqlite.PID.build.PID.tmp` (and its `-journal`) or
//! `.wfem-probe-PID`, `hks` left `.h.npy.tmp-PID-0`, six times in six. A killed run's (SIGKILL)
//! temporaries are removed by the next run of the same command.
#![cfg(unix)]

use super::common::stderr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_wfem")
}

/// Names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A temporary of any version: `.NAME.tmp-PID-N`, `.NAME.PID.build…`, `.NAME.PID.tmp…`,
/// `.wfem-probe…`.
fn is_temporary(name: &str) -> bool {
    name.starts_with('.')
        && (name.contains(".tmp-") || name.contains(".build") || name.contains("wfem-probe") || name.ends_with(".tmp"))
}

/// Every temporary under `dir` (recursively: the demo writes into a folder of its own).
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().into_owned();
        if is_temporary(&name) {
            found.push(e.path());
        } else if e.file_type().unwrap().is_dir() {
            found.extend(temporaries(&e.path()));
        }
    }
    found
}

/// One command to signal: its arguments, the folder it writes into, and how to put the old
/// outputs back and read the outputs (as bytes, or any summary that tells old from new).
struct Case {
    name: &'static str,
    args: Vec<String>,
    folder: PathBuf,
    /// Files and folders the run may leave beside its outputs other than temporaries (an
    /// SQLite index's own log while it was open).
    own: &'static [&'static str],
    reset: Box<dyn Fn()>,
    state: Box<dyn Fn() -> String>,
}

/// When to signal a run.
#[derive(Clone, Copy, Debug)]
enum Moment {
    /// This long after the first temporary appears in the folder (or the run ends).
    AfterTemporary(Duration),
    /// This fraction of the reference run's length after the start (the signal may come
    /// before the write phase, or after the run ended).
    Fraction(f64),
}

/// Runs `case`, sends `signal` at `moment` (`length`: the reference run's) and waits for it;
/// also whether a temporary was there when the signal was sent.
fn run_signalled(case: &Case, moment: Moment, length: Duration, signal: i32) -> (std::process::ExitStatus, bool) {
    let mut child = Command::new(bin())
        .args(&case.args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    match moment {
        Moment::AfterTemporary(extra) => {
            // Poll the folder until a temporary shows up: the write phase has begun.
            while child.try_wait().unwrap().is_none() && temporaries(&case.folder).is_empty() {
                std::thread::sleep(Duration::from_micros(50));
            }
            std::thread::sleep(extra);
        }
        Moment::Fraction(f) => std::thread::sleep(length.mul_f64(f)),
    }
    let writing = !temporaries(&case.folder).is_empty();
    // SAFETY: a signal to our own child, which has not been waited for yet (its pid is not
    // reused before then).
    #[allow(unsafe_code)]
    unsafe {
        libc::kill(child.id() as libc::pid_t, signal);
    }
    (child.wait().unwrap(), writing)
}

/// Runs `case` to completion, then signalled at many moments; after each run no temporary is
/// left and the outputs are the old ones or the new ones.
fn signal_at_many_moments(case: Case) {
    use std::os::unix::process::ExitStatusExt;
    (case.reset)();
    let old = (case.state)();
    let start = Instant::now();
    let o = Command::new(bin()).args(&case.args).output().unwrap();
    let length = start.elapsed();
    assert!(o.status.success(), "{}: {}", case.name, stderr(&o));
    let new = (case.state)();
    // What a finished run leaves; an interrupted one may leave less, never anything else.
    let finished_listing = listing(&case.folder);
    assert_ne!(old, new, "{}: the reference run changed nothing", case.name);
    let extras = [0, 200, 2_000, 20_000].map(Duration::from_micros);
    // 5 % of the run: surely before it ends, so that some run is interrupted whatever the
    // machine's load (a harness whose signals never arrive would otherwise pass).
    let fractions = [0.05, 0.3, 0.7, 0.9, 1.0];
    let moments = extras
        .iter()
        .map(|&d| Moment::AfterTemporary(d))
        .chain(fractions.iter().map(|&f| Moment::Fraction(f)));
    let (mut interrupted, mut finished, mut while_writing) = (0, 0, 0);
    for (k, moment) in moments.enumerate() {
        let signal = if k % 2 == 0 { libc::SIGINT } else { libc::SIGTERM };
        (case.reset)();
        let (status, writing) = run_signalled(&case, moment, length, signal);
        if status.success() {
            finished += 1;
        } else {
            assert_eq!(
                status.signal(),
                Some(signal),
                "{} at {moment:?}: ended by {status}, not by the signal",
                case.name
            );
            interrupted += 1;
            while_writing += usize::from(writing);
        }
        let left = temporaries(&case.folder);
        assert!(
            left.is_empty(),
            "{} at {moment:?} (signal {signal}): left {left:?}",
            case.name
        );
        let state = (case.state)();
        assert!(
            state == old || state == new,
            "{} at {moment:?}: the output is neither the old one nor the new one",
            case.name
        );
        let unexpected: Vec<String> = listing(&case.folder)
            .into_iter()
            .filter(|n| !finished_listing.contains(n) && !case.own.contains(&n.as_str()))
            .collect();
        assert!(
            unexpected.is_empty(),
            "{} at {moment:?}: left {unexpected:?}",
            case.name
        );
    }
    // Some runs must have been interrupted for the test to mean anything. How many while a
    // temporary existed depends on the machine's load (the write phase lasts milliseconds), so
    // it is reported, not asserted; without the signal thread the first such run fails above.
    assert!(interrupted >= 1, "{}: no run was interrupted", case.name);
    eprintln!(
        "{}: {interrupted} of {} runs interrupted, {while_writing} of them while a temporary existed",
        case.name,
        interrupted + finished
    );
}

fn write_mesh(dir: &Path, name: &str, mesh: &mesh_fem::TriMesh) -> String {
    let p = dir.join(name);
    mesh_fem::io::write_mesh(&p, mesh).unwrap();
    p.to_str().unwrap().to_string()
}

fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

/// An output file put back to `old` bytes; its state is its bytes' length and a sum.
fn file_case(name: &'static str, dir: &Path, target: &Path, args: Vec<String>) -> Case {
    let t = target.to_path_buf();
    let t2 = target.to_path_buf();
    Case {
        name,
        args,
        folder: dir.to_path_buf(),
        own: &[],
        reset: Box::new(move || std::fs::write(&t, b"old output").unwrap()),
        state: Box::new(move || {
            let b = std::fs::read(&t2).unwrap_or_default();
            format!("{} {}", b.len(), b.iter().map(|&x| u64::from(x)).sum::<u64>())
        }),
    }
}

#[test]
fn issue_41_signals_during_hks_heat_distance_and_approx_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = write_mesh(d, "sphere.off", &mesh_fem::generate::icosphere(4));
    let out = |n: &str| d.join(n).to_str().unwrap().to_string();
    let h = d.join("h.npy");
    signal_at_many_moments(file_case(
        "hks",
        d,
        &h,
        s(&[
            "hks",
            &mesh,
            "--num-times",
            "100",
            "--method",
            "spectral",
            "--eigs",
            "100",
            "-o",
            &out("h.npy"),
        ]),
    ));
    let k = d.join("k.csv");
    signal_at_many_moments(file_case(
        "heat",
        d,
        &k,
        s(&["heat", &mesh, "--t", "0.01", "--source", "3", "-o", &out("k.csv")]),
    ));
    let dist = d.join("d.csv");
    signal_at_many_moments(file_case(
        "distance",
        d,
        &dist,
        s(&["distance", &mesh, "--t", "0.01", "--from", "3", "-o", &out("d.csv")]),
    ));
    let field = d.join("f.csv");
    let o = Command::new(bin())
        .args([
            "heat",
            &mesh,
            "--t",
            "0.05",
            "--source",
            "7",
            "-o",
            field.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let a = d.join("a.npy");
    signal_at_many_moments(file_case(
        "approx",
        d,
        &a,
        s(&[
            "approx",
            &mesh,
            "--field",
            field.to_str().unwrap(),
            "--persistence",
            "0.25",
            "--scales",
            "4",
            "-o",
            &out("a.npy"),
        ]),
    ));
}

#[test]
fn issue_41_signals_during_the_demo_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    std::fs::create_dir(&out).unwrap();
    let report = out.join("report.md");
    let r2 = report.clone();
    signal_at_many_moments(Case {
        name: "demo",
        args: s(&[
            "demo",
            "--out",
            out.to_str().unwrap(),
            "--level",
            "2",
            "--eigs",
            "40",
            "--quiet",
        ]),
        folder: out.clone(),
        own: &[],
        reset: Box::new(move || std::fs::write(&report, b"old report").unwrap()),
        state: Box::new(move || std::fs::read_to_string(&r2).unwrap_or_default().len().to_string()),
    });
}

/// The shapes of an index, by name (or why it cannot be read).
fn index_state(index: &Path) -> String {
    match retrieval_store::index::SqliteIndex::new(index).open() {
        Ok((_, store)) => {
            let names: Vec<String> = store.shapes().unwrap().into_iter().map(|s| s.name).collect();
            let check = retrieval_store::Store::check(index).unwrap();
            assert!(check.is_verified(), "{}", check.to_text());
            names.join(",")
        }
        Err(e) => format!("unreadable: {e}"),
    }
}

#[test]
fn issue_41_signals_during_retrieval_build_and_add_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = write_mesh(d, "a.off", &mesh_fem::generate::icosphere(3));
    let b = write_mesh(d, "b.off", &mesh_fem::generate::torus(1.0, 0.4, 40, 20));
    let c = write_mesh(d, "c.off", &mesh_fem::generate::bumpy(3));
    let index = d.join("index.sqlite");
    let old_index = d.join("old.sqlite");
    let build = |files: &[&str], out: &Path| {
        let mut args = s(&["retrieval", "build"]);
        args.extend(files.iter().map(|f| f.to_string()));
        args.extend(s(&[
            "--out",
            out.to_str().unwrap(),
            "--eigs",
            "30",
            "--words",
            "8",
            "--force",
        ]));
        args
    };
    let o = Command::new(bin()).args(build(&[&a], &old_index)).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let (i1, i2, o1) = (index.clone(), index.clone(), old_index.clone());
    let restore = move || {
        for suffix in ["-wal", "-shm"] {
            let _ = std::fs::remove_file(format!("{}{suffix}", i1.display()));
        }
        std::fs::copy(&o1, &i1).unwrap();
    };
    signal_at_many_moments(Case {
        name: "retrieval build",
        args: build(&[&b, &c], &index),
        folder: d.to_path_buf(),
        own: &["index.sqlite-wal", "index.sqlite-shm"],
        reset: Box::new(restore.clone()),
        state: Box::new(move || index_state(&i2)),
    });
    let i3 = index.clone();
    signal_at_many_moments(Case {
        name: "retrieval add",
        args: s(&["retrieval", "add", index.to_str().unwrap(), &b, &c]),
        folder: d.to_path_buf(),
        own: &["index.sqlite-wal", "index.sqlite-shm"],
        reset: Box::new(restore),
        state: Box::new(move || index_state(&i3)),
    });
}

#[test]
fn issue_41_a_killed_runs_temporaries_are_removed_by_the_next_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = write_mesh(d, "sphere.off", &mesh_fem::generate::icosphere(3));
    // What processes killed outright left (a process id that runs on no machine), in every
    // form of name, and a running process's file (pid 1), which must stay.
    let dead = 2_147_483_000u32;
    let left = [
        format!(".h.npy.tmp-{dead}-0"),
        format!(".index.sqlite.tmp-{dead}-3"),
        format!(".index.sqlite.{dead}.build"),
        format!(".index.sqlite.{dead}.build.{dead}.tmp-journal"),
        format!(".wfem-probe-{dead}"),
    ];
    for name in &left {
        std::fs::write(d.join(name), b"x").unwrap();
    }
    std::fs::create_dir(d.join(format!(".index.sqlite.tmp-{dead}-7"))).unwrap();
    std::fs::write(d.join(format!(".index.sqlite.tmp-{dead}-7/index.sqlite-journal")), b"x").unwrap();
    let live = d.join(".h.npy.tmp-1-0");
    std::fs::write(&live, b"x").unwrap();
    let run = |args: &[&str]| {
        let o = Command::new(bin()).args(args).output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
    };
    let h = d.join("h.npy");
    run(&["hks", &mesh, "--num-times", "5", "-o", h.to_str().unwrap()]);
    let index = d.join("index.sqlite");
    run(&[
        "retrieval",
        "build",
        &mesh,
        "--out",
        index.to_str().unwrap(),
        "--eigs",
        "30",
        "--words",
        "4",
    ]);
    assert_eq!(temporaries(d), [live], "a dead process's temporaries stay");
}
