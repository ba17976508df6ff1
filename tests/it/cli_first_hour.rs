//! Issue #25, the first hour of a new user: what the computing commands say about the mesh
//! (the warnings of `wfem info`, once, with the repair flag), and the smaller messages (a
//! directory given as a mesh, a negative vertex, the dense method above its size).

use crate::common::{stderr, wfem};

fn write(dir: &std::path::Path, name: &str, mesh: &mesh_fem::TriMesh) -> String {
    let path = dir.join(name);
    mesh_fem::io::write_mesh(&path, mesh).unwrap();
    path.to_str().unwrap().to_string()
}

/// An icosphere with its first face repeated, and a second, separate icosphere.
fn flawed() -> mesh_fem::TriMesh {
    let a = mesh_fem::generate::icosphere(1);
    let n = a.n_vertices() as u32;
    let mut positions = a.positions().to_vec();
    positions.extend(a.positions().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let mut faces = a.faces().to_vec();
    faces.push(a.faces()[0]);
    faces.extend(a.faces().iter().map(|f| [f[0] + n, f[1] + n, f[2] + n]));
    mesh_fem::TriMesh::new(positions, faces).unwrap()
}

#[test]
fn computing_commands_say_what_info_knows() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "flawed.off", &flawed());
    let out = dir.path().join("h.npy");
    let info = wfem(&["info", &m]);
    let info_text = String::from_utf8_lossy(&info.stdout);
    assert!(info_text.contains("--repair duplicate-faces"), "{info_text}");
    for args in [
        vec![
            "heat",
            m.as_str(),
            "--t",
            "0.01",
            "--source",
            "0",
            "-o",
            out.to_str().unwrap(),
        ],
        vec![
            "distance",
            m.as_str(),
            "--t",
            "0.01",
            "--from",
            "0",
            "-o",
            out.to_str().unwrap(),
        ],
        vec!["hks", m.as_str(), "--times", "0.01", "-o", out.to_str().unwrap()],
    ] {
        let o = wfem(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.matches("duplicates face").count(), 1, "{err}");
        assert!(
            err.contains("warning: flawed.off: face 80 duplicates face 0")
                && err.contains("fix: --repair duplicate-faces"),
            "{err}"
        );
        assert!(err.contains("warning: flawed.off: 2 connected components"), "{err}");
    }
    // After the repair the duplicate is gone and not mentioned.
    let o = wfem(&[
        "heat",
        &m,
        "--repair",
        "duplicate-faces",
        "--t",
        "0.01",
        "--source",
        "0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        o.status.success() && !stderr(&o).contains("duplicates face"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn smaller_messages_say_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let m = write(dir.path(), "s.off", &mesh_fem::generate::icosphere(2));
    let out = dir.path().join("x.npy");
    // A directory given as the mesh.
    let o = wfem(&["info", dir.path().to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("is a directory, not a mesh file"), "{}", stderr(&o));
    // A negative vertex: our message, not clap's `-- -3` hint.
    for (command, flag) in [("distance", "--from"), ("heat", "--source")] {
        let o = wfem(&[command, &m, "--t", "0.01", flag, "-3", "-o", out.to_str().unwrap()]);
        assert!(!o.status.success());
        let err = stderr(&o);
        assert!(
            err.contains("-3 is not a vertex: vertices are numbered 0, 1, 2"),
            "{err}"
        );
        assert!(!err.contains("-- -3"), "{err}");
    }
    // The dense method above its size names the method that works.
    let big = write(dir.path(), "big.off", &mesh_fem::generate::icosphere(5));
    let o = wfem(&[
        "heat",
        &big,
        "--t",
        "0.01",
        "--source",
        "0",
        "--method",
        "dense",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("use --method fast"), "{}", stderr(&o));
    // `hks --help` says how the signature is computed.
    let o = wfem(&["--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(!help.contains("from its k smallest eigenpairs"), "{help}");
}
