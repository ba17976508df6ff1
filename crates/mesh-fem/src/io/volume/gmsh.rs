//! Gmsh `.msh` for the volume reader: 2.2 (ASCII and binary) and 4.1 (ASCII).

use super::{Parsed, Parser, Tokens};
use crate::MeshError;

impl Parser {
    pub(super) fn gmsh(&mut self, bytes: &[u8]) -> Result<Parsed, MeshError> {
        let mut t = Tokens::new(bytes, false);
        if t.next() != Some("$MeshFormat") {
            return Err(self.err(1, "not a Gmsh file (no $MeshFormat)"));
        }
        let version = self.token(&mut t, "version")?.to_string();
        let file_type = self.int(&mut t, "file type")?;
        let data_size = self.int(&mut t, "data size")?;
        match (version.as_str(), file_type) {
            ("2.2", 0) | ("4.1", 0) => {}
            ("2.2", 1) => {
                if data_size != 8 {
                    return Err(self.err(
                        t.line,
                        format!("binary data size {data_size}: only 8-byte reals are read"),
                    ));
                }
                return self.gmsh22_binary(bytes, t.pos);
            }
            (v, ft) => {
                return Err(self.err(
                    t.line,
                    format!(
                        "Gmsh {v} ({}): 2.2 ASCII or binary and 4.1 ASCII are read",
                        if ft == 0 { "ASCII" } else { "binary" }
                    ),
                ))
            }
        }
        let v4 = version == "4.1";
        let mut ids: std::collections::HashMap<i64, u32> = std::collections::HashMap::new();
        let (mut positions, mut tets) = (Vec::new(), Vec::new());
        while let Some(section) = t.next() {
            let line = t.line;
            match section {
                "$Nodes" if !v4 => {
                    let n = self.count(&mut t, "number of nodes", 4)?;
                    positions.reserve(n);
                    for _ in 0..n {
                        let id = self.int(&mut t, "node id")?;
                        ids.insert(id, positions.len() as u32);
                        positions.push([
                            self.float(&mut t, "x")?,
                            self.float(&mut t, "y")?,
                            self.float(&mut t, "z")?,
                        ]);
                    }
                }
                "$Nodes" => {
                    let blocks = self.count(&mut t, "entity blocks", 4)?;
                    let n = self.count(&mut t, "number of nodes", 4)?;
                    self.int(&mut t, "min tag")?;
                    self.int(&mut t, "max tag")?;
                    positions.reserve(n);
                    for _ in 0..blocks {
                        self.int(&mut t, "entity dimension")?;
                        self.int(&mut t, "entity tag")?;
                        let parametric = self.int(&mut t, "parametric")? != 0;
                        let k = self.count(&mut t, "nodes in block", 4)?;
                        let start = positions.len();
                        let mut tags = Vec::with_capacity(k);
                        for _ in 0..k {
                            tags.push(self.int(&mut t, "node tag")?);
                        }
                        if parametric {
                            return Err(self.err(t.line, "parametric nodes are not read"));
                        }
                        for (j, tag) in tags.into_iter().enumerate() {
                            ids.insert(tag, (start + j) as u32);
                            positions.push([
                                self.float(&mut t, "x")?,
                                self.float(&mut t, "y")?,
                                self.float(&mut t, "z")?,
                            ]);
                        }
                    }
                }
                "$Elements" if !v4 => {
                    let m = self.count(&mut t, "number of elements", 4)?;
                    for _ in 0..m {
                        self.int(&mut t, "element id")?;
                        let ty = self.int(&mut t, "element type")?;
                        let tags = self.count(&mut t, "number of tags", 1)?;
                        for _ in 0..tags {
                            self.int(&mut t, "tag")?;
                        }
                        let nodes = gmsh_nodes(ty)
                            .ok_or_else(|| self.err(t.line, format!("unknown Gmsh element type {ty}")))?;
                        self.gmsh_element(&mut t, ty, nodes, &ids, &mut tets)?;
                    }
                }
                "$Elements" => {
                    let blocks = self.count(&mut t, "entity blocks", 4)?;
                    self.count(&mut t, "number of elements", 1)?;
                    self.int(&mut t, "min tag")?;
                    self.int(&mut t, "max tag")?;
                    for _ in 0..blocks {
                        self.int(&mut t, "entity dimension")?;
                        self.int(&mut t, "entity tag")?;
                        let ty = self.int(&mut t, "element type")?;
                        let nodes = gmsh_nodes(ty)
                            .ok_or_else(|| self.err(t.line, format!("unknown Gmsh element type {ty}")))?;
                        let k = self.count(&mut t, "elements in block", nodes + 1)?;
                        for _ in 0..k {
                            self.int(&mut t, "element tag")?;
                            self.gmsh_element(&mut t, ty, nodes, &ids, &mut tets)?;
                        }
                    }
                }
                s if s.starts_with("$End") => {}
                s if s.starts_with('$') => {
                    // A section not needed ($PhysicalNames, $Entities, $NodeData …): skip to its end.
                    let end = format!("$End{}", &s[1..]);
                    loop {
                        match t.next() {
                            Some(x) if x == end => break,
                            Some(_) => {}
                            None => return Err(self.err(line, format!("section {s} has no {end}"))),
                        }
                    }
                }
                other => return Err(self.err(line, format!("unexpected {other:?} outside a section"))),
            }
        }
        Ok((positions, tets))
    }

    fn gmsh_element(
        &mut self,
        t: &mut Tokens<'_>,
        ty: i64,
        nodes: usize,
        ids: &std::collections::HashMap<i64, u32>,
        tets: &mut Vec<[u32; 4]>,
    ) -> Result<(), MeshError> {
        let mut v = [0u32; 4];
        for k in 0..nodes {
            let line = t.line;
            let id = self.int(t, "node")?;
            let i = *ids
                .get(&id)
                .ok_or_else(|| self.err(line, format!("node {id} is not defined in $Nodes")))?;
            if k < 4 {
                v[k] = i;
            }
        }
        if ty == 4 {
            tets.push(v);
        } else {
            self.ignore(gmsh_kind(ty), 1);
        }
        Ok(())
    }

    fn gmsh22_binary(&mut self, bytes: &[u8], mut pos: usize) -> Result<Parsed, MeshError> {
        let err = |s: &Self, m: String| s.err(0, m);
        let i32_at = |b: &[u8], p: usize| -> Option<i32> {
            b.get(p..p + 4).map(|x| i32::from_le_bytes([x[0], x[1], x[2], x[3]]))
        };
        let f64_at = |b: &[u8], p: usize| -> Option<f64> {
            b.get(p..p + 8)
                .map(|x| f64::from_le_bytes(x.try_into().unwrap_or([0; 8])))
        };
        // After "2.2 1 8": a newline, then the int 1 (endianness check).
        while bytes.get(pos).is_some_and(|b| b.is_ascii_whitespace()) {
            pos += 1;
        }
        if i32_at(bytes, pos) != Some(1) {
            return Err(err(
                self,
                "the binary endianness check is not 1: only little-endian files are read".into(),
            ));
        }
        pos += 4;
        let find = |b: &[u8], from: usize, pat: &[u8]| {
            b[from.min(b.len())..]
                .windows(pat.len())
                .position(|w| w == pat)
                .map(|i| i + from)
        };
        let text_line = |b: &[u8], from: usize| -> (String, usize) {
            let mut p = from;
            while b.get(p).is_some_and(|c| c.is_ascii_whitespace()) {
                p += 1;
            }
            let end = b[p.min(b.len())..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(b.len(), |i| i + p);
            (
                String::from_utf8_lossy(&b[p.min(b.len())..end]).trim().to_string(),
                end + 1,
            )
        };
        let mut ids = std::collections::HashMap::new();
        let (mut positions, mut tets) = (Vec::new(), Vec::new());
        let Some(nodes_at) = find(bytes, pos, b"$Nodes") else {
            return Err(err(self, "no $Nodes section".into()));
        };
        let (count, mut p) = text_line(bytes, nodes_at + 6);
        let n: usize = count
            .parse()
            .map_err(|_| err(self, format!("$Nodes: {count:?} is not a count")))?;
        if n.saturating_mul(28) > bytes.len() - p.min(bytes.len()) {
            return Err(err(self, format!("$Nodes: {n} declared, more than the file can hold")));
        }
        for _ in 0..n {
            let id = i32_at(bytes, p).ok_or_else(|| err(self, "the file ends in $Nodes".into()))?;
            let xyz = [f64_at(bytes, p + 4), f64_at(bytes, p + 12), f64_at(bytes, p + 20)];
            let [Some(x), Some(y), Some(z)] = xyz else {
                return Err(err(self, "the file ends in $Nodes".into()));
            };
            ids.insert(i64::from(id), positions.len() as u32);
            positions.push([x, y, z]);
            p += 28;
        }
        let Some(el_at) = find(bytes, p, b"$Elements") else {
            return Err(err(self, "no $Elements section".into()));
        };
        let (count, mut p) = text_line(bytes, el_at + 9);
        let m: usize = count
            .parse()
            .map_err(|_| err(self, format!("$Elements: {count:?} is not a count")))?;
        if m.saturating_mul(8) > bytes.len() - p.min(bytes.len()) {
            return Err(err(
                self,
                format!("$Elements: {m} declared, more than the file can hold"),
            ));
        }
        let mut done = 0;
        while done < m {
            let (Some(ty), Some(k), Some(ntags)) = (i32_at(bytes, p), i32_at(bytes, p + 4), i32_at(bytes, p + 8))
            else {
                return Err(err(self, "the file ends in $Elements".into()));
            };
            p += 12;
            let nodes =
                gmsh_nodes(i64::from(ty)).ok_or_else(|| err(self, format!("unknown Gmsh element type {ty}")))?;
            if k <= 0 || ntags < 0 || k as usize > m - done {
                return Err(err(
                    self,
                    format!("element block of {k} elements with {ntags} tags is invalid"),
                ));
            }
            let record = 4 * (1 + ntags as usize + nodes);
            if (k as usize).saturating_mul(record) > bytes.len().saturating_sub(p) {
                return Err(err(self, "the file ends in $Elements".into()));
            }
            for _ in 0..k {
                let base = p + 4 * (1 + ntags as usize);
                let mut v = [0u32; 4];
                for j in 0..nodes {
                    let id = i32_at(bytes, base + 4 * j).unwrap_or(-1);
                    let i = *ids
                        .get(&i64::from(id))
                        .ok_or_else(|| err(self, format!("node {id} is not defined in $Nodes")))?;
                    if j < 4 {
                        v[j] = i;
                    }
                }
                if ty == 4 {
                    tets.push(v);
                } else {
                    self.ignore(gmsh_kind(i64::from(ty)), 1);
                }
                p += record;
            }
            done += k as usize;
        }
        Ok((positions, tets))
    }
}

/// Nodes of a Gmsh element type (the linear and common quadratic ones).
fn gmsh_nodes(ty: i64) -> Option<usize> {
    Some(match ty {
        1 => 2,
        2 => 3,
        3 => 4,
        4 => 4,
        5 => 8,
        6 => 6,
        7 => 5,
        8 => 3,
        9 => 6,
        10 => 9,
        11 => 10,
        15 => 1,
        _ => return None,
    })
}

fn gmsh_kind(ty: i64) -> &'static str {
    match ty {
        1 => "edges",
        2 => "triangles",
        3 => "quadrangles",
        5 => "hexahedra",
        6 => "prisms",
        7 => "pyramids",
        15 => "points",
        11 => "10-node tetrahedra",
        _ => "other elements",
    }
}
