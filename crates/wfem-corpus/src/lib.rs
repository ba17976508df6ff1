//! # wfem-corpus
//!
//! The shared folder of real meshes used by tests, examples and benchmarks (test support; not
//! published). Library crates take it as a dev-dependency; tools that default to the corpus at
//! run time (`xtask`) as a dependency. No library code knows where the corpus is.
//!
//! The folder is `$WFEM_MESHES` if that variable is set, otherwise `shared/data/meshes` next
//! to the workspace checkout: starting from this crate's directory we walk up until a
//! directory `d` with `d/../shared/data/meshes` is found. Meshes are never copied into the
//! repository. Errors are [`MeshError::Io`] naming the path, as for any unreadable mesh file.

#![warn(missing_docs)]

use mesh_fem::io::MeshFormat;
use mesh_fem::MeshError;
use std::path::{Path, PathBuf};

fn missing(path: PathBuf, message: &str) -> MeshError {
    MeshError::Io {
        path,
        source: std::io::Error::new(std::io::ErrorKind::NotFound, message.to_string()),
    }
}

/// The corpus folder.
///
/// # Errors
/// [`MeshError::Io`] (kind `NotFound`) if `$WFEM_MESHES` names no directory, or if no
/// `shared/data/meshes` folder is found above the workspace.
pub fn meshes_dir() -> Result<PathBuf, MeshError> {
    if let Some(dir) = std::env::var_os("WFEM_MESHES") {
        let dir = PathBuf::from(dir);
        return if dir.is_dir() {
            Ok(dir)
        } else {
            Err(missing(dir, "WFEM_MESHES is set but does not name a directory"))
        };
    }
    let start = Path::new(env!("CARGO_MANIFEST_DIR"));
    for d in start.ancestors() {
        let candidate = d.join("..").join("shared").join("data").join("meshes");
        if candidate.is_dir() {
            // Normalise `a/b/../shared` for readable paths in messages.
            return Ok(candidate.canonicalize().unwrap_or(candidate));
        }
    }
    Err(missing(
        start.to_path_buf(),
        "no ../shared/data/meshes folder above this crate; set WFEM_MESHES to the mesh folder",
    ))
}

/// The folder of real tetrahedral meshes: `$WFEM_VOLUMES`, otherwise `volumes` beside the
/// mesh folder (`shared/data/volumes`).
///
/// # Errors
/// As [`meshes_dir`], and [`MeshError::Io`] (kind `NotFound`) if the folder does not exist.
pub fn volumes_dir() -> Result<PathBuf, MeshError> {
    if let Some(dir) = std::env::var_os("WFEM_VOLUMES") {
        let dir = PathBuf::from(dir);
        return if dir.is_dir() {
            Ok(dir)
        } else {
            Err(missing(dir, "WFEM_VOLUMES is set but does not name a directory"))
        };
    }
    let dir = meshes_dir()?.join("..").join("volumes");
    if dir.is_dir() {
        Ok(dir.canonicalize().unwrap_or(dir))
    } else {
        Err(missing(
            dir,
            "no volumes folder beside the mesh folder; set WFEM_VOLUMES",
        ))
    }
}

/// The path of a volume file relative to [`volumes_dir`], e.g. `volume_path("lapy/cubeTetra.vtk")`.
///
/// # Errors
/// As [`volumes_dir`]; [`MeshError::Io`] if the file does not exist.
pub fn volume_path(rel: &str) -> Result<PathBuf, MeshError> {
    let path = volumes_dir()?.join(rel);
    if path.is_file() {
        Ok(path)
    } else {
        Err(missing(path, "no such volume file in the corpus"))
    }
}

/// The folder of reference values computed by other libraries (`shared/reference`, e.g.
/// libigl's L, B, D as Matrix Market files), if present: `$WFEM_REFERENCE`, otherwise the
/// first `../shared/reference` above this crate. It is optional: cross-checks against it run
/// only where it exists.
pub fn reference_dir() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("WFEM_REFERENCE") {
        let dir = PathBuf::from(dir);
        return dir.is_dir().then_some(dir);
    }
    let start = Path::new(env!("CARGO_MANIFEST_DIR"));
    start
        .ancestors()
        .map(|d| d.join("..").join("shared").join("reference"))
        .find(|c| c.is_dir())
        .map(|c| c.canonicalize().unwrap_or(c))
}

/// The path of a corpus file given relative to the corpus folder, e.g.
/// `mesh_path("common-3d-test-models/spot.obj")`.
///
/// # Errors
/// The errors of [`meshes_dir`], and [`MeshError::Io`] (kind `NotFound`) if the file does not
/// exist.
pub fn mesh_path(rel: &str) -> Result<PathBuf, MeshError> {
    let path = meshes_dir()?.join(rel);
    if path.is_file() {
        Ok(path)
    } else {
        Err(missing(path, "no such file in the mesh corpus"))
    }
}

/// Every `.obj`, `.ply`, `.off` and `.stl` file (extension case-insensitive) below the corpus
/// folder, sorted by path.
///
/// # Errors
/// The errors of [`meshes_dir`], and [`MeshError::Io`] if a directory cannot be read.
pub fn all_mesh_files() -> Result<Vec<PathBuf>, MeshError> {
    let root = meshes_dir()?;
    let mut out = Vec::new();
    let mut stack = vec![root];
    while let Some(dir) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|source| MeshError::Io {
            path: dir.clone(),
            source,
        })?;
        for entry in entries {
            let entry = entry.map_err(|source| MeshError::Io {
                path: dir.clone(),
                source,
            })?;
            let path = entry.path();
            let kind = entry.file_type().map_err(|source| MeshError::Io {
                path: path.clone(),
                source,
            })?;
            if kind.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .is_some_and(|e| MeshFormat::from_extension(&e).is_some())
            {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}
