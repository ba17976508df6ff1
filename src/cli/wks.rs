//! `wfem wks`: the wave kernel signature of a mesh or point cloud (Aubry et al. 2011; pyFM's
//! energies), on the eigenpairs of the chosen kernel.

use super::output::{write_fields, Column, RenderArgs, Writing};
use super::{limits, progress, read_usable, CliError, MassArgs, MeshArgs, Output};
use clap::Args;
use serde_json::json;
use shape_retrieval::hks::Spectrum;
use shape_retrieval::wks::{wave_kernel_signature, DEFAULT_ENERGIES};
use std::io::Write;
use wfem_base::Choice;

/// Arguments of `wfem wks`.
#[derive(Args, Clone, Debug)]
pub struct WksArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Number N of energies, log λ from the first nonzero eigenvalue to the largest, trimmed by
    /// 2σ at both ends (σ = 7·range/N: pyFM's and geomfum's grid); one output column each.
    #[arg(long, default_value_t = DEFAULT_ENERGIES)]
    pub energies: usize,
    /// The kernel, by its mass (consistent: the wFEM kernel; barycentric: pyFM's spectrum).
    #[command(flatten)]
    #[allow(missing_docs)]
    pub mass: MassArgs,
    /// Number k of eigenpairs; default min(100, n), at most n/10 above 5000 vertices.
    #[arg(long = "eigenpairs", alias = "eigs")]
    pub eigenpairs: Option<usize>,
    /// Output: .npy (n × N, + .json sidecar with the energies), .csv, .ply or .png (one figure
    /// per energy, at most 64).
    #[arg(short = 'o', long = "output", value_parser = Output::parse)]
    pub output: Output,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub render: RenderArgs,
}

/// `wfem wks` (validate → compute → write).
pub fn wks(args: &WksArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let count = limits::count(
        "--energies",
        args.energies,
        1,
        limits::MAX_TIMES,
        "number of energies (output columns)",
    )?;
    let suffixes: Vec<String> = (0..count).map(|j| format!("e{j}")).collect();
    args.output.check(Some(&suffixes), count, &[&args.input.mesh])?;
    let mass = args.mass.mass()?;
    let input = read_usable(&args.input)?;
    let n = input.mesh.n_vertices();
    let k = limits::descriptor_eigenpairs(
        args.eigenpairs
            .unwrap_or(shape_retrieval::descriptor::DEFAULT_EIGENPAIRS.min(n)),
        n,
    )?;
    limits::columns("--energies", count, n)?;
    let fem = progress::run("assembling L, B, D", || input.assemble(mass.lumping()))?;
    let ops = wfem_heat::Operators::new(&fem, mass)?;
    let basis = progress::run(format!("{k} eigenpairs"), || {
        shape_retrieval::descriptor::smallest_eigenpairs(&ops, k, &Default::default())
    })
    .map_err(super::hks::retrieval)?;
    let sig = progress::run("signature", || {
        Spectrum::new(&basis.values, basis.vectors.as_ref()).and_then(|s| wave_kernel_signature(&s, count))
    })
    .map_err(super::hks::retrieval)?;
    let columns: Vec<Column> = sig
        .energies
        .energies
        .iter()
        .enumerate()
        .map(|(j, e)| Column {
            name: format!("wks_e{j}"),
            suffix: format!("e{j}"),
            title: format!("{}: WKS, log-energy {e:.3} ({} mass, k = {k})", input.name, mass.name()),
            t: None,
            values: sig.values.col(j).iter().copied().collect(),
        })
        .collect();
    let mut meta = serde_json::Map::new();
    meta.insert("command".into(), json!("wks"));
    meta.insert("input".into(), input.meta(&args.input.mesh));
    meta.insert("mass".into(), json!(mass.name()));
    meta.insert("eigenpairs".into(), json!(k));
    meta.insert("energies".into(), json!(sig.energies.energies));
    meta.insert("sigma".into(), json!(sig.energies.sigma));
    meta.insert("eigenvalues".into(), json!(basis.values));
    let how = Writing {
        render: args.render,
        splats: input.splats.as_ref(),
        highlight: &[],
        meta,
        allow_infinity: false,
        volume: input.volume.as_ref().map(|v| &v.mesh),
    };
    for path in write_fields(&args.output, &input.mesh, &columns, how)? {
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}
