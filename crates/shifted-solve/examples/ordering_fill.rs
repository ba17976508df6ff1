//! Fill and cost of the real Cholesky of the pencil M + tL with faer's AMD ordering against our
//! nested dissection (`shifted_solve::ordering`), and the analysis `CholeskyPattern` keeps:
//! n, factor entries and flops predicted from the column counts, the ordering and symbolic
//! analysis times and one numeric factorization each (faer's global parallelism, as the fast
//! path factors).
//!
//! Run: `cargo run --release -p shifted-solve --example ordering_fill -- FILE [refinements]`
//! for a tetrahedral mesh (e.g. `../shared/data/volumes/flip-free-parametrization/armadillo.mesh 1`:
//! 121K vertices), or `-- sphere LEVEL` for an icosphere surface (6: 40,962 vertices;
//! 8: 655,362). t = 1e-3·V^(2/3) on volumes, 0.01 on the sphere of area 4π. The environment
//! variables `ND_LEAF` and `ND_MAX_SIDE` override [`NdParams`] for the ND row.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMat, SymbolicSparseColMatRef, Triplet};
use faer::Side;
use mesh_fem::AssemblyParams;
use shifted_solve::ordering::{
    fill_stats, nested_dissection, symbolic_stats, work_unit, FillStats, NdParams, Permutation, ND_MIN_N,
    ND_MIN_WORK_RATIO,
};
use shifted_solve::CholeskyPattern;

type Matrix = SparseColMat<usize, f64>;

fn pencil(args: &[String]) -> Result<(String, Matrix), Box<dyn std::error::Error>> {
    let first = args.first().map_or("sphere", String::as_str);
    let count: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(0);
    let (name, ops, t) = if first == "sphere" {
        let level = u32::try_from(count)?;
        let mesh = mesh_fem::generate::icosphere(level).with_area(4.0 * std::f64::consts::PI)?;
        let ops = mesh_fem::assemble(&mesh, &AssemblyParams::default())?;
        (format!("icosphere level {level}"), ops, 0.01)
    } else {
        let mut mesh = mesh_fem::io::volume::read_volume(std::path::Path::new(first))?.mesh;
        for _ in 0..count {
            mesh = mesh.refined();
        }
        let ops = mesh_fem::volume::assemble_volume(&mesh, &AssemblyParams::default())?;
        let volume: f64 = ops.mass.val().iter().sum();
        let stem = std::path::Path::new(first)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned());
        (
            format!("{} ×{count} refined", stem.unwrap_or_default()),
            ops,
            1e-3 * volume.powf(2.0 / 3.0),
        )
    };
    let n = ops.stiffness.nrows();
    let trip: Vec<_> = ops
        .stiffness
        .triplet_iter()
        .map(|e| Triplet::new(e.row, e.col, t * *e.val))
        .chain(ops.mass.triplet_iter().map(|e| Triplet::new(e.row, e.col, *e.val)))
        .collect();
    Ok((name, SparseColMat::try_new_from_triplets(n, n, &trip)?))
}

fn supernodal_params() -> CholeskySymbolicParams<'static> {
    CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    }
}

/// Seconds of one numeric factorization on the analysis.
fn numeric(symbolic: &SymbolicCholesky<usize>, a: &Matrix) -> f64 {
    let par = faer::get_global_parallelism();
    let mut values = vec![0.0; symbolic.len_val()];
    let mut buf = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    let start = Instant::now();
    symbolic
        .factorize_numeric_llt(
            &mut values,
            a.as_ref(),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut buf),
            Default::default(),
        )
        .expect("the pencil is positive definite");
    start.elapsed().as_secs_f64()
}

fn row(
    name: &str,
    n: usize,
    ordering: &str,
    stats: FillStats,
    analysis_s: f64,
    symbolic: &SymbolicCholesky<usize>,
    a: &Matrix,
) {
    let num_s = numeric(symbolic, a);
    println!(
        "| {name} | {n} | {ordering} | {:.2}M | {:.2}M | {:.2} G | {analysis_s:.3} | {num_s:.3} |",
        stats.entries as f64 / 1e6,
        symbolic.len_val() as f64 / 1e6,
        stats.flops / 1e9,
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (name, a) = pencil(&args)?;
    let n = a.nrows();
    let pattern: SymbolicSparseColMatRef<'_, usize> = a.symbolic();
    println!("{name}: n = {n}, nnz(M + tL) = {}", pattern.compute_nnz());
    println!("| mesh | n | ordering | L entries (counts) | L stored (supernodal) | flops Σc² | ordering + symbolic (s) | numeric (s) |");
    println!("|---|---:|---|---:|---:|---:|---:|---:|");

    let mut params = NdParams::default();
    if let Ok(v) = std::env::var("ND_LEAF") {
        params.leaf_size = v.parse()?;
    }
    if let Ok(v) = std::env::var("ND_MAX_SIDE") {
        params.max_side = v.parse()?;
    }
    if std::env::var_os("AMD_SPLIT").is_some() {
        let n = pattern.nrows();
        let start = Instant::now();
        let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
        let mut buf = MemBuffer::new(faer::sparse::linalg::amd::order_scratch::<usize>(
            n,
            pattern.compute_nnz(),
        ));
        let flops =
            faer::sparse::linalg::amd::order(&mut fwd, &mut inv, pattern, Default::default(), MemStack::new(&mut buf))?;
        let t_order = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let perm = PermRef::new_checked(&fwd, &inv, n);
        let _sym = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Custom(perm),
            supernodal_params(),
        )?;
        let t_sym = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let _amd = factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, supernodal_params())?;
        println!(
            "AMD order {t_order:.3} s (flops {:.3e}), symbolic on it {t_sym:.3} s; faer Amd symbolic {:.3} s",
            flops.n_mult_subs_ldl,
            start.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    if std::env::var_os("ND_ONLY").is_some() {
        let start = Instant::now();
        let perm = nested_dissection(pattern, params).expect("square");
        let stats = fill_stats(pattern, &perm);
        println!("ND only: {:.3} s, {stats:?}", start.elapsed().as_secs_f64());
        return Ok(());
    }
    let start = Instant::now();
    let amd = factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, supernodal_params())?;
    let amd_s = start.elapsed().as_secs_f64();
    let amd_perm = amd.perm().map(|p| {
        let (fwd, inv) = p.arrays();
        Permutation {
            fwd: fwd.to_vec(),
            inv: inv.to_vec(),
        }
    });
    let amd_stats = fill_stats(pattern, amd_perm.as_ref().expect("AMD permutes"));
    row(&name, n, "AMD", amd_stats, amd_s, &amd, &a);
    let structure = symbolic_stats(&amd);
    println!(
        "(AMD: {:.0} flops per unit nnz·log₂n, {:.1} entries per entry of the lower triangle of M + tL; ND is tried from {ND_MIN_N} rows and {ND_MIN_WORK_RATIO} flops per unit)",
        structure.flops / work_unit(pattern),
        structure.entries as f64 / ((pattern.compute_nnz() + n) / 2) as f64
    );
    drop(amd);

    let start = Instant::now();
    let perm = nested_dissection(pattern, params).expect("square");
    let order_s = start.elapsed().as_secs_f64();
    let nd = factorize_symbolic_cholesky(
        pattern,
        Side::Lower,
        SymmetricOrdering::Custom(PermRef::new_checked(&perm.fwd, &perm.inv, n)),
        supernodal_params(),
    )?;
    let nd_s = start.elapsed().as_secs_f64();
    let nd_stats = fill_stats(pattern, &perm);
    row(&name, n, "ND", nd_stats, nd_s, &nd, &a);
    drop(nd);
    println!("(ND ordering alone: {order_s:.3} s)");

    let start = Instant::now();
    let chosen = CholeskyPattern::supernodal(pattern)?;
    let analysis_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let factor = chosen.factor(a.as_ref(), faer::get_global_parallelism())?;
    let factor_s = start.elapsed().as_secs_f64();
    println!(
        "CholeskyPattern::supernodal keeps {:?}: analysis (both orderings, the choice) {analysis_s:.3} s, factor {factor_s:.3} s, {:.2}M values; ND/AMD: entries {:.3}, flops {:.3}",
        chosen.ordering(),
        factor.n_values() as f64 / 1e6,
        nd_stats.entries as f64 / amd_stats.entries as f64,
        nd_stats.flops / amd_stats.flops,
    );
    Ok(())
}
