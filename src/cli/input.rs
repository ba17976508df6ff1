//! Reading the mesh of a subcommand: load, the explicit repairs of `--repair`, validation,
//! and the vertex numbering that per-vertex inputs and outputs refer to.

use super::{progress, CliError};
use clap::Args;
use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::io::{load_shape, read_field, LoadOptions, LoadReport, MeshFormat, Shape};
use mesh_fem::validate::{repair, RepairOptions, RepairReport, RepairStep};
use mesh_fem::{assemble, AssemblyParams, FemOperators, Laplacian, Lumping, MeshError, Remedy, TriMesh};
use std::path::{Path, PathBuf};
use wfem_base::Choice;
use wfem_render::Splats;

/// The mesh argument shared by every subcommand that reads a mesh.
#[derive(Args, Clone, Debug, Default)]
pub struct MeshArgs {
    /// Mesh file (.obj, .ply, .off, .stl), or a point cloud (.ply without faces, .xyz, .pts,
    /// .csv, .npy): its operators come from local triangulations of the 30 nearest neighbours.
    #[arg(id = "mesh_file", value_name = "MESH")]
    pub mesh: PathBuf,
    /// Laplacian of a mesh: cotan (the default, paper Eq. (3)) or robust (intrinsic Delaunay
    /// L of the tufted cover: for non-manifold, badly oriented or degenerate meshes; its
    /// lumped heat is never negative). Point clouds always use the robust construction.
    /// `retrieval query` describes the query with the index's Laplacian and refuses another.
    #[arg(long, value_parser = super::choice::choice::<Laplacian>())]
    pub laplacian: Option<Laplacian>,
    /// Fan-triangulate polygons with more than three corners instead of refusing them.
    #[arg(long)]
    pub triangulate: bool,
    /// Repair the mesh before use: unreferenced, duplicate-vertices (alias weld), degenerate,
    /// duplicate-faces, orient or all (comma-separated or repeated). Each change is reported;
    /// per-vertex outputs then refer to the repaired mesh.
    #[arg(long, value_parser = super::choice::choice::<RepairStep>(), value_delimiter = ',', action = clap::ArgAction::Append)]
    pub repair: Vec<RepairStep>,
    /// Distance below which --repair duplicate-vertices merges vertices, relative to the
    /// bounding-box diagonal (0: identical coordinates only).
    #[arg(long, default_value_t = mesh_fem::validate::DEFAULT_WELD_TOLERANCE, allow_negative_numbers = true)]
    pub weld_tolerance: f64,
}

impl MeshArgs {
    /// The Laplacian of `--laplacian` (the library default when absent).
    pub fn laplacian(&self) -> Laplacian {
        self.laplacian.unwrap_or_default()
    }

    /// The repairs asked for, as library options.
    ///
    /// # Errors
    /// [`CliError::OutOfRange`] for a negative or non-finite `--weld-tolerance`, or one given
    /// without `--repair duplicate-vertices`.
    pub fn repair_options(&self) -> Result<RepairOptions, CliError> {
        let options = RepairStep::options(&self.repair, self.weld_tolerance);
        let weld = options.merge_duplicate_vertices.is_some();
        if !(self.weld_tolerance.is_finite() && self.weld_tolerance >= 0.0) {
            return Err(CliError::OutOfRange {
                flag: "--weld-tolerance",
                value: self.weld_tolerance.to_string(),
                allowed: "a finite number ≥ 0".into(),
                why: "a distance relative to the bounding-box diagonal".into(),
            });
        }
        if self.weld_tolerance > 0.0 && !weld {
            return Err(CliError::Usage(format!(
                "--weld-tolerance applies to --repair {}, which is not given",
                RepairStep::DuplicateVertices.name()
            )));
        }
        Ok(options)
    }
}

/// The `--repair` flags as given, for messages.
pub fn repair_flags(args: &MeshArgs) -> String {
    let names: Vec<&str> = args.repair.iter().map(|r| r.name()).collect();
    format!("--repair {}", names.join(","))
}

/// `n file`/`n files`: a count with its noun in the right number.
pub fn count_of(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Parses a vertex index (`--source`, `--from`; clap value parser): a negative number gets a
/// message saying what the value is (vertices are numbered from 0 as in the file), not
/// clap's hint to escape it as an argument.
pub fn vertex_index(text: &str) -> Result<u32, String> {
    match text.trim().parse::<i64>() {
        Ok(i) if (0..=i64::from(u32::MAX)).contains(&i) => Ok(i as u32),
        Ok(i) if i < 0 => Err(format!(
            "{i} is not a vertex: vertices are numbered 0, 1, 2, … as in the file"
        )),
        _ => Err(format!(
            "{text:?} is not a vertex index (a whole number ≥ 0, as in the file)"
        )),
    }
}

/// Parses a `--field` path (clap value parser): its extension must name a field format that
/// can be read (`.npy` or `.csv`), so a wrong file is refused before any work.
pub fn field_path(text: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(text);
    let ext = super::output::extension(&path);
    if mesh_fem::io::FieldFormat::from_extension(&ext).is_some_and(|f| f.readable()) {
        Ok(path)
    } else {
        Err(format!(
            "cannot read {text:?} as a field: the format is chosen by the extension, {} (one value per vertex)",
            mesh_fem::io::FieldFormat::readable_extensions()
        ))
    }
}

/// A mesh read for a subcommand, after the repairs.
pub struct Input {
    /// The mesh used (repaired if `--repair` changed it).
    pub mesh: TriMesh,
    /// What was read (of a surface or point-cloud file; `None` for a volume).
    pub load_report: Option<LoadReport>,
    /// The repair's report, if `--repair` was given.
    pub repair: Option<RepairReport>,
    /// Vertices in the file.
    pub file_vertices: usize,
    /// The mesh file's name (for titles and metadata).
    pub name: String,
    /// The point cloud, when the file holds one; `mesh` is then its neighbourhood mesh (the
    /// merged local triangles on the points, for figures and graph searches).
    pub cloud: Option<PointCloud>,
    /// The point cloud drawn as splats in figures (its points with the normals of its
    /// tangent planes and radii from its neighbourhood triangles), when the file holds one.
    pub splats: Option<Splats>,
    /// The Laplacian of `--laplacian`.
    pub laplacian: Laplacian,
    /// The tetrahedra, when the file is a volume; `mesh` is then its boundary surface on all
    /// the vertices (for figures and PLY outputs).
    pub volume: Option<super::volume::Volume>,
}

impl Input {
    /// L, B, D of the input: of the mesh with the chosen Laplacian, or of the point cloud.
    ///
    /// # Errors
    /// Assembly errors.
    pub fn assemble(&self, lumping: Lumping) -> Result<FemOperators, MeshError> {
        let params = AssemblyParams {
            lumping,
            laplacian: self.laplacian,
        };
        match (&self.cloud, &self.volume) {
            (Some(cloud), _) => Ok(assemble_cloud(cloud, &CloudParams::default(), &params)?.operators),
            (None, Some(v)) => mesh_fem::volume::assemble_volume(&v.mesh, &params),
            (None, None) => assemble(&self.mesh, &params),
        }
    }

    /// Whether the vertex numbering differs from the file's (vertices dropped or merged).
    pub fn renumbered(&self) -> bool {
        self.repair
            .as_ref()
            .is_some_and(|r| r.vertex_map.iter().enumerate().any(|(i, m)| *m != Some(i as u32)))
    }

    /// The mesh's index of vertex `i` of the file (`flag` names the option it came from).
    ///
    /// # Errors
    /// [`CliError::OutOfRange`] if the file has no vertex `i` or the repair dropped it.
    pub fn vertex(&self, flag: &'static str, i: u32) -> Result<u32, CliError> {
        let n = self.file_vertices;
        if i as usize >= n {
            return Err(CliError::OutOfRange {
                flag,
                value: i.to_string(),
                allowed: format!("0..={}", n.saturating_sub(1)),
                why: format!("a vertex index of {} ({n} vertices)", self.name),
            });
        }
        match &self.repair {
            None => Ok(i),
            Some(r) => match r.vertex_map.get(i as usize).copied().flatten() {
                Some(j) => {
                    if j != i {
                        progress::note(&format!(
                            "{flag} {i}: vertex {i} of the file is vertex {j} of the repaired mesh"
                        ));
                    }
                    Ok(j)
                }
                None => Err(CliError::Usage(format!(
                    "{flag} {i}: the repair dropped vertex {i} of the file (it belongs to no face)"
                ))),
            },
        }
    }

    /// Reads a per-vertex field (`--field`): one value per vertex of the file, or of the
    /// repaired mesh. A field of the file is restricted to the kept vertices (a merged vertex
    /// takes the value of the vertex it was merged into).
    ///
    /// # Errors
    /// Those of [`read_field`]; [`MeshError::FieldLength`] names both accepted lengths.
    pub fn field(&self, path: &Path) -> Result<Vec<f64>, CliError> {
        let n = self.mesh.n_vertices();
        let Some(report) = self.repair.as_ref().filter(|_| self.renumbered()) else {
            return Ok(read_field(path, n)?);
        };
        match read_field(path, self.file_vertices) {
            Ok(values) => Ok(file_vertex_of_row(report, n)
                .into_iter()
                .map(|old| values.get(old).copied().unwrap_or(0.0))
                .collect()),
            Err(MeshError::FieldLength { found, .. }) if found == n => Ok(read_field(path, n)?),
            Err(MeshError::FieldLength { path, name, found, .. }) => Err(CliError::Usage(format!(
                "{}: field {name:?} has {found} values; it needs one per vertex of the file ({}) or of the repaired mesh ({n})",
                path.display(),
                self.file_vertices
            ))),
            Err(e) => Err(e.into()),
        }
    }

    /// What retrieval describes: the point cloud, or the (repaired) mesh.
    pub fn as_shape(&self) -> shape_retrieval::model::ShapeRef<'_> {
        match &self.cloud {
            Some(cloud) => cloud.into(),
            None => (&self.mesh).into(),
        }
    }

    /// The Laplacian the operators are assembled with: `--laplacian` for a mesh, the robust
    /// construction for a point cloud.
    pub fn laplacian_used(&self) -> Laplacian {
        match self.cloud {
            Some(_) => Laplacian::Robust(mesh_fem::RobustParams::default()),
            None => self.laplacian,
        }
    }

    /// Metadata of the input for the `.npy` sidecar (with the Laplacian used, and whether the
    /// input is a point cloud, whose `n_faces` are those of its neighbourhood mesh).
    pub fn meta(&self, path: &Path) -> serde_json::Value {
        let mut v = serde_json::json!({
            "mesh": path.display().to_string(),
            "n_vertices": self.mesh.n_vertices(),
            "n_faces": self.mesh.n_faces(),
            "laplacian": self.laplacian_used().name(),
        });
        if let (Some(_), Some(obj)) = (&self.cloud, v.as_object_mut()) {
            obj.insert("point_cloud".into(), serde_json::Value::Bool(true));
        }
        if let (Some(vol), Some(obj)) = (&self.volume, v.as_object_mut()) {
            // A volume's n_faces are those of its boundary surface.
            obj.insert("n_tets".into(), serde_json::json!(vol.mesh.n_tets()));
        }
        if let (Some(r), Some(obj)) = (&self.repair, v.as_object_mut()) {
            obj.insert(
                "repair".into(),
                serde_json::json!({
                    "file_vertices": self.file_vertices,
                    "merged_vertices": r.merged_vertices,
                    "dropped_vertices": r.dropped_vertices,
                    "dropped_faces": r.dropped_faces.len(),
                    "flipped_faces": r.flipped_faces.len(),
                    // Row i of the data is vertex file_vertex_of_row[i] of the file.
                    "file_vertex_of_row": self.renumbered().then(|| file_vertex_of_row(r, self.mesh.n_vertices())),
                }),
            );
        }
        v
    }
}

/// For each vertex of the repaired mesh, the file vertex it came from: the kept one of a
/// merged group, which is its lowest index (a vertex merges only into an earlier one).
fn file_vertex_of_row(report: &RepairReport, n: usize) -> Vec<usize> {
    let mut rows = vec![usize::MAX; n];
    for (old, m) in report.vertex_map.iter().enumerate() {
        if let Some(new) = m {
            let new = *new as usize;
            if rows[new] == usize::MAX {
                rows[new] = old;
            }
        }
    }
    rows
}

/// Loads, repairs (as asked) and validates the mesh: the one reading path of every
/// subcommand. Repairs and the change of numbering are reported on standard error; a mesh
/// with a fatal problem is refused with the error naming it and the `--repair` that fixes it.
///
/// # Errors
/// Reading, repair and validation errors.
pub fn read_input(args: &MeshArgs) -> Result<Input, CliError> {
    let opts = args.repair_options()?;
    if args.mesh.is_dir() {
        return Err(CliError::Usage(format!(
            "{} is a directory, not a mesh file: give one .obj, .ply, .off or .stl file",
            args.mesh.display()
        )));
    }
    let name = args
        .mesh
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| args.mesh.display().to_string());
    if super::volume::is_volume(args) {
        return super::volume::read(args, name);
    }
    let shape = progress::run(format!("reading {name}"), || {
        load_shape(&args.mesh, &LoadOptions::with_triangulation(args.triangulate))
    })
    .map_err(|e| match e {
        // The cloud's own checks do not know the file (issue #41: "the point cloud has 0
        // points" for an empty query file).
        MeshError::TooFewPoints { .. } => MeshError::Parse {
            path: args.mesh.clone(),
            line: 0,
            message: e.to_string(),
        },
        e => e,
    })?;
    let laplacian = args.laplacian();
    let (mesh, load_report, cloud, splats) = match shape {
        Shape::Mesh(mesh, report) => (mesh, report, None, None),
        Shape::Cloud(cloud) => {
            if !args.repair.is_empty() {
                return Err(CliError::Usage(format!(
                    "{name} is a point cloud: --repair applies to meshes (merge duplicate points beforehand)"
                )));
            }
            let ops = progress::run("local triangulations of the point cloud", || {
                assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())
            })?;
            progress::note(&format!(
                "{name}: a point cloud of {} points; operators from the {} nearest neighbours ({} triangles)",
                cloud.n_points(),
                ops.report.n_neighbours,
                ops.report.n_triangles
            ));
            let report = LoadReport {
                format: MeshFormat::Ply,
                welded_vertices: 0,
                triangulated_polygons: 0,
                notes: vec!["point cloud".into()],
            };
            let splats = Splats::from_triangles(cloud.positions().to_vec(), ops.normals, ops.neighbourhood.faces())?;
            (ops.neighbourhood, report, Some(cloud), Some(splats))
        }
    };
    let file_vertices = mesh.n_vertices();
    let mut input = Input {
        mesh,
        load_report: Some(load_report),
        repair: None,
        file_vertices,
        name,
        cloud,
        splats,
        laplacian,
        volume: None,
    };
    if !args.repair.is_empty() {
        let (repaired, report) = progress::run("repairing", || repair(&input.mesh, &opts))?;
        report_repair(args, &input.mesh, &repaired, &report);
        input.mesh = repaired;
        input.repair = Some(report);
        if input.renumbered() {
            progress::warn(&format!(
                "the vertex numbering changed ({} vertices in the file, {} after the repair): per-vertex outputs \
                 refer to the repaired mesh; --source/--from take vertex numbers of the file, --field files may have \
                 one value per vertex of the file or of the repaired mesh",
                input.file_vertices,
                input.mesh.n_vertices()
            ));
        }
    }
    Ok(input)
}

fn report_repair(args: &MeshArgs, before: &TriMesh, after: &TriMesh, report: &RepairReport) {
    let flags = repair_flags(args);
    if report.is_unchanged() {
        progress::note(&format!("{flags}: nothing to repair"));
        return;
    }
    for line in report.summary().lines().skip(1) {
        progress::note(&format!("{flags}: {}", line.trim()));
    }
    progress::note(&format!(
        "{flags}: {} → {} vertices, {} → {} faces",
        before.n_vertices(),
        after.n_vertices(),
        before.n_faces(),
        after.n_faces()
    ));
}

/// [`read_input`] followed by validation: the mesh must assemble.
///
/// # Errors
/// Those of [`read_input`]; the first fatal problem of [`mesh_fem::validate`].
pub fn read_usable(args: &MeshArgs) -> Result<Input, CliError> {
    let input = read_input(args)?;
    if input.cloud.is_some() {
        return Ok(input);
    }
    if let Some(volume) = &input.volume {
        super::volume::check_usable(&input.name, volume)?;
        return Ok(input);
    }
    let report = progress::run("validating", || {
        Ok::<_, CliError>(mesh_fem::validate::validate(&input.mesh))
    })?;
    let non_manifold = report
        .warnings()
        .filter(|p| {
            matches!(
                p,
                mesh_fem::validate::Problem::NonManifoldEdge { .. }
                    | mesh_fem::validate::Problem::NonManifoldVertex { .. }
            )
        })
        .count();
    let robust = matches!(input.laplacian, Laplacian::Robust(_));
    if non_manifold > 0 && !robust {
        progress::warn(&format!(
            "{}: {non_manifold} non-manifold edges or vertices: the cotangent L can have positive off-diagonal \
             entries there and heat can go negative; --laplacian {} gives an M-matrix",
            input.name,
            Laplacian::Robust(mesh_fem::RobustParams::default()).name()
        ));
    }
    if robust {
        // The robust Laplacian takes degenerate faces (mollified); only what it refuses is fatal.
        say_warnings(&input.name, &report);
        return Ok(input);
    }
    say_warnings(&input.name, &report);
    report.into_result()?;
    Ok(input)
}

/// A shape of a collection (`wfem retrieval`): a mesh, validated without its warnings (one
/// line per open scan would bury the report), or a point cloud as read (its operators are
/// built when it is described). With the robust Laplacian a mesh's problems are not fatal
/// (it takes degenerate and non-manifold faces), as in [`read_usable`].
///
/// # Errors
/// Reading errors; the first fatal problem of [`mesh_fem::validate`] (cotangent Laplacian).
pub fn load_shape_quietly(path: &Path, laplacian: Laplacian) -> Result<Shape, CliError> {
    if path.is_dir() {
        return Err(CliError::Usage(format!(
            "{} is a directory, not a mesh or point-cloud file",
            path.display()
        )));
    }
    if mesh_fem::io::volume::VolumeFormat::from_path(path).is_some() {
        return Err(CliError::Usage(format!(
            "{} is a tetrahedral mesh: retrieval describes surfaces and point clouds (heat, hks, wks, geodesic and info take volumes)",
            path.display()
        )));
    }
    let shape = load_shape(path, &LoadOptions::default())?;
    if let Shape::Mesh(mesh, _) = &shape {
        if !matches!(laplacian, Laplacian::Robust(_)) {
            mesh_fem::validate::validate(mesh).into_result()?;
        }
    }
    Ok(shape)
}

/// The warnings of `wfem info` about a usable mesh, once per kind and one line each, with the
/// `--repair` that applies (non-manifold edges and vertices, components, duplicate faces,
/// orientation; an open mesh is a note: its natural boundary conditions are a fact, not a
/// defect).
fn say_warnings(name: &str, report: &mesh_fem::validate::ValidationReport) {
    let summary = report.summary_with(&cli_fix);
    for line in summary.lines().skip(1) {
        let Some(text) = line.trim().strip_prefix("warning: ") else {
            continue;
        };
        let boundary = report
            .warnings()
            .find(|p| matches!(p, mesh_fem::validate::Problem::Boundary { .. }));
        if boundary.is_some_and(|p| text.starts_with(&p.to_string())) {
            progress::note(&format!("{name}: {text}"));
        } else {
            progress::warn(&format!("{name}: {text}"));
        }
    }
}

/// A remedy in the command line's words: the `--repair` steps or the flag that does it.
pub fn cli_fix(remedy: Remedy) -> String {
    match (remedy, RepairStep::for_remedy(remedy)) {
        // Dropping faces can leave vertices in no face: both steps.
        (Remedy::DropDegenerateFaces, Some(step)) => {
            format!("--repair {},{}", step.name(), RepairStep::Unreferenced.name())
        }
        (_, Some(step)) => format!("--repair {}", step.name()),
        (Remedy::TriangulatePolygons, None) => "pass --triangulate (fan triangulation)".to_string(),
        (Remedy::ScaleDown, None) => "scale the mesh coordinates down".to_string(),
        (other, None) => other.in_library().to_string(),
    }
}

/// The message of a mesh error as the CLI prints it: its remedy in flags ([`cli_fix`]), and
/// the weld tolerance named by its flag.
pub fn mesh_message(e: &MeshError) -> String {
    match e {
        MeshError::InvalidRepairOption { option, message } if *option == "merge_duplicate_vertices" => {
            format!("--weld-tolerance: {message}")
        }
        _ => e.message_with(&cli_fix),
    }
}
