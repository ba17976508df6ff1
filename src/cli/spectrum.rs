//! `wfem spectrum`: the eigenvalue spectrum of a surface or a solid and its global signature
//! (Shape-DNA, Reuter et al. 2006; shape_retrieval::global, one orchestration for both).

use super::choice::choice;
use super::output::OutputFormat;
use super::{limits, progress, read_usable, CliError, MassArgs, MeshArgs, Output};
use clap::Args;
use mesh_fem::io::{stage_columns, AtomicSet, FieldFormat};
use serde_json::json;
use shape_retrieval::global::{operators_signature, GlobalKind, Measure, DEFAULT_EIGENVALUES};
use std::io::Write;
use wfem_base::Choice;

/// Arguments of `wfem spectrum`.
#[derive(Args, Clone, Debug)]
pub struct SpectrumArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Number m of eigenvalues λ₁ … λ_m (the zero one not counted); at most n − 1, and at
    /// most n/10 above 5000 vertices.
    #[arg(long, short = 'm', default_value_t = DEFAULT_EIGENVALUES)]
    pub eigenvalues: usize,
    /// The signature written beside the eigenvalues; each is scale invariant with the area of a
    /// surface or the volume of a solid (Weyl's law in 2-D or 3-D).
    #[arg(long, value_parser = choice::<GlobalKind>(), default_value = GlobalKind::WeylShapeDna.name())]
    pub kind: GlobalKind,
    /// The kernel, by its mass (consistent: the wFEM spectrum of (L, B)).
    #[command(flatten)]
    #[allow(missing_docs)]
    pub mass: MassArgs,
    /// Output: .csv or .npy (+ .json sidecar with the eigenvalues, the measure and the kind).
    /// Columns: the eigenvalue λ_i and the signature g_i, i = 1 … m; for a signature of another
    /// length (a histogram) the signature alone.
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
}

/// `wfem spectrum` (validate → eigenpairs → signature → write).
pub fn spectrum(args: &SpectrumArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let format = match args.output.format {
        OutputFormat::Field(f @ (FieldFormat::Npy | FieldFormat::Csv)) => f,
        _ => {
            return Err(CliError::Usage(format!(
                "cannot write {}: a spectrum is a table of numbers, written as .{} or .{}",
                args.output.path.display(),
                FieldFormat::Csv.name(),
                FieldFormat::Npy.name()
            )))
        }
    };
    args.output.check(Some(&[]), 1, &[&args.input.mesh])?;
    let mass = args.mass.mass()?;
    let input = read_usable(&args.input)?;
    let n = input.mesh.n_vertices();
    // As for --eigenpairs elsewhere: the partial eigensolver slows down sharply beyond n/10.
    let (hi, why) = if n > wfem_heat::spectral::DENSE_MAX_VERTICES {
        (
            n / limits::SPECTRAL_FRACTION - 1,
            "number of nonzero eigenvalues, at most n/10 − 1 on a large mesh",
        )
    } else {
        (n.saturating_sub(1), "number of nonzero eigenvalues, at most n − 1")
    };
    let m = limits::count("--eigenvalues", args.eigenvalues, 1, hi.max(1), why)?;
    let fem = progress::run("assembling L, B, D", || input.assemble(mass.lumping()))?;
    // The measure is the geometry's (1ᵀD1: the area or the volume), whatever the kernel's mass.
    let total: f64 = fem.lumped_diagonal.iter().sum();
    let measure = match input.volume {
        Some(_) => Measure::Volume(total),
        None => Measure::Area(total),
    };
    let ops = wfem_heat::Operators::new(&fem, mass)?;
    let sig = progress::run(format!("{} eigenpairs", m + 1), || {
        operators_signature(&ops, args.kind, m, measure)
    })
    .map_err(super::hks::retrieval)?;
    let lambdas = &sig.eigenvalues[1..];
    let kind = args.kind.name();
    let mut fields: Vec<(&str, &[f64])> = Vec::new();
    if sig.signature.len() == lambdas.len() {
        fields.push(("eigenvalue", lambdas));
    }
    fields.push((kind, &sig.signature));
    let mut set = AtomicSet::new();
    stage_columns(&mut set, &args.output.path, format, sig.signature.len(), &fields)?;
    let (measure_name, measure_value) = (measure.quantity(), measure.value());
    if let Some(sidecar) = args.output.sidecar() {
        let mut meta = serde_json::Map::new();
        meta.insert("command".into(), json!("spectrum"));
        meta.insert("input".into(), input.meta(&args.input.mesh));
        meta.insert("mass".into(), json!(mass.name()));
        meta.insert("kind".into(), json!(kind));
        meta.insert("dimension".into(), json!(measure.dimension()));
        meta.insert(measure_name.into(), json!(measure_value));
        meta.insert("eigenvalues".into(), json!(sig.eigenvalues));
        let names: Vec<&str> = fields.iter().map(|(name, _)| *name).collect();
        let text = super::output::npy_sidecar(&args.output, sig.signature.len(), &names, meta)?;
        set.stage(&sidecar, |w| w.write_all(text.as_bytes()))?;
    }
    let written: Vec<std::path::PathBuf> = set.targets().map(std::path::Path::to_path_buf).collect();
    set.commit()?;
    for path in written {
        writeln!(out, "wrote {}", path.display())?;
    }
    let head: Vec<String> = sig.signature.iter().take(5).map(|g| format!("{g:.4}")).collect();
    writeln!(
        out,
        "{kind} of {} ({} {measure_value:.6e}, {} mass): {} values, the first {}{}; λ₁ = {:.6e}",
        input.name,
        measure_name,
        mass.name(),
        sig.signature.len(),
        head.join(", "),
        if sig.signature.len() > head.len() { ", …" } else { "" },
        lambdas[0],
    )?;
    Ok(())
}
