//! Tetrahedral meshes as inputs (issue #39): a file whose extension names a volume format is
//! read as a solid; its operators are the linear FEM ones of the tetrahedra and its boundary
//! surface (on all the vertices) is the mesh of figures and PLY outputs, so every per-vertex
//! command (heat, hks, wks, distance, geodesic, operators, info) works on it unchanged.

use super::input::{Input, MeshArgs};
use super::{progress, CliError};
use mesh_fem::io::volume::{read_volume, VolumeFormat};
use mesh_fem::validate::{RepairReport, RepairStep};
use mesh_fem::volume::{repair_volume, validate_volume, TetMesh, VolumeReport};
use mesh_fem::Laplacian;
use std::io::Write;
use wfem_base::Choice;

/// The solid behind an [`Input`] read from a volume file.
#[derive(Clone, Debug)]
pub struct Volume {
    /// The tetrahedra (after `--repair`).
    pub mesh: TetMesh,
    /// What validation found (after `--repair`).
    pub report: VolumeReport,
    /// The file's format.
    pub format: VolumeFormat,
}

/// Whether `args.mesh` is read as a volume (its extension names a volume format).
pub fn is_volume(args: &MeshArgs) -> bool {
    VolumeFormat::from_path(&args.mesh).is_some()
}

/// Reads a volume file, applies the repairs that mean something for tetrahedra (`orient`,
/// `degenerate`, `unreferenced`) and validates it; fatal problems are refused in
/// [`check_usable`], not here (so `wfem info` can show them).
///
/// # Errors
/// Reading errors; flags that do not apply to a volume.
pub fn read(args: &MeshArgs, name: String) -> Result<Input, CliError> {
    if args.triangulate {
        return Err(CliError::Usage(format!(
            "{name} is a tetrahedral mesh: --triangulate applies to polygon surfaces"
        )));
    }
    if let Some(l) = args.laplacian.filter(|l| *l != Laplacian::Cotan) {
        return Err(CliError::Usage(format!(
            "{name} is a tetrahedral mesh: --laplacian {} is a surface Laplacian; a volume has the linear FEM one ({})",
            l.name(),
            Laplacian::Cotan.name()
        )));
    }
    let opts = args.repair_options()?;
    let surface_only = [RepairStep::DuplicateVertices, RepairStep::DuplicateFaces];
    if args.repair.iter().any(|r| surface_only.contains(r)) {
        return Err(CliError::Usage(format!(
            "{name} is a tetrahedral mesh: its repairs are orient, degenerate and unreferenced"
        )));
    }
    let read = progress::run(format!("reading {name}"), || read_volume(&args.mesh))?;
    for (kind, count) in &read.ignored {
        progress::note(&format!(
            "{name}: {count} {kind} in the file are not used (the boundary comes from the tetrahedra)"
        ));
    }
    let file_vertices = read.mesh.n_vertices();
    let (mesh, repair) = if args.repair.is_empty() {
        (read.mesh, None)
    } else {
        let (orient, degenerate, unreferenced) = (
            opts.orient_faces,
            opts.drop_degenerate_faces,
            opts.drop_unreferenced_vertices,
        );
        let (repaired, done) = progress::run("repairing", || {
            repair_volume(&read.mesh, orient, degenerate, unreferenced)
        })?;
        progress::note(&format!(
            "{}: {} tetrahedra reoriented, {} flat ones dropped, {} unreferenced vertices dropped",
            super::input::repair_flags(args),
            done.flipped,
            done.dropped_tets,
            done.dropped_vertices
        ));
        let report = RepairReport {
            vertex_map: done.vertex_map,
            dropped_vertices: done.dropped_vertices,
            ..RepairReport::default()
        };
        (repaired, Some(report))
    };
    let report = progress::run("validating", || Ok::<_, CliError>(validate_volume(&mesh)))?;
    let surface = mesh.boundary_mesh()?;
    Ok(Input {
        mesh: surface,
        load_report: None,
        repair,
        file_vertices,
        name,
        cloud: None,
        splats: None,
        laplacian: Laplacian::Cotan,
        volume: Some(Volume {
            mesh,
            report,
            format: read.format,
        }),
    })
}

/// Refuses a volume with a fatal problem; says its warnings once each.
///
/// # Errors
/// [`CliError::Mesh`] naming the first fatal problem.
pub fn check_usable(name: &str, volume: &Volume) -> Result<(), CliError> {
    for w in volume.report.warnings() {
        progress::warn(&format!("{name}: {w}"));
    }
    Ok(volume.report.clone().into_result()?)
}

/// `wfem info` of a volume: counts, quality, the boundary, and every problem.
///
/// # Errors
/// Write errors.
pub fn info(path: &std::path::Path, volume: &Volume, json: bool, out: &mut dyn Write) -> Result<(), CliError> {
    let r = &volume.report;
    let problems = |fatal: bool| -> Vec<String> {
        r.problems
            .iter()
            .filter(|p| p.is_fatal() == fatal)
            .map(|p| p.to_string())
            .collect()
    };
    if json {
        let value = serde_json::json!({
            "file": path.display().to_string(),
            "format": volume.format.name(),
            "volume": true,
            "n_vertices": r.n_vertices,
            "n_tets": r.n_tets,
            "total_volume": r.volume,
            "n_boundary_faces": r.n_boundary_faces,
            "n_boundary_vertices": r.n_boundary_vertices,
            "boundary_euler": r.boundary_euler,
            "n_boundary_components": r.n_boundary_components,
            "boundary_genus": r.boundary_genus,
            "n_components": r.n_components,
            "quality_min": r.quality.0,
            "quality_median": r.quality.1,
            "worst_tet": r.worst_tet,
            "usable": !r.problems.iter().any(|p| p.is_fatal()),
            "errors": problems(true),
            "warnings": problems(false),
        });
        let text = serde_json::to_string_pretty(&value).map_err(|e| CliError::Usage(e.to_string()))?;
        writeln!(out, "{text}")?;
        return Ok(());
    }
    writeln!(out, "{} (tetrahedral mesh, {})", path.display(), volume.format.name())?;
    writeln!(out, "  vertices:             {}", r.n_vertices)?;
    writeln!(out, "  tetrahedra:           {}", r.n_tets)?;
    writeln!(out, "  volume:               {:.6e}", r.volume)?;
    writeln!(
        out,
        "  boundary:             {} triangles on {} vertices (Euler characteristic {})",
        r.n_boundary_faces, r.n_boundary_vertices, r.boundary_euler
    )?;
    let genus = match r.boundary_genus {
        Some(g) => format!("genus {g}"),
        None => "not a closed 2-manifold: genus undefined".to_string(),
    };
    writeln!(
        out,
        "  boundary topology:    {} component{}, {genus}",
        r.n_boundary_components,
        if r.n_boundary_components == 1 { "" } else { "s" }
    )?;
    writeln!(out, "  components:           {}", r.n_components)?;
    writeln!(
        out,
        "  quality (min/median): {:.3e} / {:.3} (6√2|T|/ℓ³_rms, 1 for the regular tetrahedron; the worst: tetrahedron {})",
        r.quality.0, r.quality.1, r.worst_tet
    )?;
    for e in problems(true) {
        writeln!(out, "  error: {e}")?;
    }
    for w in problems(false) {
        writeln!(out, "  warning: {w}")?;
    }
    let usable = !r.problems.iter().any(|p| p.is_fatal());
    writeln!(out, "  usable: {}", if usable { "yes" } else { "no" })?;
    Ok(())
}
