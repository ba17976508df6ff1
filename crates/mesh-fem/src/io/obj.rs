//! Wavefront OBJ reader.
//!
//! We read `v` and `f` records ourselves instead of going through `tobj`: `tobj` renumbers
//! vertices per `o`/`g` group in order of first use and drops unreferenced vertices, so the
//! vertex order would no longer match the file (fields written for the mesh, libigl reference
//! operators and correspondence files all index vertices in file order). `tobj` serves as an
//! independent oracle in the tests instead.

use super::text::{parse_f64, parse_i64, show, strip_comment, tokens, Lines};
use super::{checked_index, finish, parse_error, FaceSink, LoadOptions, LoadReport, MeshFormat};
use crate::{MeshError, TriMesh};
use std::path::Path;

pub(crate) fn read(bytes: &[u8], path: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    let mut report = LoadReport::new(MeshFormat::Obj);
    // A `v` record takes at least 8 bytes ("v 0 0 0\n") and an `f` record at least 8, so the
    // size bounds both counts; reserving a fraction avoids most regrowth on large files.
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(bytes.len() / 64);
    let mut sink = FaceSink::new(path, opts.triangulate_polygons, bytes.len() / 64);
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    let mut n_lines_records = 0usize;
    // A UTF-8 byte order mark before the first record is not part of it.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    for (line_no, raw) in Lines::new(bytes) {
        let line = strip_comment(raw);
        let mut it = tokens(line);
        let Some(keyword) = it.next() else { continue };
        match keyword {
            b"v" => {
                let mut p = [0.0f64; 3];
                for (k, c) in p.iter_mut().enumerate() {
                    let token = it.next().ok_or_else(|| {
                        parse_error(path, line_no, format!("vertex record has {k} coordinates, expected 3"))
                    })?;
                    *c = parse_f64(token).ok_or_else(|| {
                        parse_error(
                            path,
                            line_no,
                            format!("cannot read coordinate {:?} as a number", show(token)),
                        )
                    })?;
                }
                positions.push(p);
            }
            b"f" => {
                corners.clear();
                let face = sink.records();
                for token in it {
                    // `v`, `v/vt`, `v/vt/vn` or `v//vn`: the position index comes first.
                    let v = token.split(|&b| b == b'/').next().unwrap_or(token);
                    let index = parse_i64(v).ok_or_else(|| {
                        parse_error(
                            path,
                            line_no,
                            format!("cannot read face corner {:?} as a vertex index", show(token)),
                        )
                    })?;
                    let zero_based = match index {
                        0 => {
                            return Err(parse_error(
                                path,
                                line_no,
                                "face uses vertex index 0, but OBJ indices start at 1",
                            ))
                        }
                        i if i > 0 => i - 1,
                        // Relative index: -1 is the last vertex read so far.
                        i => positions.len() as i64 + i,
                    };
                    corners.push(checked_index(path, line_no, face, zero_based)?);
                }
                sink.push(&corners, line_no)?;
            }
            b"l" | b"p" => n_lines_records += 1,
            // vt, vn, o, g, s, usemtl, mtllib, … carry nothing we need. Every OBJ keyword
            // (and every vendor extension seen in the wild) is ASCII letters, digits and
            // `_`; anything else means the data is not OBJ (binary data, another format), and
            // skipping it would end in a misleading "empty mesh".
            other if other.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_') => {}
            other => {
                return Err(parse_error(
                    path,
                    line_no,
                    format!(
                        "\"{}\" is not an OBJ record keyword (binary data or not an OBJ file?)",
                        escaped(other)
                    ),
                ))
            }
        }
    }
    if n_lines_records > 0 {
        report
            .notes
            .push(format!("ignored {n_lines_records} line/point records (l, p)"));
    }
    finish(positions, sink, report)
}

/// The first bytes of a token with non-printable bytes escaped (`\xcf`), for error messages.
fn escaped(token: &[u8]) -> String {
    let mut s: String = token
        .iter()
        .take(16)
        .flat_map(|b| b.escape_ascii())
        .map(char::from)
        .collect();
    if token.len() > 16 {
        s.push('…');
    }
    s
}
