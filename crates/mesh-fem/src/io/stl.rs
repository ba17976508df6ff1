//! STL reader (ASCII and binary) with welding of bit-identical corners.
//!
//! Binary layout: 80-byte header, u32 little-endian triangle count, then per triangle 50
//! bytes: normal (3 × f32), three corners (9 × f32), u16 attribute. Binary files may start
//! with the word "solid" in their header, so the decision is: if the size matches the binary
//! layout exactly the file is binary; otherwise a file beginning with "solid" that contains
//! only text bytes is ASCII, and anything else is (possibly truncated or padded) binary.

use super::text::{parse_f64, show, tokens, Lines};
use super::{finish, parse_error, FaceSink, LoadOptions, LoadReport, MeshFormat};
use crate::{MeshError, TriMesh};
use std::collections::HashMap;
use std::path::Path;

const HEADER: usize = 80;
const RECORD: usize = 50;

pub(crate) fn read(bytes: &[u8], path: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    let _ = opts; // STL facets are triangles by definition.
    let declared = binary_count(bytes);
    let exact_binary =
        declared.is_some_and(|n| n.checked_mul(RECORD).and_then(|b| b.checked_add(HEADER + 4)) == Some(bytes.len()));
    let starts_with_solid = {
        let start = bytes
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(bytes.len());
        bytes[start..].starts_with(b"solid")
    };
    let mut report = LoadReport::new(MeshFormat::Stl);
    // Binary records hold NUL and other control bytes (zero normals, the u16 attribute), which
    // ASCII STL never contains; so "solid" + text ⇒ ASCII, everything else ⇒ binary.
    let textual = || {
        bytes
            .iter()
            .all(|&b| b >= 0x20 || matches!(b, b'\t' | b'\n' | b'\r' | 0x0c))
    };
    let corners = if !exact_binary && starts_with_solid && textual() {
        report.notes.push("ASCII STL".to_string());
        read_ascii(bytes, path)?
    } else {
        report.notes.push("binary STL".to_string());
        read_binary(bytes, path, &mut report)?
    };
    weld(corners, path, report)
}

fn binary_count(bytes: &[u8]) -> Option<usize> {
    let c: [u8; 4] = bytes.get(HEADER..HEADER + 4)?.try_into().ok()?;
    usize::try_from(u32::from_le_bytes(c)).ok()
}

fn read_binary(bytes: &[u8], path: &Path, report: &mut LoadReport) -> Result<Vec<[[f64; 3]; 3]>, MeshError> {
    let n = binary_count(bytes).ok_or_else(|| {
        parse_error(
            path,
            0,
            format!(
                "binary STL needs at least {} bytes, the file has {}",
                HEADER + 4,
                bytes.len()
            ),
        )
    })?;
    let body = &bytes[HEADER + 4..];
    let available = body.len() / RECORD;
    if available < n {
        return Err(parse_error(
            path,
            0,
            format!(
                "binary STL declares {n} triangles but holds only {available} ({} bytes)",
                bytes.len()
            ),
        ));
    }
    if body.len() > n * RECORD {
        report.notes.push(format!(
            "ignored {} bytes after the last triangle",
            body.len() - n * RECORD
        ));
    }
    let mut tris = Vec::with_capacity(n);
    for rec in body.chunks_exact(RECORD).take(n) {
        let mut t = [[0.0f64; 3]; 3];
        // Skip the 12-byte normal; corners follow as 9 f32.
        for (k, c) in rec[12..48].chunks_exact(4).enumerate() {
            let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            t[k / 3][k % 3] = f64::from(v);
        }
        tris.push(t);
    }
    Ok(tris)
}

fn read_ascii(bytes: &[u8], path: &Path) -> Result<Vec<[[f64; 3]; 3]>, MeshError> {
    let mut tris = Vec::with_capacity(bytes.len() / 256);
    let mut current: [[f64; 3]; 3] = [[0.0; 3]; 3];
    let mut n_in_loop: Option<usize> = None;
    let mut facet_line = 0;
    for (line_no, line) in Lines::new(bytes) {
        let mut it = tokens(line);
        let Some(keyword) = it.next() else { continue };
        match keyword {
            b"vertex" => {
                let k = n_in_loop.ok_or_else(|| parse_error(path, line_no, "'vertex' outside an 'outer loop'"))?;
                if k >= 3 {
                    return Err(parse_error(
                        path,
                        line_no,
                        format!("facet starting at line {facet_line} has more than 3 vertices"),
                    ));
                }
                for (c, slot) in current[k].iter_mut().enumerate() {
                    let t = it
                        .next()
                        .ok_or_else(|| parse_error(path, line_no, format!("vertex has {c} coordinates, expected 3")))?;
                    *slot = parse_f64(t).ok_or_else(|| {
                        parse_error(
                            path,
                            line_no,
                            format!("cannot read coordinate {:?} as a number", show(t)),
                        )
                    })?;
                }
                n_in_loop = Some(k + 1);
            }
            b"outer" => {
                facet_line = line_no;
                n_in_loop = Some(0);
            }
            b"endloop" => {
                let k = n_in_loop
                    .take()
                    .ok_or_else(|| parse_error(path, line_no, "'endloop' without 'outer loop'"))?;
                if k != 3 {
                    return Err(parse_error(
                        path,
                        line_no,
                        format!("facet starting at line {facet_line} has {k} vertices, expected 3"),
                    ));
                }
                tris.push(current);
            }
            b"solid" | b"facet" | b"endfacet" | b"endsolid" => {}
            other => {
                return Err(parse_error(
                    path,
                    line_no,
                    format!("unexpected keyword {:?} in ASCII STL", show(other)),
                ))
            }
        }
    }
    if n_in_loop.is_some() {
        return Err(parse_error(path, facet_line, "unexpected end of file inside a facet"));
    }
    Ok(tris)
}

/// Merges corners with bit-identical coordinates (−0 and +0 count as equal) into shared
/// vertices, numbered in order of first appearance.
fn weld(tris: Vec<[[f64; 3]; 3]>, path: &Path, mut report: LoadReport) -> Result<(TriMesh, LoadReport), MeshError> {
    let key = |p: &[f64; 3]| p.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
    let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(tris.len());
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(tris.len() / 2 + 3);
    let mut sink = FaceSink::new(path, false, tris.len());
    for t in &tris {
        let mut f = [0u32; 3];
        for (slot, p) in f.iter_mut().zip(t) {
            let next = u32::try_from(positions.len())
                .map_err(|_| parse_error(path, 0, "more than 2³² distinct STL vertices"))?;
            *slot = *index.entry(key(p)).or_insert_with(|| {
                positions.push(*p);
                next
            });
        }
        sink.push(&f, 0)?;
    }
    report.welded_vertices = 3 * tris.len() - positions.len();
    finish(positions, sink, report)
}
