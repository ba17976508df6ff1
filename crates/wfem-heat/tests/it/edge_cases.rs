//! Numerical edge cases of `K_t f = exp(−t M⁻¹L) f` (paper, Eq. (6)) that must still give
//! correct results (issue #8): meshes scaled by 1e−8 and 1e8, obtuse triangles (negative
//! cotangent weights), face areas varying by 10⁶, t from 1e−8 to 1e4 times the squared mean
//! edge length, several connected components and open boundaries, for the wFEM (B) and the
//! lumped (D) kernel.
//!
//! Every result of the default rational method, the fast path and (where its truncation is
//! negligible) the spectral method is compared with an INDEPENDENT dense reference: nalgebra's
//! Cholesky M = RRᵀ and nalgebra's symmetric eigensolver of C = R⁻¹LR⁻ᵀ = YΛYᵀ (none of the
//! code under test, which uses faer), `K_t f = R⁻ᵀ Y e^{−tΛ} Yᵀ Rᵀ f`. The error is measured in
//! the M-norm: ‖g − g_ref‖_M ≤ 1e−10‖g_ref‖_M + 1e−12‖f‖_M (the absolute floor matters only
//! where K_t f has decayed).
use crate::common;
use common::{dot, matvec, rel_err, unit};
use faer::sparse::SparseColMat;
use mesh_fem::{assemble, generate, AssemblyParams, FemOperators, Mass, TriMesh};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use shifted_solve::function::KrylovParams;
use wfem_heat::method::Method;
use wfem_heat::spectral::{EigenParams, Eigenbasis};
use wfem_heat::{HeatKernel, HeatParams};

const REL_TOL: f64 = 1e-10;
const ABS_FLOOR: f64 = 1e-12;

fn to_dense(a: &SparseColMat<usize, f64>) -> DMatrix<f64> {
    let mut d = DMatrix::<f64>::zeros(a.nrows(), a.ncols());
    let s = a.symbolic();
    for j in 0..a.ncols() {
        for p in s.col_range(j) {
            d[(s.row_idx()[p], j)] += a.val()[p];
        }
    }
    d
}

/// Dense reference `K_t = R⁻ᵀ Y e^{−tΛ} Yᵀ Rᵀ` from nalgebra (independent of faer), with the
/// null space of L deflated exactly.
///
/// A plain eigendecomposition returns the zero eigenvalues with an absolute error ≈ ε‖C‖
/// (measured 2.5e−12 on a 16 × 16 grid, ‖C‖ = 8.1e3), so e^{−tλ₁} misses 1 by tλ₁ ≈ 1.4e−10
/// at t = 1e4·h̄²: the reference, not the code under test, would be wrong at large t. The null
/// space is known exactly (L·1_c = 0 for the indicator 1_c of every connected component), so
/// C = R⁻¹LR⁻ᵀ has the exact null vectors q_c = Rᵀ1_c/‖Rᵀ1_c‖. With Q₀ = [q_c] and
/// P = I − Q₀Q₀ᵀ: `K_t = R⁻ᵀ (Q₀Q₀ᵀ + Σ_{k>c} y_k e^{−tλ_k} y_kᵀ P) Rᵀ`, the sum over the
/// eigenpairs of PCP without its #components smallest (≈ span Q₀).
struct Reference {
    r: DMatrix<f64>,
    y: DMatrix<f64>,
    lambda: Vec<f64>,
    q0: DMatrix<f64>,
}

/// Connected components of the sparsity graph of `a` (one label per vertex) and their count.
fn components(a: &SparseColMat<usize, f64>) -> (Vec<usize>, usize) {
    let n = a.nrows();
    let s = a.symbolic();
    let mut label = vec![usize::MAX; n];
    let mut count = 0;
    for seed in 0..n {
        if label[seed] != usize::MAX {
            continue;
        }
        let mut stack = vec![seed];
        label[seed] = count;
        while let Some(j) = stack.pop() {
            for p in s.col_range(j) {
                let i = s.row_idx()[p];
                if label[i] == usize::MAX {
                    label[i] = count;
                    stack.push(i);
                }
            }
        }
        count += 1;
    }
    (label, count)
}

impl Reference {
    fn new(stiffness: &SparseColMat<usize, f64>, mass: &SparseColMat<usize, f64>) -> Self {
        let n = stiffness.nrows();
        let l = to_dense(stiffness);
        let m = to_dense(mass);
        let r = m.cholesky().expect("reference: M is SPD").l();
        let y = r.solve_lower_triangular(&l).expect("R invertible");
        let c = r.solve_lower_triangular(&y.transpose()).expect("R invertible");
        let c = (&c + c.transpose()) * 0.5;
        // Exact null vectors q_c = Rᵀ1_c / ‖Rᵀ1_c‖ (disjoint supports: already orthogonal).
        let (label, nc) = components(stiffness);
        let mut q0 = DMatrix::<f64>::zeros(n, nc);
        for (i, &c) in label.iter().enumerate() {
            q0[(i, c)] = 1.0;
        }
        let mut q0 = r.transpose() * q0;
        for mut col in q0.column_iter_mut() {
            let nrm = col.norm();
            col /= nrm;
        }
        let p = DMatrix::<f64>::identity(n, n) - &q0 * q0.transpose();
        let pcp = &p * c * &p;
        let pcp = (&pcp + pcp.transpose()) * 0.5;
        let eig = SymmetricEigen::new(pcp);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
        let keep = &order[nc..];
        let y = DMatrix::<f64>::from_fn(n, keep.len(), |i, k| eig.eigenvectors[(i, keep[k])]);
        let yp = y.transpose() * &p; // y_kᵀP
        Self {
            r,
            y: yp.transpose(),
            lambda: keep.iter().map(|&k| eig.eigenvalues[k]).collect(),
            q0,
        }
    }

    fn apply(&self, f: &[f64], t: f64) -> Vec<f64> {
        let f = DVector::from_column_slice(f);
        let rf = self.r.transpose() * f;
        // Columns of self.y are P y_k, so self.yᵀ u = y_kᵀ P u.
        let mut c = self.y.transpose() * &rf;
        for (ck, lk) in c.iter_mut().zip(&self.lambda) {
            *ck *= (-t * lk).exp();
        }
        // P y_k ≈ y_k (y_k ⟂ Q₀ up to rounding); use P y_k on the left too.
        let u = &self.y * c + &self.q0 * (self.q0.transpose() * &rf);
        let g = self.r.transpose().solve_upper_triangular(&u).expect("R invertible");
        g.iter().copied().collect()
    }

    /// The (k+1)-th smallest eigenvalue (spectral truncation error ≈ e^{−tλ_{k+1}}).
    fn sorted_lambda(&self, k: usize) -> f64 {
        // self.lambda is sorted and misses the #components zeros.
        let nc = self.q0.ncols();
        if k < nc {
            0.0
        } else {
            self.lambda[(k - nc).min(self.lambda.len() - 1)]
        }
    }
}

fn mass_of(ops: &FemOperators, kind: Mass) -> SparseColMat<usize, f64> {
    match kind {
        Mass::Consistent => ops.mass.clone(),
        Mass::Lumped(_) => ops.lumped_mass(),
        Mass::Identity => ops.identity_mass(),
    }
}

fn norm_m(m: &SparseColMat<usize, f64>, v: &[f64]) -> f64 {
    dot(v, &matvec(m, v)).max(0.0).sqrt()
}

/// A rough test function with a nonzero mean (so K_t f tends to a nonzero constant and the
/// relative error stays meaningful for large t); index-based, hence the same on scaled meshes.
fn test_function(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let h = ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f64 / (1u64 << 24) as f64;
            1.0 + 0.5 * (0.37 * i as f64).sin() + 0.25 * (h - 0.5)
        })
        .collect()
}

fn mean_edge_length(mesh: &TriMesh) -> f64 {
    let p = mesh.positions();
    let (mut sum, mut count) = (0.0, 0usize);
    for f in mesh.faces() {
        for k in 0..3 {
            let (a, b) = (p[f[k] as usize], p[f[(k + 1) % 3] as usize]);
            sum += ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            count += 1;
        }
    }
    sum / count as f64
}

fn ops(mesh: &TriMesh) -> FemOperators {
    assemble(mesh, &AssemblyParams::default()).expect("assembly")
}

/// The methods under test, with a label. Spectral uses k = min(n, 60) eigenpairs and is
/// only checked where its truncation e^{−tλ_{k+1}} is below 1e−14; Dense is faer's full
/// generalized eigendecomposition (the crate's own reference) against nalgebra's.
fn methods(n: usize) -> Vec<(&'static str, Method)> {
    vec![
        ("rational16", Method::rational(shifted_solve::poles::DEFAULT_DEGREE)),
        ("fast", Method::Fast(KrylovParams::default())),
        ("spectral", Method::spectral(n.min(60))),
        ("dense", Method::Dense),
    ]
}

/// Checks every method of `methods` and both kinds against the reference at every t; returns
/// the worst ratio error / bound seen (for the messages).
fn check_against_reference(label: &str, ops: &FemOperators, times: &[f64], kinds: &[Mass]) -> f64 {
    let n = ops.n();
    let mut worst = 0.0f64;
    let mut spectral_checked = 0;
    for &kind in kinds {
        let mass = mass_of(ops, kind);
        let reference = Reference::new(&ops.stiffness, &mass);
        // f with a nonzero mean, and the same f without its M-mean on every component (no
        // λ = 0 component: K_t f decays to 0, the absolute floor applies).
        let f = test_function(n);
        let (comp, nc) = components(&ops.stiffness);
        let (mf, m1) = (matvec(&mass, &f), matvec(&mass, &vec![1.0; n]));
        let (mut num, mut den) = (vec![0.0; nc], vec![0.0; nc]);
        for i in 0..n {
            num[comp[i]] += mf[i];
            den[comp[i]] += m1[i];
        }
        let f0: Vec<f64> = (0..n).map(|i| f[i] - num[comp[i]] / den[comp[i]]).collect();
        for (name, method) in methods(n) {
            let spectral_k = match &method {
                Method::Spectral { k, .. } => Some(*k),
                _ => None,
            };
            let kernel = HeatKernel::new(
                ops,
                HeatParams {
                    mass: kind,
                    method: method.clone(),
                },
            )
            .unwrap_or_else(|e| panic!("{label} {kind:?} {name}: {e}"));
            for (&t, (fname, f)) in times.iter().flat_map(|t| [(t, ("f", &f)), (t, ("f − mean", &f0))]) {
                if let Some(k) = spectral_k {
                    if k < n && (-t * reference.sorted_lambda(k)).exp() > 1e-14 {
                        continue; // truncated spectral sum not accurate at this t (Eq. (8))
                    }
                }
                let g = kernel
                    .apply(f, t)
                    .unwrap_or_else(|e| panic!("{label} {kind:?} {name} t={t:e}: {e}"));
                let g_ref = reference.apply(f, t);
                let diff: Vec<f64> = g.iter().zip(&g_ref).map(|(a, b)| a - b).collect();
                let err = norm_m(&mass, &diff);
                let scale = norm_m(&mass, &g_ref);
                let bound = REL_TOL * scale + ABS_FLOOR * norm_m(&mass, f);
                assert!(
                    err <= bound,
                    "{label} {kind:?} {name} {fname} t={t:e}: ‖g − g_ref‖_M = {err:e} > {bound:e} (relative {:e})",
                    err / scale
                );
                worst = worst.max(err / bound);
                spectral_checked += spectral_k.is_some() as usize;
            }
        }
    }
    // Every case has times large enough for the truncated spectral sum.
    assert!(spectral_checked > 0, "{label}: the spectral method was never checked");
    worst
}

const KINDS: [Mass; 2] = [Mass::Consistent, Mass::Lumped(mesh_fem::Lumping::Barycentric)];

fn times_relative(mesh: &TriMesh, factors: &[f64]) -> Vec<f64> {
    let h2 = mean_edge_length(mesh).powi(2);
    factors.iter().map(|s| s * h2).collect()
}

/// Meshes scaled by α = 1e−8 and 1e8 (t scaled by α²) against the reference, and scale
/// covariance `K_{α²t}(αM) f = K_t(M) f` for the rational and the fast method.
#[test]
fn extreme_scales_match_reference_and_are_covariant() {
    let base_mesh = generate::irregular_sphere(2, 5.6);
    let base_ops = ops(&base_mesh);
    let f = test_function(base_mesh.n_vertices());
    let t0s = times_relative(&base_mesh, &[1e-3, 1.0, 1e2]);
    for alpha in [1e-8, 1e8] {
        let mesh = base_mesh.scaled(alpha).unwrap();
        let scaled_ops = ops(&mesh);
        let times: Vec<f64> = t0s.iter().map(|t| alpha * alpha * t).collect();
        let worst = check_against_reference(&format!("α={alpha:e}"), &scaled_ops, &times, &KINDS);
        eprintln!("scale α = {alpha:e}: worst error/bound {worst:.2e}");
        for kind in KINDS {
            for method in [
                Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
                Method::Fast(KrylovParams::default()),
            ] {
                let params = HeatParams {
                    mass: kind,
                    method: method.clone(),
                };
                let base = HeatKernel::new(&base_ops, params.clone()).unwrap();
                let scaled = HeatKernel::new(&scaled_ops, params).unwrap();
                for &t0 in &t0s {
                    let a = scaled.apply(&f, alpha * alpha * t0).unwrap();
                    let b = base.apply(&f, t0).unwrap();
                    let err = common::rel_err(&a, &b);
                    assert!(
                        err < 1e-10,
                        "covariance {kind:?} {method:?} α={alpha:e} t0={t0:e}: {err:e}"
                    );
                }
            }
        }
    }
}

/// A sheared and jittered grid: many obtuse triangles, so some cotangent weights are negative
/// (L has positive off-diagonal entries; L is still PSD).
fn obtuse_mesh() -> TriMesh {
    let g = generate::grid(14, 14);
    let positions = g
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let j = ((i * 7919) % 97) as f64 / 97.0 - 0.5;
            [p[0] + 1.6 * p[1] + 0.02 * j, p[1] + 0.015 * j, 0.0]
        })
        .collect();
    TriMesh::new(positions, g.faces().to_vec()).unwrap()
}

#[test]
fn obtuse_triangles_with_negative_cotangent_weights() {
    let mesh = obtuse_mesh();
    let ops = ops(&mesh);
    // The case really has negative cotangent weights: L_ij = −w_ij > 0 off the diagonal.
    let s = ops.stiffness.symbolic();
    let mut positive_off_diagonal = 0;
    for j in 0..ops.n() {
        for p in s.col_range(j) {
            if s.row_idx()[p] != j && ops.stiffness.val()[p] > 1e-12 {
                positive_off_diagonal += 1;
            }
        }
    }
    assert!(
        positive_off_diagonal >= 20,
        "only {positive_off_diagonal} negative cotangent weights"
    );
    let times = times_relative(&mesh, &[1e-8, 1e-4, 1e-2, 1.0, 1e2, 1e4]);
    let worst = check_against_reference("obtuse", &ops, &times, &KINDS);
    eprintln!("obtuse: {positive_off_diagonal} negative weights, worst error/bound {worst:.2e}");
}

/// A graded disk: rings at radii r_k = q^k·1e−3 (geometric, so cells keep their shape) around
/// a centre fan; face areas vary by more than 10⁶ and the outer ring is an open boundary.
fn graded_disk(segments: usize, rings: usize, ratio: f64) -> TriMesh {
    let q = ratio.powf(1.0 / (rings - 1) as f64);
    let r0 = 1.0 / ratio;
    let mut positions = vec![[0.0, 0.0, 0.0]];
    for k in 0..rings {
        let r = r0 * q.powi(k as i32);
        let twist = 0.5 * (k % 2) as f64;
        for s in 0..segments {
            let a = 2.0 * std::f64::consts::PI * (s as f64 + twist) / segments as f64;
            positions.push([r * a.cos(), r * a.sin(), 0.0]);
        }
    }
    let id = |k: usize, s: usize| (1 + k * segments + s % segments) as u32;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, id(0, s), id(0, s + 1)]);
    }
    for k in 0..rings - 1 {
        for s in 0..segments {
            if k % 2 == 0 {
                faces.push([id(k, s), id(k + 1, s), id(k, s + 1)]);
                faces.push([id(k, s + 1), id(k + 1, s), id(k + 1, s + 1)]);
            } else {
                faces.push([id(k, s), id(k + 1, s + 1), id(k, s + 1)]);
                faces.push([id(k, s), id(k + 1, s), id(k + 1, s + 1)]);
            }
        }
    }
    TriMesh::new(positions, faces).unwrap()
}

#[test]
fn face_areas_varying_by_a_million() {
    let mesh = graded_disk(20, 22, 2e3);
    let areas: Vec<f64> = (0..mesh.n_faces()).map(|f| mesh.face_area(f)).collect();
    let (amin, amax) = areas
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &a| (lo.min(a), hi.max(a)));
    assert!(amax / amin >= 1e6, "area ratio only {:e}", amax / amin);
    let ops = ops(&mesh);
    let times = times_relative(&mesh, &[1e-8, 1e-4, 1e-2, 1.0, 1e2, 1e4]);
    let worst = check_against_reference("graded", &ops, &times, &KINDS);
    eprintln!(
        "graded disk: n = {}, area ratio {:.1e}, worst error/bound {worst:.2e}",
        mesh.n_vertices(),
        amax / amin
    );
}

/// t from 1e−8 to 1e4 times the squared mean edge length on a closed irregular sphere and a
/// uv-sphere with poles (fans of thin triangles).
#[test]
fn time_range_from_1e_minus_8_to_1e4_edge_lengths_squared() {
    let factors = [1e-8, 1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4];
    for (label, mesh) in [
        ("irregular_sphere2", generate::irregular_sphere(2, 5.6)),
        ("uv_sphere", generate::uv_sphere(12, 16)),
    ] {
        let ops = ops(&mesh);
        let times = times_relative(&mesh, &factors);
        let worst = check_against_reference(label, &ops, &times, &KINDS);
        eprintln!("{label}: worst error/bound {worst:.2e}");
    }
}

/// Concatenates meshes (vertex indices shifted), returning the union and each part's vertex
/// range.
fn union(parts: &[TriMesh]) -> (TriMesh, Vec<std::ops::Range<usize>>) {
    let (mut positions, mut faces, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
    for (i, m) in parts.iter().enumerate() {
        let base = positions.len();
        positions.extend(m.positions().iter().map(|p| [p[0] + 3.0 * i as f64, p[1], p[2]]));
        faces.extend(m.faces().iter().map(|f| f.map(|v| v + base as u32)));
        ranges.push(base..positions.len());
    }
    (TriMesh::new(positions, faces).unwrap(), ranges)
}

/// Three connected components (closed sphere, open grid, torus): the kernel is block
/// diagonal (entries between components are exactly zero) and each block is the kernel of
/// the component alone; the whole against the dense reference.
#[test]
fn several_connected_components_stay_block_diagonal() {
    let parts = [
        generate::icosphere(1),
        generate::grid(7, 7),
        generate::torus(1.0, 0.4, 10, 6),
    ];
    let (mesh, ranges) = union(&parts);
    let ops = ops(&mesh);
    let n = ops.n();
    let h2 = mean_edge_length(&mesh).powi(2);
    let times: Vec<f64> = [1e-4, 1e-1, 1.0, 1e2].iter().map(|s| s * h2).collect();
    let worst = check_against_reference("components", &ops, &times, &KINDS);
    eprintln!("components: worst error/bound {worst:.2e}");

    let f = test_function(n);
    for kind in KINDS {
        for method in [
            Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
            Method::Fast(KrylovParams::default()),
        ] {
            let params = HeatParams {
                mass: kind,
                method: method.clone(),
            };
            let kernel = HeatKernel::new(&ops, params.clone()).unwrap();
            let alone: Vec<HeatKernel> = parts
                .iter()
                .map(|p| HeatKernel::new(&self::ops(p), params.clone()).unwrap())
                .collect();
            for &t in &times {
                // Columns K_t e_i for one vertex of every component.
                let anchors: Vec<usize> = ranges.iter().map(|r| r.start + r.len() / 2).collect();
                let e = faer::Mat::<f64>::from_fn(n, anchors.len(), |i, j| if i == anchors[j] { 1.0 } else { 0.0 });
                let cols = kernel.apply_many(e.as_ref(), t).unwrap();
                for (j, r) in ranges.iter().enumerate() {
                    let big = (0..n).map(|i| cols[(i, j)].abs()).fold(0.0, f64::max);
                    for i in (0..n).filter(|i| !r.contains(i)) {
                        assert!(
                            cols[(i, j)].abs() <= 1e-14 * big,
                            "{kind:?} {method:?} t={t:e}: K_t[{i}, {}] = {:e} leaks across components",
                            anchors[j],
                            cols[(i, j)]
                        );
                    }
                }
                // Each block is the kernel of the component alone.
                let g = kernel.apply(&f, t).unwrap();
                for (r, k) in ranges.iter().zip(&alone) {
                    let gp = k.apply(&f[r.clone()], t).unwrap();
                    let err = common::rel_err(&g[r.clone()], &gp);
                    assert!(err < 1e-10, "{kind:?} {method:?} t={t:e}: block differs by {err:e}");
                }
                // Mass is conserved per component (piecewise-constant long-time limit).
                let mass = mass_of(&ops, kind);
                let (mg, mf) = (matvec(&mass, &g), matvec(&mass, &f));
                for r in &ranges {
                    let (a, b): (f64, f64) = (mg[r.clone()].iter().sum(), mf[r.clone()].iter().sum());
                    assert!((a - b).abs() <= 1e-11 * b.abs(), "{kind:?} t={t:e}: {a} vs {b}");
                }
            }
        }
    }
    // The eigensolver finds one zero eigenvalue per component.
    let basis = Eigenbasis::partial(&ops.stiffness, &ops.mass, 5, &EigenParams::default()).unwrap();
    let zeros = basis.values.iter().filter(|l| l.abs() < 1e-9).count();
    assert_eq!(zeros, 3, "eigenvalues {:?}", basis.values);
}

/// Open boundaries (grid, graded disk): against the reference, and the Neumann mass
/// conservation `1ᵀM K_t f = 1ᵀM f` for every t and both kernels.
#[test]
fn open_boundaries_conserve_mass() {
    for (label, mesh) in [("grid", generate::grid(16, 16)), ("disk", graded_disk(16, 10, 30.0))] {
        let ops = ops(&mesh);
        let n = ops.n();
        let times = times_relative(&mesh, &[1e-6, 1e-2, 1.0, 1e2, 1e4]);
        let worst = check_against_reference(label, &ops, &times, &KINDS);
        eprintln!("{label}: worst error/bound {worst:.2e}");
        for kind in KINDS {
            let mass = mass_of(&ops, kind);
            for method in [
                Method::rational(shifted_solve::poles::DEFAULT_DEGREE),
                Method::Fast(KrylovParams::default()),
            ] {
                let kernel = HeatKernel::new(
                    &ops,
                    HeatParams {
                        mass: kind,
                        method: method.clone(),
                    },
                )
                .unwrap();
                // Far beyond the reference range too: t = 1e8·h̄² (the constant mode used to
                // drift by 1.6e−5 there before the null space was deflated exactly).
                let long = times_relative(&mesh, &[1e6, 1e8]);
                for f in [test_function(n), unit(n, 0), unit(n, n / 2)] {
                    let total: f64 = matvec(&mass, &f).iter().sum();
                    let mean = total / matvec(&mass, &vec![1.0; n]).iter().sum::<f64>();
                    for &t in &long {
                        let g = kernel.apply(&f, t).unwrap();
                        let dev = g.iter().map(|g| (g - mean).abs()).fold(0.0, f64::max);
                        assert!(
                            dev <= 1e-12 * mean.abs(),
                            "{label} {kind:?} {method:?} t={t:e}: K_t f deviates from its mean by {dev:e}"
                        );
                    }
                    for &t in times.iter().chain(&long) {
                        let g = kernel.apply(&f, t).unwrap();
                        let kept: f64 = matvec(&mass, &g).iter().sum();
                        assert!(
                            (kept - total).abs() <= 1e-13 * total.abs(),
                            "{label} {kind:?} {method:?} t={t:e}: 1ᵀMK_tf = {kept:e} vs 1ᵀMf = {total:e}"
                        );
                    }
                }
            }
        }
    }
}

/// Issue #16: a tiny disjoint component (an icosphere plus a tetrahedron of scale 1e−12, like
/// spot plus a stray 1e−12 tetrahedron). Each component's heat kernel is its own, so the big
/// component's K_t f must equal the kernel of the big component alone, and the tiny one (all of
/// whose non-constant modes have λ ≈ 1e24) must hold its M-mean. Every method either gets this
/// right or refuses with a typed error that is not a false "L is not positive semidefinite".
#[test]
fn issue_16_tiny_disjoint_component() {
    let big = generate::icosphere(2).with_area(4.0 * std::f64::consts::PI).unwrap();
    let (mut positions, mut faces) = big.clone().into_parts();
    let nb = positions.len() as u32;
    let s = 1e-12;
    for p in [[5.0, 0.0, 0.0], [5.0 + s, 0.0, 0.0], [5.0, s, 0.0], [5.0, 0.0, s]] {
        positions.push(p);
    }
    for f in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
        faces.push([nb + f[0], nb + f[1], nb + f[2]]);
    }
    let mesh = mesh_fem::TriMesh::new(positions, faces).unwrap();
    let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
    let big_ops = assemble(&big, &AssemblyParams::default()).unwrap();
    let n = mesh.n_vertices();
    let nb = nb as usize;
    let f: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|p| p[1] + 0.3 * p[2] + p[0] * p[0])
        .collect();
    let t = 0.05;
    let reference = HeatKernel::new(
        &big_ops,
        HeatParams {
            method: Method::Dense,
            ..Default::default()
        },
    )
    .unwrap()
    .apply(&f[..nb], t)
    .unwrap();
    let tiny_mass: Vec<f64> = {
        let b1 = matvec(&ops.mass, &vec![1.0; n]);
        b1[nb..].to_vec()
    };
    let tiny_mean = f[nb..].iter().zip(&tiny_mass).map(|(a, b)| a * b).sum::<f64>() / tiny_mass.iter().sum::<f64>();
    for (name, method) in [
        ("fast", Method::fast()),
        ("rational", Method::rational(shifted_solve::poles::DEFAULT_DEGREE)),
        ("rational r=7", Method::rational(7)),
        ("dense", Method::Dense),
        ("spectral", Method::spectral(60)),
    ] {
        let kernel = HeatKernel::new(
            &ops,
            HeatParams {
                method,
                ..Default::default()
            },
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        let g = kernel.apply(&f, t).unwrap_or_else(|e| panic!("{name}: {e}"));
        let err = rel_err(&g[..nb], &reference);
        // E_7 ≈ 9.3⁻⁷ ≈ 1.6e−7 is the degree-7 approximant's own error.
        let tol = match name {
            "spectral" => 1e-4,
            "rational r=7" => 1e-6,
            _ => 1e-9,
        };
        assert!(err < tol, "{name}: big component error {err:e}");
        for (i, v) in g[nb..].iter().enumerate() {
            assert!(
                (v - tiny_mean).abs() < 1e-9 * tiny_mean.abs(),
                "{name}: tiny vertex {i}: {v} vs {tiny_mean}"
            );
        }
    }
}

/// Issue #16: at huge t the kernel is the projection onto the constants for every kernel and
/// method (the lumped kernel was 94× off at t = 1e16 and the HKS 0 at t = 1e300, because the
/// constant mode's eigenvalue came out as rounding noise instead of 0). The eigensolvers now
/// return λ₁ = 0 exactly for a Neumann Laplacian.
#[test]
fn issue_16_huge_times_give_the_mean() {
    let mesh = generate::irregular_sphere(2, 5.6)
        .with_area(4.0 * std::f64::consts::PI)
        .unwrap();
    let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
    let n = ops.n();
    let f: Vec<f64> = mesh
        .positions()
        .iter()
        .map(|p| p[0] + 2.0 * p[1] * p[2] + 3.0)
        .collect();
    for kind in [Mass::Consistent, Mass::Lumped(Default::default()), Mass::Identity] {
        let mass = match kind {
            Mass::Consistent => ops.mass.clone(),
            Mass::Lumped(_) => ops.lumped_mass(),
            Mass::Identity => ops.identity_mass(),
        };
        let m1 = matvec(&mass, &vec![1.0; n]);
        let mean = f.iter().zip(&m1).map(|(a, b)| a * b).sum::<f64>() / m1.iter().sum::<f64>();
        for method in [
            Method::Dense,
            Method::spectral(20),
            Method::fast(),
            Method::rational(16),
        ] {
            let kernel = HeatKernel::new(
                &ops,
                HeatParams {
                    mass: kind,
                    method: method.clone(),
                },
            )
            .unwrap();
            if let Some(basis) = kernel.eigenbasis() {
                assert_eq!(basis.values[0], 0.0, "{kind:?} {method:?}");
            }
            for t in [1e16, 1e300] {
                let g = kernel.apply(&f, t).unwrap();
                for v in &g {
                    assert!(
                        (v - mean).abs() <= 1e-12 * mean.abs(),
                        "{kind:?} {method:?} t={t}: {v} vs {mean}"
                    );
                }
            }
        }
    }
}

/// Issue #16: the kernel is scale covariant, K_t(αM) = K_{α⁻²t}(M) (paper, Sect. 5), and every
/// method and backend must honour it on meshes scaled by 1e150 (t = 1e298; the LDLᵀ returned
/// the t → ∞ constant there) and 1e−78 (t = 1e−158; the LDLᵀ lost accuracy, then refused).
#[test]
fn issue_16_scaled_meshes_for_every_backend() {
    let base = generate::icosphere(2).with_area(4.0 * std::f64::consts::PI).unwrap();
    let base_ops = assemble(&base, &AssemblyParams::default()).unwrap();
    let f: Vec<f64> = base.positions().iter().map(|p| p[0] + p[1] * p[2]).collect();
    let t0 = 0.01;
    let reference = HeatKernel::new(
        &base_ops,
        HeatParams {
            method: Method::Dense,
            ..Default::default()
        },
    )
    .unwrap()
    .apply(&f, t0)
    .unwrap();
    for alpha in [1e150, 1e-78] {
        let mesh = base.scaled(alpha).unwrap();
        let ops = assemble(&mesh, &AssemblyParams::default()).unwrap();
        let t = t0 * alpha * alpha;
        let mut methods: Vec<(String, Method)> = <shifted_solve::backend::Backend as wfem_base::Choice>::names()
            .map(|name| {
                (
                    format!("rational/{name}"),
                    Method::Rational {
                        degree: 16,
                        backend: <shifted_solve::backend::Backend as wfem_base::Choice>::parse(name).unwrap(),
                    },
                )
            })
            .collect();
        methods.push(("fast".into(), Method::fast()));
        methods.push(("dense".into(), Method::Dense));
        for (name, method) in methods {
            let kernel = HeatKernel::new(
                &ops,
                HeatParams {
                    method,
                    ..Default::default()
                },
            )
            .unwrap_or_else(|e| panic!("α = {alpha:e} {name}: {e}"));
            let g = kernel
                .apply(&f, t)
                .unwrap_or_else(|e| panic!("α = {alpha:e} {name}: {e}"));
            let err = rel_err(&g, &reference);
            assert!(err < 1e-10, "α = {alpha:e} {name}: {err:e}");
        }
    }
}

/// A lattice of flat obtuse triangles (every row at height `h` over the previous, odd rows
/// shifted by 1/2): every angle is within about 2h of 0 or π.
fn obtuse_lattice(h: f64) -> TriMesh {
    let (m, r) = (10, 6);
    let mut p = Vec::new();
    for j in 0..r {
        for i in 0..m {
            p.push([i as f64 + 0.5 * (j % 2) as f64, j as f64 * h, 0.0]);
        }
    }
    let mut f = Vec::new();
    for j in 0..r - 1 {
        for i in 0..m - 1 {
            let a = (j * m + i) as u32;
            let (b, c) = (a + 1, a + m as u32);
            let d = c + 1;
            if j % 2 == 0 {
                f.extend([[a, b, c], [b, d, c]]);
            } else {
                f.extend([[a, b, d], [a, d, c]]);
            }
        }
    }
    TriMesh::new(p, f).unwrap()
}

/// Issue #16: near-degenerate meshes either give the right answer or are refused, naming a
/// vertex. On the obtuse lattice a 60-digit evaluation of the same double-precision matrices
/// (a 60-digit reference, recorded in `Conditioning`'s docs) gave 1e−9 errors at h = 1e−4,
/// 3e−4 at h = 1e−7 and 91 % at h = 1e−10 (the assembled L is indefinite there) for every
/// method; before, h = 1e−10 returned values of ±4.7e268 (dense) or disagreeing answers.
#[test]
fn issue_16_near_degenerate_meshes_are_refused_or_right() {
    for h in [1e-7, 1e-10] {
        let ops = assemble(&obtuse_lattice(h), &AssemblyParams::default()).unwrap();
        for method in [Method::fast(), Method::Dense, Method::rational(16)] {
            let err = HeatKernel::new(
                &ops,
                HeatParams {
                    method: method.clone(),
                    ..Default::default()
                },
            )
            .unwrap_err();
            match err {
                wfem_heat::HeatError::IllConditionedMesh {
                    vertex,
                    estimated_error,
                    ..
                } => {
                    assert!(vertex < ops.n() && estimated_error > wfem_heat::MAX_ROUNDING_ERROR);
                    assert!(err.to_string().contains(&format!("vertex {vertex}")), "{err}");
                }
                other => panic!("h = {h} {method:?}: {other}"),
            }
        }
    }
    // Mild: accepted, the methods agree, and the estimate says what to expect.
    let ops = assemble(&obtuse_lattice(1e-4), &AssemblyParams::default()).unwrap();
    let f: Vec<f64> = (0..ops.n()).map(|i| (i % 7) as f64).collect();
    let fast = HeatKernel::new(&ops, HeatParams::default()).unwrap();
    let dense = HeatKernel::new(
        &ops,
        HeatParams {
            method: Method::Dense,
            ..Default::default()
        },
    )
    .unwrap();
    let est = fast.rounding_error();
    assert!(est > 1e-10 && est < 1e-6, "{est:e}");
    let err = rel_err(&fast.apply(&f, 0.05).unwrap(), &dense.apply(&f, 0.05).unwrap());
    assert!(err < 100.0 * est, "{err:e} vs estimate {est:e}");
    // A well-shaped mesh is far from it.
    let sphere = assemble(&generate::irregular_sphere(3, 5.6), &AssemblyParams::default()).unwrap();
    let k = HeatKernel::new(&sphere, HeatParams::default()).unwrap();
    assert!(k.rounding_error() < 1e-12, "{:e}", k.rounding_error());
}
