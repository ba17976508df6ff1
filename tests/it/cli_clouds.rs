//! The CLI on point clouds and with `--laplacian` (issue #27).

use crate::common::{read_npy, stderr, wfem};
use std::fmt::Write as _;

/// A point cloud on the unit sphere (a Fibonacci lattice), as `.xyz` text.
fn write_cloud(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
    let mut text = String::new();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        writeln!(text, "{} {} {}", r * phi.cos(), r * phi.sin(), z).unwrap();
    }
    let path = dir.join("cloud.xyz");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn heat_and_operators_read_a_point_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = write_cloud(dir.path(), 800);
    let out = dir.path().join("k.npy");
    let o = wfem(&[
        "heat",
        cloud.to_str().unwrap(),
        "--t",
        "0.05",
        "--source",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("point cloud of 800 points"), "{}", stderr(&o));
    let (shape, values) = read_npy(&out).unwrap();
    assert_eq!(shape[0], 800);
    assert!(values.iter().all(|v| v.is_finite()));
    // The sidecar records the Laplacian used: a cloud's is the robust one.
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("k.json")).unwrap()).unwrap();
    assert_eq!(sidecar["input"]["laplacian"], "robust", "{sidecar}");
    assert_eq!(sidecar["input"]["point_cloud"], true, "{sidecar}");

    let ops = dir.path().join("ops");
    let o = wfem(&["operators", cloud.to_str().unwrap(), "--out", ops.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(ops.join("mass.mtx").exists());
}

/// The feature-driven approximation runs on a point cloud (its critical points on the
/// non-manifold neighbourhood mesh): f_glob + f_loc = f at every point, and at the finest
/// scale f_glob stays within 3 % of the range of a smooth f, as on a mesh.
#[test]
fn approx_runs_on_a_point_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = write_cloud(dir.path(), 800);
    let points: Vec<[f64; 3]> = std::fs::read_to_string(&cloud)
        .unwrap()
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let f: Vec<f64> = points.iter().map(|p| p[0] + 0.5 * p[1] * p[2]).collect();
    let field = dir.path().join("f.csv");
    std::fs::write(&field, f.iter().map(|v| format!("{v:.17e}\n")).collect::<String>()).unwrap();
    let out = dir.path().join("approx.csv");
    let o = wfem(&[
        "approx",
        cloud.to_str().unwrap(),
        "--field",
        field.to_str().unwrap(),
        "--scales",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(&out).unwrap();
    let data: Vec<Vec<f64>> = csv
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').map(|x| x.trim().parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(data.len(), 800);
    let range = f.iter().cloned().fold(f64::MIN, f64::max) - f.iter().cloned().fold(f64::MAX, f64::min);
    let mut best = f64::INFINITY;
    for s in 0..3 {
        let mut linf = 0.0f64;
        for (i, row) in data.iter().enumerate() {
            assert!((row[0] - f[i]).abs() < 1e-12);
            assert!((row[1 + s] + row[4 + s] - f[i]).abs() < 1e-9, "point {i} scale {s}");
            linf = linf.max(row[4 + s].abs());
        }
        best = best.min(linf / range);
    }
    assert!(best <= 0.03, "finest relative L∞ error {best}");
}

#[test]
fn laplacian_flag_takes_the_library_names_and_non_manifold_meshes_are_warned() {
    let dir = tempfile::tempdir().unwrap();
    // Three triangles on one edge: a non-manifold mesh.
    let mesh = dir.path().join("fins.obj");
    std::fs::write(
        &mesh,
        "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0.2\nv 0.5 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let out = dir.path().join("k.npy");
    let args = |lap: Option<&str>| {
        let mut a = vec![
            "heat",
            mesh.to_str().unwrap(),
            "--t",
            "0.01",
            "--source",
            "0",
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(l) = lap {
            a.extend(["--laplacian", l]);
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |lap: Option<&str>| {
        let a = args(lap);
        wfem(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let o = run(None);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--laplacian robust"), "{}", stderr(&o));
    for name in <mesh_fem::Laplacian as wfem_base::Choice>::names() {
        let o = run(Some(name));
        assert!(o.status.success(), "{name}: {}", stderr(&o));
    }
    let o = run(Some("intrinsic"));
    assert!(!o.status.success());
    assert!(stderr(&o).contains("robust"), "{}", stderr(&o));
}

/// n points uniformly distributed on the surface of `mesh` (an area-weighted face, then
/// uniform barycentric coordinates; SplitMix64 numbers), as `.xyz` text in `path`.
fn write_samples(mesh: &mesh_fem::TriMesh, n: usize, path: &std::path::Path) {
    let mut state = 0x5eed_u64;
    let mut uniform = move || {
        state = state.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        (((z ^ (z >> 31)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut cumulative = Vec::with_capacity(mesh.n_faces());
    let mut total = 0.0;
    for f in 0..mesh.n_faces() {
        total += mesh.face_area(f);
        cumulative.push(total);
    }
    let mut text = String::new();
    for _ in 0..n {
        let r = uniform() * total;
        let f = cumulative.partition_point(|&c| c < r).min(mesh.n_faces() - 1);
        let (mut u, mut v) = (uniform(), uniform());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let c = mesh.corners(f);
        let p = [0, 1, 2].map(|a| (1.0 - u - v) * c[0][a] + u * c[1][a] + v * c[2][a]);
        writeln!(text, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(path, text).unwrap();
}

/// The RGB pixels of a PNG, its width and height.
fn read_png(path: &std::path::Path) -> (Vec<u8>, usize, usize) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (buf, info.width as usize, info.height as usize)
}

/// Issue #27: a cloud's figures draw it as splats — a closed surface with the silhouette of
/// the mesh it was sampled from (the first three views are the same for both: front, side,
/// top; the fourth faces each one's source), and the source's red dot.
#[test]
fn cloud_figures_are_splats_with_the_silhouette_of_the_sampled_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let torus = mesh_fem::generate::torus(1.0, 0.4, 96, 48);
    let mesh = dir.path().join("torus.obj");
    mesh_fem::io::write_mesh(&mesh, &torus).unwrap();
    let cloud = dir.path().join("torus.xyz");
    write_samples(&torus, 10_000, &cloud);
    let figure = |input: &std::path::Path, command: &str, out: &str| {
        let out = dir.path().join(out);
        let flag = if command == "heat" { "--source" } else { "--from" };
        let mut args = vec![command, input.to_str().unwrap(), "--t", "0.02", flag, "0", "--up", "z"];
        args.extend(["-o", out.to_str().unwrap()]);
        let o = wfem(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        (read_png(&out), stderr(&o))
    };
    for command in ["heat", "distance"] {
        let ((mesh_px, w, h), mesh_log) = figure(&mesh, command, "mesh.png");
        let ((cloud_px, cw, ch), cloud_log) = figure(&cloud, command, "cloud.png");
        assert!(!mesh_log.contains("splats"), "{mesh_log}");
        assert!(cloud_log.contains("the 10000 points drawn as splats"), "{cloud_log}");
        // The same layout but for the width of the title.
        assert_eq!(h, ch);
        let (mesh_img, cloud_img) = ((mesh_px.as_slice(), w), (cloud_px.as_slice(), cw));
        let pixel = |(px, width): (&[u8], usize), x: usize, y: usize| -> [u8; 3] {
            let i = 3 * (y * width + x);
            [px[i], px[i + 1], px[i + 2]]
        };
        let covered = |img, x, y| pixel(img, x, y) != [255; 3];
        let view = 480; // RenderParams::default().width
                        // The views, below the title.
        let (top, bottom) = (h - view, h);
        // The sources' red dots (radius ≈ 8 px with the rim) reach past the surfaces: skip them.
        let mut near_dot = vec![false; 3 * view * h];
        for y in top..bottom {
            for x in 0..3 * view {
                if [mesh_img, cloud_img]
                    .iter()
                    .any(|&img| pixel(img, x, y) == [225, 25, 30])
                {
                    for yy in y.saturating_sub(10)..(y + 11).min(h) {
                        for xx in x.saturating_sub(10)..(x + 11).min(3 * view) {
                            near_dot[yy * 3 * view + xx] = true;
                        }
                    }
                }
            }
        }
        let (mut area, mut differ, mut holes) = (0, 0, 0);
        for y in top..bottom {
            for x in 0..3 * view {
                if near_dot[y * 3 * view + x] {
                    continue;
                }
                let a = covered(mesh_img, x, y);
                area += a as usize;
                differ += (a != covered(cloud_img, x, y)) as usize;
                let interior = (y.saturating_sub(2)..(y + 3).min(bottom))
                    .all(|yy| (x.saturating_sub(2)..(x + 3).min(3 * view)).all(|xx| covered(mesh_img, xx, yy)));
                holes += (interior && !covered(cloud_img, x, y)) as usize;
            }
        }
        eprintln!("{command}: {differ} of {area} silhouette pixels differ, {holes} holes");
        assert_eq!(holes, 0, "{command}: {holes} holes in the splats");
        assert!(
            (differ as f64) < 0.03 * area as f64,
            "{command}: {differ} of {area} pixels differ"
        );
        let red = cloud_px.chunks(3).filter(|p| *p == [225, 25, 30]).count();
        assert!(red > 20, "{command}: {red} red pixels");
    }
}

/// Writes an (n, 3) float64 array as `.npy` (format 1.0).
fn write_npy(path: &std::path::Path, points: &[[f64; 3]]) {
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, 3), }}",
        points.len()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for p in points {
        for c in p {
            bytes.extend(c.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// Writes points as `.xyz` text.
fn write_xyz(path: &std::path::Path, points: &[[f64; 3]]) {
    let mut text = String::new();
    for p in points {
        writeln!(text, "{:?} {:?} {:?}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(path, text).unwrap();
}

/// n points uniform on a mesh's surface (the workspace's seeded generator).
fn sample(mesh: &mesh_fem::TriMesh, n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = wfem_base::rng::SplitMix64::new(seed);
    mesh_fem::cloud::sample_surface(mesh, n, &mut || rng.next_f64())
        .unwrap()
        .positions()
        .to_vec()
}

#[test]
fn retrieval_indexes_meshes_and_point_clouds_together() {
    use mesh_fem::generate::{bumpy, torus};
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let (t, b) = (torus(1.0, 0.4, 48, 24), bumpy(3));
    mesh_fem::io::write_mesh(std::path::Path::new(&p("torus.obj")), &t).unwrap();
    mesh_fem::io::write_mesh(std::path::Path::new(&p("bumpy.off")), &b).unwrap();
    write_npy(std::path::Path::new(&p("torus-cloud.npy")), &sample(&t, 1500, 1));
    write_xyz(std::path::Path::new(&p("bumpy-cloud.xyz")), &sample(&b, 1500, 2));
    let index = p("index.sqlite");
    let files = ["torus.obj", "bumpy.off", "torus-cloud.npy", "bumpy-cloud.xyz"].map(p);
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(String::as_str));
    args.extend(["--out", &index, "--words", "6", "--eigenpairs", "30"]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("indexed 4 files, 2 of them point clouds"), "{out}");

    // A new cloud of the torus finds a torus first (its mesh or its cloud).
    let query = p("query.xyz");
    write_xyz(std::path::Path::new(&query), &sample(&t, 1500, 3));
    let o = wfem(&["retrieval", "query", &index, &query, "--top", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let first = out.lines().next().unwrap_or_default();
    assert!(first.contains("torus"), "{out}");

    // The index records the cotangent L: a query asking for another one is refused, naming
    // both; asking for the recorded one is the same as not asking.
    let o = wfem(&["retrieval", "query", &index, &files[0], "--laplacian", "robust"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("--laplacian robust") && err.contains("cotan"), "{err}");
    let o = wfem(&[
        "retrieval",
        "query",
        &index,
        &files[0],
        "--laplacian",
        "cotan",
        "--top",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("torus.obj"));

    // Clouds are appended like meshes.
    let more = p("more-torus.csv");
    let text: String = sample(&t, 1200, 4)
        .iter()
        .map(|q| format!("{},{},{}\n", q[0], q[1], q[2]))
        .collect();
    std::fs::write(&more, format!("x,y,z\n{text}")).unwrap();
    let o = wfem(&["retrieval", "add", &index, &more]);
    assert!(o.status.success(), "{}", stderr(&o));

    // A robust index records its Laplacian and takes the same mix.
    let robust = p("robust.sqlite");
    let mut args = vec!["retrieval", "build"];
    args.extend(files.iter().map(String::as_str));
    args.extend([
        "--out",
        &robust,
        "--words",
        "6",
        "--eigenpairs",
        "30",
        "--laplacian",
        "robust",
    ]);
    let o = wfem(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = wfem(&["retrieval", "query", &robust, &files[0], "--top", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Issue #41 (small messages): an empty point file is refused naming the file (every command
/// reads its input through the same `read_input`; `hks` here), and nothing is written.
#[test]
fn an_empty_point_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty.xyz");
    std::fs::write(&empty, "").unwrap();
    let e = empty.to_str().unwrap();
    let out = dir.path().join("h.npy");
    let o = wfem(&["hks", e, "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("empty.xyz") && err.contains("0 points"), "{err}");
    assert!(!out.exists());
}
