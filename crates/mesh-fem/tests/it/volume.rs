//! Tetrahedral meshes (issue #39): the FEM identities of L, B, D on tetrahedra, the element
//! against a hand-computed one, refinement, the boundary, validation and repairs, and every
//! reader on the real volumes of the corpus with the counts of its SOURCES.md.

use mesh_fem::generate::tet_cube;
use mesh_fem::io::volume::{read_volume, VolumeFormat};
use mesh_fem::volume::{
    assemble_volume, boundary_faces, repair_volume, tet_element, validate_volume, TetMesh, VolumeProblem,
};
use mesh_fem::{AssemblyParams, Laplacian, Lumping, MeshError};

fn dense(m: &faer::sparse::SparseColMat<usize, f64>) -> Vec<Vec<f64>> {
    let n = m.nrows();
    let mut out = vec![vec![0.0; n]; n];
    let r = m.as_ref();
    for j in 0..n {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            out[i][j] += v;
        }
    }
    out
}

#[test]
fn the_operators_of_a_cube_keep_the_fem_identities() {
    let mesh = tet_cube(4);
    let ops = assemble_volume(&mesh, &AssemblyParams::default()).unwrap();
    let (l, b) = (dense(&ops.stiffness), dense(&ops.mass));
    let n = mesh.n_vertices();
    let total: f64 = b.iter().flatten().sum();
    assert!((total - 1.0).abs() < 1e-13, "1ᵀB1 = {total}");
    assert!((ops.lumped_diagonal.iter().sum::<f64>() - 1.0).abs() < 1e-13);
    for i in 0..n {
        let row: f64 = l[i].iter().sum();
        assert!(row.abs() < 1e-12, "L·1 at {i}: {row}");
        assert!(
            (b[i].iter().sum::<f64>() - ops.lumped_diagonal[i]).abs() < 1e-15,
            "D = row sums of B"
        );
        assert!(l[i][i] > 0.0);
        for j in 0..n {
            assert_eq!(l[i][j], l[j][i]);
            assert_eq!(b[i][j], b[j][i]);
        }
    }
    // A linear function is harmonic inside: (Lx)_i = 0 at interior vertices.
    let x: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
    for (i, p) in mesh.positions().iter().enumerate() {
        if p.iter().all(|c| *c > 1e-9 && *c < 1.0 - 1e-9) {
            let lx: f64 = (0..n).map(|j| l[i][j] * x[j]).sum();
            assert!(lx.abs() < 1e-12, "{lx}");
        }
    }
}

#[test]
fn the_element_of_the_reference_tetrahedron() {
    // Corners 0, e1, e2, e3: volume 1/6, ∇φ₀ = (−1, −1, −1), ∇φᵢ = eᵢ.
    let e = tet_element([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap();
    assert!((e.volume - 1.0 / 6.0).abs() < 1e-16);
    assert_eq!(e.gradients[0], [-1.0, -1.0, -1.0]);
    assert_eq!(e.gradients[1], [1.0, 0.0, 0.0]);
    // L_01 = V ∇φ₀·∇φ₁ = −1/6 (the −(1/6) ℓ cot θ of the opposite edge's dihedral angle 90°… for
    // the edge 23 of length √2 with dihedral angle 60°: −√2·cot 60°/6 = −1/(3√6)·√3 = −1/6·…).
    let mesh = TetMesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2, 3]],
    )
    .unwrap();
    let ops = assemble_volume(&mesh, &AssemblyParams::default()).unwrap();
    let l = dense(&ops.stiffness);
    assert!((l[0][1] + 1.0 / 6.0).abs() < 1e-15 && (l[1][2]).abs() < 1e-15 && (l[0][0] - 0.5).abs() < 1e-15);
    let b = dense(&ops.mass);
    assert!((b[0][0] - 1.0 / 60.0).abs() < 1e-16 && (b[0][1] - 1.0 / 120.0).abs() < 1e-16);
    // An inverted copy gives the same matrices.
    let flipped = TetMesh::new(mesh.positions().to_vec(), vec![[1, 0, 2, 3]]).unwrap();
    let f = assemble_volume(&flipped, &AssemblyParams::default()).unwrap();
    assert_eq!(dense(&f.stiffness), l);
}

#[test]
fn scaling_multiplies_l_by_s_and_b_by_s_cubed() {
    let mesh = tet_cube(2);
    let a = assemble_volume(&mesh, &AssemblyParams::default()).unwrap();
    for s in [1e-6, 1e6] {
        let b = assemble_volume(&mesh.scaled(s).unwrap(), &AssemblyParams::default()).unwrap();
        for (x, y) in a.stiffness.val().iter().zip(b.stiffness.val()) {
            assert!((y - s * x).abs() <= 1e-12 * (s * x).abs().max(s * 1e-3));
        }
        for (x, y) in a.mass.val().iter().zip(b.mass.val()) {
            assert!((y - s * s * s * x).abs() <= 1e-12 * (s * s * s * x).abs());
        }
    }
}

#[test]
fn refinement_and_the_boundary_keep_the_solid() {
    let mesh = tet_cube(2);
    let fine = mesh.refined();
    assert_eq!(fine.n_tets(), 8 * mesh.n_tets());
    assert!((fine.volume() - 1.0).abs() < 1e-14);
    assert!((0..fine.n_tets()).all(|t| fine.signed_volume(t) > 0.0));
    let report = validate_volume(&fine);
    assert!(report.problems.is_empty(), "{:?}", report.problems);
    // The boundary of the cube: 2 triangles per boundary square, 6 sides, closed (χ = 2),
    // oriented outward (its divergence-theorem volume is the volume).
    let faces = boundary_faces(&mesh);
    assert_eq!(faces.len(), 12 * 4);
    assert_eq!(validate_volume(&mesh).boundary_euler, 2);
    let p = mesh.positions();
    let volume: f64 = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|v| p[v as usize]);
            mesh_fem::vec3::dot(a, mesh_fem::vec3::cross(b, c)) / 6.0
        })
        .sum();
    assert!((volume - 1.0).abs() < 1e-14, "{volume}");
    let surface = mesh.boundary_mesh().unwrap();
    assert_eq!(surface.n_vertices(), mesh.n_vertices());
}

/// The cells of `tet_cube(n)` whose centre passes `keep`, without the vertices they leave out.
fn cells_of_cube(n: usize, keep: impl Fn([f64; 3]) -> bool) -> TetMesh {
    let cube = tet_cube(n);
    let tets: Vec<[u32; 4]> = (0..cube.n_tets())
        .filter(|&t| {
            let c = cube.corners(t);
            // The cell of a tetrahedron: the floor of its centroid in cell units.
            let centre = [0, 1, 2].map(|k| c.iter().map(|p| p[k]).sum::<f64>() / 4.0);
            keep(centre.map(|x| ((x * n as f64).floor() + 0.5) / n as f64))
        })
        .map(|t| cube.tets()[t])
        .collect();
    let kept = TetMesh::new(cube.positions().to_vec(), tets).unwrap();
    repair_volume(&kept, false, false, true).unwrap().0
}

#[test]
fn the_boundary_genus_and_the_worst_element_are_reported() {
    let ball = validate_volume(&tet_cube(3));
    assert_eq!((ball.n_boundary_components, ball.boundary_genus), (1, Some(0)));
    // The 3 × 3 × 3 cube without its central column of cells: a solid torus.
    let middle = |x: f64| (x - 0.5).abs() < 0.1;
    let torus = validate_volume(&cells_of_cube(3, |c| !(middle(c[0]) && middle(c[1]))));
    assert_eq!(torus.boundary_euler, 0);
    assert_eq!((torus.n_boundary_components, torus.boundary_genus), (1, Some(1)));
    // Without its central cell: a hollow cube, two boundary spheres.
    let hollow = validate_volume(&cells_of_cube(3, |c| !c.iter().all(|&x| middle(x))));
    assert_eq!(hollow.boundary_euler, 4);
    assert_eq!((hollow.n_boundary_components, hollow.boundary_genus), (2, Some(0)));
    // Two columns of cells meeting along an edge: that edge is on four boundary triangles, so
    // the boundary is no closed 2-manifold and its genus is not given.
    let pinched = validate_volume(&cells_of_cube(2, |c| (c[0] < 0.5) == (c[1] < 0.5)));
    assert_eq!(pinched.boundary_genus, None);
    // The worst element is named, and it has the smallest quality.
    let mut squashed = tet_cube(2).positions().to_vec();
    squashed[13][2] += 0.499; // the centre next to the top one: tetrahedra of both flatten
    let squashed = TetMesh::new(squashed, tet_cube(2).tets().to_vec()).unwrap();
    let r = validate_volume(&squashed);
    let q = mesh_fem::volume::tet_quality(squashed.corners(r.worst_tet));
    assert_eq!(q, r.quality.0);
    assert!(squashed.tets()[r.worst_tet].contains(&13));
    assert!(r
        .problems
        .iter()
        .any(|p| matches!(p, VolumeProblem::Slivers { worst, .. } if *worst == r.worst_tet)));
}

#[test]
fn validation_names_every_problem_and_the_repairs_fix_them() {
    let cube = tet_cube(2);
    let mut positions = cube.positions().to_vec();
    positions.push([5.0, 5.0, 5.0]); // unreferenced
    let mut tets = cube.tets().to_vec();
    tets[0].swap(0, 1); // inverted
    let flat = [0u32, 1, 2, 0];
    tets.push([flat[0], flat[1], flat[2], 2]); // repeated vertex: zero volume
    let mesh = TetMesh::new(positions, tets).unwrap();
    let report = validate_volume(&mesh);
    assert!(report.problems.iter().any(|p| matches!(p, VolumeProblem::Flat { .. })));
    assert!(report
        .problems
        .iter()
        .any(|p| matches!(p, VolumeProblem::Unreferenced { count: 1, .. })));
    assert!(report
        .problems
        .iter()
        .any(|p| matches!(p, VolumeProblem::Inverted { count: 1, first: 0 })));
    assert!(report.clone().into_result().is_err());
    assert!(matches!(
        assemble_volume(&mesh, &AssemblyParams::default()),
        Err(MeshError::DegenerateTet { .. })
    ));
    let (fixed, rep) = repair_volume(&mesh, true, true, true).unwrap();
    assert_eq!((rep.flipped, rep.dropped_tets, rep.dropped_vertices), (1, 1, 1));
    assert!(validate_volume(&fixed).problems.is_empty());
    assert!(assemble_volume(&fixed, &AssemblyParams::default()).is_ok());
    // What tetrahedra cannot have.
    for params in [
        AssemblyParams::for_mass(mesh_fem::Mass::Lumped(Lumping::Voronoi)),
        AssemblyParams {
            laplacian: Laplacian::Robust(Default::default()),
            ..Default::default()
        },
    ] {
        assert!(matches!(
            assemble_volume(&fixed, &params),
            Err(MeshError::InvalidParameter { .. })
        ));
    }
    assert!(matches!(
        TetMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2, 3]]),
        Err(MeshError::TetIndexOutOfRange { index: 3, .. })
    ));
    assert!(matches!(
        TetMesh::new(vec![[f64::NAN; 3]; 4], vec![[0, 1, 2, 3]]),
        Err(MeshError::NonFiniteCoordinate { .. })
    ));
}

/// (file, format, vertices, tetrahedra, ignored elements) from the corpus' SOURCES.md.
const FILES: [(&str, VolumeFormat, usize, usize, &[(&str, usize)]); 8] = [
    (
        "flip-free-parametrization/cow.mesh",
        VolumeFormat::Medit,
        2304,
        8103,
        &[("triangles", 3318)],
    ),
    (
        "libigl-tutorial-data/octopus-low.mesh",
        VolumeFormat::Medit,
        452,
        1140,
        &[("triangles", 898)],
    ),
    ("sfepy/unit_ball.mesh", VolumeFormat::Medit, 363, 1110, &[]),
    (
        "libigl-tutorial-data/hand.msh",
        VolumeFormat::Gmsh,
        7234,
        29998,
        &[("triangles", 9556)],
    ),
    (
        "scikit-fem/box.msh",
        VolumeFormat::Gmsh,
        358,
        1105,
        &[("triangles", 312)],
    ),
    (
        "scikit-fem/cuubat.msh",
        VolumeFormat::Gmsh,
        419,
        1391,
        &[("triangles", 132)],
    ),
    ("lapy/cubeTetra.vtk", VolumeFormat::Vtk, 9261, 48000, &[]),
    (
        "flip-free-parametrization/fish.mesh",
        VolumeFormat::Medit,
        1890,
        6418,
        &[("triangles", 2896)],
    ),
];

#[test]
fn every_reader_reads_the_corpus_with_its_counts() {
    let Ok(_) = wfem_corpus::volumes_dir() else {
        eprintln!("skipped: no volume corpus");
        return;
    };
    for (rel, format, n, m, ignored) in FILES {
        let path = wfem_corpus::volume_path(rel).unwrap();
        let read = read_volume(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(read.format, format, "{rel}");
        assert_eq!((read.mesh.n_vertices(), read.mesh.n_tets()), (n, m), "{rel}");
        for (kind, count) in ignored {
            assert!(
                read.ignored.iter().any(|(k, c)| k == kind && c == count),
                "{rel}: {:?}",
                read.ignored
            );
        }
        let report = validate_volume(&read.mesh);
        match rel {
            "sfepy/unit_ball.mesh" => {
                assert!(report
                    .problems
                    .iter()
                    .any(|p| matches!(p, VolumeProblem::Unreferenced { count: 1, first: 0 })));
                assert!((report.volume - 4.10663).abs() < 1e-5, "{}", report.volume);
            }
            "lapy/cubeTetra.vtk" => {
                assert!(report
                    .problems
                    .iter()
                    .any(|p| matches!(p, VolumeProblem::Inverted { count: 24000, .. })));
                assert!((report.volume - 1.0).abs() < 1e-12);
                assert_eq!(report.n_boundary_faces, 4800);
            }
            "libigl-tutorial-data/hand.msh" => {
                assert!(report
                    .problems
                    .iter()
                    .any(|p| matches!(p, VolumeProblem::Slivers { count: 17, .. })));
            }
            // One tet of quality 0.00998, just under the sliver bound 0.01.
            "libigl-tutorial-data/octopus-low.mesh" => {
                assert!(report
                    .problems
                    .iter()
                    .any(|p| matches!(p, VolumeProblem::Slivers { count: 1, .. })));
            }
            "scikit-fem/cuubat.msh" => assert!((report.volume - 2.0).abs() < 1e-12),
            _ => assert!(report.problems.is_empty(), "{rel}: {:?}", report.problems),
        }
        assert_eq!(report.boundary_euler, 2, "{rel}");
        if report.clone().into_result().is_ok() {
            assemble_volume(&read.mesh, &AssemblyParams::default()).unwrap();
        }
    }
}

#[test]
fn bad_volume_files_get_typed_errors_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &str); 10] = [
        ("a.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n2\n0 0 0 0\n1 1 1\n", "ends"),
        ("b.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n-4\n", "negative"),
        ("c.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n1000000000\n0 0 0 0\n", "more than the file"),
        ("d.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 nan 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n", "not finite"),
        ("e.mesh", "MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\nTetrahedra\n1\n1 2 3 9 0\nEnd\n", "out of range"),
        ("f.mesh", "MeshVersionFormatted 1\nDimension 2\n", "dimension 3"),
        ("g.mesh", "MeshVersionFormatted 1\nDimension 3\nBananas 3\n", "unknown MEDIT keyword"),
        ("h.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n", "not defined"),
        ("i.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\n", "only ASCII"),
        ("j.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 2\n10\n", "ends"),
    ];
    for (name, text, expected) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let err = read_volume(&path).unwrap_err().to_string();
        assert!(err.contains(expected), "{name}: {err}");
    }
    // A FIFO is refused, never waited on; an unknown extension names the volume formats.
    #[cfg(unix)]
    {
        let fifo = dir.path().join("x.mesh");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(status.success());
        let err = read_volume(&fifo).unwrap_err().to_string();
        assert!(err.contains("FIFO"), "{err}");
    }
    let err = read_volume(&dir.path().join("x.tet")).unwrap_err().to_string();
    assert!(err.contains(".mesh, .msh, .vtk"), "{err}");
}

#[test]
fn tetgen_files_are_read_from_either_path() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("t.node"),
        "# a tetrahedron\n4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n",
    )
    .unwrap();
    std::fs::write(dir.path().join("t.ele"), "1 4 0\n1 1 2 3 4\n").unwrap();
    for name in ["t.ele", "t.node"] {
        let read = read_volume(&dir.path().join(name)).unwrap();
        assert_eq!(read.mesh.tets(), &[[0, 1, 2, 3]]);
        assert!((read.mesh.volume() - 1.0 / 6.0).abs() < 1e-16);
    }
}

#[test]
fn vtu_holds_the_tetrahedra_and_refuses_bad_fields() {
    use mesh_fem::io::vtu::{stage_vtu, Cells};
    use mesh_fem::io::AtomicSet;
    let cube = mesh_fem::generate::tet_cube(2);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.vtu");
    let f: Vec<f64> = cube.positions().iter().map(|p| p[0]).collect();
    let mut set = AtomicSet::new();
    stage_vtu(
        &mut set,
        &path,
        cube.positions(),
        Cells::Tetrahedra(cube.tets()),
        &[("x<1>", &f)],
        false,
    )
    .unwrap();
    set.commit().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(&format!(
        "NumberOfPoints=\"{}\" NumberOfCells=\"{}\"",
        cube.n_vertices(),
        cube.n_tets()
    )));
    assert!(text.contains("Name=\"x&lt;1&gt;\""));
    assert!(text.matches(" 10").count() >= cube.n_tets());
    let short = vec![0.0; 3];
    let nan = vec![f64::NAN; cube.n_vertices()];
    let other = dir.path().join("d.vtu");
    for (fields, expected) in [
        (vec![("a", short.as_slice())], "values"),
        (vec![("a", nan.as_slice())], "NaN"),
        (vec![("a", f.as_slice()), ("a", f.as_slice())], "twice"),
        (vec![], "at least one field"),
    ] {
        let mut set = AtomicSet::new();
        let err = stage_vtu(
            &mut set,
            &other,
            cube.positions(),
            Cells::Tetrahedra(cube.tets()),
            &fields,
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains(expected), "{err}");
    }
    assert!(!other.exists());
}

#[test]
fn a_cut_shows_the_interior_field_exactly() {
    use mesh_fem::volume::cut::cut;
    // The cube cut at x = 0.37 (between grid planes): the section is the unit square at x = 0.37,
    // the kept boundary is the part of the surface with x ≤ 0.37 (area 1 + 4·0.37), and a linear
    // field is interpolated exactly (P1).
    let cube = mesh_fem::generate::tet_cube(4);
    let c = cut(&cube, [1.0, 0.0, 0.0], 0.37).unwrap();
    let p = c.mesh.positions();
    assert!(p.iter().all(|q| q[0] <= 0.37 + 1e-12));
    let f: Vec<f64> = cube
        .positions()
        .iter()
        .map(|q| q[0] + 2.0 * q[1] - 3.0 * q[2])
        .collect();
    for (q, v) in p.iter().zip(c.values(&f)) {
        assert!((v - (q[0] + 2.0 * q[1] - 3.0 * q[2])).abs() < 1e-12);
    }
    let area = |face: &[u32; 3]| {
        let [a, b, d] = face.map(|i| p[i as usize]);
        0.5 * mesh_fem::vec3::norm(mesh_fem::vec3::cross(
            mesh_fem::vec3::sub(b, a),
            mesh_fem::vec3::sub(d, a),
        ))
    };
    let on_plane = |face: &[u32; 3]| face.iter().all(|&i| (p[i as usize][0] - 0.37).abs() < 1e-12);
    let section: f64 = c.mesh.faces().iter().filter(|f| on_plane(f)).map(area).sum();
    let rest: f64 = c.mesh.faces().iter().filter(|f| !on_plane(f)).map(area).sum();
    assert!((section - 1.0).abs() < 1e-12, "section {section}");
    assert!((rest - (1.0 + 4.0 * 0.37)).abs() < 1e-12, "kept boundary {rest}");
    // A plane beyond the volume leaves nothing.
    assert!(cut(&cube, [1.0, 0.0, 0.0], -1.0).is_err());
}

/// A fuzzing pass that runs in CI (the libFuzzer targets `volume_*` run longer, docs/FUZZING.md):
/// small real files of each one-file format, mutated 3,000 times each (bytes flipped, runs
/// deleted or repeated, cut short) with the project's RNG, read from memory: a typed error
/// or tetrahedra in range, never a panic.
#[test]
fn mutated_volume_files_give_typed_errors_or_valid_tetrahedra() {
    use mesh_fem::io::volume::{parse_volume, VolumeFormat};
    use wfem_base::rng::SplitMix64;
    let Ok(dir) = wfem_corpus::volumes_dir() else {
        eprintln!("skipped: no volume corpus");
        return;
    };
    let mut rng = SplitMix64::new(0x7e7);
    for (rel, format) in [
        ("scikit-fem/cuubat.msh", VolumeFormat::Gmsh),
        ("scikit-fem/box.msh", VolumeFormat::Gmsh),
        ("sfepy/unit_ball.mesh", VolumeFormat::Medit),
        ("libigl-tutorial-data/octopus-low.mesh", VolumeFormat::Medit),
    ] {
        let original = std::fs::read(dir.join(rel)).unwrap();
        let original = &original[..original.len().min(64 * 1024)];
        for _ in 0..3000 {
            let mut data = original.to_vec();
            for _ in 0..1 + rng.next_below(4) {
                let at = rng.next_below(data.len().max(1));
                match rng.next_below(4) {
                    0 => data[at] = rng.next_u64() as u8,
                    1 => {
                        let end = (at + rng.next_below(64)).min(data.len());
                        data.drain(at..end);
                    }
                    2 => {
                        let end = (at + rng.next_below(16)).min(data.len());
                        let run = data[at..end].to_vec();
                        data.splice(at..at, run);
                    }
                    _ => data.truncate(at),
                }
                if data.is_empty() {
                    break;
                }
            }
            match parse_volume(&data, format, std::path::Path::new(rel)) {
                Ok(read) => {
                    let n = read.mesh.n_vertices();
                    assert!(read.mesh.tets().iter().flatten().all(|&i| (i as usize) < n));
                    assert!(read.mesh.positions().iter().flatten().all(|c| c.is_finite()));
                }
                Err(e) => assert!(!e.to_string().is_empty()),
            }
        }
    }
    // The VTK reader on mutations of a small generated grid.
    let mut text = String::from("# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 double\n");
    text.push_str("0 0 0 1 0 0 0 1 0 0 0 1 1 1 1\nCELLS 2 10\n4 0 1 2 3\n4 1 2 3 4\nCELL_TYPES 2\n10\n10\n");
    assert!(parse_volume(text.as_bytes(), VolumeFormat::Vtk, std::path::Path::new("g.vtk")).is_ok());
    for _ in 0..3000 {
        let mut data = text.clone().into_bytes();
        let at = rng.next_below(data.len());
        data[at] = b"0123456789 -.\ne"[rng.next_below(15)];
        if let Ok(read) = parse_volume(&data, VolumeFormat::Vtk, std::path::Path::new("g.vtk")) {
            let n = read.mesh.n_vertices();
            assert!(read.mesh.tets().iter().flatten().all(|&i| (i as usize) < n));
        }
    }
}

#[test]
fn the_generated_bumpy_solid_is_a_valid_ball_filled_with_positive_tetrahedra() {
    for (level, shells) in [(0, 1), (1, 3), (2, 4), (3, 8)] {
        let solid = mesh_fem::generate::tet_bumpy(level, shells);
        let per_shell = mesh_fem::generate::icosphere_vertex_count(level);
        assert_eq!(solid.n_vertices(), 1 + shells * per_shell);
        // Orientation is fixed by the generator; no tetrahedron is flat or nearly so.
        let r = validate_volume(&solid);
        assert!(r.problems.is_empty(), "{level}/{shells}: {:?}", r.problems);
        assert!(r.quality.0 > 0.02, "{level}/{shells}: quality {}", r.quality.0);
        assert_eq!((r.n_boundary_components, r.boundary_genus), (1, Some(0)));
        // Its boundary is the outer shell, between the bump's radii 0.6 and 1.4.
        assert_eq!(r.n_boundary_vertices, per_shell);
        assert_eq!(solid.positions()[0], [0.0; 3]);
        for f in boundary_faces(&solid) {
            for v in f {
                let radius = mesh_fem::vec3::norm(solid.positions()[v as usize]);
                assert!((0.6..1.4).contains(&radius), "boundary radius {radius}");
            }
        }
        // The tetrahedra fill what the boundary encloses, once (divergence theorem).
        let p = solid.positions();
        let enclosed: f64 = boundary_faces(&solid)
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| p[v as usize]);
                mesh_fem::vec3::dot(a, mesh_fem::vec3::cross(b, c)) / 6.0
            })
            .sum();
        assert!(
            (enclosed - solid.volume()).abs() < 1e-12 * enclosed,
            "{enclosed} vs {}",
            solid.volume()
        );
    }
}

/// (L_ij, B_ij) by (i, j).
type Entries = std::collections::BTreeMap<(usize, usize), (f64, f64)>;

/// The plain element-by-element scatter of the module docs' matrices (no column machinery,
/// sequential, a map per entry): L_ij += |T|∇φᵢ·∇φⱼ, B_ij += |T|(1 + δ_ij)/20, D_ii += |T|/4.
fn scattered(mesh: &TetMesh) -> (Entries, Vec<f64>) {
    let mut entries = std::collections::BTreeMap::new();
    let mut d = vec![0.0; mesh.n_vertices()];
    for (t, tet) in mesh.tets().iter().enumerate() {
        let e = tet_element(mesh.corners(t)).unwrap();
        for a in 0..4 {
            d[tet[a] as usize] += e.volume / 4.0;
            for b in 0..4 {
                let l = e.volume * mesh_fem::vec3::dot(e.gradients[a], e.gradients[b]);
                let m = e.volume * if a == b { 2.0 } else { 1.0 } / 20.0;
                let x = entries.entry((tet[a] as usize, tet[b] as usize)).or_insert((0.0, 0.0));
                x.0 += l;
                x.1 += m;
            }
        }
    }
    (entries, d)
}

/// The parallel column assembly against the plain scatter: the same pattern, every entry of L
/// to 1e−13 of max|L|, of B and D to 1e−13 of their largest (mixed orientation, a refined
/// irregular solid, the real files of the corpus), and L, B bitwise symmetric.
#[test]
fn the_column_assembly_equals_the_plain_element_scatter() {
    let mut cases = vec![(
        "bumpy solid, refined".to_string(),
        mesh_fem::generate::tet_bumpy(1, 3).refined(),
    )];
    // Every third tetrahedron inverted: the matrices do not depend on the orientation.
    let cube = tet_cube(5);
    let mixed: Vec<[u32; 4]> = cube
        .tets()
        .iter()
        .enumerate()
        .map(|(t, &[a, b, c, d])| if t % 3 == 0 { [b, a, c, d] } else { [a, b, c, d] })
        .collect();
    cases.push((
        "mixed orientation".to_string(),
        TetMesh::new(cube.positions().to_vec(), mixed).unwrap(),
    ));
    for rel in ["scikit-fem/cuubat.msh", "flip-free-parametrization/cow.mesh"] {
        if let Ok(path) = wfem_corpus::volume_path(rel) {
            cases.push((rel.to_string(), read_volume(&path).unwrap().mesh));
        }
    }
    for (name, mesh) in cases {
        let ops = assemble_volume(&mesh, &AssemblyParams::default()).unwrap();
        let (reference, d) = scattered(&mesh);
        let (l, b) = (ops.stiffness.as_ref(), ops.mass.as_ref());
        assert_eq!(l.val().len(), reference.len(), "{name}: pattern size");
        let l_max = reference.values().fold(0.0f64, |m, x| m.max(x.0.abs()));
        let b_max = reference.values().fold(0.0f64, |m, x| m.max(x.1.abs()));
        let mut stored = std::collections::BTreeMap::new();
        for j in 0..ops.n() {
            let rows = l.row_idx_of_col_raw(j);
            assert_eq!(rows, b.row_idx_of_col_raw(j), "{name}: one pattern");
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "{name}: sorted rows");
            for (p, &i) in rows.iter().enumerate() {
                let (lv, bv) = (l.val_of_col(j)[p], b.val_of_col(j)[p]);
                let (rl, rb) = reference[&(i, j)];
                assert!((lv - rl).abs() <= 1e-13 * l_max, "{name}: L[{i}, {j}] = {lv} vs {rl}");
                assert!((bv - rb).abs() <= 1e-13 * b_max, "{name}: B[{i}, {j}] = {bv} vs {rb}");
                stored.insert((i, j), (lv, bv));
            }
        }
        for (&(i, j), &(lv, bv)) in &stored {
            assert_eq!(stored[&(j, i)], (lv, bv), "{name}: ({i}, {j}) not bitwise symmetric");
        }
        let d_max = d.iter().fold(0.0f64, |m, x| m.max(*x));
        for (i, (x, y)) in ops.lumped_diagonal.iter().zip(&d).enumerate() {
            assert!((x - y).abs() <= 1e-13 * d_max, "{name}: D[{i}]");
        }
    }
}
