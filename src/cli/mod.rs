//! The `wfem` command-line tool, as a library module so that it can be tested.
//!
//! Every subcommand reads its input read-only, writes its outputs atomically (temporary file
//! in the same directory, then rename; see [`mesh_fem::io::write_atomic`]) and refuses to write
//! over its input. Output formats are chosen by extension: `.ply` (mesh with named float
//! vertex properties and vertex colors), `.npy`, `.csv`, and `.png` (a rendered figure).

mod approx;
mod distance;
mod heat;
pub use distance::{distance, DistanceArgs, DistanceKindArg};
pub mod hks;
pub mod retrieval;

pub use approx::{approx, ApproxArgs, CoefficientsArg};
pub use heat::{demo, heat, DemoArgs, HeatArgs, KernelArg, MethodArg};

use crate::render::{render_png, symmetric_range, Colormap, RenderError, RenderParams};
use clap::{Args, ValueEnum};
use mesh_fem::io::{load, write_atomic, write_field, LoadOptions};
use mesh_fem::{assemble, AssemblyParams, LumpedMassKind, MeshError, TriMesh};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Failures of the CLI: printed as one line `wfem: error: …`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CliError {
    /// Mesh reading, validation, assembly or writing.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Heat kernel evaluation.
    #[error(transparent)]
    Heat(#[from] wfem_heat::HeatError),
    /// Descriptors, vocabularies, indexes and their files.
    #[error(transparent)]
    Retrieval(#[from] shape_retrieval::RetrievalError),
    /// Rendering a PNG.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Arguments that do not fit together.
    #[error("{0}")]
    Usage(String),
    /// Writing to the terminal failed.
    #[error("cannot write to standard output: {0}")]
    Stdout(#[from] std::io::Error),
}

/// The mesh argument shared by every subcommand that reads a mesh.
#[derive(Args, Clone, Debug, Default)]
pub struct MeshArgs {
    /// Mesh file (.obj, .ply, .off, .stl).
    pub mesh: PathBuf,
    /// Fan-triangulate polygons with more than three corners instead of refusing them.
    #[arg(long)]
    pub triangulate: bool,
}

impl MeshArgs {
    /// Loads the mesh (read-only).
    pub fn load(&self) -> Result<TriMesh, CliError> {
        let (mesh, _) = load(&self.mesh, &LoadOptions::with_triangulation(self.triangulate))?;
        Ok(mesh)
    }
}

/// Loads and validates a mesh; a mesh with a fatal problem is refused with the error naming it.
pub(crate) fn load_usable(args: &MeshArgs) -> Result<TriMesh, CliError> {
    let mesh = args.load()?;
    mesh_fem::validate(&mesh).into_result()?;
    Ok(mesh)
}

/// Refuses an output path that is the input file.
pub(crate) fn check_output(input: &Path, output: &Path) -> Result<(), CliError> {
    if let (Ok(a), Ok(b)) = (input.canonicalize(), output.canonicalize()) {
        if a == b {
            return Err(CliError::Usage(format!(
                "output {} is the input file; wfem never writes over its input",
                output.display()
            )));
        }
    }
    Ok(())
}

/// Writes per-vertex fields by the extension of `path`. For `.png` every field becomes its own
/// figure: `path` itself for one field, `stem-<name>.png` beside it for several. For `.ply` the
/// vertex colors show the first field.
pub fn write_fields(
    path: &Path,
    mesh: &TriMesh,
    fields: &[(String, Vec<f64>)],
    highlight: &[u32],
) -> Result<Vec<PathBuf>, CliError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if fields.is_empty() {
        return Err(CliError::Usage("nothing to write".into()));
    }
    if ext == "png" {
        // Render every figure first, then write the set all-or-nothing (`write_set`).
        let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::with_capacity(fields.len());
        for (name, values) in fields {
            let target = if fields.len() == 1 {
                path.to_path_buf()
            } else {
                let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("field");
                let safe: String = name
                    .chars()
                    .map(|c| {
                        if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                            c
                        } else {
                            '_'
                        }
                    })
                    .collect();
                path.with_file_name(format!("{stem}-{safe}.png"))
            };
            let png = render_png(mesh, values, &figure_params(name, values, highlight))?;
            files.push((target, png));
        }
        write_set(&files)?;
        return Ok(files.into_iter().map(|(p, _)| p).collect());
    }
    let refs: Vec<(&str, &[f64])> = fields.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
    let colors = if ext == "ply" {
        Some(colors_of(&fields[0].1))
    } else {
        None
    };
    write_field(path, mesh, &refs, colors.as_deref())?;
    Ok(vec![path.to_path_buf()])
}

/// Writes several files all-or-nothing: each is first written atomically
/// ([`write_atomic`]) under a hidden staging name `.NAME.staged-PID` beside its target; only
/// when all are written (and no target is a directory) are they renamed onto their targets.
/// On failure the staged files are removed and no target has changed.
pub(crate) fn write_set(files: &[(PathBuf, Vec<u8>)]) -> Result<(), CliError> {
    let staged_name = |target: &Path| -> PathBuf {
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        target.with_file_name(format!(".{name}.staged-{}", std::process::id()))
    };
    let remove = |upto: usize| {
        for (target, _) in &files[..upto] {
            let _ = std::fs::remove_file(staged_name(target));
        }
    };
    if files.len() == 1 {
        let (target, bytes) = &files[0];
        return Ok(write_atomic(target, |w| w.write_all(bytes))?);
    }
    for (k, (target, bytes)) in files.iter().enumerate() {
        if target.is_dir() {
            remove(k);
            return Err(MeshError::Io {
                path: target.clone(),
                source: std::io::Error::new(std::io::ErrorKind::IsADirectory, "the output path is a directory"),
            }
            .into());
        }
        if let Err(e) = write_atomic(&staged_name(target), |w| w.write_all(bytes)) {
            remove(k);
            return Err(match e {
                // Name the file the user asked for, not the staging name.
                MeshError::Io { source, .. } => MeshError::Io {
                    path: target.clone(),
                    source,
                },
                other => other,
            }
            .into());
        }
    }
    for (k, (target, _)) in files.iter().enumerate() {
        if let Err(source) = std::fs::rename(staged_name(target), target) {
            for (t, _) in &files[k..] {
                let _ = std::fs::remove_file(staged_name(t));
            }
            return Err(MeshError::Io {
                path: target.clone(),
                source,
            }
            .into());
        }
    }
    Ok(())
}

/// Render parameters for a field: Viridis for one-signed fields, Coolwarm centred on zero for
/// fields that change sign.
pub(crate) fn figure_params(title: &str, values: &[f64], highlight: &[u32]) -> RenderParams {
    // A diverging map centred on zero when the field really changes sign; a field with only
    // round-off-sized negative values (e.g. K_t e_i of the wFEM kernel) keeps Viridis over its
    // true range.
    let (lo, hi) = values.iter().fold((0.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
    let signed = lo < 0.0 && hi > 0.0 && (-lo).min(hi) > 1e-2 * (-lo).max(hi);
    RenderParams {
        title: Some(title.to_string()),
        highlight: highlight.to_vec(),
        colormap: if signed { Colormap::Coolwarm } else { Colormap::Viridis },
        range: if signed { symmetric_range(values) } else { None },
        ..RenderParams::default()
    }
}

/// Vertex colors of a field through Viridis over its range.
fn colors_of(values: &[f64]) -> Vec<[u8; 3]> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    values.iter().map(|&v| Colormap::Viridis.map((v - lo) / span)).collect()
}

// ---------------------------------------------------------------------------------------------
// wfem info

/// Arguments of `wfem info`.
#[derive(Args, Clone, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// `wfem info`: statistics and the validation report of a mesh.
pub fn info(args: &InfoArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let (mesh, load_report) = load(
        &args.input.mesh,
        &LoadOptions::with_triangulation(args.input.triangulate),
    )?;
    let stats = mesh_fem::stats::stats(&mesh);
    let report = mesh_fem::validate(&mesh);
    if args.json {
        let value = serde_json::json!({
            "file": args.input.mesh.display().to_string(),
            "format": format!("{:?}", load_report.format),
            "welded_vertices": load_report.welded_vertices,
            "triangulated_polygons": load_report.triangulated_polygons,
            "load_notes": load_report.notes,
            "stats": stats,
            "usable": report.is_usable(),
            "errors": report.errors().map(|p| p.to_string()).collect::<Vec<_>>(),
            "warnings": report.warnings().map(|p| p.to_string()).collect::<Vec<_>>(),
        });
        let text = serde_json::to_string_pretty(&value).map_err(|e| CliError::Usage(e.to_string()))?;
        writeln!(out, "{text}")?;
    } else {
        let s = &stats;
        writeln!(out, "{} ({:?})", args.input.mesh.display(), load_report.format)?;
        for note in &load_report.notes {
            writeln!(out, "  note: {note}")?;
        }
        if load_report.welded_vertices > 0 {
            writeln!(out, "  welded vertices:      {}", load_report.welded_vertices)?;
        }
        if load_report.triangulated_polygons > 0 {
            writeln!(out, "  triangulated polygons: {}", load_report.triangulated_polygons)?;
        }
        writeln!(out, "  vertices              {}", s.n_vertices)?;
        writeln!(out, "  faces                 {}", s.n_faces)?;
        writeln!(out, "  edges                 {}", s.n_edges)?;
        writeln!(out, "  boundary loops        {}", s.n_boundary_loops)?;
        writeln!(out, "  components            {}", s.n_components)?;
        writeln!(out, "  Euler characteristic  {}", s.euler_characteristic)?;
        match s.genus {
            Some(g) => writeln!(out, "  genus                 {g}")?,
            None => writeln!(
                out,
                "  genus                 undefined (not a single orientable manifold)"
            )?,
        }
        writeln!(out, "  area                  {:.6e}", s.area)?;
        writeln!(out, "  bbox diagonal         {:.6e}", s.bbox_diagonal)?;
        writeln!(out, "  mean edge length      {:.6e}", s.mean_edge_length)?;
        writeln!(
            out,
            "  angles (deg)          {:.3} .. {:.3}",
            s.min_angle_deg, s.max_angle_deg
        )?;
        writeln!(out, "  manifold / closed     {} / {}", s.is_manifold, s.is_closed)?;
        writeln!(out, "{}", report.summary())?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// wfem operators

/// Which lumped mass to write.
#[derive(ValueEnum, Clone, Copy, Debug, Default)]
pub enum LumpedArg {
    /// One third of the incident triangle areas (paper, Eq. (7)).
    #[default]
    Barycentric,
    /// Mixed Voronoi areas (Meyer et al. 2003).
    Voronoi,
}

/// Arguments of `wfem operators`.
#[derive(Args, Clone, Debug)]
pub struct OperatorsArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Output directory (created if missing) for stiffness.mtx, mass.mtx and lumped_mass.mtx.
    #[arg(long)]
    pub out: PathBuf,
    /// Lumped mass kind.
    #[arg(long, value_enum, default_value_t = LumpedArg::Barycentric)]
    pub lumped: LumpedArg,
}

/// `wfem operators`: writes `DIR/stiffness.mtx` (L, positive semidefinite), `DIR/mass.mtx` (B)
/// and `DIR/lumped_mass.mtx` (D) in Matrix Market format.
pub fn operators(args: &OperatorsArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let mesh = load_usable(&args.input)?;
    let lumped = match args.lumped {
        LumpedArg::Barycentric => LumpedMassKind::Barycentric,
        LumpedArg::Voronoi => LumpedMassKind::Voronoi,
    };
    let ops = assemble(&mesh, &AssemblyParams { lumped })?;
    std::fs::create_dir_all(&args.out).map_err(|source| MeshError::Io {
        path: args.out.clone(),
        source,
    })?;
    mesh_fem::mtx::write_operators(&args.out, &ops)?;
    writeln!(
        out,
        "wrote {}/{{stiffness,mass,lumped_mass}}.mtx ({} × {}, {} nonzeros each)",
        args.out.display(),
        ops.n(),
        ops.n(),
        ops.stiffness.compute_nnz()
    )?;
    Ok(())
}
