//! Validation and repair: every problem kind is triggered from arrays, fatal problems agree
//! with what `assemble` rejects, and every repair is checked against the mesh it should
//! reproduce.

mod minimal_reader;

use mesh_fem::generate::{grid, icosphere, torus};
use mesh_fem::validate::{is_degenerate_triangle, DEGENERATE_AREA_RATIO};
use mesh_fem::{
    assemble, repair, stats, validate, AssemblyParams, MeshError, Problem, RepairOptions, Severity, TriMesh,
};

fn mesh(p: Vec<[f64; 3]>, f: Vec<[u32; 3]>) -> TriMesh {
    TriMesh::new(p, f).unwrap()
}

/// A mesh assembles if and only if it validates as usable, and both name the same culprit.
fn assert_agrees_with_assemble(m: &TriMesh) {
    let report = validate(m);
    let assembled = assemble(m, &AssemblyParams::default());
    assert_eq!(report.is_usable(), assembled.is_ok(), "{}", report.summary());
    match (report.into_result(), assembled) {
        (Ok(_), Ok(_)) => {}
        (Err(MeshError::DegenerateFace { face: a, .. }), Err(MeshError::DegenerateFace { face: b, .. }))
        | (Err(MeshError::RepeatedIndex { face: a, .. }), Err(MeshError::DegenerateFace { face: b, .. }))
        | (Err(MeshError::UnreferencedVertex { vertex: a }), Err(MeshError::UnreferencedVertex { vertex: b })) => {
            assert_eq!(a, b)
        }
        (v, a) => panic!("validate says {v:?}, assemble says {a:?}"),
    }
}

#[test]
fn generated_meshes_are_clean() {
    for m in [icosphere(3), torus(2.0, 0.5, 16, 8)] {
        let r = validate(&m);
        assert!(r.problems.is_empty(), "{}", r.summary());
        assert!(r.is_usable());
        assert!(r.summary().contains("usable"));
        assert_eq!(r.clone().into_result().unwrap(), r);
        assert_agrees_with_assemble(&m);
    }
    // An open grid is usable with a single boundary warning.
    let r = validate(&grid(6, 6));
    assert_eq!(r.problems, vec![Problem::Boundary { loops: 1, edges: 20 }]);
    assert!(r.is_usable());
}

#[test]
fn repeated_index_is_fatal_and_names_the_face() {
    let (p, mut f) = icosphere(1).into_parts();
    f[7] = [f[7][0], f[7][0], f[7][2]];
    let m = mesh(p, f.clone());
    let r = validate(&m);
    assert_eq!(r.counts.repeated_index, 1);
    assert_eq!(
        r.problems[0],
        Problem::RepeatedIndex {
            face: 7,
            vertices: f[7]
        }
    );
    assert_eq!(r.problems[0].severity(), Severity::Error);
    assert!(!r.is_usable());
    match r.clone().into_result() {
        Err(MeshError::RepeatedIndex { face: 7, vertices }) => assert_eq!(vertices, f[7].to_vec()),
        other => panic!("{other:?}"),
    }
    assert!(r.summary().contains("face 7"), "{}", r.summary());
    assert_agrees_with_assemble(&m);
}

#[test]
fn zero_area_face_is_fatal_and_agrees_with_assemble() {
    // Move a vertex onto the midpoint of the opposite edge of face 3 → collinear corners.
    let m0 = icosphere(1);
    let (mut p, f) = m0.into_parts();
    let [a, b, c] = f[3];
    p[a as usize] = [
        0.5 * (p[b as usize][0] + p[c as usize][0]),
        0.5 * (p[b as usize][1] + p[c as usize][1]),
        0.5 * (p[b as usize][2] + p[c as usize][2]),
    ];
    let m = mesh(p, f.clone());
    let r = validate(&m);
    assert!(
        r.problems.contains(&Problem::ZeroAreaFace {
            face: 3,
            vertices: f[3]
        }),
        "{}",
        r.summary()
    );
    assert!(matches!(
        r.clone().into_result(),
        Err(MeshError::DegenerateFace { face: 3, .. })
    ));
    assert_agrees_with_assemble(&m);
}

#[test]
fn needle_threshold_is_relative_and_shared_with_assemble() {
    // Triangle (0,0,0), (L,0,0), (L/2, h, 0): |T| = L h / 2, ℓ_max ≈ L, so the ratio is h / (2L).
    for scale in [1e-6, 1.0, 1e6] {
        for (k, expect_degenerate) in [(-10, false), (-13, false), (-15, true), (-17, true), (-300, true)] {
            let l = scale;
            let h = l * 10f64.powi(k);
            let corners = [[0.0, 0.0, 0.0], [l, 0.0, 0.0], [l / 2.0, h, 0.0]];
            assert_eq!(
                is_degenerate_triangle(corners),
                expect_degenerate,
                "scale {scale}, h/L = 1e{k}"
            );
            // The same face inside a mesh: validate and assemble agree on it.
            let m = mesh(corners.to_vec(), vec![[0, 1, 2]]);
            assert_eq!(validate(&m).is_usable(), !expect_degenerate);
            assert_agrees_with_assemble(&m);
        }
    }
    // Exactly at the threshold.
    let ratio = DEGENERATE_AREA_RATIO;
    assert!(is_degenerate_triangle([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0]
    ]));
    assert!(!is_degenerate_triangle([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, 4.0 * ratio, 0.0]
    ]));
    // Overflowing coordinates give an infinite area: degenerate, never NaN cotangents.
    assert!(is_degenerate_triangle([
        [0.0, 0.0, 0.0],
        [1e300, 0.0, 0.0],
        [0.0, 1e300, 0.0]
    ]));
}

#[test]
fn unreferenced_vertex_is_fatal_and_repair_drops_it() {
    let (mut p, f) = icosphere(1).into_parts();
    let n = p.len();
    p.insert(5, [9.0, 9.0, 9.0]);
    p.push([7.0, 7.0, 7.0]);
    let f_shifted: Vec<[u32; 3]> = f.iter().map(|t| t.map(|v| if v >= 5 { v + 1 } else { v })).collect();
    let m = mesh(p, f_shifted);
    let r = validate(&m);
    assert_eq!(r.counts.unreferenced_vertices, 2);
    assert!(matches!(
        r.clone().into_result(),
        Err(MeshError::UnreferencedVertex { vertex: 5 })
    ));
    assert_agrees_with_assemble(&m);

    let opts = RepairOptions {
        drop_unreferenced_vertices: true,
        ..Default::default()
    };
    let (fixed, rep) = repair(&m, &opts).unwrap();
    assert_eq!(fixed, icosphere(1));
    assert_eq!(rep.dropped_vertices, 2);
    assert_eq!(rep.vertex_map.len(), n + 2);
    assert_eq!(rep.vertex_map[5], None);
    assert_eq!(rep.vertex_map[n + 1], None);
    assert_eq!(rep.vertex_map[4], Some(4));
    assert_eq!(rep.vertex_map[6], Some(5));
    assert!(rep.dropped_faces.is_empty());
    assert!(
        rep.summary().contains("dropped 2 unreferenced vertices"),
        "{}",
        rep.summary()
    );
    assert!(validate(&fixed).is_usable());
}

#[test]
fn non_manifold_edge_is_a_warning_and_still_assembles() {
    let m = mesh(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    let r = validate(&m);
    assert!(r.is_usable());
    assert_eq!(r.counts.non_manifold_edges, 1);
    assert!(r.problems.contains(&Problem::NonManifoldEdge {
        edge: [0, 1],
        n_faces: 3
    }));
    assert!(r.warnings().all(|p| p.severity() == Severity::Warning));
    assert!(r.summary().contains("still assemble"), "{}", r.summary());
    assert_agrees_with_assemble(&m);
}

#[test]
fn pinched_vertex_is_reported() {
    let m = mesh(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [-1.0, -1.0, 0.0],
        ],
        vec![[0, 1, 2], [0, 3, 4]],
    );
    let r = validate(&m);
    assert_eq!(r.counts.non_manifold_vertices, 1);
    assert!(r.problems.contains(&Problem::NonManifoldVertex { vertex: 0 }));
    assert!(r.is_usable());
}

#[test]
fn flipped_faces_are_found_and_reoriented() {
    let good = icosphere(2);
    let (p, mut f) = good.clone().into_parts();
    for &i in &[3usize, 100, 101] {
        f[i].swap(0, 1);
    }
    let bad = mesh(p, f);
    let r = validate(&bad);
    assert!(r.is_usable());
    // Faces 100 and 101 may share an edge (then that edge is consistent again), so count the
    // inconsistent edges independently: an edge is inconsistent iff its two faces have the
    // same directed edge.
    let mut directed = std::collections::HashMap::new();
    for t in bad.faces() {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let expected = directed.values().filter(|&&c| c == 2).count();
    assert!(expected >= 3);
    assert_eq!(r.counts.inconsistently_oriented_edges, expected);
    assert_eq!(r.counts.non_orientable_components, 0);
    assert!(!stats(&bad).is_consistently_oriented && stats(&bad).is_orientable);

    let (fixed, rep) = repair(
        &bad,
        &RepairOptions {
            orient_faces: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(rep.flipped_faces, vec![3, 100, 101]);
    assert!(validate(&fixed).problems.is_empty());
    // Flipping again swaps corners 1 and 2: same cyclic orientation as the original face.
    for (a, b) in fixed.faces().iter().zip(good.faces()) {
        let rot = |t: [u32; 3]| [t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]];
        assert!(rot(*b).contains(a), "{a:?} vs {b:?}");
    }
}

#[test]
fn moebius_strip_is_non_orientable_and_left_alone() {
    let n = 10;
    let mut p = Vec::new();
    for i in 0..n {
        let u = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
        for v in [0.3f64, -0.3] {
            let r = 1.0 + v * (u / 2.0).cos();
            p.push([r * u.cos(), r * u.sin(), v * (u / 2.0).sin()]);
        }
    }
    let mut f = Vec::new();
    for i in 0..n as u32 {
        let (t, b) = (2 * i, 2 * i + 1);
        let (tn, bn) = if i + 1 < n as u32 {
            (2 * i + 2, 2 * i + 3)
        } else {
            (1, 0)
        };
        f.push([t, b, bn]);
        f.push([t, bn, tn]);
    }
    let m = mesh(p, f);
    let r = validate(&m);
    assert_eq!(r.counts.non_orientable_components, 1);
    assert!(r.problems.iter().any(|p| matches!(p, Problem::NonOrientable { .. })));
    assert!(r.is_usable());
    assert_agrees_with_assemble(&m);
    let (fixed, rep) = repair(
        &m,
        &RepairOptions {
            orient_faces: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(rep.non_orientable_components, 1);
    assert!(rep.flipped_faces.is_empty());
    assert_eq!(fixed, m);
    assert!(rep.summary().contains("non-orientable"), "{}", rep.summary());
}

#[test]
fn duplicate_faces_are_reported_and_dropped() {
    let (p, mut f) = icosphere(1).into_parts();
    f.push([f[4][1], f[4][2], f[4][0]]);
    f.push([f[9][0], f[9][2], f[9][1]]);
    let m = mesh(p, f);
    let r = validate(&m);
    assert_eq!(r.counts.duplicate_faces, 2);
    assert!(r.problems.contains(&Problem::DuplicateFace { face: 80, first: 4 }));
    assert!(r.problems.contains(&Problem::DuplicateFace { face: 81, first: 9 }));
    assert!(r.is_usable());
    let (fixed, rep) = repair(
        &m,
        &RepairOptions {
            drop_duplicate_faces: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(fixed, icosphere(1));
    assert_eq!(rep.dropped_duplicate_faces, vec![80, 81]);
    assert_eq!(rep.dropped_faces, vec![80, 81]);
    assert_eq!(rep.face_map[80], None);
    assert_eq!(rep.face_map[79], Some(79));
}

#[test]
fn several_components_are_a_warning() {
    let a = icosphere(1);
    let n = a.n_vertices() as u32;
    let (mut p, mut f) = a.clone().into_parts();
    p.extend(a.positions().iter().map(|q| [q[0] + 5.0, q[1], q[2]]));
    f.extend(a.faces().iter().map(|t| t.map(|v| v + n)));
    let r = validate(&mesh(p, f));
    assert_eq!(r.problems, vec![Problem::SeveralComponents { count: 2 }]);
    assert!(r.is_usable());
}

/// Splits every face into its own three vertices ("triangle soup"), with optional jitter.
fn soup(m: &TriMesh, jitter: f64) -> TriMesh {
    let mut p = Vec::new();
    let mut f = Vec::new();
    for (i, t) in m.faces().iter().enumerate() {
        for (k, &v) in t.iter().enumerate() {
            let q = m.positions()[v as usize];
            // Deterministic pseudo-random jitter in [−jitter, jitter].
            let s = (((i * 3 + k) as f64 * 12.9898).sin() * 43758.5453).fract();
            p.push([q[0] + jitter * s, q[1] - jitter * s, q[2]]);
        }
        f.push([3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2]);
    }
    mesh(p, f)
}

#[test]
fn merging_a_triangle_soup_restores_the_mesh() {
    let m = icosphere(2);
    let s = soup(&m, 0.0);
    let sv = validate(&s);
    assert_eq!(sv.counts.components, m.n_faces());
    let (fixed, rep) = repair(
        &s,
        &RepairOptions {
            merge_duplicate_vertices: Some(0.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(fixed.n_vertices(), m.n_vertices());
    assert_eq!(rep.merged_vertices, 3 * m.n_faces() - m.n_vertices());
    let st = stats(&fixed);
    assert!(st.is_closed && st.genus == Some(0) && st.n_edges == stats(&m).n_edges);
    // Every soup vertex maps to a vertex at the same position.
    for (v, new) in rep.vertex_map.iter().enumerate() {
        assert_eq!(fixed.positions()[new.unwrap() as usize], s.positions()[v]);
    }
    assert!(rep.summary().contains("merged"), "{}", rep.summary());

    // With jitter 1e-9 (relative to a bbox diagonal of ≈ 3.5): tolerance 1e-8 merges, 1e-12 does not.
    let s = soup(&m, 1e-9);
    let tol = 1e-8;
    let (fixed, rep) = repair(
        &s,
        &RepairOptions {
            merge_duplicate_vertices: Some(tol),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(fixed.n_vertices(), m.n_vertices());
    let d = stats(&s).bbox_diagonal;
    for (v, new) in rep.vertex_map.iter().enumerate() {
        let (a, b) = (fixed.positions()[new.unwrap() as usize], s.positions()[v]);
        let dist = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        assert!(dist <= tol * d);
    }
    let (fixed, _) = repair(
        &s,
        &RepairOptions {
            merge_duplicate_vertices: Some(1e-12),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(fixed.n_vertices() > m.n_vertices());
}

#[test]
fn merging_can_create_degenerate_faces_which_repair_drops() {
    // Grid whose vertex 1 is moved next to vertex 0: merging makes the faces at that
    // corner repeat an index.
    let (mut p, f) = grid(4, 4).into_parts();
    p[1] = [1e-12, 0.0, 0.0];
    let m = mesh(p, f);
    let opts = RepairOptions {
        merge_duplicate_vertices: Some(1e-9),
        ..Default::default()
    };
    let (merged, _) = repair(&m, &opts).unwrap();
    assert!(!validate(&merged).is_usable());
    let opts = RepairOptions {
        merge_duplicate_vertices: Some(1e-9),
        drop_degenerate_faces: true,
        drop_unreferenced_vertices: true,
        ..Default::default()
    };
    let (fixed, rep) = repair(&m, &opts).unwrap();
    assert_eq!(rep.merged_vertices, 1);
    assert_eq!(rep.vertex_map[1], Some(0));
    // Exactly the faces containing both vertex 0 and vertex 1.
    let expected: Vec<usize> = m
        .faces()
        .iter()
        .enumerate()
        .filter(|(_, t)| t.contains(&0) && t.contains(&1))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(rep.dropped_degenerate_faces, expected);
    assert!(validate(&fixed).is_usable(), "{}", validate(&fixed).summary());
    assert!(assemble(&fixed, &AssemblyParams::default()).is_ok());
}

#[test]
fn repair_rejects_bad_tolerance_and_reports_empty_results() {
    let m = icosphere(0);
    for tol in [-1.0, f64::NAN, f64::INFINITY] {
        let e = repair(
            &m,
            &RepairOptions {
                merge_duplicate_vertices: Some(tol),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(matches!(e, MeshError::InvalidRepairOption { .. }), "{e}");
    }
    let flat = mesh(vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], vec![[0, 1, 2]]);
    let e = repair(
        &flat,
        &RepairOptions {
            drop_degenerate_faces: true,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::Empty { n_faces: 0, .. }), "{e}");
    // Nothing turned on: nothing changes.
    let (same, rep) = repair(&m, &RepairOptions::default()).unwrap();
    assert_eq!(same, m);
    assert!(rep.is_unchanged());
    assert_eq!(rep.summary(), "repair: nothing changed");
}

#[test]
fn corpus_bunny_with_unreferenced_vertices() {
    let Some(m) = minimal_reader::read_corpus("common-3d-test-models/stanford-bunny.obj") else {
        return;
    };
    let r = validate(&m);
    assert_eq!(r.counts.unreferenced_vertices, 1113);
    assert_eq!(r.counts.boundary_loops, 5);
    assert!(!r.is_usable());
    assert_agrees_with_assemble(&m);
    let (fixed, rep) = repair(
        &m,
        &RepairOptions {
            drop_unreferenced_vertices: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(rep.dropped_vertices, 1113);
    assert_eq!(fixed.n_vertices(), 35947 - 1113);
    assert_agrees_with_assemble(&fixed);
    let s = stats(&fixed);
    assert_eq!((s.euler_characteristic, s.genus, s.n_boundary_loops), (-3, Some(0), 5));
}

#[test]
fn corpus_non_manifold_meshes_still_assemble() {
    for file in [
        "common-3d-test-models/cow.obj",
        "deftransfer-pyfm/camel_gallop/camel-gallop-01.off",
    ] {
        let Some(m) = minimal_reader::read_corpus(file) else {
            return;
        };
        let r = validate(&m);
        assert!(
            r.counts.non_manifold_edges + r.counts.non_manifold_vertices > 0,
            "{file}"
        );
        assert_agrees_with_assemble(&m);
    }
}
