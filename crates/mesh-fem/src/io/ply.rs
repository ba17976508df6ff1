//! PLY reader on top of `ply-rs-bw` (ASCII, binary little and big endian).
//!
//! Elements are parsed into small typed structs (no per-element hash maps): `x`, `y`, `z` of
//! `vertex` (any scalar type), the `vertex_indices`/`vertex_index` list of `face` (any
//! integer list type). Other elements are parsed with a struct that ignores everything.

use super::text::{show, Lines};
use super::{checked_index, finish, parse_error, FaceSink, LoadOptions, LoadReport, MeshFormat};
use crate::{MeshError, TriMesh};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};
use std::path::Path;

/// One PLY vertex: the coordinates (and the normal, read for point clouds).
struct Vertex {
    p: [f64; 3],
    n: [f64; 3],
}

impl Vertex {
    fn set(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        match name {
            "x" => self.p[0] = value,
            "y" => self.p[1] = value,
            "z" => self.p[2] = value,
            "nx" => self.n[0] = value,
            "ny" => self.n[1] = value,
            "nz" => self.n[2] = value,
            _ => return PropertyAccessResult::Ignored,
        }
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self {
            p: [0.0; 3],
            n: [0.0; 3],
        }
    }
    fn set_char(&mut self, name: &str, v: i8) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_uchar(&mut self, name: &str, v: u8) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_short(&mut self, name: &str, v: i16) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_ushort(&mut self, name: &str, v: u16) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_int(&mut self, name: &str, v: i32) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_uint(&mut self, name: &str, v: u32) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.set(name, f64::from(v))
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.set(name, v)
    }
}

/// One PLY face: its corner indices, widened to i64 so that negative values can be named.
struct Face {
    corners: Vec<i64>,
}

fn is_index_name(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

macro_rules! set_list {
    ($fn:ident, $t:ty) => {
        fn $fn(&mut self, name: &str, v: Vec<$t>) -> PropertyAccessResult {
            if !is_index_name(name) {
                return PropertyAccessResult::Ignored;
            }
            self.corners.clear();
            self.corners.extend(v.into_iter().map(i64::from));
            PropertyAccessResult::Set
        }
    };
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self { corners: Vec::new() }
    }
    set_list!(set_list_char, i8);
    set_list!(set_list_uchar, u8);
    set_list!(set_list_short, i16);
    set_list!(set_list_ushort, u16);
    set_list!(set_list_int, i32);
    set_list!(set_list_uint, u32);
}

/// Any other element: everything ignored (the parser still consumes its bytes).
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

fn is_integer(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

fn ply_error(path: &Path, header: &Header, e: &ply_rs_bw::parser::ParseError) -> MeshError {
    // ply-rs-bw counts lines for ASCII data; for binary payloads a line means nothing.
    let line = match header.encoding {
        Encoding::Ascii => e.line().unwrap_or(0),
        _ => 0,
    };
    parse_error(path, line, e.to_string())
}

/// Whether a PLY file declares faces (a `face` element with at least one record): a mesh;
/// otherwise a point cloud. `None` if the header cannot be read.
pub(crate) fn has_faces(bytes: &[u8]) -> Option<bool> {
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skip>::new().read_header(&mut reader).ok()?;
    Some(header.elements.get("face").is_some_and(|f| f.count > 0))
}

/// Reads the `vertex` element of a PLY file as a point cloud: positions, and normals when
/// the vertices have `nx`, `ny`, `nz`. Other elements are skipped; a `face` element with
/// records is refused (the file is a mesh).
pub(crate) fn read_points(bytes: &[u8], path: &Path) -> Result<crate::cloud::PointCloud, MeshError> {
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| parse_error(path, e.line().unwrap_or(0), format!("PLY header: {e}")))?;
    check_vertex_header(path, &header)?;
    let vertex_def = &header.elements["vertex"];
    let with_normals = ["nx", "ny", "nz"].iter().all(|c| {
        matches!(
            vertex_def.properties.get(*c).map(|p| &p.data_type),
            Some(PropertyType::Scalar(_))
        )
    });
    let mut points: Vec<Vertex> = Vec::new();
    let elements: Vec<&ElementDef> = header.elements.iter().map(|(_, e)| e).collect();
    for def in elements {
        if def.name == "face" && def.count > 0 {
            return Err(parse_error(
                path,
                0,
                format!("the file has {} faces: read it as a mesh", def.count),
            ));
        }
        if def.name == "vertex" {
            points = Parser::<Vertex>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| ply_error(path, &header, &e))?;
        } else {
            Parser::<Skip>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| ply_error(path, &header, &e))?;
        }
    }
    let normals = with_normals.then(|| points.iter().map(|v| v.n).collect());
    crate::cloud::PointCloud::new(points.into_iter().map(|v| v.p).collect(), normals)
}

fn check_vertex_header(path: &Path, header: &Header) -> Result<(), MeshError> {
    let vertex = header
        .elements
        .get("vertex")
        .ok_or_else(|| parse_error(path, 0, "the PLY header declares no 'vertex' element"))?;
    for c in ["x", "y", "z"] {
        match vertex.properties.get(c).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => {
                return Err(parse_error(
                    path,
                    0,
                    format!("vertex property {c:?} is a list, expected a number"),
                ))
            }
            None => {
                return Err(parse_error(
                    path,
                    0,
                    format!("the 'vertex' element has no property {c:?}"),
                ))
            }
        }
    }
    Ok(())
}

fn check_header(path: &Path, header: &Header) -> Result<(), MeshError> {
    check_vertex_header(path, header)?;
    let face = header
        .elements
        .get("face")
        .ok_or_else(|| parse_error(path, 0, "the PLY header declares no 'face' element"))?;
    let list = face
        .properties
        .iter()
        .find(|(name, _)| is_index_name(name))
        .map(|(_, p)| &p.data_type)
        .ok_or_else(|| {
            parse_error(
                path,
                0,
                "the 'face' element has neither 'vertex_indices' nor 'vertex_index'",
            )
        })?;
    match list {
        PropertyType::List(_, t) if is_integer(t) => Ok(()),
        other => Err(parse_error(
            path,
            0,
            format!("face indices have type {other:?}, expected a list of integers"),
        )),
    }
}

pub(crate) fn read(bytes: &[u8], path: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    let mut report = LoadReport::new(MeshFormat::Ply);
    let mut reader = Reader::new(bytes);
    let header = Parser::<Skip>::new().read_header(&mut reader).map_err(|e| {
        // The parser's message ends in its internal grammar state; keep the line it quotes.
        let text = e.to_string();
        let text = text.split("\n\tError:").next().unwrap_or(&text);
        let text = text.replace("\n\tString: ", " ").replace('\n', "");
        parse_error(path, e.line().unwrap_or(0), format!("PLY header: {text}"))
    })?;
    check_header(path, &header)?;
    report.notes.push(
        match header.encoding {
            Encoding::Ascii => "ASCII PLY",
            Encoding::BinaryLittleEndian => "binary little-endian PLY",
            Encoding::BinaryBigEndian => "binary big-endian PLY",
        }
        .to_string(),
    );

    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut sink = FaceSink::new(path, opts.triangulate_polygons, 0);
    let elements: Vec<&ElementDef> = header.elements.iter().map(|(_, e)| e).collect();
    for def in elements {
        match def.name.as_str() {
            "vertex" => {
                let vs = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &header, &e))?;
                positions = vs.into_iter().map(|v| v.p).collect();
            }
            "face" => {
                let fs = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &header, &e))?;
                sink.faces.reserve(fs.len());
                let mut corners: Vec<u32> = Vec::with_capacity(8);
                for (f, face) in fs.iter().enumerate() {
                    corners.clear();
                    for &i in &face.corners {
                        corners.push(checked_index(path, 0, f, i)?);
                    }
                    sink.push(&corners, 0)?;
                }
            }
            other => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| ply_error(path, &header, &e))?;
                report
                    .notes
                    .push(format!("skipped element {other:?} ({} records)", def.count));
            }
        }
    }
    check_trailing(path, &header, reader.line(), reader.get_ref(), &mut report)?;
    finish(positions, sink, report)
}

/// Data after the last declared element. In ASCII PLY a non-blank line there almost always
/// means an element count that is too small (the records it would have covered would be
/// dropped silently), so it is an error naming the line. In binary PLY the extra bytes are
/// reported in a note (there are no lines to name, and some writers pad files).
fn check_trailing(
    path: &Path,
    header: &Header,
    next_line: usize,
    rest: &[u8],
    report: &mut LoadReport,
) -> Result<(), MeshError> {
    match header.encoding {
        Encoding::Ascii => {
            // `next_line` is the 1-based number of the first line after the last element.
            let extra = Lines::new(rest).find(|(_, line)| !line.iter().all(|b| b.is_ascii_whitespace()));
            match extra {
                Some((k, line)) => Err(parse_error(
                    path,
                    next_line + k - 1,
                    format!(
                        "data after the last declared element ({:?}); does the header declare too few elements?",
                        show(line)
                    ),
                )),
                None => Ok(()),
            }
        }
        _ => {
            if !rest.is_empty() {
                report
                    .notes
                    .push(format!("ignored {} bytes after the last declared element", rest.len()));
            }
            Ok(())
        }
    }
}
