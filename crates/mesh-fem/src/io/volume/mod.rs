//! Reading tetrahedral meshes: MEDIT `.mesh` (versions 1 and 2), Gmsh `.msh` (2.2 ASCII and
//! binary, 4.1 ASCII), VTK legacy `.vtk` (ASCII unstructured grids with cell type 10, and the
//! tetrahedra-as-4-gons POLYDATA that LaPy writes) and TetGen `.node`/`.ele`. Regular files only;
//! every count a file declares is checked against what the file can hold before anything is
//! allocated; every problem names the line. Coordinates are read as the decimal text says, into
//! f64 (even where a header says `float`). Elements other than linear tetrahedra (triangles,
//! edges, points, other cells) are counted in [`VolumeRead::ignored`], never used: the boundary is
//! computed from the tetrahedra.

mod gmsh;

use crate::volume::TetMesh;
use crate::MeshError;
use std::path::{Path, PathBuf};

/// The volume formats, named by their extensions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VolumeFormat {
    /// MEDIT `.mesh`.
    #[default]
    Medit,
    /// Gmsh `.msh`, 2.2 (ASCII, binary) or 4.1 (ASCII).
    Gmsh,
    /// VTK legacy `.vtk` (ASCII).
    Vtk,
    /// TetGen `.ele` with its `.node`.
    TetGen,
}

wfem_base::registry! {
    VolumeFormat as "volume format" {
        VolumeFormat::Medit = VolumeFormat::Medit => "mesh" ["medit"]: "MEDIT .mesh, versions 1 and 2",
        VolumeFormat::Gmsh = VolumeFormat::Gmsh => "msh" ["gmsh"]: "Gmsh .msh 2.2 (ASCII or binary) or 4.1 (ASCII)",
        VolumeFormat::Vtk = VolumeFormat::Vtk => "vtk": "VTK legacy ASCII: unstructured grid (cell type 10) or LaPy's tetrahedra as 4-gons",
        VolumeFormat::TetGen = VolumeFormat::TetGen => "ele" ["node", "tetgen"]: "TetGen .ele (with the .node beside it)",
    }
}

impl VolumeFormat {
    /// The volume format of a path's extension, if it is one.
    pub fn from_path(path: &Path) -> Option<Self> {
        use wfem_base::Choice;
        let ext = path.extension()?.to_string_lossy().to_ascii_lowercase();
        Self::parse(&ext).ok().filter(|_| !ext.is_empty())
    }
}

/// What was read from a volume file.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeRead {
    /// The tetrahedra (indices 0-based, in file order; vertices in file order).
    pub mesh: TetMesh,
    /// Elements that are not linear tetrahedra, by kind: ("triangles", 312), …
    pub ignored: Vec<(String, usize)>,
    /// The format.
    pub format: VolumeFormat,
}

/// Reads a tetrahedral mesh by its extension.
///
/// # Errors
/// [`MeshError::UnknownFormat`] for another extension; [`MeshError::Io`] (a FIFO, a directory,
/// a missing file); [`MeshError::VolumeParse`] naming the line; [`MeshError::Empty`] without
/// tetrahedra; [`MeshError::TetIndexOutOfRange`], [`MeshError::NonFiniteCoordinate`].
pub fn read_volume(path: &Path) -> Result<VolumeRead, MeshError> {
    let Some(format) = VolumeFormat::from_path(path) else {
        return Err(MeshError::UnknownFormat {
            path: path.to_path_buf(),
            extension: format!(
                "{} (volume meshes: .mesh, .msh, .vtk, .ele/.node)",
                path.extension()
                    .map(|e| e.to_string_lossy().into_owned())
                    .unwrap_or_default()
            ),
        });
    };
    if format == VolumeFormat::TetGen {
        let mut p = Parser {
            path: path.to_path_buf(),
            ..Parser::default()
        };
        let (node, ele) = (path.with_extension("node"), path.with_extension("ele"));
        let nodes = super::read_regular_file(&node)?;
        let elements = super::read_regular_file(&ele)?;
        let (positions, tets) = p.tetgen(&node, &nodes, &ele, &elements)?;
        return Ok(VolumeRead {
            mesh: TetMesh::new(positions, tets)?,
            ignored: p.ignored,
            format,
        });
    }
    parse_volume(&super::read_regular_file(path)?, format, path)
}

/// Parses the bytes of a one-file volume format (MEDIT, Gmsh, VTK; `name` is the path errors
/// name): what [`read_volume`] does after reading the file, for data already in memory.
///
/// # Errors
/// As [`read_volume`]; [`MeshError::UnknownFormat`] for TetGen, which is two files.
pub fn parse_volume(bytes: &[u8], format: VolumeFormat, name: &Path) -> Result<VolumeRead, MeshError> {
    let mut p = Parser {
        path: name.to_path_buf(),
        ..Parser::default()
    };
    let (positions, tets) = match format {
        VolumeFormat::Medit => p.medit(bytes)?,
        VolumeFormat::Gmsh => p.gmsh(bytes)?,
        VolumeFormat::Vtk => p.vtk(bytes)?,
        VolumeFormat::TetGen => {
            return Err(MeshError::UnknownFormat {
                path: name.to_path_buf(),
                extension: "ele (TetGen is two files, .node and .ele: use read_volume)".into(),
            })
        }
    };
    Ok(VolumeRead {
        mesh: TetMesh::new(positions, tets)?,
        ignored: p.ignored,
        format,
    })
}

/// What a reader returns: the positions and the tetrahedra (0-based).
type Parsed = (Vec<[f64; 3]>, Vec<[u32; 4]>);

/// Whitespace-separated tokens with their line numbers ('#' starts a comment in the formats
/// that allow it).
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    comments: bool,
}

impl<'a> Tokens<'a> {
    fn new(bytes: &'a [u8], comments: bool) -> Self {
        Self {
            bytes,
            pos: 0,
            line: 1,
            comments,
        }
    }

    fn next(&mut self) -> Option<&'a str> {
        loop {
            while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
                if self.bytes[self.pos] == b'\n' {
                    self.line += 1;
                }
                self.pos += 1;
            }
            if self.comments && self.bytes.get(self.pos) == Some(&b'#') {
                while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
                    self.pos += 1;
                }
                continue;
            }
            break;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        std::str::from_utf8(&self.bytes[start..self.pos])
            .ok()
            .or(Some("\u{fffd}"))
    }

    /// An upper bound of the tokens left (each needs one byte and a separator).
    fn room(&self) -> usize {
        (self.bytes.len() - self.pos) / 2 + 1
    }
}

#[derive(Default)]
struct Parser {
    path: PathBuf,
    ignored: Vec<(String, usize)>,
}

impl Parser {
    fn err(&self, line: usize, message: impl Into<String>) -> MeshError {
        MeshError::VolumeParse {
            path: self.path.clone(),
            line,
            message: message.into(),
        }
    }

    fn ignore(&mut self, kind: &str, count: usize) {
        if count == 0 {
            return;
        }
        match self.ignored.iter_mut().find(|(k, _)| k == kind) {
            Some((_, c)) => *c += count,
            None => self.ignored.push((kind.to_string(), count)),
        }
    }

    fn token<'a>(&self, t: &mut Tokens<'a>, what: &str) -> Result<&'a str, MeshError> {
        t.next()
            .ok_or_else(|| self.err(t.line, format!("the file ends where {what} was expected")))
    }

    fn int(&self, t: &mut Tokens<'_>, what: &str) -> Result<i64, MeshError> {
        let s = self.token(t, what)?;
        s.parse::<i64>()
            .map_err(|_| self.err(t.line, format!("{what}: {s:?} is not an integer")))
    }

    fn float(&self, t: &mut Tokens<'_>, what: &str) -> Result<f64, MeshError> {
        let s = self.token(t, what)?;
        match s.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(x) => Err(self.err(t.line, format!("{what}: {x} is not finite"))),
            Err(_) => Err(self.err(t.line, format!("{what}: {s:?} is not a number"))),
        }
    }

    /// A count declared by the file, at most what the rest of the file can hold with
    /// `per_item` tokens each.
    fn count(&self, t: &mut Tokens<'_>, what: &str, per_item: usize) -> Result<usize, MeshError> {
        let line = t.line;
        let c = self.int(t, what)?;
        if c < 0 {
            return Err(self.err(line, format!("{what}: negative count {c}")));
        }
        let c = c as usize;
        if c.saturating_mul(per_item.max(1)) > t.room() {
            return Err(self.err(line, format!("{what}: {c} declared, more than the file can hold")));
        }
        Ok(c)
    }

    /// A vertex index of the file (`base` 0 or 1) as a 0-based u32.
    fn index(&self, t: &mut Tokens<'_>, base: i64, n: usize) -> Result<u32, MeshError> {
        let line = t.line;
        let i = self.int(t, "vertex index")? - base;
        if i < 0 || i as usize >= n {
            return Err(self.err(line, format!("vertex index {} is out of range 1..={n}", i + base)));
        }
        Ok(i as u32)
    }

    // ---- MEDIT -----------------------------------------------------------------------------

    fn medit(&mut self, bytes: &[u8]) -> Result<Parsed, MeshError> {
        let mut t = Tokens::new(bytes, true);
        let (mut positions, mut tets) = (Vec::new(), Vec::new());
        while let Some(kw) = t.next() {
            let line = t.line;
            match kw.to_ascii_lowercase().as_str() {
                "meshversionformatted" => {
                    let v = self.int(&mut t, "MeshVersionFormatted")?;
                    if !(1..=2).contains(&v) {
                        return Err(self.err(line, format!("MeshVersionFormatted {v}: only 1 and 2 are read")));
                    }
                }
                "dimension" => {
                    let d = self.int(&mut t, "Dimension")?;
                    if d != 3 {
                        return Err(self.err(line, format!("Dimension {d}: a volume mesh has dimension 3")));
                    }
                }
                "vertices" => {
                    let n = self.count(&mut t, "Vertices", 4)?;
                    positions.reserve(n);
                    for _ in 0..n {
                        let p = [
                            self.float(&mut t, "x")?,
                            self.float(&mut t, "y")?,
                            self.float(&mut t, "z")?,
                        ];
                        self.int(&mut t, "vertex reference")?;
                        positions.push(p);
                    }
                }
                "tetrahedra" => {
                    let m = self.count(&mut t, "Tetrahedra", 5)?;
                    tets.reserve(m);
                    for _ in 0..m {
                        let n = positions.len();
                        let tet = [
                            self.index(&mut t, 1, n)?,
                            self.index(&mut t, 1, n)?,
                            self.index(&mut t, 1, n)?,
                            self.index(&mut t, 1, n)?,
                        ];
                        self.int(&mut t, "tetrahedron reference")?;
                        tets.push(tet);
                    }
                }
                "end" => break,
                other => {
                    let per = match other {
                        "triangles" => 4,
                        "edges" => 3,
                        "quadrilaterals" => 5,
                        "hexahedra" => 9,
                        "prisms" => 7,
                        "corners" | "ridges" | "requiredvertices" | "requirededges" | "requiredtriangles" => 1,
                        "normals" | "tangents" => 3,
                        "normalatvertices" | "tangentatedges" => 2,
                        _ => return Err(self.err(line, format!("unknown MEDIT keyword {kw:?}"))),
                    };
                    let c = self.count(&mut t, kw, per)?;
                    for _ in 0..c * per {
                        self.token(&mut t, kw)?;
                    }
                    self.ignore(other, c);
                }
            }
        }
        Ok((positions, tets))
    }

    // ---- VTK legacy ------------------------------------------------------------------------

    fn vtk(&mut self, bytes: &[u8]) -> Result<Parsed, MeshError> {
        // Header: a version line, a title line, ASCII|BINARY, then tokens.
        let mut lines = bytes.splitn(4, |&b| b == b'\n');
        let version = lines.next().unwrap_or_default();
        if !String::from_utf8_lossy(version)
            .to_ascii_lowercase()
            .contains("vtk datafile")
        {
            return Err(self.err(
                1,
                "not a VTK legacy file (the first line is not '# vtk DataFile Version …')",
            ));
        }
        let _title = lines.next();
        let kind = String::from_utf8_lossy(lines.next().unwrap_or_default())
            .trim()
            .to_ascii_uppercase();
        if kind != "ASCII" {
            return Err(self.err(3, format!("{kind:?}: only ASCII VTK files are read")));
        }
        let rest = lines.next().unwrap_or_default();
        let mut t = Tokens::new(rest, false);
        t.line = 4;
        let (mut positions, mut cells, mut types): (Vec<[f64; 3]>, Vec<Vec<u32>>, Option<Vec<i64>>) =
            (Vec::new(), Vec::new(), None);
        let mut polydata = false;
        while let Some(kw) = t.next() {
            let line = t.line;
            match kw.to_ascii_uppercase().as_str() {
                "DATASET" => {
                    let d = self.token(&mut t, "DATASET")?.to_ascii_uppercase();
                    polydata = match d.as_str() {
                        "UNSTRUCTURED_GRID" => false,
                        "POLYDATA" => true,
                        other => {
                            return Err(self.err(
                                line,
                                format!("DATASET {other}: only UNSTRUCTURED_GRID and POLYDATA hold tetrahedra"),
                            ))
                        }
                    };
                }
                "POINTS" => {
                    let n = self.count(&mut t, "POINTS", 3)?;
                    self.token(&mut t, "POINTS data type")?;
                    positions.reserve(n);
                    for _ in 0..n {
                        positions.push([
                            self.float(&mut t, "x")?,
                            self.float(&mut t, "y")?,
                            self.float(&mut t, "z")?,
                        ]);
                    }
                }
                "CELLS" | "POLYGONS" => {
                    let m = self.count(&mut t, kw, 2)?;
                    let _size = self.int(&mut t, "size")?;
                    cells.reserve(m);
                    for _ in 0..m {
                        let k = self.count(&mut t, "cell size", 1)?;
                        let n = positions.len();
                        let mut c = Vec::with_capacity(k.min(64));
                        for _ in 0..k {
                            c.push(self.index(&mut t, 0, n)?);
                        }
                        cells.push(c);
                    }
                }
                "CELL_TYPES" => {
                    let m = self.count(&mut t, "CELL_TYPES", 1)?;
                    let mut v = Vec::with_capacity(m);
                    for _ in 0..m {
                        v.push(self.int(&mut t, "cell type")?);
                    }
                    types = Some(v);
                }
                "VERTICES" | "LINES" | "TRIANGLE_STRIPS" => {
                    let m = self.count(&mut t, kw, 2)?;
                    let size = self.count(&mut t, "size", 1)?;
                    for _ in 0..size {
                        self.token(&mut t, kw)?;
                    }
                    self.ignore(&kw.to_ascii_lowercase(), m);
                }
                "POINT_DATA" | "CELL_DATA" | "FIELD" | "METADATA" => break,
                "OFFSETS" | "CONNECTIVITY" => return Err(self.err(
                    line,
                    "VTK 5.1 cell arrays (OFFSETS/CONNECTIVITY) are not read; write the file in the legacy 4.2 layout",
                )),
                other => return Err(self.err(line, format!("unexpected VTK keyword {other:?}"))),
            }
        }
        let mut tets = Vec::new();
        for (i, c) in cells.iter().enumerate() {
            let tet_like = match &types {
                Some(ty) => match ty.get(i) {
                    Some(10) => true,
                    Some(&other) => {
                        self.ignore(&format!("VTK cells of type {other}"), 1);
                        false
                    }
                    None => return Err(self.err(t.line, format!("cell {i} has no CELL_TYPES entry"))),
                },
                // POLYDATA: LaPy's tetrahedra are 4-vertex polygons; other polygons are faces.
                None if polydata && c.len() == 4 => true,
                None => {
                    self.ignore(&format!("{}-vertex polygons", c.len()), 1);
                    false
                }
            };
            if tet_like {
                if c.len() != 4 {
                    return Err(self.err(t.line, format!("cell {i} is a tetrahedron with {} vertices", c.len())));
                }
                tets.push([c[0], c[1], c[2], c[3]]);
            }
        }
        Ok((positions, tets))
    }

    // ---- TetGen ----------------------------------------------------------------------------

    fn tetgen(
        &mut self,
        node_path: &Path,
        nodes: &[u8],
        ele_path: &Path,
        elements: &[u8],
    ) -> Result<Parsed, MeshError> {
        self.path = node_path.to_path_buf();
        let mut t = Tokens::new(nodes, true);
        let n = self.count(&mut t, "number of nodes", 4)?;
        let dim = self.int(&mut t, "dimension")?;
        if dim != 3 {
            return Err(self.err(t.line, format!("dimension {dim}: a volume mesh has dimension 3")));
        }
        let attrs = self.count(&mut t, "attributes", 0)?;
        let marker = self.int(&mut t, "boundary markers")? != 0;
        let mut positions = Vec::with_capacity(n);
        let mut base = 0;
        for k in 0..n {
            let idx = self.int(&mut t, "node index")?;
            if k == 0 {
                base = idx;
            }
            if idx != base + k as i64 {
                return Err(self.err(
                    t.line,
                    format!("node {idx}: nodes must be numbered consecutively from {base}"),
                ));
            }
            positions.push([
                self.float(&mut t, "x")?,
                self.float(&mut t, "y")?,
                self.float(&mut t, "z")?,
            ]);
            for _ in 0..attrs + marker as usize {
                self.token(&mut t, "node attribute")?;
            }
        }
        self.path = ele_path.to_path_buf();
        let mut t = Tokens::new(elements, true);
        let m = self.count(&mut t, "number of tetrahedra", 5)?;
        let per = self.int(&mut t, "nodes per tetrahedron")?;
        if per != 4 && per != 10 {
            return Err(self.err(t.line, format!("{per} nodes per tetrahedron: 4 or 10 are read")));
        }
        let region = self.int(&mut t, "region attribute")? != 0;
        let mut tets = Vec::with_capacity(m);
        for _ in 0..m {
            self.int(&mut t, "tetrahedron index")?;
            let tet = [
                self.index(&mut t, base, n)?,
                self.index(&mut t, base, n)?,
                self.index(&mut t, base, n)?,
                self.index(&mut t, base, n)?,
            ];
            for _ in 4..per as usize + region as usize {
                self.token(&mut t, "tetrahedron attribute")?;
            }
            tets.push(tet);
        }
        if per == 10 {
            self.ignore("second-order nodes of 10-node tetrahedra", 6 * m);
        }
        Ok((positions, tets))
    }

    // ---- Gmsh ------------------------------------------------------------------------------
}
