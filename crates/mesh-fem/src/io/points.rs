//! Reading point clouds, and [`load_shape`]: a mesh or a point cloud, whichever a file holds.
//!
//! | extension | content |
//! |---|---|
//! | `.ply` | the `vertex` element (`x y z`, and `nx ny nz` when present) of a PLY without faces |
//! | `.xyz` | one point per line, whitespace-separated: `x y z`, or `x y z nx ny nz` (6 columns) |
//! | `.pts` | an optional first line with the point count, then `x y z [more columns]` per line (intensity and colors are ignored, never read as normals) |
//! | `.csv` | comma-separated `x,y,z` or `x,y,z,nx,ny,nz` per line; an optional header line |
//! | `.npy` | a float64/float32 array of shape (n, 3), or (n, 6) with normals |
//!
//! Blank lines and `#` comments are skipped in the text formats; every malformed line is an
//! error naming it, and NaN/∞ coordinates are [`MeshError::NonFinitePoint`].

use super::field::parse_npy_array;
use super::text::{show, Lines};
use super::{load_bytes, parse_error, read_regular_file, LoadOptions, LoadReport, MeshFormat};
use crate::cloud::PointCloud;
use crate::{MeshError, TriMesh};
use std::path::Path;

/// A point-cloud file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PointFormat {
    /// PLY without faces.
    Ply,
    /// `.xyz` text.
    Xyz,
    /// `.pts` text.
    Pts,
    /// Comma-separated values.
    Csv,
    /// NumPy `.npy`.
    Npy,
}

impl PointFormat {
    /// The extensions read as point clouds, for messages.
    pub const EXTENSIONS: &'static str = ".ply (without faces), .xyz, .pts, .csv, .npy";

    /// The format named by a file extension (case-insensitive, without the dot), if any.
    pub fn from_extension(extension: &str) -> Option<Self> {
        match extension.to_ascii_lowercase().as_str() {
            "ply" => Some(Self::Ply),
            "xyz" => Some(Self::Xyz),
            "pts" => Some(Self::Pts),
            "csv" => Some(Self::Csv),
            "npy" => Some(Self::Npy),
            _ => None,
        }
    }
}

/// What a shape file holds.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A triangle mesh, with its load report.
    Mesh(TriMesh, LoadReport),
    /// A point cloud.
    Cloud(PointCloud),
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Reads a mesh or a point cloud: `.obj`, `.off`, `.stl` and a PLY with faces are meshes
/// ([`super::load`]); a PLY without faces, `.xyz`, `.pts`, `.csv` and `.npy` are point clouds
/// ([`load_points`]).
///
/// # Errors
/// [`MeshError::UnknownFormat`] for another extension, and the errors of the reader.
pub fn load_shape(path: &Path, opts: &LoadOptions) -> Result<Shape, MeshError> {
    let ext = extension(path);
    if let Some(format) = MeshFormat::from_extension(&ext) {
        let bytes = read_regular_file(path)?;
        if format != MeshFormat::Ply || super::ply::has_faces(&bytes) != Some(false) {
            let (mesh, report) = load_bytes(&bytes, format, path, opts)?;
            return Ok(Shape::Mesh(mesh, report));
        }
        return super::ply::read_points(&bytes, path).map(Shape::Cloud);
    }
    if PointFormat::from_extension(&ext).is_some() {
        return load_points(path).map(Shape::Cloud);
    }
    Err(MeshError::UnknownFormat {
        path: path.to_path_buf(),
        extension: ext,
    })
}

/// Reads a point cloud; the format is chosen by the extension (module documentation).
///
/// # Errors
/// [`MeshError::UnknownFormat`] for another extension, [`MeshError::Io`] for a file that
/// cannot be read or is not a regular file, [`MeshError::Parse`] naming the line of bad data,
/// and the errors of [`PointCloud::new`].
pub fn load_points(path: &Path) -> Result<PointCloud, MeshError> {
    let ext = extension(path);
    let format = PointFormat::from_extension(&ext).ok_or_else(|| MeshError::UnknownFormat {
        path: path.to_path_buf(),
        extension: ext,
    })?;
    let bytes = read_regular_file(path)?;
    read_points(&bytes, format, path)
}

/// [`load_points`] on bytes in memory (`path` names them in errors).
///
/// # Errors
/// As [`load_points`].
pub fn read_points(bytes: &[u8], format: PointFormat, path: &Path) -> Result<PointCloud, MeshError> {
    match format {
        PointFormat::Ply => super::ply::read_points(bytes, path),
        PointFormat::Npy => read_npy(bytes, path),
        PointFormat::Xyz | PointFormat::Pts | PointFormat::Csv => read_text(bytes, format, path),
    }
}

fn read_npy(bytes: &[u8], path: &Path) -> Result<PointCloud, MeshError> {
    let (values, dims) = parse_npy_array(bytes, path)?;
    let cols = match dims.as_slice() {
        [_, c @ (3 | 6)] => *c,
        _ => {
            return Err(parse_error(
                path,
                0,
                format!("NPY: shape {dims:?} is not (n, 3) or (n, 6)"),
            ))
        }
    };
    let row = |r: &[f64], k: usize| [r[k], r[k + 1], r[k + 2]];
    let positions = values.chunks_exact(cols).map(|r| row(r, 0)).collect();
    let normals = (cols == 6).then(|| values.chunks_exact(6).map(|r| row(r, 3)).collect());
    PointCloud::new(positions, normals)
}

fn read_text(bytes: &[u8], format: PointFormat, path: &Path) -> Result<PointCloud, MeshError> {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    let mut positions = Vec::new();
    let mut normals: Vec<[f64; 3]> = Vec::new();
    let mut columns: Option<usize> = None;
    let mut first = true;
    for (line_no, line) in Lines::new(bytes) {
        let t = line.trim_ascii();
        if t.is_empty() || t.starts_with(b"#") {
            continue;
        }
        let was_first = std::mem::replace(&mut first, false);
        let fields: Vec<&[u8]> = if format == PointFormat::Csv {
            t.split(|&b| b == b',').map(|f| f.trim_ascii()).collect()
        } else {
            t.split(|b| b.is_ascii_whitespace()).filter(|f| !f.is_empty()).collect()
        };
        let parsed: Option<Vec<f64>> = fields
            .iter()
            .map(|f| std::str::from_utf8(f).ok().and_then(|s| s.parse::<f64>().ok()))
            .collect();
        let Some(parsed) = parsed else {
            if was_first && format == PointFormat::Csv {
                continue; // a header line
            }
            return Err(parse_error(
                path,
                line_no,
                format!("cannot read {:?} as numbers", show(t)),
            ));
        };
        // The optional point count of a .pts file.
        if was_first && format == PointFormat::Pts && parsed.len() == 1 {
            continue;
        }
        let wanted = match format {
            PointFormat::Pts => 3,
            _ if parsed.len() == 6 => 6,
            _ => 3,
        };
        if parsed.len() < 3 || (format != PointFormat::Pts && parsed.len() != 3 && parsed.len() != 6) {
            return Err(parse_error(
                path,
                line_no,
                format!(
                    "{} values; expected x y z{}",
                    parsed.len(),
                    if format == PointFormat::Pts {
                        " [more columns]"
                    } else {
                        " or x y z nx ny nz"
                    }
                ),
            ));
        }
        match columns {
            None => columns = Some(wanted),
            Some(c) if c != wanted => {
                return Err(parse_error(
                    path,
                    line_no,
                    format!("{wanted} values where earlier lines have {c}"),
                ))
            }
            _ => {}
        }
        positions.push([parsed[0], parsed[1], parsed[2]]);
        if wanted == 6 {
            normals.push([parsed[3], parsed[4], parsed[5]]);
        }
    }
    let normals = (columns == Some(6)).then_some(normals);
    PointCloud::new(positions, normals)
}
