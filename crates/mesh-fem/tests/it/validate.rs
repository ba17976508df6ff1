//! Validation and repair: every problem kind is triggered from arrays, fatal problems agree
//! with what `assemble` rejects, and every repair is checked against the mesh it should
//! reproduce.

use crate::minimal_reader;

use mesh_fem::generate::{grid, icosphere, torus};
use mesh_fem::stats::stats;
use mesh_fem::validate::{
    is_degenerate_triangle, repair, validate, Problem, RepairOptions, Severity, DEGENERATE_AREA_RATIO,
};
use mesh_fem::{assemble, AssemblyParams, MeshError, TriMesh};

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
        (Err(MeshError::DegenerateMesh { area: a }), Err(MeshError::DegenerateMesh { area: b })) => {
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
    // Huge coordinates: the area 5e599 is not a double, but the triangle is well shaped, so it
    // is not degenerate (its cotangents are computed on exactly rescaled edges, finite); the
    // overflowing total area is the mesh-level problem that validate and assemble both name.
    let big = [[0.0, 0.0, 0.0], [1e300, 0.0, 0.0], [0.0, 1e300, 0.0]];
    assert!(!is_degenerate_triangle(big));
    let m = mesh(big.to_vec(), vec![[0, 1, 2]]);
    assert_eq!(validate(&m).problems[0], Problem::AreaOverflow { area: f64::INFINITY });
    assert_agrees_with_assemble(&m);
    // Coordinates whose differences overflow have no finite edge: degenerate.
    assert!(is_degenerate_triangle([
        [-1e308, 0.0, 0.0],
        [1e308, 0.0, 0.0],
        [0.0, 1.0, 0.0]
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
    for tol in [-1.0, f64::NAN, f64::INFINITY, 1e308] {
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

/// Small deterministic generator (64-bit LCG) for the randomized cross-check.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Topology recomputed by brute force (hash maps, per-vertex BFS, BFS 2-colouring), with
/// none of mesh-fem's union-find code: (edges, boundary edges, non-manifold edges,
/// inconsistent edges, non-manifold vertices, components, non-orientable components,
/// boundary loops).
fn brute_force(n: usize, faces: &[[u32; 3]]) -> [usize; 8] {
    use std::collections::{HashMap, HashSet, VecDeque};
    let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
    for (f, t) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                edges.entry((a.min(b), a.max(b))).or_default().push((f, a < b));
            }
        }
    }
    let boundary = edges.values().filter(|v| v.len() == 1).count();
    let non_manifold = edges.values().filter(|v| v.len() > 2).count();
    let inconsistent = edges.values().filter(|v| v.len() == 2 && v[0].1 == v[1].1).count();

    // Fans at each vertex: incident faces joined when they share an edge through v.
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (f, t) in faces.iter().enumerate() {
        for &v in t.iter().collect::<HashSet<_>>() {
            incident[v as usize].push(f);
        }
    }
    let mut fan_of: HashMap<(usize, usize), usize> = HashMap::new(); // (vertex, face) → fan id
    let mut pinched = 0;
    let mut next_fan = 0;
    for (v, around) in incident.iter().enumerate() {
        let mut fans_here = 0;
        for &start in around {
            if fan_of.contains_key(&(v, start)) {
                continue;
            }
            fans_here += 1;
            let id = next_fan;
            next_fan += 1;
            let mut queue = VecDeque::from([start]);
            fan_of.insert((v, start), id);
            while let Some(f) = queue.pop_front() {
                for &w in &faces[f] {
                    if w as usize == v {
                        continue;
                    }
                    let key = ((v as u32).min(w), (v as u32).max(w));
                    for &(g, _) in &edges[&key] {
                        if let std::collections::hash_map::Entry::Vacant(e) = fan_of.entry((v, g)) {
                            e.insert(id);
                            queue.push_back(g);
                        }
                    }
                }
            }
        }
        if fans_here > 1 {
            pinched += 1;
        }
    }

    // Vertex components by BFS.
    let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in faces {
        for k in 0..3 {
            adj[t[k] as usize].push(t[(k + 1) % 3]);
            adj[t[(k + 1) % 3] as usize].push(t[k]);
        }
    }
    let mut comp = vec![usize::MAX; n];
    let mut n_comp = 0;
    for s in 0..n {
        if incident[s].is_empty() || comp[s] != usize::MAX {
            continue;
        }
        comp[s] = n_comp;
        let mut queue = VecDeque::from([s]);
        while let Some(v) = queue.pop_front() {
            for &w in &adj[v] {
                if comp[w as usize] == usize::MAX {
                    comp[w as usize] = n_comp;
                    queue.push_back(w as usize);
                }
            }
        }
        n_comp += 1;
    }

    // Orientability: BFS 2-colouring of faces across two-face edges.
    let mut face_adj: Vec<Vec<(usize, bool)>> = vec![Vec::new(); faces.len()];
    for v in edges.values() {
        if v.len() == 2 {
            let flip = v[0].1 == v[1].1;
            face_adj[v[0].0].push((v[1].0, flip));
            face_adj[v[1].0].push((v[0].0, flip));
        }
    }
    let mut colour: Vec<Option<bool>> = vec![None; faces.len()];
    let mut bad_components = HashSet::new();
    for s in 0..faces.len() {
        if colour[s].is_some() {
            continue;
        }
        colour[s] = Some(false);
        let mut queue = VecDeque::from([s]);
        while let Some(f) = queue.pop_front() {
            let c = colour[f].unwrap();
            for &(g, flip) in &face_adj[f] {
                match colour[g] {
                    None => {
                        colour[g] = Some(c ^ flip);
                        queue.push_back(g);
                    }
                    Some(cg) if cg != c ^ flip => {
                        bad_components.insert(comp[faces[f][0] as usize]);
                    }
                    _ => {}
                }
            }
        }
    }

    // Boundary loops: boundary edges joined where they meet in the same fan.
    let bedges: Vec<((u32, u32), usize)> = edges
        .iter()
        .filter(|(_, v)| v.len() == 1)
        .map(|(&k, v)| (k, v[0].0))
        .collect();
    let mut loop_id: Vec<usize> = (0..bedges.len()).collect();
    let mut by_fan: HashMap<usize, Vec<usize>> = HashMap::new();
    for (i, &((a, b), f)) in bedges.iter().enumerate() {
        for v in [a, b] {
            by_fan.entry(fan_of[&(v as usize, f)]).or_default().push(i);
        }
    }
    // Relabel until stable (fine for small meshes).
    let mut changed = true;
    while changed {
        changed = false;
        for members in by_fan.values() {
            let m = members.iter().map(|&i| loop_id[i]).min().unwrap();
            for &i in members {
                if loop_id[i] != m {
                    loop_id[i] = m;
                    changed = true;
                }
            }
        }
    }
    let loops = loop_id.iter().collect::<HashSet<_>>().len();

    [
        edges.len(),
        boundary,
        non_manifold,
        inconsistent,
        pinched,
        n_comp,
        bad_components.len(),
        loops,
    ]
}

#[test]
fn topology_matches_brute_force_on_random_meshes() {
    let mut rng = Lcg(0x5eed_1234);
    let base = icosphere(1);
    // How many trials had more than one of each counted thing: the check must not be vacuous.
    let mut seen = [0usize; 8];
    let mut non_orientable_trials = 0;
    for trial in 0..300 {
        let mut faces: Vec<[u32; 3]> = if trial % 2 == 0 {
            // Random soups on few vertices: many non-manifold edges and pinched vertices.
            let n = 6 + rng.below(10);
            (0..5 + rng.below(25))
                .map(|_| {
                    let mut t = [rng.below(n) as u32, rng.below(n) as u32, rng.below(n) as u32];
                    if rng.below(10) > 0 {
                        while t[1] == t[0] {
                            t[1] = rng.below(n) as u32;
                        }
                        while t[2] == t[0] || t[2] == t[1] {
                            t[2] = rng.below(n) as u32;
                        }
                    }
                    t
                })
                .collect()
        } else {
            // An icosphere with faces deleted, flipped and duplicated.
            let mut f = Vec::new();
            for t in base.faces() {
                match rng.below(12) {
                    0 => {}
                    1 => f.push([t[0], t[2], t[1]]),
                    2 => {
                        f.push(*t);
                        f.push(*t);
                    }
                    _ => f.push(*t),
                }
            }
            f
        };
        if trial % 4 == 0 {
            // A disjoint second copy: at least two components.
            let k = faces.iter().flatten().max().unwrap() + 1;
            let copy: Vec<[u32; 3]> = faces.iter().map(|t| t.map(|v| v + k)).collect();
            faces.extend(copy);
        }
        let n = faces.iter().flatten().map(|&v| v as usize + 1).max().unwrap();
        let positions: Vec<[f64; 3]> = (0..n)
            .map(|i| [(i as f64).sin(), (i as f64 * 1.7).cos(), (i as f64 * 0.3).sin()])
            .collect();
        let m = mesh(positions, faces.clone());
        let s = stats(&m);
        let r = validate(&m);
        let got = [
            s.n_edges,
            s.n_boundary_edges,
            s.n_non_manifold_edges,
            r.counts.inconsistently_oriented_edges,
            s.n_non_manifold_vertices,
            s.n_components,
            r.counts.non_orientable_components,
            s.n_boundary_loops,
        ];
        let want = brute_force(n, &faces);
        assert_eq!(got, want, "trial {trial}: faces {faces:?}");
        for k in 0..8 {
            seen[k] += usize::from(want[k] > 1);
        }
        non_orientable_trials += usize::from(want[6] > 0);
        assert_eq!(r.counts.non_manifold_edges, s.n_non_manifold_edges);
        assert_eq!(r.counts.unreferenced_vertices, s.n_unreferenced_vertices);
        // χ from the same counts.
        let used = n - s.n_unreferenced_vertices;
        assert_eq!(
            s.euler_characteristic,
            used as i64 - s.n_edges as i64 + faces.len() as i64
        );

        // Orientation repair on every orientable component leaves no inconsistent edge there.
        let (fixed, rep) = repair(
            &m,
            &RepairOptions {
                orient_faces: true,
                ..Default::default()
            },
        )
        .unwrap();
        if rep.non_orientable_components == 0 {
            assert_eq!(
                validate(&fixed).counts.inconsistently_oriented_edges,
                0,
                "trial {trial}"
            );
        }
    }
    // The check must not be vacuous: every counted thing occurs more than once in some
    // trial (non-orientable components at least once).
    assert!(seen.iter().enumerate().all(|(k, &c)| c > 0 || k == 6), "{seen:?}");
    assert!(non_orientable_trials > 0);
}

#[test]
fn summaries_read_well() {
    // icosphere(1) with one face repeating an index, one unreferenced vertex, one duplicate
    // face and one flipped face.
    let (mut p, mut f) = icosphere(1).into_parts();
    p.push([3.0, 0.0, 0.0]);
    f[2] = [f[2][0], f[2][1], f[2][1]];
    f[5].swap(0, 1);
    f.push(f[10]);
    let m = mesh(p, f);
    let r = validate(&m);
    insta::assert_snapshot!("validation_summary", r.summary());
    let opts = RepairOptions {
        drop_degenerate_faces: true,
        drop_duplicate_faces: true,
        orient_faces: true,
        drop_unreferenced_vertices: true,
        ..Default::default()
    };
    let (fixed, rep) = repair(&m, &opts).unwrap();
    insta::assert_snapshot!("repair_summary", rep.summary());
    insta::assert_snapshot!("repaired_validation_summary", validate(&fixed).summary());
}

/// Issue #16: needle and cap faces (an angle within 1e−4 rad of 0 or π) are reported as
/// warnings naming the face, with the largest |cot|; well-shaped faces are not.
#[test]
fn needle_and_cap_faces_are_warned() {
    let h = 1e-7;
    // A cap (apex angle π − 4h) and a needle (angle ≈ h at vertex 3), plus a fine triangle.
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.5, h, 0.0],
        [10.0, 0.0, 0.0],
        [11.0, 0.0, 0.0],
        [11.0, h, 0.0],
        [20.0, 0.0, 0.0],
        [21.0, 0.0, 0.0],
        [20.5, 0.8, 0.0],
    ];
    let mesh = TriMesh::new(p, vec![[0, 1, 2], [3, 4, 5], [6, 7, 8]]).unwrap();
    let report = validate(&mesh);
    assert!(report.is_usable());
    let needles: Vec<(usize, f64)> = report
        .problems
        .iter()
        .filter_map(|p| match p {
            Problem::NeedleFace { face, cotangent, .. } => Some((*face, *cotangent)),
            _ => None,
        })
        .collect();
    assert_eq!(needles.iter().map(|n| n.0).collect::<Vec<_>>(), [0, 1]);
    assert_eq!(report.counts.needle_faces, 2);
    for (face, cot) in needles {
        assert!(cot > 1e6 && cot.is_finite(), "face {face}: {cot}");
    }
    assert!(report.summary().contains("needle or cap"), "{}", report.summary());
}

/// Issue #37: remedies are data, named by each front end in its own words; the library's own
/// messages name its options, and nothing else is written into them.
#[test]
fn remedies_are_data_that_each_front_end_names() {
    use mesh_fem::validate::RepairStep;
    use mesh_fem::Remedy;
    let unreferenced = MeshError::UnreferencedVertex { vertex: 4 };
    assert_eq!(unreferenced.remedy(), Some(Remedy::DropUnreferencedVertices));
    assert_eq!(
        unreferenced.to_string(),
        "vertex 4 belongs to no face or tetrahedron; fix: RepairOptions::drop_unreferenced_vertices"
    );
    assert_eq!(
        unreferenced.message_with(&|r| format!("<{r:?}>")),
        "vertex 4 belongs to no face or tetrahedron; fix: <DropUnreferencedVertices>"
    );
    let polygon = MeshError::Polygon {
        path: "q.obj".into(),
        face: 2,
        corners: 4,
    };
    assert!(polygon
        .message_with(&|_| "X".into())
        .ends_with("q.obj: face 2 has 4 corners; fix: X"));
    // An error without a remedy reads as it always did.
    let empty = MeshError::Empty {
        n_vertices: 0,
        n_faces: 0,
    };
    assert_eq!(empty.remedy(), None);
    assert_eq!(empty.message_with(&|_| "X".into()), empty.to_string());
    // Every fatal problem of a broken mesh has a remedy, which is a repair step, and a summary
    // names it in the front end's words only.
    let (mut p, mut f) = icosphere(1).into_parts();
    p.push([3.0, 0.0, 0.0]);
    f[2] = [f[2][0], f[2][1], f[2][1]];
    f[5].swap(0, 1);
    f.push(f[10]);
    let r = validate(&mesh(p, f));
    for problem in r.errors() {
        let remedy = problem.remedy().expect("a fatal problem has a remedy");
        assert!(RepairStep::for_remedy(remedy).is_some(), "{problem}");
    }
    let summary = r.summary_with(&|r| format!("step {:?}", RepairStep::for_remedy(r)));
    assert!(!summary.contains("Options::"), "{summary}");
    assert_eq!(summary.matches("fix: step Some(").count(), 4, "{summary}");
}
