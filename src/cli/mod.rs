//! The `wfem` command-line tool (private to the binary; tested through the binary in tests/it/cli*.rs).
//!
//! Every subcommand reads its input read-only, writes its outputs atomically (temporary file
//! in the same directory, then rename; see [`mesh_fem::io::write_atomic`]) and refuses to write
//! over its input. Output formats are chosen by extension: `.ply` (mesh with named float
//! vertex properties and vertex colors), `.npy`, `.csv`, and `.png` (a rendered figure).

mod approx;
mod distance;
mod heat;
pub use distance::{distance, DistanceArgs};
pub mod hks;
pub mod retrieval;

pub use approx::{approx, ApproxArgs};
pub use heat::{demo, heat, DemoArgs, HeatArgs, KernelArg};

use clap::{Args, ValueEnum};
use mesh_fem::io::{load, stage_field, AtomicSet, FieldFormat, LoadOptions};
use mesh_fem::{assemble, AssemblyParams, LumpedMassKind, MeshError, TriMesh};
use std::io::Write;
use std::path::{Path, PathBuf};
use wfem_render::{render_png, symmetric_range, Colormap, RenderError, RenderParams};

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

/// The format of an output file, from its extension: a per-vertex field file or a rendered
/// figure. Parsed once, when the arguments are parsed, so a wrong extension is refused before
/// any work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// `.ply`, `.npy`, `.csv` ([`mesh_fem::io::write_field`]).
    Field(FieldFormat),
    /// `.png`: one rendered figure per field.
    Png,
}

/// An output path given on the command line, with its format.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Output {
    /// The path as given.
    pub path: PathBuf,
    /// Its format.
    pub format: OutputFormat,
}

impl Output {
    /// The extensions `-o` accepts, as messages list them.
    pub const EXTENSIONS: &'static str = ".ply, .npy, .csv, .png";

    /// Parses an output path (clap value parser): the extension must name a format.
    pub fn parse(text: &str) -> Result<Self, String> {
        let path = PathBuf::from(text);
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let format = match FieldFormat::from_extension(&ext) {
            Some(f) => OutputFormat::Field(f),
            None if ext == "png" => OutputFormat::Png,
            None => {
                return Err(format!(
                    "cannot write {:?}: the output format is chosen by the extension, one of {}",
                    text,
                    Self::EXTENSIONS
                ))
            }
        };
        Ok(Self { path, format })
    }
}

/// Writes per-vertex fields in the format of `output`. For `.png` every field becomes its own
/// figure: the path itself for one field, `stem-<name>.png` beside it for several. For `.ply`
/// the vertex colors show the first field. All files are written all-or-nothing.
pub fn write_fields(
    output: &Output,
    mesh: &TriMesh,
    fields: &[(String, Vec<f64>)],
    highlight: &[u32],
) -> Result<Vec<PathBuf>, CliError> {
    let path = &output.path;
    if fields.is_empty() {
        return Err(CliError::Usage("nothing to write".into()));
    }
    let mut set = AtomicSet::new();
    match output.format {
        OutputFormat::Png => {
            // Render every figure first, then write the set all-or-nothing.
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
                set.stage(&target, |w| w.write_all(&png))?;
            }
        }
        OutputFormat::Field(format) => {
            let refs: Vec<(&str, &[f64])> = fields.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
            let colors = (format == FieldFormat::Ply).then(|| colors_of(&fields[0].1));
            stage_field(&mut set, path, format, mesh, &refs, colors.as_deref())?;
        }
    }
    let written: Vec<PathBuf> = set.targets().map(Path::to_path_buf).collect();
    set.commit()?;
    Ok(written)
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
pub(crate) fn colors_of(values: &[f64]) -> Vec<[u8; 3]> {
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
