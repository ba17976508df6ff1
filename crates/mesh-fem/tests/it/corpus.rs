//! Walks the whole real-mesh corpus (`wfem_corpus`): every file loads with default
//! options or fails with the error listed below; counts agree with the corpus' SOURCES.md.

use mesh_fem::io::{load, LoadOptions, LoadReport};
use mesh_fem::{MeshError, TriMesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use wfem_corpus::{all_mesh_files, mesh_path, meshes_dir};

/// Number of mesh files SOURCES.md's per-file table lists.
const CORPUS_FILES: usize = 209;

/// The SHREC'11 collection (500-face copy): its own folder, SOURCES.md and `labels.csv`
/// (`file,class`), 600 closed triangle meshes of 250–252 vertices and 500 faces each.
const SHREC11: &str = "shrec11-meshcnn500/";
const SHREC11_FILES: usize = 600;

/// Files that do NOT load with default options, and the error they must give: the polygon
/// meshes (`MeshError::Polygon` naming the first polygon, 0-based record index, and its
/// corner count). Every other corpus file must load.
const POLYGON_FILES: [(&str, usize, usize); 6] = [
    ("geometry-central-test-assets/dodecahedron_poly.obj", 0, 5),
    ("geometry-central-test-assets/moebius.obj", 0, 4),
    ("geometry-central-test-assets/platonic_shelf.obj", 0, 4),
    ("libigl-tutorial-data/cube.off", 0, 4),
    ("pmp-data/fandisk_quads.off", 0, 4),
    ("potpourri3d-test/bunny_poly.ply", 1, 4),
];

/// Hand-checked counts (vertices, faces after loading, welded, triangulated) for a handful
/// of files, with triangulation on. Faces after fan triangulation: a k-gon gives k − 2.
const SPOT_CHECKS: [(&str, usize, usize, usize, usize); 9] = [
    ("common-3d-test-models/spot.obj", 2930, 5856, 0, 0),
    ("geometry-central-test-assets/spot.ply", 2930, 5856, 0, 0),
    ("common-3d-test-models/horse.ply", 48485, 96966, 0, 0),
    ("geometry-central-test-assets/stl_box_ascii.stl", 8, 12, 28, 0),
    ("geometry-central-test-assets/stl_box_binary.stl", 8, 12, 28, 0),
    ("pmp-data/icosahedron_ascii.stl", 12, 20, 48, 0),
    ("pmp-data/icosahedron_binary.stl", 12, 20, 48, 0),
    // 12 pentagons → 36 triangles; 6 quads → 12 triangles.
    ("geometry-central-test-assets/dodecahedron_poly.obj", 20, 36, 0, 12),
    ("libigl-tutorial-data/cube.off", 8, 12, 0, 6),
];

fn rel(path: &Path, root: &Path) -> String {
    path.strip_prefix(root)
        .unwrap_or(path)
        .to_string_lossy()
        .replace('\\', "/")
}

/// `file → (format column, V, F)` from the per-file table of SOURCES.md.
fn sources_table(root: &Path) -> BTreeMap<String, (String, usize, usize)> {
    let text = std::fs::read_to_string(root.join("SOURCES.md")).expect("SOURCES.md in corpus");
    let mut table = BTreeMap::new();
    for line in text.lines() {
        let cols: Vec<&str> = line.split('|').map(str::trim).collect();
        // | `file` | fmt | V | F | …
        if cols.len() < 6 || !cols[1].starts_with('`') {
            continue;
        }
        let (Ok(v), Ok(f)) = (cols[3].parse::<usize>(), cols[4].parse::<usize>()) else {
            continue; // the sources table has no counts
        };
        table.insert(cols[1].trim_matches('`').to_string(), (cols[2].to_string(), v, f));
    }
    table
}

type Outcome = Result<(TriMesh, LoadReport), MeshError>;

fn load_all(files: &[PathBuf], opts: &LoadOptions) -> Vec<Outcome> {
    files.par_iter().map(|p| load(p, opts)).collect()
}

#[test]
fn every_corpus_file_loads_or_gives_its_expected_error() {
    let root = meshes_dir().unwrap();
    let (shrec11, files): (Vec<PathBuf>, Vec<PathBuf>) = all_mesh_files()
        .unwrap()
        .into_iter()
        .partition(|p| rel(p, &root).starts_with(SHREC11));
    assert_eq!(files.len(), CORPUS_FILES, "corpus at {}", root.display());
    check_shrec11(&root, &shrec11);
    let names: Vec<String> = files.iter().map(|p| rel(p, &root)).collect();
    for (polygon_file, _, _) in POLYGON_FILES {
        assert!(names.iter().any(|n| n == polygon_file), "{polygon_file} missing");
    }
    let table = sources_table(&root);
    assert_eq!(table.len(), CORPUS_FILES, "rows with counts in SOURCES.md");

    let strict = load_all(&files, &LoadOptions::default());
    let triangulated = load_all(&files, &LoadOptions::with_triangulation(true));
    let mut failures = Vec::new();
    for ((name, strict), triangulated) in names.iter().zip(strict).zip(triangulated) {
        let polygon = POLYGON_FILES.iter().find(|(n, _, _)| n == name);
        match (polygon, &strict) {
            (None, Ok(_)) => {}
            (
                Some((_, face, corners)),
                Err(MeshError::Polygon {
                    face: f, corners: c, ..
                }),
            ) if (f, c) == (face, corners) => {}
            (_, other) => {
                failures.push(format!("{name}: default load gave {:?}", other.as_ref().err()));
                continue;
            }
        }
        let (mesh, report) = match triangulated {
            Ok(x) => x,
            Err(e) => {
                failures.push(format!("{name}: triangulating load failed: {e}"));
                continue;
            }
        };
        // Without polygons both loads agree exactly.
        if let Ok((m, r)) = &strict {
            assert_eq!((m, r), (&mesh, &report), "{name}");
        } else {
            assert!(report.triangulated_polygons > 0, "{name}");
        }
        let Some((fmt, v, f)) = table.get(name) else {
            failures.push(format!("{name}: not in SOURCES.md"));
            continue;
        };
        if mesh.n_vertices() != *v {
            failures.push(format!("{name}: {} vertices, SOURCES.md says {v}", mesh.n_vertices()));
        }
        // F counts face records; each polygon adds (corners − 3) triangles, so the record
        // count is at most the triangle count, with equality exactly for triangle meshes.
        let records_ok = if polygon.is_some() {
            mesh.n_faces() > *f && report.triangulated_polygons <= *f
        } else {
            mesh.n_faces() == *f
        };
        if !records_ok {
            failures.push(format!(
                "{name}: {} faces ({} polygons triangulated), SOURCES.md says {f} records",
                mesh.n_faces(),
                report.triangulated_polygons
            ));
        }
        let expected_format = match fmt.split_whitespace().next() {
            Some("OBJ") => mesh_fem::io::MeshFormat::Obj,
            Some("OFF") => mesh_fem::io::MeshFormat::Off,
            Some("PLY") => mesh_fem::io::MeshFormat::Ply,
            _ => mesh_fem::io::MeshFormat::Stl,
        };
        assert_eq!(report.format, expected_format, "{name}");
        assert!(mesh.area() > 0.0, "{name}");
    }
    assert!(
        failures.is_empty(),
        "{} problems:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Every SHREC'11 file is listed once in `labels.csv` and loads as a closed 500-face mesh of
/// 250–252 vertices (its SOURCES.md).
fn check_shrec11(root: &Path, files: &[PathBuf]) {
    assert_eq!(files.len(), SHREC11_FILES, "{SHREC11} files");
    let labels = std::fs::read_to_string(root.join(SHREC11).join("labels.csv")).expect("labels.csv");
    let listed: std::collections::BTreeSet<String> = labels
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .map(|f| format!("{SHREC11}{f}"))
        .collect();
    assert_eq!(listed.len(), SHREC11_FILES, "labels.csv rows");
    let outcomes = load_all(files, &LoadOptions::default());
    for (path, outcome) in files.iter().zip(outcomes) {
        let name = rel(path, root);
        assert!(listed.contains(&name), "{name} is not in labels.csv");
        let (mesh, _) = outcome.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            (250..=252).contains(&mesh.n_vertices()),
            "{name}: {} vertices",
            mesh.n_vertices()
        );
        assert_eq!(mesh.n_faces(), 500, "{name}");
    }
}

#[test]
fn spot_checks_against_hand_read_counts() {
    let opts = LoadOptions::with_triangulation(true);
    for (name, v, f, welded, triangulated) in SPOT_CHECKS {
        let (mesh, report) = load(&mesh_path(name).unwrap(), &opts).unwrap();
        assert_eq!(
            (
                mesh.n_vertices(),
                mesh.n_faces(),
                report.welded_vertices,
                report.triangulated_polygons
            ),
            (v, f, welded, triangulated),
            "{name}"
        );
    }
    // bunny_poly: 1482 polygon records over the same 1241 vertices as bunny_small.
    let (poly, report) = load(&mesh_path("potpourri3d-test/bunny_poly.ply").unwrap(), &opts).unwrap();
    let (small, _) = load(&mesh_path("potpourri3d-test/bunny_small.ply").unwrap(), &opts).unwrap();
    assert_eq!(poly.n_vertices(), 1241);
    assert!(report.triangulated_polygons > 0 && report.triangulated_polygons <= 1482);
    assert_eq!(small.n_vertices(), 1241);
}

#[test]
fn same_surface_in_two_formats_reads_identically() {
    let opts = LoadOptions::default();
    let get = |n: &str| load(&mesh_path(n).unwrap(), &opts).unwrap().0;
    // STL ASCII and binary boxes: same welded topology and positions (f32 in both).
    assert_eq!(
        get("geometry-central-test-assets/stl_box_ascii.stl").faces(),
        get("geometry-central-test-assets/stl_box_binary.stl").faces()
    );
    let (a, b) = (
        get("pmp-data/icosahedron_ascii.stl"),
        get("pmp-data/icosahedron_binary.stl"),
    );
    assert_eq!(a.faces(), b.faces());
    for (p, q) in a.positions().iter().zip(b.positions()) {
        for k in 0..3 {
            // ASCII prints ~7 digits of the same f32 values.
            assert!((p[k] - q[k]).abs() <= 1e-6 * (1.0 + p[k].abs()), "{p:?} vs {q:?}");
        }
    }
    // spot as OBJ and as PLY (float): same faces, positions equal to f32 precision.
    let (obj, ply) = (
        get("common-3d-test-models/spot.obj"),
        get("geometry-central-test-assets/spot.ply"),
    );
    assert_eq!(obj.faces(), ply.faces());
    for (p, q) in obj.positions().iter().zip(ply.positions()) {
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() <= 1e-6, "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn corpus_helpers_name_missing_files() {
    match mesh_path("no/such/mesh.obj") {
        Err(MeshError::Io { path, source }) => {
            assert!(path.ends_with("no/such/mesh.obj"));
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("expected Io NotFound, got {other:?}"),
    }
}
