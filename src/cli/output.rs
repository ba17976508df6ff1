//! Output paths, checked before any work, and the one writer of per-vertex fields (PLY, NPY
//! with its `.json` sidecar, CSV, PNG figures), all through [`mesh_fem::io::AtomicSet`].

use super::progress;
use super::CliError;
use clap::Args;
use mesh_fem::io::{stage_field_with, AtomicSet, FieldFormat};
use mesh_fem::TriMesh;
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};
use wfem_base::Choice;
use wfem_render::{render_png, render_splats_png, symmetric_range, Colormap, Frame, RenderParams, Splats, Up, View};

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

/// A file name in a folder, for checking the folder ([`check_folder`] looks at its parent).
const PROBE: &str = "wfem-output";

/// The extension of rendered figures.
const PNG: &str = "png";

/// An output path given on the command line, with its format.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Output {
    /// The path as given.
    pub path: PathBuf,
    /// Its format.
    pub format: OutputFormat,
}

impl Output {
    /// The extensions `-o` accepts, as messages list them: the field formats and `.png`.
    pub fn extensions() -> String {
        format!("{}, .{PNG}", FieldFormat::extensions())
    }

    /// Parses an output path (clap value parser): the extension must name a format.
    pub fn parse(text: &str) -> Result<Self, String> {
        let path = PathBuf::from(text);
        let ext = extension(&path);
        let format = match FieldFormat::from_extension(&ext) {
            Some(f) => OutputFormat::Field(f),
            None if ext == PNG => OutputFormat::Png,
            None => {
                return Err(format!(
                    "cannot write {text:?}: the output format is chosen by the extension, one of {}",
                    Self::extensions()
                ))
            }
        };
        if path.file_stem().is_none_or(|s| s.is_empty()) {
            return Err(format!("cannot write {text:?}: the output path names no file"));
        }
        Ok(Self { path, format })
    }

    /// The metadata sidecar of an `.npy` output: `x.npy` → `x.json` (times, field names,
    /// method, kernel, …; NPY itself stores only the numbers).
    pub fn sidecar(&self) -> Option<PathBuf> {
        (self.format == OutputFormat::Field(FieldFormat::Npy)).then(|| self.path.with_extension("json"))
    }

    /// Every file written for fields whose file-name parts are `suffixes` (see
    /// [`Column::suffix`]): the path itself, or for several PNG figures `stem-<suffix>.png`
    /// beside it; plus the sidecar of an `.npy` output.
    pub fn targets(&self, suffixes: &[String]) -> Vec<PathBuf> {
        let mut targets = match (self.format, suffixes.len()) {
            (OutputFormat::Png, n) if n > 1 => {
                let stem = self.path.file_stem().map(|s| s.to_string_lossy()).unwrap_or_default();
                suffixes
                    .iter()
                    .map(|s| self.path.with_file_name(format!("{stem}-{s}.png")))
                    .collect()
            }
            _ => vec![self.path.clone()],
        };
        targets.extend(self.sidecar());
        targets
    }

    /// `--all-pairs` writes a matrix: the output must be an `.npy`.
    ///
    /// # Errors
    /// [`CliError::Usage`] for another format.
    pub fn require_matrix(&self) -> Result<(), CliError> {
        if self.format == OutputFormat::Field(FieldFormat::Npy) {
            Ok(())
        } else {
            Err(CliError::Usage(
                "--all-pairs writes an .npy matrix: give -o D.npy".into(),
            ))
        }
    }

    /// Checks, before any work, that the outputs for fields named by `suffixes` can be
    /// written: see [`check_targets`]. `suffixes` is `None` when the names are known only
    /// after the computation (then the folder and the single-file targets are checked).
    ///
    /// # Errors
    /// [`CliError::Output`] naming the path and the problem; [`CliError::OutOfRange`] for
    /// more than [`super::limits::MAX_FIGURES`] figures.
    pub fn check(&self, suffixes: Option<&[String]>, n_fields: usize, inputs: &[&Path]) -> Result<(), CliError> {
        if self.format == OutputFormat::Png {
            super::limits::count(
                "-o",
                n_fields,
                1,
                super::limits::MAX_FIGURES,
                "number of PNG figures (one per field); write .npy, .csv or .ply for more",
            )?;
        }
        let targets = match suffixes {
            Some(s) => self.targets(s),
            None if self.format == OutputFormat::Png && n_fields > 1 => self.sidecar().into_iter().collect(),
            None => self.targets(&[]),
        };
        check_folder(&self.path)?;
        check_targets(&targets, inputs)
    }
}

/// The extension of a path, lower case ("" if none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Why an output path cannot be used.
fn output_error(path: &Path, reason: impl Into<String>) -> CliError {
    CliError::Output {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// The folder of a path (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The folder of `path` exists, is a folder, and a file can be created in it (probed by
/// creating and removing an empty hidden file).
pub(crate) fn check_folder(path: &Path) -> Result<(), CliError> {
    let dir = folder_of(path);
    match std::fs::metadata(&dir) {
        Err(_) => {
            return Err(output_error(
                path,
                format!("the folder {} does not exist", dir.display()),
            ))
        }
        Ok(m) if !m.is_dir() => return Err(output_error(path, format!("{} is not a folder", dir.display()))),
        Ok(_) => {}
    }
    // A registered temporary (wfem_base::tempfiles): a signal during the probe removes it,
    // and a killed run's probe is removed by the next one here.
    match wfem_base::tempfiles::TempPath::file(&dir.join("wfem-probe")) {
        Ok(_) => Ok(()),
        Err(e) => Err(output_error(
            path,
            format!("cannot create files in {}: {e}", dir.display()),
        )),
    }
}

/// Checks targets before any work: none is a directory or another non-regular file (a FIFO,
/// a device: wfem replaces only regular files), none is an input file, and no two are the
/// same file.
pub fn check_targets(targets: &[PathBuf], inputs: &[&Path]) -> Result<(), CliError> {
    let inputs: Vec<PathBuf> = inputs.iter().filter_map(|p| p.canonicalize().ok()).collect();
    let mut seen: Vec<PathBuf> = Vec::with_capacity(targets.len());
    for target in targets {
        if let Ok(meta) = std::fs::symlink_metadata(target) {
            if meta.is_dir() {
                return Err(output_error(target, "it is a directory"));
            }
            if !meta.is_file() && !meta.file_type().is_symlink() {
                return Err(output_error(
                    target,
                    "it exists and is not a regular file (a FIFO or a device); wfem replaces only regular files",
                ));
            }
        }
        if let Ok(real) = target.canonicalize() {
            if inputs.contains(&real) {
                return Err(output_error(
                    target,
                    "it is an input file; wfem never writes over its input",
                ));
            }
        }
        let resolved = folder_of(target)
            .canonicalize()
            .unwrap_or_else(|_| folder_of(target))
            .join(target.file_name().unwrap_or_default());
        if seen.contains(&resolved) {
            return Err(output_error(target, "two outputs of this run would be written to it"));
        }
        seen.push(resolved);
    }
    Ok(())
}

/// Checks an output folder (`demo --out`, `operators --out`) before any work: it is a folder
/// or can be created (its nearest existing ancestor is a writable folder), and the files that
/// will be written in it pass [`check_targets`].
pub fn check_out_dir(dir: &Path, files: &[&str], inputs: &[&Path]) -> Result<(), CliError> {
    match std::fs::metadata(dir) {
        Ok(m) if !m.is_dir() => return Err(output_error(dir, "it exists and is not a folder")),
        Ok(_) => check_folder(&dir.join(PROBE))?,
        Err(_) => {
            let existing = dir
                .ancestors()
                .skip(1)
                .find(|a| a.as_os_str().is_empty() || a.exists())
                .unwrap_or(Path::new("."));
            let existing = if existing.as_os_str().is_empty() {
                Path::new(".")
            } else {
                existing
            };
            if !existing.is_dir() {
                return Err(output_error(
                    dir,
                    format!("cannot create it: {} is not a folder", existing.display()),
                ));
            }
            check_folder(&existing.join(PROBE))?;
        }
    }
    let targets: Vec<PathBuf> = files.iter().map(|f| dir.join(f)).collect();
    check_targets(&targets, inputs)
}

/// Creates an output folder checked by [`check_out_dir`] (after the work succeeded).
pub fn create_out_dir(dir: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|source| {
        CliError::Mesh(mesh_fem::MeshError::Io {
            path: dir.to_path_buf(),
            source,
        })
    })
}

// ---------------------------------------------------------------------------------------------
// Short numbers for names

/// `x` rounded to `digits` significant digits, printed as briefly as Rust prints a double
/// (`0.01`, `2.5e-5`, `1e300`).
fn short(x: f64, digits: usize) -> String {
    let rounded: f64 = format!("{:.*e}", digits.saturating_sub(1), x).parse().unwrap_or(x);
    // Near the largest double, rounding up overflows: keep every digit there.
    let shown = if rounded.is_finite() { rounded } else { x };
    format!("{shown:?}")
}

/// Short, distinct labels for distinct numbers: 4 significant digits, more only where two
/// values would otherwise print alike (so `0.010000000000000002` prints `0.01`).
pub fn short_labels(values: &[f64]) -> Vec<String> {
    for digits in 4..=17 {
        let labels: Vec<String> = values.iter().map(|&v| short(v, digits)).collect();
        let distinct = labels.iter().enumerate().all(|(i, l)| {
            labels[..i]
                .iter()
                .zip(&values[..i])
                .all(|(m, &w)| m != l || w == values[i])
        });
        if distinct {
            return labels;
        }
    }
    values.iter().map(|v| format!("{v:?}")).collect()
}

/// One short label.
pub fn short_label(value: f64) -> String {
    short(value, 4)
}

// ---------------------------------------------------------------------------------------------
// Rendering options

/// Options of rendered figures (`-o x.png`).
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct RenderArgs {
    /// Up direction of the figures (.png).
    #[arg(long, value_parser = super::choice::choice::<Up>(), default_value = Up::default_name(), allow_hyphen_values = true)]
    pub up: Up,
    /// A volume's figures also show its interior: the cut by the plane AXIS=VALUE (x, y or z,
    /// in the mesh's coordinates, e.g. x=0.1), keeping the side below it; by default the plane
    /// through the centre facing the front view.
    #[arg(long, value_parser = parse_cut, allow_hyphen_values = true)]
    pub cut: Option<([f64; 3], f64)>,
}

/// Parses `--cut AXIS=VALUE`: the axis as `--up` names them (x, -y, …), the plane's normal.
fn parse_cut(text: &str) -> Result<([f64; 3], f64), String> {
    let bad = || {
        format!(
            "{text:?} is not a plane: give AXIS=VALUE with AXIS x, y or z (or -x, …) and a finite VALUE, e.g. x=0.1"
        )
    };
    let (axis, value) = text.rsplit_once('=').ok_or_else(bad)?;
    let normal = match Up::parse(axis.trim()) {
        Ok(Up::Axis(axis)) => Frame::from_up(axis).up,
        _ => return Err(bad()),
    };
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok((normal, v)),
        _ => Err(bad()),
    }
}

impl RenderArgs {
    /// The frame (right, up, front) of the standard views for `mesh`.
    pub fn frame(&self, mesh: &TriMesh) -> Frame {
        self.up.frame(mesh)
    }
}

/// Render parameters for a field: Viridis for one-signed fields, Coolwarm centred on zero for
/// fields that change sign.
pub fn figure_params(title: &str, values: &[f64], highlight: &[u32], views: Vec<View>) -> RenderParams {
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
        views,
        ..RenderParams::default()
    }
}

/// A view facing vertex `v` from outside: along its area-weighted normal (the normal of its
/// splat for a point cloud, whose neighbourhood triangles are not consistently oriented),
/// turned to point away from the centroid (orientation-independent), with the frame's up as
/// screen-up where it can be. `None` for a vertex without faces.
fn source_view(mesh: &TriMesh, splats: Option<&Splats>, v: u32, frame: &Frame) -> Option<View> {
    use mesh_fem::vec3::{cross, dot, norm, sub};
    let positions = mesh.positions();
    let p = *positions.get(v as usize)?;
    let mut normal = [0.0; 3];
    if let Some(splats) = splats {
        normal = *splats.normals().get(v as usize)?;
    } else {
        for f in mesh.faces().iter().filter(|f| f.contains(&v)) {
            let [a, b, c] = f.map(|i| positions[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            normal = [normal[0] + n[0], normal[1] + n[1], normal[2] + n[2]];
        }
    }
    let n = positions.len() as f64;
    let centroid = positions
        .iter()
        .fold([0.0; 3], |s, q| [s[0] + q[0] / n, s[1] + q[1] / n, s[2] + q[2] / n]);
    let out = sub(p, centroid);
    let mut d = if norm(normal) > 0.0 { normal } else { out };
    if dot(d, out) < 0.0 {
        d = d.map(|x| -x);
    }
    let length = norm(d);
    if !(length > 0.0 && length.is_finite()) {
        return None;
    }
    let d = d.map(|x| x / length);
    // Screen-up: the frame's up without its part along d (the front where they are parallel).
    let pick = if norm(cross(frame.up, d)) > 0.1 {
        frame.up
    } else {
        frame.front
    };
    let k = dot(pick, d);
    Some(View::new(
        d,
        [pick[0] - k * d[0], pick[1] - k * d[1], pick[2] - k * d[2]],
    ))
}

/// Vertex colors of a field through Viridis over its range.
pub fn colors_of(values: &[f64]) -> Vec<[u8; 3]> {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    values.iter().map(|&v| Colormap::Viridis.map((v - lo) / span)).collect()
}

// ---------------------------------------------------------------------------------------------
// Writing

/// The values with `+∞` replaced by the largest finite value (0 when none is finite), for colours.
fn finite_for_figures(values: &[f64]) -> Vec<f64> {
    let top = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    let top = if top.is_finite() { top } else { 0.0 };
    values.iter().map(|&v| if v.is_finite() { v } else { top }).collect()
}

/// One per-vertex output field.
#[derive(Clone, Debug)]
pub struct Column {
    /// Its name in PLY/CSV headers and the sidecar (e.g. `t=0.01`).
    pub name: String,
    /// Its part of a figure's file name (e.g. `t0.01` → `x-t0.01.png`).
    pub suffix: String,
    /// The figure's title.
    pub title: String,
    /// The diffusion time it belongs to, if any (recorded in the sidecar).
    pub t: Option<f64>,
    /// One value per vertex.
    pub values: Vec<f64>,
}

/// How the fields are written: the rendering options and vertices to highlight in figures,
/// and the metadata recorded in the `.npy` sidecar.
pub struct Writing<'a> {
    /// Figure options.
    pub render: RenderArgs,
    /// The point cloud as splats, when the input is one: figures draw it instead of the mesh
    /// (its neighbourhood triangles).
    pub splats: Option<&'a Splats>,
    /// Vertices marked in the figures (e.g. the source of K_t e_i).
    pub highlight: &'a [u32],
    /// Metadata of the run (command, mesh, method, kernel, …) for the sidecar.
    pub meta: Map<String, Value>,
    /// `+∞` is a value (a distance no source reaches): written as ∞ (`inf` in CSV), drawn at
    /// the largest finite value in figures. Otherwise every value must be finite.
    pub allow_infinity: bool,
    /// The tetrahedra when the input is a volume: a `.vtu` output holds them (figures and
    /// `.ply` show the boundary surface `mesh`).
    pub volume: Option<&'a mesh_fem::volume::TetMesh>,
}

/// Writes per-vertex fields in the format of `output`, all-or-nothing: `.png` renders one
/// figure per field (the path itself for one field, `stem-<suffix>.png` beside it for several;
/// a point cloud is drawn as splats, in the views chosen from its neighbourhood mesh),
/// `.ply` holds the mesh with one vertex property per field and vertex colors of the first,
/// `.csv` one column per field, `.vtu` the triangles (or a volume's tetrahedra) with one
/// array per field, and `.npy` an n × k array plus its `.json` sidecar.
///
/// # Errors
/// Rendering and writing errors; [`CliError::NonFinite`] if a field holds NaN or ∞.
pub fn write_fields(
    output: &Output,
    mesh: &TriMesh,
    columns: &[Column],
    how: Writing<'_>,
) -> Result<Vec<PathBuf>, CliError> {
    if columns.is_empty() {
        return Err(CliError::Usage("nothing to write".into()));
    }
    let bad = |v: f64| !(v.is_finite() || (how.allow_infinity && v == f64::INFINITY));
    for c in columns {
        if let Some((vertex, &value)) = c.values.iter().enumerate().find(|(_, v)| bad(**v)) {
            return Err(CliError::NonFinite {
                what: c.name.clone(),
                vertex,
                value,
            });
        }
    }
    let suffixes: Vec<String> = columns.iter().map(|c| c.suffix.clone()).collect();
    let targets = output.targets(&suffixes);
    let mut set = AtomicSet::new();
    match output.format {
        OutputFormat::Png => {
            let frame = how.render.frame(mesh);
            let mut views = View::standard_in(&frame);
            // The last (oblique) view looks at the highlighted vertex, so it is seen at least once.
            let source = how
                .highlight
                .first()
                .and_then(|&v| source_view(mesh, how.splats, v, &frame));
            if let Some(view) = source {
                views[3] = view;
            }
            let last = match (source, how.highlight.first()) {
                (Some(_), Some(v)) => format!("facing vertex {v} (red dot)"),
                _ => "oblique".to_string(),
            };
            // The up direction is named when it was guessed (an explicit --up is the user's own).
            let up = if how.render.up == Up::Auto {
                format!(
                    "up is {} (--up auto, from the extents of the mesh; --up x|y|z|-x|-y|-z overrides); ",
                    wfem_render::direction_label(frame.up)
                )
            } else {
                String::new()
            };
            let splatted = match how.splats {
                Some(splats) => format!("; the {} points drawn as splats", splats.len()),
                None => String::new(),
            };
            progress::note(&format!(
                "figures: {up}views from {} (the broadest side), {}, above, and {last}{splatted}",
                wfem_render::direction_label(frame.front),
                wfem_render::direction_label(frame.right),
            ));
            let cut = match how.volume {
                Some(volume) => Some(volume_cut(volume, how.render.cut, &frame)?),
                None => {
                    if how.render.cut.is_some() {
                        progress::warn("--cut shows the interior of a tetrahedral mesh; this input is a surface, so it is not used");
                    }
                    None
                }
            };
            let bar = progress::bar(columns.len(), "rendering figures");
            for (column, target) in columns.iter().zip(&targets) {
                bar.set_detail(&column.suffix);
                let values = finite_for_figures(&column.values);
                let params = figure_params(&column.title, &values, how.highlight, views.clone());
                let png = match (how.splats, &cut) {
                    (Some(splats), _) => render_splats_png(splats, &values, &params)?,
                    (None, Some(cut)) => with_cut(mesh, cut, &values, params, &frame)?,
                    (None, None) => render_png(mesh, &values, &params)?,
                };
                set.stage(target, |w| w.write_all(&png))?;
                bar.inc(&column.suffix);
            }
            bar.done();
        }
        OutputFormat::Field(format) => {
            let step = progress::step(format!("writing {}", output.path.display()));
            let refs: Vec<(&str, &[f64])> = columns.iter().map(|c| (c.name.as_str(), c.values.as_slice())).collect();
            let colors = (format == FieldFormat::Ply).then(|| colors_of(&finite_for_figures(&columns[0].values)));
            match (format, how.volume) {
                (FieldFormat::Vtu, Some(volume)) => mesh_fem::io::vtu::stage_vtu(
                    &mut set,
                    &output.path,
                    volume.positions(),
                    mesh_fem::io::vtu::Cells::Tetrahedra(volume.tets()),
                    &refs,
                    how.allow_infinity,
                )?,
                _ => stage_field_with(
                    &mut set,
                    &output.path,
                    format,
                    mesh,
                    &refs,
                    colors.as_deref(),
                    how.allow_infinity,
                )?,
            }
            if let Some(sidecar) = output.sidecar() {
                let text = sidecar_json(output, mesh, columns, how.meta)?;
                set.stage(&sidecar, |w| w.write_all(text.as_bytes()))?;
            }
            step.done();
        }
    }
    let written: Vec<PathBuf> = set.targets().map(Path::to_path_buf).collect();
    set.commit()?;
    Ok(written)
}

/// A volume's cut for its figures, with the plane's name: `--cut AXIS=VALUE`, or the plane
/// through the centre of the bounding box facing the front view.
pub(super) fn volume_cut(
    volume: &mesh_fem::volume::TetMesh,
    plane: Option<([f64; 3], f64)>,
    frame: &Frame,
) -> Result<(mesh_fem::volume::cut::Cut, [f64; 3], String), CliError> {
    let (normal, offset, name) = match plane {
        Some((n, value)) => {
            let axis = wfem_render::direction_label(n);
            (n, value, format!("{}={value}", axis.trim_start_matches('+')))
        }
        None => {
            let (lo, hi) = mesh_fem::vec3::bounding_box(volume.positions());
            let centre = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
            let n = frame.front;
            (
                n,
                mesh_fem::vec3::dot(centre, n),
                "the centre, facing the front view".to_string(),
            )
        }
    };
    let cut = mesh_fem::volume::cut::cut(volume, normal, offset).map_err(|e| {
        CliError::Usage(format!(
            "--cut {name}: the plane leaves nothing of the volume below it ({e})"
        ))
    })?;
    progress::note(&format!(
        "figures: the interior shown by a cut at {name} ({} triangles), below the surface views",
        cut.mesh.n_faces()
    ));
    Ok((cut, normal, name))
}

/// The figure of a volume's boundary with the figure of its cut below it, on one colour scale.
pub(super) fn with_cut(
    mesh: &TriMesh,
    cut: &(mesh_fem::volume::cut::Cut, [f64; 3], String),
    values: &[f64],
    mut params: wfem_render::RenderParams,
    frame: &Frame,
) -> Result<Vec<u8>, CliError> {
    let (cut, normal, name) = cut;
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    params.range = params.range.or(Some((lo, hi.max(lo))));
    let surface = wfem_render::render_rgb(mesh, values, &params)?;
    // Looking along the plane's normal; a horizontal cut is seen from above, back at the top.
    let vertical = mesh_fem::vec3::dot(*normal, frame.up).abs() > 0.9;
    let screen_up = if vertical { frame.front.map(|x| -x) } else { frame.up };
    let side = View::new(*normal, screen_up);
    let oblique = View::new(
        [0, 1, 2].map(|k| normal[k] + 0.5 * frame.up[k] + 0.5 * frame.right[k]),
        screen_up,
    );
    let inside = wfem_render::RenderParams {
        title: Some(format!("cut at {name}: the interior")),
        highlight: Vec::new(),
        views: vec![side, oblique],
        ..params
    };
    let section = wfem_render::render_rgb(&cut.mesh, &cut.values(values), &inside)?;
    Ok(wfem_render::RgbImage::stacked(&[surface, section]).to_png()?)
}

/// The sidecar of an `.npy` output of per-vertex fields: what its columns are.
fn sidecar_json(
    output: &Output,
    mesh: &TriMesh,
    columns: &[Column],
    mut meta: Map<String, Value>,
) -> Result<String, CliError> {
    if columns.iter().any(|c| c.t.is_some()) {
        meta.insert("times".into(), json!(columns.iter().map(|c| c.t).collect::<Vec<_>>()));
    }
    let names: Vec<&str> = columns.iter().map(|c| c.name.as_str()).collect();
    npy_sidecar(output, mesh.n_vertices(), &names, meta)
}

/// The sidecar of any `.npy` table of `rows` rows and the named columns (per-vertex fields, a
/// spectrum): the wfem version, the data file, its shape and dtype, the column names, then
/// `meta` (the command's own keys).
pub(super) fn npy_sidecar(
    output: &Output,
    rows: usize,
    names: &[&str],
    meta: Map<String, Value>,
) -> Result<String, CliError> {
    let mut doc = Map::new();
    doc.insert("wfem_version".into(), json!(env!("CARGO_PKG_VERSION")));
    doc.insert(
        "data".into(),
        json!(output.path.file_name().map(|f| f.to_string_lossy().into_owned())),
    );
    let shape = if names.len() == 1 {
        json!([rows])
    } else {
        json!([rows, names.len()])
    };
    doc.insert("shape".into(), shape);
    doc.insert("dtype".into(), json!("float64"));
    doc.insert("columns".into(), json!(names));
    doc.extend(meta);
    serde_json::to_string_pretty(&Value::Object(doc)).map_err(|e| CliError::Usage(e.to_string()))
}

/// `--all-pairs` of `distance` and `geodesic`: the n × n matrix streamed to the `.npy` of
/// `output` a block of rows at a time (resumable: `key` names the computation), with a bar, and
/// its sidecar.
///
/// # Errors
/// Those of [`wfem_heat::distance::write_rows`] and of writing the sidecar.
pub fn write_all_pairs(
    output: &Output,
    n: usize,
    key: &str,
    compute: impl Fn(std::ops::Range<usize>, &mut [f64]) -> Result<(), wfem_heat::HeatError>,
    mut meta: Map<String, Value>,
    out: &mut dyn std::io::Write,
) -> Result<(), CliError> {
    output.require_matrix()?;
    let bar = progress::bar(n, "all-pairs rows");
    let mut last = 0;
    let report = wfem_heat::distance::write_rows(&output.path, n, n, key, None, compute, &mut |done, _| {
        bar.inc_by(done - last, &format!("{done}/{n} rows"));
        last = done;
    })?;
    bar.done();
    if report.resumed_from > 0 {
        progress::note(&format!(
            "resumed after the {} rows of an interrupted run",
            report.resumed_from
        ));
    }
    meta.insert("shape".into(), json!([n, n]));
    meta.insert("dtype".into(), json!("float64"));
    meta.insert("rows".into(), json!("row i holds the distances from vertex i"));
    if let Some(sidecar) = output.sidecar() {
        let text = serde_json::to_string_pretty(&Value::Object(meta)).map_err(|e| CliError::Usage(e.to_string()))?;
        mesh_fem::io::write_atomic(&sidecar, |w| w.write_all(text.as_bytes()))?;
        writeln!(out, "wrote {}", sidecar.display())?;
    }
    writeln!(out, "wrote {} ({n} × {n})", report.path.display())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_labels_are_short_and_distinct() {
        assert_eq!(short_labels(&[0.01, 0.1, 1.0]), ["0.01", "0.1", "1.0"]);
        assert_eq!(short_labels(&[0.010000000000000002]), ["0.01"]);
        assert_eq!(short_labels(&[f64::MAX]), ["1.7976931348623157e308"]);
        assert_eq!(short_labels(&[1e300]), ["1e300"]);
        assert_eq!(short_labels(&[2.5e-7]), ["2.5e-7"]);
        assert_eq!(short_labels(&[0.0123456, 0.0123457]), ["0.0123456", "0.0123457"]);
        assert_eq!(short_labels(&[0.01, 0.01]), ["0.01", "0.01"]);
    }

    #[test]
    fn png_sets_and_npy_sidecars_have_their_targets() {
        let png = Output::parse("dir/x.png").unwrap();
        assert_eq!(png.targets(&["t0.01".into()]), [PathBuf::from("dir/x.png")]);
        assert_eq!(
            png.targets(&["t0.01".into(), "t0.1".into()]),
            [PathBuf::from("dir/x-t0.01.png"), PathBuf::from("dir/x-t0.1.png")]
        );
        let npy = Output::parse("x.npy").unwrap();
        assert_eq!(
            npy.targets(&["a".into()]),
            [PathBuf::from("x.npy"), PathBuf::from("x.json")]
        );
        assert!(Output::parse("x.obj")
            .unwrap_err()
            .contains(".ply, .npy, .csv, .vtu, .png"));
        assert!(Output::parse(".png").is_err());
    }
}
