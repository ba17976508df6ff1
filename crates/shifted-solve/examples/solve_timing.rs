//! One-shot wall-clock timing of r_16(t B⁻¹L) f (all 8 poles, factorization included) on an
//! icosphere, for both backends; optionally dumps L and B as `i j v` triplet text files for
//! `tools/scipy_reference.py` (the scipy/SuperLU comparison in docs/BENCHMARKS.md).
//!
//! Run: `cargo run --release -p shifted-solve --example solve_timing -- 6 [--dump /tmp]`

use faer::Mat;
use shifted_solve::backend::Backend;
use shifted_solve::iterative::MinresParams;
use shifted_solve::poles::RationalApprox;
use shifted_solve::ShiftedSolver;
use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let level: u32 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let mesh = mesh_fem::generate::icosphere(level);
    let ops = mesh_fem::assemble(&mesh, &mesh_fem::AssemblyParams::default())?;
    let (l, b) = (ops.stiffness, ops.mass);
    if let Some(pos) = args.iter().position(|a| a == "--dump") {
        let dir = args.get(pos + 1).ok_or("--dump needs a directory")?;
        for (name, m) in [("L", &l), ("B", &b)] {
            let mut f = std::io::BufWriter::new(std::fs::File::create(format!("{dir}/solve_{name}{level}.txt"))?);
            for j in 0..m.ncols() {
                for (&i, &v) in m.symbolic().row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
                    writeln!(f, "{i} {j} {v:.17e}")?;
                }
            }
        }
    }
    let n = l.nrows();
    let f = Mat::<f64>::from_fn(n, 1, |i, _| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5);
    let approx = RationalApprox::cram(16)?;
    for (name, backend) in [
        ("direct_lu", Backend::DirectLu),
        ("direct_ldlt", Backend::DirectLdlt),
        ("minres_s=|z|", Backend::Minres(MinresParams::default())),
    ] {
        let solver = ShiftedSolver::new(l.as_ref(), b.as_ref(), backend)?;
        let start = std::time::Instant::now();
        let (_, report) = solver.apply(approx, 0.01, f.as_ref())?;
        println!(
            "n={n} {name}: all 8 poles deg16 1 rhs (incl. factorization): {:.3} s, iterations {}, max residual {:.1e}",
            start.elapsed().as_secs_f64(),
            report.total_iterations(),
            report.max_relative_residual()
        );
    }
    Ok(())
}
