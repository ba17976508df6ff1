//! Critical points and 0-dimensional persistence (paper, Sect. 4.2), checked against
//! independent references: the Morse/Banchoff Euler-characteristic identity, hand-computed
//! critical points of height functions, and a brute-force persistence pairing computed by
//! minimax ("bottleneck") flooding from every extremum instead of a union–find sweep.

use mesh_fem::generate::{bumpy, grid, icosphere, torus, uv_sphere};
use mesh_fem::morse::{
    critical_points, local_maxima, local_minima, persistence, persistent_extrema, persistent_extrema_relative,
    CriticalKind, CriticalPoint, PersistencePair,
};
use mesh_fem::{MeshError, TriMesh};
use std::cmp::Reverse;
use std::collections::{BTreeMap, BTreeSet, BinaryHeap, HashMap};

// ---------------------------------------------------------------------------------------------
// Independent helpers.

/// Deterministic pseudo-random numbers in [−1, 1) (xorshift64*).
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            let x = s.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
            2.0 * (x as f64 / (1u64 << 53) as f64) - 1.0
        })
        .collect()
}

fn field(mesh: &TriMesh, g: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    mesh.positions().iter().map(|&p| g(p)).collect()
}

/// Undirected edges → number of incident faces.
fn edge_faces(mesh: &TriMesh) -> BTreeMap<(u32, u32), usize> {
    let mut edges = BTreeMap::new();
    for &[a, b, c] in mesh.faces() {
        for (x, y) in [(a, b), (b, c), (c, a)] {
            *edges.entry((x.min(y), x.max(y))).or_insert(0) += 1;
        }
    }
    edges
}

/// χ = V − E + F.
fn euler_characteristic(mesh: &TriMesh) -> i64 {
    mesh.n_vertices() as i64 - edge_faces(mesh).len() as i64 + mesh.n_faces() as i64
}

fn boundary_vertices(mesh: &TriMesh) -> BTreeSet<u32> {
    edge_faces(mesh)
        .into_iter()
        .filter(|&(_, k)| k == 1)
        .flat_map(|((a, b), _)| [a, b])
        .collect()
}

fn neighbour_sets(mesh: &TriMesh) -> Vec<BTreeSet<u32>> {
    let mut adj = vec![BTreeSet::new(); mesh.n_vertices()];
    for &[a, b, c] in mesh.faces() {
        for (x, y) in [(a, b), (b, c), (c, a)] {
            adj[x as usize].insert(y);
            adj[y as usize].insert(x);
        }
    }
    adj
}

/// Position of every vertex in the order (f, index), by a plain comparison sort.
fn sos_rank(f: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..f.len()).collect();
    idx.sort_by(|&a, &b| f[a].partial_cmp(&f[b]).unwrap().then(a.cmp(&b)));
    let mut rank = vec![0; f.len()];
    for (r, &v) in idx.iter().enumerate() {
        rank[v] = r;
    }
    rank
}

/// Index of a critical point: +1 for extrema, −multiplicity for saddles, 0 otherwise.
fn index(kind: CriticalKind) -> i64 {
    match kind {
        CriticalKind::Minimum | CriticalKind::Maximum => 1,
        CriticalKind::Saddle { multiplicity } => -(multiplicity as i64),
        CriticalKind::Regular => 0,
    }
}

fn count(cps: &[CriticalPoint], pred: impl Fn(CriticalKind) -> bool) -> usize {
    cps.iter().filter(|c| pred(c.kind)).count()
}

fn saddle_units(cps: &[CriticalPoint]) -> usize {
    cps.iter()
        .map(|c| match c.kind {
            CriticalKind::Saddle { multiplicity } => multiplicity,
            _ => 0,
        })
        .sum()
}

/// Brute-force 0-dimensional persistence by minimax flooding, independent of union–find:
/// with keys `rank` (smaller = earlier in the filtration), an extremum m (no earlier
/// neighbour) dies at the smallest level r at which the component of m in {rank ≤ r}
/// contains a vertex earlier than m. That level is the bottleneck value of the best path
/// from m to any earlier vertex (Dijkstra with max instead of +). Returns
/// birth → (death, or None if essential, with the last vertex of the component).
fn reference_pairs(mesh: &TriMesh, rank: &[usize]) -> BTreeMap<u32, (Option<u32>, u32)> {
    let adj = neighbour_sets(mesh);
    let n = rank.len();
    let mut by_rank = vec![0u32; n];
    for v in 0..n {
        by_rank[rank[v]] = v as u32;
    }
    let mut out = BTreeMap::new();
    for m in 0..n {
        if adj[m].iter().any(|&w| rank[w as usize] < rank[m]) {
            continue;
        }
        let mut best = vec![usize::MAX; n];
        let mut heap = BinaryHeap::new();
        best[m] = rank[m];
        heap.push(Reverse((rank[m], m)));
        let mut death = None;
        let mut top = rank[m];
        while let Some(Reverse((level, v))) = heap.pop() {
            if level > best[v] {
                continue;
            }
            if rank[v] < rank[m] {
                death = Some(by_rank[level]);
                break;
            }
            top = top.max(rank[v]);
            for &w in &adj[v] {
                let l = level.max(rank[w as usize]);
                if l < best[w as usize] {
                    best[w as usize] = l;
                    heap.push(Reverse((l, w as usize)));
                }
            }
        }
        out.insert(m as u32, (death, by_rank[top]));
    }
    out
}

fn check_against_reference(mesh: &TriMesh, f: &[f64]) {
    let diagram = persistence(mesh, f).unwrap();
    let rank = sos_rank(f);
    let n = f.len();
    let rev: Vec<usize> = rank.iter().map(|&r| n - 1 - r).collect();
    for (pairs, keys, sign) in [(&diagram.minima, &rank, 1.0), (&diagram.maxima, &rev, -1.0)] {
        let reference = reference_pairs(mesh, keys);
        assert_eq!(pairs.len(), reference.len(), "number of pairs");
        for p in pairs {
            let &(death, top) = reference
                .get(&p.birth)
                .unwrap_or_else(|| panic!("vertex {} is not an extremum", p.birth));
            assert_eq!(p.death, death, "death of {}", p.birth);
            let end = death.unwrap_or(top);
            let expected = sign * (f[end as usize] - f[p.birth as usize]);
            assert_eq!(p.persistence, expected, "persistence of {}", p.birth);
            assert!(p.persistence >= 0.0);
            assert_eq!(p.birth_value, f[p.birth as usize]);
            assert_eq!(p.death_value, p.death.map(|d| f[d as usize]));
        }
        // Sorted by decreasing persistence.
        assert!(pairs.windows(2).all(|w| w[0].persistence >= w[1].persistence));
    }
}

// ---------------------------------------------------------------------------------------------
// Test meshes and functions.

fn closed_surfaces() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("icosphere(3)", icosphere(3)),
        ("bumpy(3)", bumpy(3)),
        ("torus", torus(2.0, 0.7, 40, 20)),
        ("thin torus", torus(1.0, 0.2, 24, 9)),
        ("uv sphere (valence-40 poles)", uv_sphere(12, 40)),
    ]
}

fn generic_functions(mesh: &TriMesh) -> Vec<Vec<f64>> {
    let noisy = noise(mesh.n_vertices(), 7);
    vec![
        field(mesh, |p| p[2] + 0.1 * p[0]),
        field(mesh, |p| {
            (3.0 * p[0]).sin() * (2.0 * p[1]).cos() + 0.5 * (4.0 * p[2]).sin()
        }),
        field(mesh, |p| p[0] * p[1] + 0.3 * (5.0 * p[2]).cos() + 0.05 * p[1]),
        noisy.clone(),
        field(mesh, |p| p[2])
            .into_iter()
            .zip(&noisy)
            .map(|(a, b)| a + 0.05 * b)
            .collect(),
        vec![0.0; mesh.n_vertices()], // a plateau: ties are broken by vertex index only
    ]
}

// ---------------------------------------------------------------------------------------------
// Critical points.

#[test]
fn morse_identity_on_closed_surfaces() {
    for (name, mesh) in closed_surfaces() {
        let chi = euler_characteristic(&mesh);
        assert!(boundary_vertices(&mesh).is_empty());
        for (k, f) in generic_functions(&mesh).iter().enumerate() {
            let cps = critical_points(&mesh, f).unwrap();
            let total: i64 = cps.iter().map(|c| index(c.kind)).sum();
            assert_eq!(total, chi, "{name}, function {k}: #max + #min − #saddles ≠ χ");
            assert!(count(&cps, |k| k == CriticalKind::Minimum) >= 1);
            assert!(count(&cps, |k| k == CriticalKind::Maximum) >= 1);
        }
    }
}

#[test]
fn morse_identity_on_doubled_surface_with_boundary() {
    // Boundary vertices are classified as in the doubled surface M ∪_∂ M, whose Euler
    // characteristic is 2χ(M): 2·Σ_interior ind + Σ_boundary ind = 2χ(M) (χ = 1 for the grid).
    let mesh = grid(23, 19);
    let chi = euler_characteristic(&mesh);
    assert_eq!(chi, 1);
    let boundary = boundary_vertices(&mesh);
    let mut fs = generic_functions(&mesh);
    fs.push(field(&mesh, |p| (p[0] - 0.5).powi(2) - (p[1] - 0.4).powi(2)));
    for (k, f) in fs.iter().enumerate() {
        let cps = critical_points(&mesh, f).unwrap();
        let doubled: i64 = cps
            .iter()
            .map(|c| index(c.kind) * if boundary.contains(&c.vertex) { 1 } else { 2 })
            .sum();
        assert_eq!(doubled, 2 * chi, "function {k}");
    }
}

#[test]
fn height_on_icosphere_has_one_maximum_and_one_minimum() {
    let mesh = icosphere(3);
    let f = field(&mesh, |p| p[2]);
    let cps = critical_points(&mesh, &f).unwrap();
    let top = (0..f.len()).max_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap() as u32;
    let bottom = (0..f.len()).min_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap() as u32;
    assert!((f[top as usize] - 1.0).abs() < 1e-12 && (f[bottom as usize] + 1.0).abs() < 1e-12);
    assert_eq!(
        cps,
        vec![
            CriticalPoint {
                vertex: top.min(bottom),
                kind: if top < bottom {
                    CriticalKind::Maximum
                } else {
                    CriticalKind::Minimum
                },
                value: f[top.min(bottom) as usize],
            },
            CriticalPoint {
                vertex: top.max(bottom),
                kind: if top < bottom {
                    CriticalKind::Minimum
                } else {
                    CriticalKind::Maximum
                },
                value: f[top.max(bottom) as usize],
            },
        ]
    );
}

#[test]
fn height_on_flat_torus_has_max_min_and_two_saddles() {
    // Torus in the xy-plane, height x = (R + r cos v) cos u: maximum at (u, v) = (0, 0),
    // minimum at (π, 0), saddles at (0, π) and (π, π).
    let (nu, nv) = (32, 16);
    let mesh = torus(2.0, 0.7, nu, nv);
    let f = field(&mesh, |p| p[0]);
    let id = |i: usize, j: usize| (i * nv + j) as u32;
    let cps = critical_points(&mesh, &f).unwrap();
    let got: BTreeMap<u32, CriticalKind> = cps.iter().map(|c| (c.vertex, c.kind)).collect();
    let expected = BTreeMap::from([
        (id(0, 0), CriticalKind::Maximum),
        (id(nu / 2, 0), CriticalKind::Minimum),
        (id(0, nv / 2), CriticalKind::Saddle { multiplicity: 1 }),
        (id(nu / 2, nv / 2), CriticalKind::Saddle { multiplicity: 1 }),
    ]);
    assert_eq!(got, expected);
}

#[test]
fn tilted_plane_on_grid_has_only_corner_extrema() {
    let (nx, ny) = (17, 13);
    let mesh = grid(nx, ny);
    let f = field(&mesh, |p| p[0] + 0.3 * p[1]);
    let cps = critical_points(&mesh, &f).unwrap();
    let got: Vec<(u32, CriticalKind)> = cps.iter().map(|c| (c.vertex, c.kind)).collect();
    assert_eq!(
        got,
        vec![
            (0, CriticalKind::Minimum),
            ((nx * ny - 1) as u32, CriticalKind::Maximum)
        ]
    );
}

#[test]
fn monkey_saddle_has_multiplicity_two() {
    // f = r³ cos(3θ + 0.3) around the centre node of the grid, whose valence is 8: the link
    // signs are + − + + − + − − (six sign changes), i.e. index 1 − 6/2 = −2.
    let n = 21;
    let mesh = grid(n, n);
    let f = field(&mesh, |p| {
        let (x, y) = (p[0] - 0.5, p[1] - 0.5);
        (x * x + y * y).powf(1.5) * (3.0 * y.atan2(x) + 0.3).cos()
    });
    let centre = (n / 2 * n + n / 2) as u32;
    assert_eq!(neighbour_sets(&mesh)[centre as usize].len(), 8);
    let cps = critical_points(&mesh, &f).unwrap();
    let at_centre: Vec<CriticalKind> = cps.iter().filter(|c| c.vertex == centre).map(|c| c.kind).collect();
    assert_eq!(at_centre, vec![CriticalKind::Saddle { multiplicity: 2 }]);
    let interior_saddles = cps
        .iter()
        .filter(|c| !boundary_vertices(&mesh).contains(&c.vertex))
        .filter(|c| matches!(c.kind, CriticalKind::Saddle { .. }))
        .count();
    assert_eq!(interior_saddles, 1);
}

#[test]
fn boundary_vertices_follow_the_doubled_surface_convention() {
    // f = y − 4(x − ½)² on the unit square: no interior critical point; on the boundary the
    // top midpoint is a maximum, the bottom corners are minima (the tie f = −1 is broken by
    // index, both are still minima), and the bottom midpoint, whose link path runs
    // lower → higher → lower (two sign changes), is a saddle of the doubled square.
    let n = 21;
    let mesh = grid(n, n);
    let f = field(&mesh, |p| p[1] - 4.0 * (p[0] - 0.5).powi(2));
    let cps = critical_points(&mesh, &f).unwrap();
    let got: Vec<(u32, CriticalKind)> = cps.iter().map(|c| (c.vertex, c.kind)).collect();
    let mid = (n / 2) as u32;
    assert_eq!(
        got,
        vec![
            (0, CriticalKind::Minimum),
            (mid, CriticalKind::Saddle { multiplicity: 1 }),
            ((n - 1) as u32, CriticalKind::Minimum),
            ((n * (n - 1)) as u32 + mid, CriticalKind::Maximum),
        ]
    );
    // The saddle is where the two corner basins merge in the sublevel filtration.
    let d = persistence(&mesh, &f).unwrap();
    assert_eq!(d.minima.len(), 2);
    assert_eq!((d.minima[1].birth, d.minima[1].death), ((n - 1) as u32, Some(mid)));
    assert_eq!(d.minima[1].persistence, 1.0);
}

#[test]
fn classification_ignores_face_orientation() {
    // The link rule only needs the link as an undirected cycle or path, so flipping some
    // triangles (an inconsistently oriented input) changes nothing.
    let mesh = bumpy(2);
    let faces: Vec<[u32; 3]> = mesh
        .faces()
        .iter()
        .enumerate()
        .map(|(i, &[a, b, c])| if i % 3 == 0 { [a, c, b] } else { [a, b, c] })
        .collect();
    let flipped = TriMesh::new(mesh.positions().to_vec(), faces).unwrap();
    for f in generic_functions(&mesh) {
        assert_eq!(
            critical_points(&mesh, &f).unwrap(),
            critical_points(&flipped, &f).unwrap()
        );
        assert_eq!(persistence(&mesh, &f).unwrap(), persistence(&flipped, &f).unwrap());
    }
}

#[test]
fn local_extrema_are_the_critical_extrema() {
    for (_, mesh) in closed_surfaces().into_iter().chain([("grid", grid(20, 20))]) {
        let adj = neighbour_sets(&mesh);
        for f in generic_functions(&mesh) {
            let cps = critical_points(&mesh, &f).unwrap();
            let of_kind = |kind| -> Vec<u32> { cps.iter().filter(|c| c.kind == kind).map(|c| c.vertex).collect() };
            let maxima = local_maxima(&mesh, &f).unwrap();
            let minima = local_minima(&mesh, &f).unwrap();
            assert_eq!(maxima, of_kind(CriticalKind::Maximum));
            assert_eq!(minima, of_kind(CriticalKind::Minimum));
            // Brute force over the one-ring with the (f, index) order.
            let rank = sos_rank(&f);
            let brute: Vec<u32> = (0..f.len())
                .filter(|&v| adj[v].iter().all(|&w| rank[w as usize] < rank[v]))
                .map(|v| v as u32)
                .collect();
            assert_eq!(maxima, brute);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Persistence.

#[test]
fn persistence_matches_bottleneck_flooding_reference() {
    let mut cases: Vec<(TriMesh, Vec<f64>)> = Vec::new();
    for (_, mesh) in closed_surfaces() {
        for f in generic_functions(&mesh) {
            cases.push((mesh.clone(), f));
        }
    }
    let g = grid(24, 21);
    for f in generic_functions(&g) {
        cases.push((g.clone(), f));
    }
    // Quantised noise: many exact ties, resolved by vertex index.
    let mesh = icosphere(2);
    let f: Vec<f64> = noise(mesh.n_vertices(), 3).iter().map(|x| (4.0 * x).round()).collect();
    cases.push((mesh, f));
    for (mesh, f) in &cases {
        check_against_reference(mesh, f);
    }
}

#[test]
fn persistence_of_disconnected_mesh_has_one_essential_class_per_component() {
    // Two disjoint tetrahedra.
    let mut positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    positions.extend(positions.clone().iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
    let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let faces: Vec<[u32; 3]> = tet
        .iter()
        .chain(tet.map(|f| f.map(|i| i + 4)).iter())
        .copied()
        .collect();
    let mesh = TriMesh::new(positions, faces).unwrap();
    let f = vec![0.0, 3.0, 1.0, 2.0, 10.0, 11.0, 12.0, 13.5];
    let d = persistence(&mesh, &f).unwrap();
    let essential = |pairs: &[PersistencePair]| -> Vec<(u32, f64)> {
        let mut e: Vec<(u32, f64)> = pairs
            .iter()
            .filter(|p| p.is_essential())
            .map(|p| (p.birth, p.persistence))
            .collect();
        e.sort_by_key(|x| x.0);
        e
    };
    assert_eq!(essential(&d.minima), vec![(0, 3.0), (4, 3.5)]);
    assert_eq!(essential(&d.maxima), vec![(1, 3.0), (7, 3.5)]);
    assert_eq!(d.minima.len(), 2);
    assert_eq!(d.value_range, 13.5);
    check_against_reference(&mesh, &f);
}

#[test]
fn pair_counts_are_consistent_with_critical_points() {
    for (name, mesh) in closed_surfaces() {
        let genus = (2 - euler_characteristic(&mesh)) / 2;
        for f in generic_functions(&mesh) {
            let cps = critical_points(&mesh, &f).unwrap();
            let d = persistence(&mesh, &f).unwrap();
            assert_eq!(d.minima.len(), count(&cps, |k| k == CriticalKind::Minimum));
            assert_eq!(d.maxima.len(), count(&cps, |k| k == CriticalKind::Maximum));
            assert_eq!(d.minima.iter().filter(|p| p.is_essential()).count(), 1);
            assert_eq!(d.maxima.iter().filter(|p| p.is_essential()).count(), 1);
            // Every death is a saddle, each saddle kills at most `multiplicity` components
            // (sub- and superlevel together), and 2g saddle units create the 1-cycles.
            let kinds: HashMap<u32, CriticalKind> = cps.iter().map(|c| (c.vertex, c.kind)).collect();
            let mut deaths: HashMap<u32, usize> = HashMap::new();
            for p in d.minima.iter().chain(&d.maxima) {
                if let Some(s) = p.death {
                    *deaths.entry(s).or_insert(0) += 1;
                }
            }
            for (s, k) in &deaths {
                match kinds.get(s) {
                    Some(CriticalKind::Saddle { multiplicity }) => assert!(k <= multiplicity),
                    other => panic!("{name}: death vertex {s} is {other:?}"),
                }
            }
            let finite: usize = deaths.values().sum();
            assert_eq!(finite as i64, saddle_units(&cps) as i64 - 2 * genus, "{name}");
        }
    }
}

fn gaussian(p: [f64; 3], c: [f64; 2], sigma: f64) -> f64 {
    let r2 = (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
    (-r2 / (2.0 * sigma * sigma)).exp()
}

#[test]
fn two_gaussian_bumps_have_the_expected_persistence() {
    // Heights 1 and 0.5 on a flat background 0.05, centres on grid nodes.
    let (nx, sigma, background) = (41, 0.08, 0.05);
    let (c1, c2) = ([0.3, 0.5], [0.7, 0.5]);
    let mesh = grid(nx, nx);
    let bumps = |p: [f64; 3]| background + gaussian(p, c1, sigma) + 0.5 * gaussian(p, c2, sigma);
    let f = field(&mesh, bumps);
    let node = |c: [f64; 2]| ((c[1] * 40.0).round() as usize * nx + (c[0] * 40.0).round() as usize) as u32;
    let d = persistence(&mesh, &f).unwrap();
    check_against_reference(&mesh, &f);

    // Essential maximum: the top of the high bump, persisting down to the global minimum.
    let fmin = f.iter().copied().fold(f64::INFINITY, f64::min);
    let first = d.maxima[0];
    assert_eq!((first.birth, first.death), (node(c1), None));
    assert!((first.persistence - (1.0 + 0.5 * gaussian([0.3, 0.5, 0.0], c2, sigma) + background - fmin)).abs() < 1e-12);
    assert!((first.persistence - 1.0).abs() < 1e-3);

    // The low bump dies at the pass between the bumps: on the segment joining the centres
    // (y = 0.5) the pass is the minimum of f along x, computed here in closed form by a
    // fine 1-D search, and the grid pass can only differ by the grid resolution.
    let second = d.maxima[1];
    assert_eq!(second.birth, node(c2));
    let pass = (0..=40_000)
        .map(|i| bumps([0.3 + 0.4 * i as f64 / 40_000.0, 0.5, 0.0]))
        .fold(f64::INFINITY, f64::min);
    let height2 = bumps([0.7, 0.5, 0.0]);
    assert!(
        (second.persistence - (height2 - pass)).abs() < 5e-3,
        "{} vs {}",
        second.persistence,
        height2 - pass
    );
    let death = second.death.unwrap() as usize;
    let y_death = mesh.positions()[death][1];
    assert!(
        (y_death - 0.5).abs() < 1e-12,
        "the pass lies on the line between the bumps"
    );
    // All other maxima are discretisation noise far below both bumps.
    assert!(d.maxima[2..].iter().all(|p| p.persistence < 1e-3));

    // Simplification to p = 0.25 keeps the two bumps, their pass and the global minimum.
    let kept = persistent_extrema(&d, 0.25);
    let global_min = d.minima[0].birth;
    let mut expected = vec![node(c1), node(c2), death as u32, global_min];
    expected.sort_unstable();
    assert_eq!(kept, expected);
    // 0.25 of a range of ≈ 1: same set; 0.6 of the range drops the low bump.
    assert_eq!(persistent_extrema_relative(&d, 0.25), expected);
    let mut high_only = vec![node(c1), global_min];
    high_only.sort_unstable();
    assert_eq!(persistent_extrema_relative(&d, 0.6), high_only);
}

#[test]
fn simplification_keeps_exactly_the_persistent_extrema() {
    let mesh = bumpy(3);
    let f: Vec<f64> = field(&mesh, |p| (3.0 * p[0]).sin() + p[1] * p[2])
        .iter()
        .zip(noise(mesh.n_vertices(), 11))
        .map(|(a, b)| a + 0.3 * b)
        .collect();
    let d = persistence(&mesh, &f).unwrap();
    let rank = sos_rank(&f);
    let n = f.len();
    let rev: Vec<usize> = rank.iter().map(|&r| n - 1 - r).collect();
    let sub = reference_pairs(&mesh, &rank);
    let sup = reference_pairs(&mesh, &rev);
    let mut sizes = Vec::new();
    for p in [0.0, 0.01, 0.05, 0.1, 0.3, 1.0, 10.0] {
        let mut expected = BTreeSet::new();
        for (pairs, sign) in [(&sub, 1.0), (&sup, -1.0)] {
            for (&birth, &(death, top)) in pairs.iter() {
                let end = death.unwrap_or(top);
                let pers = sign * (f[end as usize] - f[birth as usize]);
                if death.is_none() || pers >= p {
                    expected.insert(birth);
                    expected.extend(death);
                }
            }
        }
        let kept = persistent_extrema(&d, p);
        sizes.push(kept.len());
        assert_eq!(kept, expected.into_iter().collect::<Vec<_>>(), "threshold {p}");
    }
    // Raising the threshold removes extrema step by step.
    assert!(sizes.windows(2).all(|w| w[0] >= w[1]), "{sizes:?}");
    let distinct: BTreeSet<usize> = sizes.iter().copied().collect();
    assert!(distinct.len() >= 4, "{sizes:?}");
    // A huge threshold leaves only the global minimum and maximum.
    assert_eq!(persistent_extrema(&d, 1e9).len(), 2);
    let all = persistent_extrema(&d, 0.0).len();
    assert!(all > 20, "the noise creates many extrema, got {all}");
}

// ---------------------------------------------------------------------------------------------
// Bad input.

#[test]
fn wrong_length_is_a_typed_error() {
    let mesh = icosphere(1);
    let f = vec![0.0; mesh.n_vertices() - 1];
    assert!(matches!(
        critical_points(&mesh, &f),
        Err(MeshError::ScalarFieldLength {
            len: 41,
            n_vertices: 42
        })
    ));
    assert!(matches!(
        persistence(&mesh, &f),
        Err(MeshError::ScalarFieldLength { .. })
    ));
    assert!(matches!(
        local_maxima(&mesh, &f),
        Err(MeshError::ScalarFieldLength { .. })
    ));
    assert!(matches!(
        local_minima(&mesh, &f),
        Err(MeshError::ScalarFieldLength { .. })
    ));
}

#[test]
fn non_finite_values_are_a_typed_error() {
    let mesh = icosphere(1);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut f = vec![0.0; mesh.n_vertices()];
        f[17] = bad;
        let err = critical_points(&mesh, &f).unwrap_err();
        assert!(
            matches!(err, MeshError::NonFiniteScalarField { vertex: 17, .. }),
            "{err}"
        );
        assert!(matches!(
            persistence(&mesh, &f),
            Err(MeshError::NonFiniteScalarField { vertex: 17, .. })
        ));
        assert!(matches!(
            local_maxima(&mesh, &f),
            Err(MeshError::NonFiniteScalarField { vertex: 17, .. })
        ));
    }
}

#[test]
fn non_manifold_vertices_are_classified_on_the_edge_graph() {
    // Bow tie: two triangles sharing only vertex 0 (its link is two disjoint edges).
    let positions = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    let bowtie = TriMesh::new(positions.clone(), vec![[0, 1, 2], [0, 3, 4]]).unwrap();
    let kind_of = |mesh: &TriMesh, f: &[f64], v: u32| {
        critical_points(mesh, f)
            .unwrap()
            .into_iter()
            .find(|c| c.vertex == v)
            .map_or(CriticalKind::Regular, |c| c.kind)
    };
    // f(0) lowest: every link vertex is above, a minimum; highest: a maximum.
    assert_eq!(kind_of(&bowtie, &[0.0, 1.0, 2.0, 3.0, 4.0], 0), CriticalKind::Minimum);
    assert_eq!(kind_of(&bowtie, &[9.0, 1.0, 2.0, 3.0, 4.0], 0), CriticalKind::Maximum);
    // In the middle: the two wings' sublevel sets (1 and 3) and superlevel sets (2 and 4) meet
    // only at vertex 0, where persistence kills a minimum and a maximum: a saddle.
    let f = [2.0, 0.0, 4.0, 1.0, 3.0];
    assert_eq!(kind_of(&bowtie, &f, 0), CriticalKind::Saddle { multiplicity: 1 });
    let d = persistence(&bowtie, &f).unwrap();
    assert_eq!(d.minima.len(), 2);
    assert!(
        d.minima.iter().any(|p| p.birth == 3 && p.death == Some(0)),
        "{:?}",
        d.minima
    );
    assert_eq!(local_maxima(&bowtie, &f).unwrap(), vec![2, 4]);
    check_against_reference(&bowtie, &f);

    // Three triangles on the edge 0–1 (a fin): the link of 0 is the star 1–{2, 3, 4}.
    let fin = TriMesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    )
    .unwrap();
    // 1 below 0, the three tips above and joined only through 0 and 1: three superlevel
    // components meet at 0 → a saddle of multiplicity 2.
    let f = [1.0, 0.0, 2.0, 3.0, 4.0];
    assert_eq!(kind_of(&fin, &f, 0), CriticalKind::Saddle { multiplicity: 2 });
    let d = persistence(&fin, &f).unwrap();
    assert_eq!(
        d.maxima.iter().filter(|p| p.death == Some(0)).count(),
        2,
        "{:?}",
        d.maxima
    );
    // 1 above 0 and every tip above too: a minimum; the tips below and 1 above: the mirror
    // saddle.
    assert_eq!(kind_of(&fin, &[0.0, 1.0, 2.0, 3.0, 4.0], 0), CriticalKind::Minimum);
    let mirrored = [2.0, 9.0, 1.0, 0.0, -1.0];
    assert_eq!(kind_of(&fin, &mirrored, 0), CriticalKind::Saddle { multiplicity: 2 });
    // 1 and 2 below (joined by their edge), 3 and 4 above (joined only through 0 and 1): a
    // saddle of multiplicity 1. With 1, 2, 3 below and 4 above nothing merges at 0: regular.
    assert_eq!(
        kind_of(&fin, &[1.5, 0.0, 1.0, 2.0, 3.0], 0),
        CriticalKind::Saddle { multiplicity: 1 }
    );
    assert_eq!(kind_of(&fin, &[2.5, 0.0, 1.0, 2.0, 3.0], 0), CriticalKind::Regular);
    check_against_reference(&fin, &f);

    // A face repeating a vertex, and a vertex in no face.
    let repeated = TriMesh::new(positions[..4].to_vec(), vec![[0, 1, 2], [2, 3, 3]]).unwrap();
    assert!(matches!(
        critical_points(&repeated, &f[..4]),
        Err(MeshError::RepeatedIndex { face: 1, .. })
    ));
    let lonely = TriMesh::new(positions, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    assert!(matches!(
        critical_points(&lonely, &f),
        Err(MeshError::UnreferencedVertex { vertex: 4 })
    ));
}

/// On the neighbourhood mesh of a point cloud (non-manifold: the distinct local triangles of
/// its points) every vertex is classified on the edge graph: each death vertex of the
/// persistence sweeps is a saddle, and a height function on a sphere cloud, whose surface has
/// 2 critical points, has few of them (the graph's own small extrema, each paired with a
/// saddle) instead of the hundreds the link rule would find on fragmented links.
#[test]
fn a_point_cloud_neighbourhood_mesh_is_classified_on_its_edge_graph() {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let n = 2000;
    let points: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            // A small tilt so that z is not constant along the lattice's rows.
            [r * phi.cos(), r * phi.sin(), z + 0.01 * r * phi.sin()]
        })
        .collect();
    let cloud = mesh_fem::cloud::PointCloud::new(points.clone(), None).unwrap();
    let built = mesh_fem::cloud::assemble_cloud(&cloud, &Default::default(), &Default::default()).unwrap();
    let mesh = &built.neighbourhood;
    let f: Vec<f64> = points.iter().map(|p| p[2]).collect();
    let critical = critical_points(mesh, &f).unwrap();
    let saddles: BTreeSet<u32> = critical
        .iter()
        .filter(|c| matches!(c.kind, CriticalKind::Saddle { .. }))
        .map(|c| c.vertex)
        .collect();
    let d = persistence(mesh, &f).unwrap();
    for p in d.minima.iter().chain(&d.maxima) {
        if let Some(death) = p.death {
            assert!(saddles.contains(&death), "death vertex {death} is not a saddle");
        }
    }
    let extrema = critical.len() - saddles.len();
    assert!(extrema >= 2);
    assert!(critical.len() <= n / 50, "{} critical points of 2000", critical.len());
}
