//! ASCII OFF reader (OFF, COFF, NOFF, CNOFF, STOFF, … headers).
//!
//! Layout: a header keyword (optional in some files, and possibly followed by the counts on
//! the same line), then `n_vertices n_faces n_edges`, then one vertex per line (extra values
//! such as colours or normals after x y z are ignored), then one face per line
//! `k i₁ … i_k [colour]` with 0-based indices. `#` starts a comment; blank lines are skipped.

use super::text::{parse_f64, parse_i64, show, strip_comment, tokens, Lines};
use super::{checked_index, finish, parse_error, FaceSink, LoadOptions, LoadReport, MeshFormat};
use crate::{MeshError, TriMesh};
use std::path::Path;

/// Next line that is not blank after removing comments.
fn next_content<'a>(lines: &mut Lines<'a>) -> Option<(usize, &'a [u8])> {
    lines.find_map(|(n, l)| {
        let l = strip_comment(l);
        l.iter().any(|b| !b.is_ascii_whitespace()).then_some((n, l))
    })
}

pub(crate) fn read(bytes: &[u8], path: &Path, opts: &LoadOptions) -> Result<(TriMesh, LoadReport), MeshError> {
    let mut report = LoadReport::new(MeshFormat::Off);
    let mut lines = Lines::new(bytes);
    let eof = |lines: &Lines<'_>, what: &str| {
        parse_error(
            path,
            lines.line(),
            format!("unexpected end of file while reading {what}"),
        )
    };

    // Header keyword and counts.
    let (line_no, first) = next_content(&mut lines).ok_or_else(|| eof(&lines, "the header"))?;
    let mut header_tokens = tokens(first).peekable();
    let mut counts: Vec<(usize, &[u8])> = Vec::with_capacity(3);
    if let Some(keyword) = header_tokens.peek().copied() {
        if keyword.first().is_some_and(|b| b.is_ascii_alphabetic()) || keyword.ends_with(b"OFF") {
            header_tokens.next();
            let prefix = keyword.strip_suffix(b"OFF").ok_or_else(|| {
                parse_error(
                    path,
                    line_no,
                    format!("expected an OFF header, found {:?}", show(keyword)),
                )
            })?;
            // ST (texture), C (colour), N (normal) add per-vertex values we skip; "4OFF" and
            // "nOFF" describe other dimensions.
            if !prefix.iter().all(|b| b"STCN".contains(b)) {
                return Err(parse_error(
                    path,
                    line_no,
                    format!("{:?} is not a 3-D OFF variant", show(keyword)),
                ));
            }
            if header_tokens.peek().is_some_and(|t| t.eq_ignore_ascii_case(b"BINARY")) {
                return Err(parse_error(path, line_no, "binary OFF is not supported"));
            }
            if !prefix.is_empty() {
                report
                    .notes
                    .push(format!("{} header: extra per-vertex values ignored", show(keyword)));
            }
        }
    }
    counts.extend(header_tokens.map(|t| (line_no, t)));
    while counts.len() < 2 {
        let (n, l) = next_content(&mut lines).ok_or_else(|| eof(&lines, "the element counts"))?;
        counts.extend(tokens(l).map(|t| (n, t)));
    }
    let count = |k: usize, what: &str| -> Result<usize, MeshError> {
        let (n, t) = counts[k];
        parse_i64(t)
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| parse_error(path, n, format!("cannot read the {what} count {:?}", show(t))))
    };
    let n_vertices = count(0, "vertex")?;
    let n_faces = count(1, "face")?;
    // The edge count (third number) is ignored: many writers put a nonzero value there.

    // Each vertex line needs at least 6 bytes and each face line 8, so the file size bounds
    // what a (possibly corrupt) header may make us reserve.
    let mut positions: Vec<[f64; 3]> = Vec::with_capacity(n_vertices.min(bytes.len() / 6));
    for v in 0..n_vertices {
        let (n, l) = next_content(&mut lines).ok_or_else(|| eof(&lines, &format!("vertex {v} of {n_vertices}")))?;
        let mut it = tokens(l);
        let mut p = [0.0f64; 3];
        for (k, c) in p.iter_mut().enumerate() {
            let t = it
                .next()
                .ok_or_else(|| parse_error(path, n, format!("vertex {v} has {k} coordinates, expected 3")))?;
            *c = parse_f64(t)
                .ok_or_else(|| parse_error(path, n, format!("cannot read coordinate {:?} of vertex {v}", show(t))))?;
        }
        positions.push(p);
    }

    let mut sink = FaceSink::new(path, opts.triangulate_polygons, n_faces.min(bytes.len() / 8));
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for f in 0..n_faces {
        let (n, l) = next_content(&mut lines).ok_or_else(|| eof(&lines, &format!("face {f} of {n_faces}")))?;
        let mut it = tokens(l);
        let k_token = it.next().unwrap_or(l);
        let k = parse_i64(k_token)
            .and_then(|k| usize::try_from(k).ok())
            .ok_or_else(|| {
                parse_error(
                    path,
                    n,
                    format!("cannot read the corner count {:?} of face {f}", show(k_token)),
                )
            })?;
        corners.clear();
        for c in 0..k {
            let t = it
                .next()
                .ok_or_else(|| parse_error(path, n, format!("face {f} declares {k} corners but lists {c}")))?;
            let index = parse_i64(t)
                .ok_or_else(|| parse_error(path, n, format!("cannot read vertex index {:?} of face {f}", show(t))))?;
            corners.push(checked_index(path, n, f, index)?);
        }
        // Anything after the indices (a face colour) is ignored.
        sink.push(&corners, n)?;
    }
    if next_content(&mut lines).is_some() {
        report
            .notes
            .push("ignored content after the declared faces".to_string());
    }
    finish(positions, sink, report)
}
