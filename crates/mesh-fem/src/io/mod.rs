//! Reading triangle meshes (OBJ, PLY, OFF, STL) and point clouds (PLY without faces, XYZ,
//! PTS, CSV, NPY: [`load_points`], and [`load_shape`] for either), and writing meshes and
//! per-vertex fields.
//!
//! # Reading
//! [`load`] picks the format from the file extension (case-insensitive) and returns the mesh
//! together with a [`LoadReport`] that says what was changed on the way (welded STL corners,
//! fan-triangulated polygons). [`load_bytes`] does the same for data already in memory, so
//! tests and fuzzers need no files.
//!
//! * Vertex order is the file's order and unreferenced vertices are kept, so a field written
//!   for a mesh lines up with the file as other tools (libigl, potpourri3d, scipy) read it.
//! * Faces with more than three corners are an error ([`MeshError::Polygon`]) unless
//!   [`LoadOptions::triangulate_polygons`] is on; then a face `(v₀, v₁, …, v_{k−1})` becomes
//!   the fan `(v₀, v_{i}, v_{i+1})`, i = 1 … k−2.
//! * Only regular files are read ([`read_regular_file`]): a FIFO, socket, device or directory
//!   is refused with [`MeshError::Io`] before it is opened, because opening a FIFO for reading
//!   blocks until a writer appears (no `O_NONBLOCK` trick: the file type is checked first).
//! * Bad data never panics: truncated or garbage files give [`MeshError::Parse`] with the
//!   1-based line (0 for binary data), NaN/∞ coordinates give
//!   [`MeshError::NonFiniteCoordinate`], indices give [`MeshError::IndexOutOfRange`] or
//!   [`MeshError::NegativeIndex`]. Declared element counts are never trusted for allocation
//!   beyond what the file size allows.
//!
//! # Writing
//! [`write_atomic`] writes through a temporary file in the target directory and renames it
//! into place, so a crash or an error never leaves a half-written file; [`AtomicSet`] does the
//! same for a set of files replaced all-or-nothing. [`write_field`] writes
//! per-vertex fields as PLY (binary little-endian), NPY or CSV; [`read_field`] reads NPY/CSV
//! fields back; [`write_mesh`] writes OFF, OBJ or PLY meshes.

use crate::{MeshError, TriMesh};
use std::path::Path;

mod atomic;
mod field;
mod obj;
mod off;
mod ply;
mod points;
pub mod rows;
mod stl;
mod text;
pub mod volume;
pub mod vtu;

pub use atomic::{write_atomic, AtomicSet};
pub use field::{read_field, stage_columns, stage_field, stage_field_with, write_field, write_mesh, FieldFormat};
pub use points::{load_points, load_shape, read_points, PointFormat, Shape};

/// A supported mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (`v` and `f` records; texture/normal indices ignored).
    Obj,
    /// Stanford PLY, ASCII or binary (little or big endian).
    Ply,
    /// Object File Format (OFF, COFF, NOFF, CNOFF, STOFF, …), ASCII.
    Off,
    /// Stereolithography STL, ASCII or binary.
    Stl,
}

wfem_base::registry! {
    MeshFormat as "mesh format" {
        MeshFormat::Obj = MeshFormat::Obj => "obj": "Wavefront OBJ (v and f records)",
        MeshFormat::Ply = MeshFormat::Ply => "ply": "Stanford PLY, ASCII or binary",
        MeshFormat::Off = MeshFormat::Off => "off": "Object File Format (OFF, COFF, NOFF, …), ASCII",
        MeshFormat::Stl = MeshFormat::Stl => "stl": "stereolithography STL, ASCII or binary",
    }
}

impl MeshFormat {
    /// The format named by a file extension (its registry name; case-insensitive, without the
    /// dot), if any.
    pub fn from_extension(extension: &str) -> Option<Self> {
        <Self as wfem_base::Choice>::parse(extension).ok()
    }

    /// The format of a path, judged by its extension.
    ///
    /// # Errors
    /// [`MeshError::UnknownFormat`] if the extension is missing or names no supported format.
    pub fn from_path(path: &Path) -> Result<Self, MeshError> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        Self::from_extension(&extension).ok_or_else(|| MeshError::UnknownFormat {
            path: path.to_path_buf(),
            extension,
        })
    }
}

/// Options for [`load`] and [`load_bytes`].
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Fan-triangulate faces with more than three corners instead of failing with
    /// [`MeshError::Polygon`]. Off by default, because a silent triangulation changes the
    /// operators a user gets.
    pub triangulate_polygons: bool,
}

impl LoadOptions {
    /// Options with polygon triangulation switched on or off.
    pub fn with_triangulation(triangulate_polygons: bool) -> Self {
        Self { triangulate_polygons }
    }
}

/// What happened while a mesh was read.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadReport {
    /// The format that was read.
    pub format: MeshFormat,
    /// Vertices merged into an earlier vertex with bit-identical position (STL only: STL
    /// stores every triangle corner separately).
    pub welded_vertices: usize,
    /// Polygons (faces with more than three corners) that were fan-triangulated.
    pub triangulated_polygons: usize,
    /// Human-readable remarks (e.g. ignored trailing data or ASCII/binary variant).
    pub notes: Vec<String>,
}

impl LoadReport {
    fn new(format: MeshFormat) -> Self {
        Self {
            format,
            welded_vertices: 0,
            triangulated_polygons: 0,
            notes: Vec::new(),
        }
    }
}

/// Reads a mesh file; the format is chosen by the extension (case-insensitive).
///
/// # Errors
/// [`MeshError::UnknownFormat`] for an unsupported extension, [`MeshError::Io`] if the file
/// cannot be read or is not a regular file ([`read_regular_file`]), and every error of
/// [`load_bytes`].
pub fn load(path: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    let format = MeshFormat::from_path(path)?;
    let bytes = read_regular_file(path)?;
    load_bytes(&bytes, format, path, opts)
}

/// Reads the whole of a regular file (a symbolic link to one is followed).
///
/// The file type is checked with [`std::fs::metadata`] *before* the file is opened: opening a
/// FIFO for reading blocks until some process opens it for writing, and reading a device
/// (`/dev/zero`) or a socket may never end, so anything but a regular file is refused up front.
/// (Checking before opening leaves a window in which the path could be replaced; that needs a
/// deliberate race by someone who can already write to the folder, while the blocking open
/// was reachable by an ordinary mistake such as `wfem heat mesh.off --field <(…)>`.)
///
/// # Errors
/// [`MeshError::Io`] naming `path`: kind `InvalidInput` for a directory, FIFO, socket or
/// device; the operating system's error if the file is missing or unreadable.
pub fn read_regular_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut open_regular_file(path)?, &mut bytes).map_err(|e| io_error(path, e))?;
    Ok(bytes)
}

/// Opens a file for reading after checking that it is a regular file (see
/// [`read_regular_file`]), e.g. to read only its header.
///
/// # Errors
/// As [`read_regular_file`].
pub fn open_regular_file(path: &Path) -> Result<std::fs::File, MeshError> {
    let meta = std::fs::metadata(path).map_err(|e| io_error(path, e))?;
    if !meta.file_type().is_file() {
        return Err(io_error(
            path,
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "{} is not a regular file; only regular files are read",
                    wfem_base::fs::file_kind(&meta.file_type())
                ),
            ),
        ));
    }
    std::fs::File::open(path).map_err(|e| io_error(path, e))
}

/// Reads a mesh of the given format from memory. `name` is only used in error messages.
///
/// # Errors
/// [`MeshError::Parse`] for malformed data (with the 1-based line, 0 for binary data),
/// [`MeshError::Polygon`] for a face with more than three corners unless
/// `opts.triangulate_polygons`, [`MeshError::NegativeIndex`], [`MeshError::IndexOutOfRange`],
/// [`MeshError::NonFiniteCoordinate`] and [`MeshError::Empty`].
pub fn load_bytes(
    bytes: &[u8],
    format: MeshFormat,
    name: &Path,
    opts: &LoadOptions,
) -> Result<(TriMesh, LoadReport), MeshError> {
    match format {
        MeshFormat::Obj => read_obj(bytes, name, opts),
        MeshFormat::Ply => read_ply(bytes, name, opts),
        MeshFormat::Off => read_off(bytes, name, opts),
        MeshFormat::Stl => read_stl(bytes, name, opts),
    }
}

/// Reads an OBJ mesh from memory (`v` and `f` records; `f` corners may be `v`, `v/vt`,
/// `v/vt/vn` or `v//vn`; negative indices count back from the last vertex read; values after
/// x y z on a `v` line (w or colours) and `l`/`p` records are ignored). `o`/`g`
/// groups share the one vertex list of the file, so the mesh stays connected across groups.
/// Records with other keywords (`vt`, `vn`, `usemtl`, …) are skipped, but a keyword that is not
/// made of ASCII letters, digits and `_` is a [`MeshError::Parse`] naming its line: the data
/// is binary or not OBJ at all. A leading UTF-8 byte order mark is ignored.
///
/// # Errors
/// See [`load_bytes`].
pub fn read_obj(bytes: &[u8], name: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    obj::read(bytes, name, opts)
}

/// Reads a PLY mesh (ASCII, binary little or big endian) from memory: `x`, `y`, `z` of the
/// `vertex` element (any scalar type) and the `vertex_indices` or `vertex_index` list of the
/// `face` element (any integer type). Other properties and elements are skipped. In ASCII
/// PLY a non-blank line after the last declared element is a [`MeshError::Parse`] naming that
/// line (the header declares too few elements, and the extra records would otherwise be
/// dropped); in binary PLY extra bytes at the end are reported in [`LoadReport::notes`].
///
/// # Errors
/// See [`load_bytes`].
pub fn read_ply(bytes: &[u8], name: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    ply::read(bytes, name, opts)
}

/// Reads an ASCII OFF mesh (OFF, COFF, NOFF, CNOFF, STOFF headers; `#` comments; colours
/// after vertex coordinates or face indices are ignored) from memory.
///
/// # Errors
/// See [`load_bytes`].
pub fn read_off(bytes: &[u8], name: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    off::read(bytes, name, opts)
}

/// Reads an ASCII or binary STL mesh from memory and welds corners with bit-identical
/// positions into shared vertices (the count is [`LoadReport::welded_vertices`]).
///
/// # Errors
/// See [`load_bytes`].
pub fn read_stl(bytes: &[u8], name: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    stl::read(bytes, name, opts)
}

/// Collects faces, turning polygons into fans or into [`MeshError::Polygon`].
pub(crate) struct FaceSink<'a> {
    pub faces: Vec<[u32; 3]>,
    triangulate: bool,
    pub triangulated: usize,
    path: &'a Path,
    n_records: usize,
}

impl<'a> FaceSink<'a> {
    pub fn new(path: &'a Path, triangulate: bool, capacity: usize) -> Self {
        Self {
            faces: Vec::with_capacity(capacity),
            triangulate,
            triangulated: 0,
            path,
            n_records: 0,
        }
    }

    /// Number of face records pushed so far (the 0-based index of the next record).
    pub fn records(&self) -> usize {
        self.n_records
    }

    /// Adds one face record (corners already resolved to 0-based indices). `line` is used for
    /// the error of a face with fewer than three corners.
    pub fn push(&mut self, corners: &[u32], line: usize) -> Result<(), MeshError> {
        let face = self.n_records;
        self.n_records += 1;
        match corners {
            [a, b, c] => self.faces.push([*a, *b, *c]),
            [first, rest @ ..] if rest.len() > 2 => {
                if !self.triangulate {
                    return Err(MeshError::Polygon {
                        path: self.path.to_path_buf(),
                        face,
                        corners: corners.len(),
                    });
                }
                self.triangulated += 1;
                for w in rest.windows(2) {
                    self.faces.push([*first, w[0], w[1]]);
                }
            }
            _ => {
                return Err(parse_error(
                    self.path,
                    line,
                    format!("face {face} has {} corners; a face needs at least three", corners.len()),
                ))
            }
        }
        Ok(())
    }
}

pub(crate) fn parse_error(path: &Path, line: usize, message: impl Into<String>) -> MeshError {
    MeshError::Parse {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

pub(crate) fn io_error(path: &Path, source: std::io::Error) -> MeshError {
    MeshError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Converts a 0-based index read from a file into `u32`, naming negative or huge indices.
pub(crate) fn checked_index(path: &Path, line: usize, face: usize, index: i64) -> Result<u32, MeshError> {
    if index < 0 {
        return Err(MeshError::NegativeIndex {
            path: path.to_path_buf(),
            line,
            face,
            index,
        });
    }
    u32::try_from(index).map_err(|_| {
        parse_error(
            path,
            line,
            format!("face {face} uses vertex index {index}, which does not fit in 32 bits"),
        )
    })
}

/// Builds the mesh and keeps the file name on errors that TriMesh::new reports without one.
pub(crate) fn finish(
    positions: Vec<[f64; 3]>,
    sink: FaceSink<'_>,
    mut report: LoadReport,
) -> Result<(TriMesh, LoadReport), MeshError> {
    report.triangulated_polygons = sink.triangulated;
    let mesh = TriMesh::new(positions, sink.faces)?;
    Ok((mesh, report))
}
