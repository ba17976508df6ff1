//! The `wfem` command-line tool (private to the binary; tested through the binary in
//! tests/it/cli*.rs and tests/it/hostile.rs).
//!
//! Every subcommand reads its input read-only (only regular files: a FIFO is refused, not
//! waited on), checks its output paths and every size that comes from the command line
//! before any work ([`output`], [`limits`]), shows progress on standard error ([`progress`]),
//! and writes its outputs atomically through [`mesh_fem::io::AtomicSet`], never over its
//! input. Output formats are chosen by extension: `.ply` (mesh with named float vertex
//! properties and vertex colors), `.npy` (with a `.json` sidecar naming its columns), `.csv`,
//! and `.png` (rendered figures).

mod approx;
pub mod choice;
mod demo;
mod demo_approx;
mod demo_volume;
mod distance;
mod geodesic;
mod heat;
mod input;
pub mod limits;
pub mod output;
pub mod progress;
pub mod times;
mod volume;
pub use distance::{distance, DistanceArgs};
pub use geodesic::{geodesic, GeodesicArgs};
pub mod hks;
pub mod retrieval;
pub mod signals;
pub mod spectrum;
pub mod wks;

pub use approx::{approx, ApproxArgs};
pub use demo::{demo, DemoArgs};
pub use heat::{heat, HeatArgs};
pub use input::{read_input, read_usable, MeshArgs};
pub use output::{Output, OutputFormat};

use clap::Args;
use mesh_fem::{Lumping, Mass, MeshError};
use std::io::Write;
use std::path::{Path, PathBuf};
use wfem_base::Choice;
use wfem_render::RenderError;

/// Failures of the CLI: printed as one line `wfem: error: …`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CliError {
    /// Mesh reading, validation, assembly or writing (library names replaced by the flags).
    #[error("{}", input::mesh_message(.0))]
    Mesh(#[from] MeshError),
    /// Heat kernel evaluation.
    #[error("{}", heat_message(.0))]
    Heat(#[from] wfem_heat::HeatError),
    /// Descriptors, vocabularies, indexes and their files.
    #[error("{}", retrieval_message(.0))]
    Retrieval(#[from] shape_retrieval::RetrievalError),
    /// Rendering a PNG.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// Arguments that do not fit together.
    #[error("{0}")]
    Usage(String),
    /// A number given on the command line outside its range.
    #[error("{flag} {value} is out of range: allowed {allowed} ({why})")]
    OutOfRange {
        /// The flag.
        flag: &'static str,
        /// The value given.
        value: String,
        /// The allowed range.
        allowed: String,
        /// Why.
        why: String,
    },
    /// An output path that cannot be written (checked before any work).
    #[error("cannot write {}: {reason}", path.display())]
    Output {
        /// The output path.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
    /// A computed field holds NaN or ∞ (never written).
    #[error("{what} has the non-finite value {value} at vertex {vertex}{}; nothing was written",
        if value.is_infinite() { " (beyond the largest finite number, 1.8e308: scale the input down)" } else { "" })]
    NonFinite {
        /// Which field.
        what: String,
        /// Its first bad vertex.
        vertex: usize,
        /// The value.
        value: f64,
    },
    /// An approximate method is further from the exact K_t f than allowed.
    #[error(
        "--method {method} is off by {error:.1e} (relative max error against the exact fast path) at t = {t}; \
         use --method rational, fast or dense, or pass --allow-inaccurate to write it anyway"
    )]
    Inaccurate {
        /// The method.
        method: String,
        /// The diffusion time.
        t: f64,
        /// max|g − g_exact| / max|g_exact|.
        error: f64,
    },
    /// A collection was used without some of its files (each reported on standard error):
    /// exit status [`EXIT_REFUSED`].
    #[error(
        "{refused} of {total} files were refused (listed above); {done} from the other {} — pass --strict to refuse the whole collection instead",
        total - refused
    )]
    Refused {
        /// Files refused.
        refused: usize,
        /// Files given.
        total: usize,
        /// What was done with the others ("the index was built").
        done: String,
    },
    /// `retrieval check` found damaged records (each listed on standard output).
    #[error("{} is damaged: {damaged} damaged record{} (listed above); rebuild it, or restore it from a copy", path.display(), if *damaged == 1 { "" } else { "s" })]
    Damaged {
        /// The index.
        path: PathBuf,
        /// How many records are damaged.
        damaged: usize,
    },
    /// `retrieval check` found nothing wrong in an index without checksums, which therefore
    /// could not be verified: exit status [`EXIT_UNCHECKED`].
    #[error("{} could not be verified: {why}", path.display())]
    Unchecked {
        /// The index.
        path: PathBuf,
        /// Why (and how to make it verifiable).
        why: String,
    },
    /// Writing to the terminal failed.
    #[error("cannot write to standard output: {0}")]
    Stdout(#[from] std::io::Error),
}

/// A heat-kernel error as the CLI prints it: a mesh error inside it with its remedy in flags.
fn heat_message(e: &wfem_heat::HeatError) -> String {
    match e {
        wfem_heat::HeatError::Mesh(m) => input::mesh_message(m),
        other => other.to_string(),
    }
}

/// A retrieval error as the CLI prints it: a mesh error inside it (also within a heat-kernel
/// error) with its remedy in flags.
fn retrieval_message(e: &shape_retrieval::RetrievalError) -> String {
    match e {
        shape_retrieval::RetrievalError::Mesh(m) => input::mesh_message(m),
        shape_retrieval::RetrievalError::Heat(h) => heat_message(h),
        other => other.to_string(),
    }
}

/// The exit status of a collection command that used only some of its files
/// ([`CliError::Refused`]): the outputs are written, but not from every file given.
pub const EXIT_REFUSED: u8 = 3;

/// The exit status of `retrieval check` on an index that has no checksums (a version 1
/// SQLite file, or JSON) and showed no damage: nothing found, but nothing verified either.
pub const EXIT_UNCHECKED: u8 = 4;

/// `--mass`: which heat kernel, named by its mass matrix M (mesh_fem's [`Mass`] registry).
#[derive(Args, Clone, Debug)]
pub struct MassArgs {
    /// The mass matrix M of the kernel K_t = exp(−t M⁻¹L) (paper, Table 1).
    #[arg(long, alias = "kernel", value_parser = choice::choice::<Mass>(), default_value = Mass::default_name())]
    pub mass: Mass,
    /// Older spelling of a lumped mass (`--kernel lumped --lumped voronoi`); use --mass voronoi.
    #[arg(long, hide = true, value_parser = choice::choice::<Lumping>())]
    pub lumped: Option<Lumping>,
}

impl MassArgs {
    /// The mass, with the older `--lumped` folded in.
    pub fn mass(&self) -> Result<Mass, CliError> {
        match self.lumped {
            None => Ok(self.mass),
            Some(lumping) => self.mass.with_lumping(lumping).ok_or_else(|| {
                CliError::Usage(format!(
                    "--lumped applies to a lumped --mass, not to --mass {} (use --mass {})",
                    self.mass.name(),
                    Mass::Lumped(lumping).name()
                ))
            }),
        }
    }
}

/// Checks one output file before any work (its folder exists and is writable, it is not a
/// directory or special file, and it is not `input`).
pub(crate) fn check_output(input: &Path, output: &Path) -> Result<(), CliError> {
    output::check_folder(output)?;
    output::check_targets(&[output.to_path_buf()], &[input])
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

/// `wfem info`: statistics and the validation report of a mesh (after `--repair`, if given:
/// then it shows what the repair leaves).
pub fn info(args: &InfoArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let input = read_input(&args.input)?;
    let (mesh, load_report) = match (&input.volume, &input.load_report) {
        (Some(v), _) => return volume::info(&args.input.mesh, v, args.json, out),
        (None, Some(report)) => (&input.mesh, report),
        (None, None) => return Err(CliError::Usage(format!("{}: nothing was read", input.name))),
    };
    let stats = progress::run("statistics", || Ok::<_, CliError>(mesh_fem::stats::stats(mesh)))?;
    let report = progress::run("validating", || Ok::<_, CliError>(mesh_fem::validate::validate(mesh)))?;
    if args.json {
        let value = serde_json::json!({
            "file": args.input.mesh.display().to_string(),
            "format": format!("{:?}", load_report.format),
            "welded_vertices": load_report.welded_vertices,
            "triangulated_polygons": load_report.triangulated_polygons,
            "load_notes": load_report.notes,
            "repair": input.repair.as_ref().map(|r| serde_json::json!({
                "file_vertices": input.file_vertices,
                "merged_vertices": r.merged_vertices,
                "dropped_vertices": r.dropped_vertices,
                "dropped_degenerate_faces": r.dropped_degenerate_faces.len(),
                "dropped_duplicate_faces": r.dropped_duplicate_faces.len(),
                "flipped_faces": r.flipped_faces.len(),
            })),
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
        if input.repair.is_some() {
            writeln!(out, "  after {}:", input::repair_flags(&args.input))?;
        }
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
        writeln!(out, "{}", report.summary_with(&input::cli_fix))?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// wfem operators

/// Arguments of `wfem operators`.
#[derive(Args, Clone, Debug)]
pub struct OperatorsArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: MeshArgs,
    /// Output directory (created if missing) for stiffness.mtx, mass.mtx and lumped_mass.mtx.
    #[arg(long)]
    pub out: PathBuf,
    /// Which lumped mass D to write in lumped_mass.mtx.
    #[arg(long, value_parser = choice::choice::<Lumping>(), default_value = Lumping::default_name())]
    pub lumped: Lumping,
}

/// `wfem operators`: writes `DIR/stiffness.mtx` (L, positive semidefinite), `DIR/mass.mtx` (B)
/// and `DIR/lumped_mass.mtx` (D) in Matrix Market format, all-or-nothing.
pub fn operators(args: &OperatorsArgs, out: &mut dyn Write) -> Result<(), CliError> {
    const FILES: [&str; 3] = ["stiffness.mtx", "mass.mtx", "lumped_mass.mtx"];
    output::check_out_dir(&args.out, &FILES, &[&args.input.mesh])?;
    let input = read_usable(&args.input)?;
    let ops = progress::run("assembling L, B, D", || input.assemble(args.lumped))?;
    output::create_out_dir(&args.out)?;
    progress::run("writing Matrix Market files", || {
        mesh_fem::mtx::write_operators(&args.out, &ops)
    })?;
    writeln!(
        out,
        "wrote {}/{{stiffness,mass,lumped_mass}}.mtx ({} × {}; L and B {} nonzeros, D diagonal){}",
        args.out.display(),
        ops.n(),
        ops.n(),
        ops.stiffness.compute_nnz(),
        if input.renumbered() {
            " for the repaired mesh"
        } else {
            ""
        }
    )?;
    Ok(())
}

/// The old spellings among `args` (the command line as given): hidden aliases of a flag of the
/// subcommand they follow, which are the names a flag had before it was renamed (issue #37:
/// kept for one release). Returns `(old, new)` pairs, in order.
pub fn old_spellings(command: &clap::Command, args: &[String]) -> Vec<(String, String)> {
    let mut current = command;
    let mut out = Vec::new();
    for token in args.iter().skip(1) {
        if token == "--" {
            break;
        }
        if let Some(flag) = token.strip_prefix("--") {
            let name = flag.split('=').next().unwrap_or(flag);
            let renamed = current.get_arguments().find(|a| {
                a.get_long().is_some_and(|long| long != name)
                    && a.get_all_aliases().is_some_and(|aliases| aliases.contains(&name))
                    && !a.get_visible_aliases().is_some_and(|visible| visible.contains(&name))
            });
            if let Some(arg) = renamed.and_then(|a| a.get_long()) {
                out.push((format!("--{name}"), format!("--{arg}")));
            }
        } else if !token.starts_with('-') {
            if let Some(sub) = current.find_subcommand(token) {
                current = sub;
            }
        }
    }
    out
}

/// Warns about every old spelling of a flag in `args` ([`old_spellings`]).
pub fn warn_old_spellings(command: &clap::Command, args: &[String]) {
    for (old, new) in old_spellings(command, args) {
        progress::warn(&format!(
            "{old} is the old spelling of {new}; it still works in this release but will be removed"
        ));
    }
}
