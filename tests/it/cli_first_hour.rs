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

/// Issue #25: a collection with broken files still indexes; each refused file is named with
/// its reason at the end and the exit status is 3; `--strict` keeps all-or-nothing.
#[test]
fn collections_tolerate_bad_files() {
    let dir = tempfile::tempdir().unwrap();
    let good = [
        write(dir.path(), "sphere.off", &mesh_fem::generate::icosphere(2)),
        write(dir.path(), "torus.off", &mesh_fem::generate::torus(1.0, 0.4, 20, 10)),
    ];
    // A zero-area face (three collinear vertices), and a file that is not a mesh.
    let broken = dir.path().join("broken.off");
    std::fs::write(&broken, "OFF\n4 2 0\n0 0 0\n1 0 0\n2 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n").unwrap();
    let garbage = dir.path().join("garbage.off");
    std::fs::write(&garbage, "this is not a mesh\n").unwrap();
    let bad = [
        broken.to_str().unwrap().to_string(),
        garbage.to_str().unwrap().to_string(),
    ];
    let index = dir.path().join("index.sqlite");
    let mut args = vec![
        "retrieval",
        "build",
        good[0].as_str(),
        bad[0].as_str(),
        good[1].as_str(),
        bad[1].as_str(),
    ];
    args.extend(["--out", index.to_str().unwrap(), "--eigenpairs", "30", "--words", "8"]);
    let o = wfem(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("indexed 2 files"), "{err}");
    assert!(
        err.contains(&format!("refused {}: ", bad[0])) && err.contains("zero area"),
        "{err}"
    );
    assert!(err.contains(&format!("refused {}: ", bad[1])), "{err}");
    assert!(
        err.contains("2 of 4 files were refused (listed above); the index was built from the other 2"),
        "{err}"
    );
    assert!(index.exists());
    // `add` with one good and one broken file: the good one is added.
    let more = write(dir.path(), "bumpy.off", &mesh_fem::generate::bumpy(2));
    let o = wfem(&[
        "retrieval",
        "add",
        index.to_str().unwrap(),
        bad[0].as_str(),
        more.as_str(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("added 1 file to"),
        "{}",
        stderr(&o)
    );
    let o = wfem(&[
        "retrieval",
        "query",
        index.to_str().unwrap(),
        more.as_str(),
        "--top",
        "1",
    ]);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("bumpy.off"),
        "{}",
        stderr(&o)
    );
    // `--strict`: all or nothing, exit status 1, no output.
    let strict = dir.path().join("strict.sqlite");
    let o = wfem(&[
        "retrieval",
        "build",
        good[0].as_str(),
        bad[0].as_str(),
        "--out",
        strict.to_str().unwrap(),
        "--strict",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!strict.exists());
    // `vocab` too; and nothing usable at all is an error.
    let vocab = dir.path().join("v.json");
    let o = wfem(&[
        "retrieval",
        "vocab",
        good[0].as_str(),
        good[1].as_str(),
        bad[1].as_str(),
        "--out",
        vocab.to_str().unwrap(),
        "--eigenpairs",
        "30",
        "--words",
        "8",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("on 2 shapes"),
        "{}",
        stderr(&o)
    );
    let o = wfem(&[
        "retrieval",
        "vocab",
        bad[0].as_str(),
        bad[1].as_str(),
        "--out",
        vocab.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("none of the 2 files could be used"),
        "{}",
        stderr(&o)
    );
}

/// Red pixels of the source's dot in each of the four views of a heat figure.
fn red_dots_per_view(path: &std::path::Path) -> [usize; 4] {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let (w, h) = (info.width as usize, info.height as usize);
    let view = 480; // RenderParams::default().width
    let mut counts = [0; 4];
    for y in 0..h {
        for x in 0..(4 * view).min(w) {
            let p = &buf[3 * (y * w + x)..3 * (y * w + x) + 3];
            if p == [225, 25, 30] {
                counts[x / view] += 1;
            }
        }
    }
    counts
}

/// Issue #25: the source of a heat figure is seen in at least one view (the last view faces
/// it), even at the bottom of the shape where the standard front, side, top and oblique
/// views cannot see it; the note names the views by their true directions.
#[test]
fn heat_figures_show_their_source() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = mesh_fem::generate::bumpy(3);
    let m = write(dir.path(), "bumpy.off", &mesh);
    let bottom = (0..mesh.n_vertices())
        .min_by(|&a, &b| mesh.positions()[a][1].total_cmp(&mesh.positions()[b][1]))
        .unwrap();
    let out = dir.path().join("h.png");
    let o = wfem(&[
        "heat",
        &m,
        "--t",
        "1e-3",
        "--source",
        &bottom.to_string(),
        "--up",
        "y",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "views from +z (the broadest side), +x, above, and facing vertex {bottom}"
        )),
        "{err}"
    );
    let dots = red_dots_per_view(&out);
    assert_eq!(dots[2], 0, "{dots:?}"); // the top view cannot see the bottom
    assert!(dots[3] > 20, "{dots:?}");
}
