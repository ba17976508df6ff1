//! Atomic writing of per-vertex fields (PLY/NPY/CSV) and meshes (OFF/OBJ/PLY), and reading
//! fields back (NPY/CSV).

use super::parse_error;
use super::text::{parse_f64, show, Lines};
use super::{write_atomic, AtomicSet};
use crate::{MeshError, TriMesh};
use std::io::Write;
use std::path::Path;
use wfem_base::Choice;

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn unsupported(path: &Path, supported: &str) -> MeshError {
    MeshError::UnknownFormat {
        path: path.to_path_buf(),
        extension: format!("{} (supported here: {supported})", extension(path)),
    }
}

/// Every field has one value per vertex (of `n`), finite (or `+∞` when `allow_infinity`);
/// `colors` too has one per vertex. Shared by every field writer (PLY, NPY, CSV, VTU).
pub(super) fn check_fields(
    path: &Path,
    n: usize,
    fields: &[(&str, &[f64])],
    colors: Option<&[[u8; 3]]>,
    allow_infinity: bool,
) -> Result<(), MeshError> {
    for (name, values) in fields {
        if values.len() != n {
            return Err(MeshError::FieldLength {
                path: path.to_path_buf(),
                name: (*name).to_string(),
                expected: n,
                found: values.len(),
            });
        }
        let bad = |v: f64| !(v.is_finite() || (allow_infinity && v == f64::INFINITY));
        if let Some((vertex, &value)) = values.iter().enumerate().find(|(_, v)| bad(**v)) {
            return Err(MeshError::NonFiniteValue {
                path: path.to_path_buf(),
                name: (*name).to_string(),
                vertex,
                value,
            });
        }
    }
    if let Some(c) = colors {
        if c.len() != n {
            return Err(MeshError::FieldLength {
                path: path.to_path_buf(),
                name: "colors".to_string(),
                expected: n,
                found: c.len(),
            });
        }
    }
    Ok(())
}

fn invalid_name(path: &Path, name: &str, why: &str) -> MeshError {
    MeshError::Invalid {
        reason: format!("{}: field name {name:?} {why}", path.display()),
    }
}

/// No field name appears twice (PLY properties, VTU arrays).
pub(super) fn unique_names(path: &Path, fields: &[(&str, &[f64])]) -> Result<(), MeshError> {
    for (i, (name, _)) in fields.iter().enumerate() {
        if fields[..i].iter().any(|(other, _)| other == name) {
            return Err(invalid_name(path, name, "appears twice"));
        }
    }
    Ok(())
}

/// `fields` must not be empty: `file` ("an NPY file", …) holds at least one.
pub(super) fn require_fields(path: &Path, fields: &[(&str, &[f64])], file: &str) -> Result<(), MeshError> {
    if fields.is_empty() {
        let why = format!("list is empty: {file} needs at least one field");
        return Err(invalid_name(path, "", &why));
    }
    Ok(())
}

/// A file format for per-vertex fields ([`write_field`], [`read_field`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FieldFormat {
    /// Binary little-endian PLY: the mesh with one `double` vertex property per field.
    Ply,
    /// NumPy `.npy`: an n × k float64 array (1-D for one field).
    Npy,
    /// Comma-separated values with a header line of field names.
    Csv,
    /// VTK XML unstructured grid (ParaView): the points, the cells and one array per field.
    Vtu,
}

wfem_base::registry! {
    FieldFormat as "field format" {
        FieldFormat::Ply = FieldFormat::Ply => "ply":
            "binary PLY: the mesh with one double vertex property per field (MeshLab, Polyscope)",
        FieldFormat::Npy = FieldFormat::Npy => "npy": "NumPy .npy: an n × k float64 array",
        FieldFormat::Csv = FieldFormat::Csv => "csv": "comma-separated values with a header of field names",
        FieldFormat::Vtu = FieldFormat::Vtu => "vtu":
            "VTK XML unstructured grid (ParaView): the mesh's triangles or the volume's tetrahedra, one array per field",
    }
}

impl FieldFormat {
    /// Whether [`read_field`] reads fields in this format (NPY and CSV: one value per vertex).
    pub fn readable(self) -> bool {
        matches!(self, FieldFormat::Npy | FieldFormat::Csv)
    }

    /// The extensions [`read_field`] reads, as a message lists them (`.npy, .csv`).
    pub fn readable_extensions() -> String {
        <Self as wfem_base::Choice>::entries()
            .iter()
            .filter(|e| Self::from_extension(e.name).is_some_and(Self::readable))
            .map(|e| format!(".{}", e.name))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The extensions, as a message lists them (`.ply, .npy, .csv`).
    pub fn extensions() -> String {
        <Self as wfem_base::Choice>::names()
            .map(|n| format!(".{n}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The format named by a file extension (its registry name; case-insensitive, without the
    /// dot), if any.
    pub fn from_extension(extension: &str) -> Option<Self> {
        <Self as wfem_base::Choice>::parse(extension).ok()
    }

    /// The format of a path, judged by its extension.
    ///
    /// # Errors
    /// [`MeshError::UnknownFormat`] if the extension is missing or names no field format.
    pub fn from_path(path: &Path) -> Result<Self, MeshError> {
        Self::from_extension(&extension(path)).ok_or_else(|| unsupported(path, &Self::extensions()))
    }
}

/// Writes per-vertex fields for `mesh`, atomically ([`write_atomic`]); the format follows
/// the extension ([`FieldFormat::from_path`]):
///
/// * `.ply`: binary little-endian PLY with `double x, y, z`, one `double` vertex property per
///   field (named as given, reduced to letters, digits and `_` so that every PLY reader accepts it), optional `uchar red, green, blue`, and the faces as
///   `list uchar int vertex_indices`. Viewers such as MeshLab and Polyscope show the fields.
/// * `.npy`: an n × k float64 array in C order (1-D of length n when k = 1), NPY format 1.0.
/// * `.csv`: a header line with the field names, then one row per vertex (values printed with
///   Rust's shortest round-trip representation, so reading them back is exact).
/// * `.vtu`: VTK XML unstructured grid of the triangles with one point-data array per field
///   ([`super::vtu`], which also writes a volume's tetrahedra).
///
/// `colors` is used by PLY only.
///
/// # Errors
/// [`MeshError::FieldLength`] if a field (or `colors`) does not have one value per vertex,
/// [`MeshError::NonFiniteValue`] for NaN/∞, [`MeshError::Invalid`] for an unusable field name
/// or no field for NPY/CSV, [`MeshError::UnknownFormat`] for another extension,
/// [`MeshError::Io`] on write failure.
pub fn write_field(
    path: &Path,
    mesh: &TriMesh,
    fields: &[(&str, &[f64])],
    colors: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    let format = FieldFormat::from_path(path)?;
    let mut set = AtomicSet::new();
    stage_field(&mut set, path, format, mesh, fields, colors)?;
    set.commit()
}

/// [`write_field`] in a given format, staged in `set` so that it lands together with the
/// set's other files ([`AtomicSet::commit`]).
///
/// # Errors
/// As [`write_field`] (but for the format, which is given).
pub fn stage_field(
    set: &mut AtomicSet,
    path: &Path,
    format: FieldFormat,
    mesh: &TriMesh,
    fields: &[(&str, &[f64])],
    colors: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    stage_field_with(set, path, format, mesh, fields, colors, false)
}

/// [`stage_field`] that also writes `+∞` (e.g. the distance to a vertex no source reaches:
/// `inf` in CSV, IEEE ∞ in PLY and NPY) when `allow_infinity`; NaN and −∞ are always refused.
///
/// # Errors
/// As [`stage_field`].
pub fn stage_field_with(
    set: &mut AtomicSet,
    path: &Path,
    format: FieldFormat,
    mesh: &TriMesh,
    fields: &[(&str, &[f64])],
    colors: Option<&[[u8; 3]]>,
    allow_infinity: bool,
) -> Result<(), MeshError> {
    check_fields(path, mesh.n_vertices(), fields, colors, allow_infinity)?;
    match format {
        FieldFormat::Ply => {
            const RESERVED: [&str; 6] = ["x", "y", "z", "red", "green", "blue"];
            for (i, (name, _)) in fields.iter().enumerate() {
                if name.is_empty() || !name.chars().all(|c| c.is_ascii_graphic()) {
                    return Err(invalid_name(
                        path,
                        name,
                        "must be non-empty printable ASCII without spaces",
                    ));
                }
                if RESERVED.contains(name) {
                    return Err(invalid_name(path, name, "collides with a PLY vertex property"));
                }
                if fields[..i].iter().any(|(other, _)| other == name) {
                    return Err(invalid_name(path, name, "appears twice"));
                }
            }
            set.stage(path, |w| write_ply(w, mesh, fields, colors))
        }
        FieldFormat::Npy | FieldFormat::Csv => {
            stage_table(set, path, format, mesh.n_vertices(), fields, allow_infinity)
        }
        FieldFormat::Vtu => super::vtu::stage_vtu(
            set,
            path,
            mesh.positions(),
            super::vtu::Cells::Triangles(mesh.faces()),
            fields,
            allow_infinity,
        ),
    }
}

/// Named columns of `rows` values each (not tied to a mesh: a spectrum, a signature) as NPY
/// (an array of shape (rows,) or (rows, k)) or CSV (a header of the names, shortest round-trip
/// values), staged in `set`; the per-vertex NPY and CSV of [`stage_field`] are this with
/// rows = n.
///
/// # Errors
/// [`MeshError::FieldLength`] for a column of another length, [`MeshError::NonFiniteValue`]
/// for NaN/∞, [`MeshError::Invalid`] for no column or an unusable name,
/// [`MeshError::Invalid`] for PLY or VTU (they hold a mesh).
pub fn stage_columns(
    set: &mut AtomicSet,
    path: &Path,
    format: FieldFormat,
    rows: usize,
    fields: &[(&str, &[f64])],
) -> Result<(), MeshError> {
    stage_table(set, path, format, rows, fields, false)
}

/// [`stage_columns`], also writing +∞ when `allow_infinity` ([`stage_field_with`]).
fn stage_table(
    set: &mut AtomicSet,
    path: &Path,
    format: FieldFormat,
    rows: usize,
    fields: &[(&str, &[f64])],
    allow_infinity: bool,
) -> Result<(), MeshError> {
    check_fields(path, rows, fields, None, allow_infinity)?;
    match format {
        FieldFormat::Npy => {
            require_fields(path, fields, "an NPY file")?;
            set.stage(path, |w| write_npy(w, rows, fields))
        }
        FieldFormat::Csv => {
            require_fields(path, fields, "a CSV file")?;
            for (name, _) in fields {
                if name.contains([',', '"', '\n', '\r']) {
                    return Err(invalid_name(path, name, "contains a comma, quote or line break"));
                }
            }
            set.stage(path, |w| {
                let names: Vec<&str> = fields.iter().map(|(n, _)| *n).collect();
                writeln!(w, "{}", names.join(","))?;
                for i in 0..rows {
                    for (k, (_, values)) in fields.iter().enumerate() {
                        if k > 0 {
                            w.write_all(b",")?;
                        }
                        write!(w, "{:?}", values[i])?;
                    }
                    w.write_all(b"\n")?;
                }
                Ok(())
            })
        }
        FieldFormat::Ply | FieldFormat::Vtu => Err(MeshError::Invalid {
            reason: format!(
                "{}: a table of values is written as .npy or .csv (a .{} file holds a mesh)",
                path.display(),
                format.name()
            ),
        }),
    }
}

/// PLY property names every reader accepts (ours, plyfile, MeshLab): letters, digits and `_`;
/// any other character (the `.` of `t0.002`, a sign, a space) becomes `_`, and a name that then
/// repeats an earlier one (or x, y, z) gets a numeric suffix.
pub(crate) fn ply_property_names<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut taken: Vec<String> = ["x", "y", "z", "red", "green", "blue"].map(String::from).to_vec();
    let mut out = Vec::new();
    for name in names {
        let mut clean: String = name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' })
            .collect();
        if clean.is_empty() {
            clean.push_str("field");
        }
        let base = clean.clone();
        let mut k = 1;
        while taken.contains(&clean) {
            k += 1;
            clean = format!("{base}_{k}");
        }
        taken.push(clean.clone());
        out.push(clean);
    }
    out
}

fn write_ply(
    w: &mut dyn Write,
    mesh: &TriMesh,
    fields: &[(&str, &[f64])],
    colors: Option<&[[u8; 3]]>,
) -> std::io::Result<()> {
    let n = mesh.n_vertices();
    writeln!(w, "ply\nformat binary_little_endian 1.0\ncomment written by wfem")?;
    writeln!(w, "element vertex {n}")?;
    writeln!(w, "property double x\nproperty double y\nproperty double z")?;
    for name in ply_property_names(fields.iter().map(|(name, _)| *name)) {
        writeln!(w, "property double {name}")?;
    }
    if colors.is_some() {
        writeln!(w, "property uchar red\nproperty uchar green\nproperty uchar blue")?;
    }
    writeln!(w, "element face {}", mesh.n_faces())?;
    writeln!(w, "property list uchar int vertex_indices\nend_header")?;
    for (i, p) in mesh.positions().iter().enumerate() {
        for c in p {
            w.write_all(&c.to_le_bytes())?;
        }
        for (_, values) in fields {
            w.write_all(&values[i].to_le_bytes())?;
        }
        if let Some(c) = colors {
            w.write_all(&c[i])?;
        }
    }
    for f in mesh.faces() {
        w.write_all(&[3u8])?;
        for &i in f {
            // Indices are < n_vertices, which a PLY `int` holds for any mesh we can store.
            w.write_all(&(i as i32).to_le_bytes())?;
        }
    }
    Ok(())
}

/// NPY 1.0: magic, version, u16 header length, a Python-dict header padded with spaces so that
/// the data starts at a multiple of 64 bytes, then the raw little-endian float64 data.
fn write_npy(w: &mut dyn Write, n: usize, fields: &[(&str, &[f64])]) -> std::io::Result<()> {
    let shape = if fields.len() == 1 {
        format!("({n},)")
    } else {
        format!("({n}, {})", fields.len())
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}");
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    w.write_all(b"\x93NUMPY\x01\x00")?;
    let len = u16::try_from(header.len())
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidInput, "NPY header too long"))?;
    w.write_all(&len.to_le_bytes())?;
    w.write_all(header.as_bytes())?;
    for i in 0..n {
        for (_, values) in fields {
            w.write_all(&values[i].to_le_bytes())?;
        }
    }
    Ok(())
}

/// Reads one per-vertex field for a mesh with `n_vertices` vertices.
///
/// * `.npy`: float64 or float32 (either byte order), shape `(n,)` or `(n, 1)`.
/// * `.csv`: one value per line; a first line that is not a number is taken as a header;
///   blank lines are skipped; a leading UTF-8 byte order mark (written by Excel and many
///   Windows tools) is ignored.
///
/// Only regular files are read ([`super::read_regular_file`]): a FIFO is refused, not waited on.
///
/// # Errors
/// [`MeshError::FieldLength`] if the field does not have `n_vertices` values,
/// [`MeshError::NonFiniteValue`] for NaN/∞, [`MeshError::Parse`] for malformed files,
/// [`MeshError::UnknownFormat`] for another extension, [`MeshError::Io`] if unreadable.
pub fn read_field(path: &Path, n_vertices: usize) -> Result<Vec<f64>, MeshError> {
    let format = match FieldFormat::from_path(path) {
        Ok(f) if f.readable() => f,
        _ => return Err(unsupported(path, &FieldFormat::readable_extensions())),
    };
    let bytes = super::read_regular_file(path)?;
    let values = match format {
        FieldFormat::Npy => parse_npy(&bytes, path)?,
        _ => parse_csv(&bytes, path)?,
    };
    let name = path
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    if values.len() != n_vertices {
        return Err(MeshError::FieldLength {
            path: path.to_path_buf(),
            name,
            expected: n_vertices,
            found: values.len(),
        });
    }
    if let Some((vertex, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(MeshError::NonFiniteValue {
            path: path.to_path_buf(),
            name,
            vertex,
            value,
        });
    }
    Ok(values)
}

/// Value of `'key': value` in an NPY header dict (a tiny, sufficient reading of the literal).
fn npy_entry<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let start = header.find(&format!("'{key}'"))? + key.len() + 2;
    let rest = header[start..].trim_start().strip_prefix(':')?.trim_start();
    let end = if rest.starts_with('(') {
        rest.find(')')? + 1
    } else {
        rest.find([',', '}']).unwrap_or(rest.len())
    };
    Some(rest[..end].trim())
}

fn parse_npy(bytes: &[u8], path: &Path) -> Result<Vec<f64>, MeshError> {
    let (values, dims) = parse_npy_array(bytes, path)?;
    match dims.as_slice() {
        [_] | [_, 1] => Ok(values),
        _ => Err(parse_error(
            path,
            0,
            format!("NPY: shape {dims:?} is not (n,) or (n, 1)"),
        )),
    }
}

/// A float64/float32 NPY array (either byte order) as its values in C order and its shape
/// (a Fortran-order array is transposed into C order).
pub(crate) fn parse_npy_array(bytes: &[u8], path: &Path) -> Result<(Vec<f64>, Vec<usize>), MeshError> {
    let bad = |m: String| parse_error(path, 0, format!("NPY: {m}"));
    if !bytes.starts_with(b"\x93NUMPY") {
        return Err(bad("missing the \\x93NUMPY magic".into()));
    }
    let major = *bytes.get(6).ok_or_else(|| bad("truncated preamble".into()))?;
    let (len, start): (usize, usize) = match major {
        1 => {
            let b = bytes.get(8..10).ok_or_else(|| bad("truncated preamble".into()))?;
            (usize::from(u16::from_le_bytes([b[0], b[1]])), 10)
        }
        2 | 3 => {
            let b = bytes.get(8..12).ok_or_else(|| bad("truncated preamble".into()))?;
            let l = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            (usize::try_from(l).map_err(|_| bad("header too long".into()))?, 12)
        }
        v => return Err(bad(format!("unsupported format version {v}"))),
    };
    let header_bytes = bytes
        .get(start..start.saturating_add(len))
        .ok_or_else(|| bad("truncated header".into()))?;
    let header = std::str::from_utf8(header_bytes).map_err(|_| bad("header is not text".into()))?;
    let descr = npy_entry(header, "descr").ok_or_else(|| bad("header has no 'descr'".into()))?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let (width, little) = match descr {
        "<f8" => (8, true),
        ">f8" => (8, false),
        "<f4" => (4, true),
        ">f4" => (4, false),
        other => return Err(bad(format!("dtype {other:?} is not float64/float32"))),
    };
    let shape = npy_entry(header, "shape").ok_or_else(|| bad("header has no 'shape'".into()))?;
    let dims: Vec<usize> = shape
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>().map_err(|_| bad(format!("bad shape {shape}"))))
        .collect::<Result<_, _>>()?;
    let fortran = npy_entry(header, "fortran_order").is_some_and(|v| v.starts_with("True"));
    let n = dims
        .iter()
        .try_fold(1usize, |acc, &d| acc.checked_mul(d))
        .ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let data = bytes.get(start + len..).unwrap_or(&[]);
    let needed = n
        .checked_mul(width)
        .ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    if data.len() < needed {
        return Err(bad(format!(
            "shape {shape} needs {needed} data bytes, the file has {}",
            data.len()
        )));
    }
    let values: Vec<f64> = data[..needed]
        .chunks_exact(width)
        .map(|c| match (width, little) {
            (8, true) => f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]),
            (8, false) => f64::from_be_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]),
            (_, true) => f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            (_, false) => f64::from(f32::from_be_bytes([c[0], c[1], c[2], c[3]])),
        })
        .collect();
    if fortran && dims.len() == 2 {
        let (rows, cols) = (dims[0], dims[1]);
        let values: Vec<f64> = (0..rows * cols).map(|k| values[(k % cols) * rows + k / cols]).collect();
        return Ok((values, dims));
    }
    if fortran && dims.len() > 2 {
        return Err(bad(format!("a Fortran-order array of shape {shape} is not supported")));
    }
    Ok((values, dims))
}

fn parse_csv(bytes: &[u8], path: &Path) -> Result<Vec<f64>, MeshError> {
    // Without this, "\u{feff}1.5" on the first line read as a non-numeric header and the field
    // lost its first value (issue #16).
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let mut values = Vec::with_capacity(bytes.len() / 8);
    let mut first = true;
    for (line_no, line) in Lines::new(bytes) {
        let t = line.trim_ascii();
        if t.is_empty() {
            continue;
        }
        if t.contains(&b',') {
            return Err(parse_error(
                path,
                line_no,
                "expected one value per line (a single-column field)",
            ));
        }
        match parse_f64(t) {
            Some(v) => values.push(v),
            // A non-numeric first line is a header (e.g. the field name).
            None if first => {}
            None => {
                return Err(parse_error(
                    path,
                    line_no,
                    format!("cannot read {:?} as a number", show(t)),
                ))
            }
        }
        first = false;
    }
    Ok(values)
}

/// Writes a mesh atomically ([`write_atomic`]) as `.off`, `.obj` or `.ply` (binary
/// little-endian, `double` coordinates). ASCII coordinates use Rust's shortest round-trip
/// representation, so reading the file back gives bit-identical positions.
///
/// # Errors
/// [`MeshError::UnknownFormat`] for another extension, [`MeshError::Io`] on write failure.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), MeshError> {
    match extension(path).as_str() {
        "off" => write_atomic(path, |w| {
            writeln!(w, "OFF\n{} {} 0", mesh.n_vertices(), mesh.n_faces())?;
            for [x, y, z] in mesh.positions() {
                writeln!(w, "{x:?} {y:?} {z:?}")?;
            }
            for [a, b, c] in mesh.faces() {
                writeln!(w, "3 {a} {b} {c}")?;
            }
            Ok(())
        }),
        "obj" => write_atomic(path, |w| {
            for [x, y, z] in mesh.positions() {
                writeln!(w, "v {x:?} {y:?} {z:?}")?;
            }
            for [a, b, c] in mesh.faces() {
                writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
            }
            Ok(())
        }),
        "ply" => write_atomic(path, |w| write_ply(w, mesh, &[], None)),
        _ => Err(unsupported(path, ".off, .obj, .ply")),
    }
}
