//! Per-vertex fields on a mesh or a volume as a VTK XML unstructured grid (`.vtu`, ASCII), the
//! file ParaView, VisIt and meshio open: the points, the cells (triangles or tetrahedra) and one
//! `Float64` point-data array per field. Values are printed in Rust's shortest round-trip form
//! (read back exactly); `+∞`, where allowed, is `inf`.

use super::AtomicSet;
use crate::MeshError;
use std::io::Write;
use std::path::Path;

/// The cells of a `.vtu`: a surface's triangles or a volume's tetrahedra.
#[derive(Clone, Copy, Debug)]
pub enum Cells<'a> {
    /// Triangles (VTK cell type 5).
    Triangles(&'a [[u32; 3]]),
    /// Tetrahedra (VTK cell type 10).
    Tetrahedra(&'a [[u32; 4]]),
}

impl Cells<'_> {
    fn len(&self) -> usize {
        match self {
            Cells::Triangles(c) => c.len(),
            Cells::Tetrahedra(c) => c.len(),
        }
    }

    fn corners(&self) -> usize {
        match self {
            Cells::Triangles(_) => 3,
            Cells::Tetrahedra(_) => 4,
        }
    }

    fn vtk_type(&self) -> u8 {
        match self {
            Cells::Triangles(_) => 5,
            Cells::Tetrahedra(_) => 10,
        }
    }

    fn cell(&self, i: usize) -> &[u32] {
        match self {
            Cells::Triangles(c) => &c[i],
            Cells::Tetrahedra(c) => &c[i],
        }
    }
}

/// Text safe inside an XML attribute.
fn attribute(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Stages the `.vtu` of `fields` on `positions` and `cells` in `set`.
///
/// # Errors
/// [`MeshError::FieldLength`] for a field without one value per point, [`MeshError::NonFiniteValue`]
/// for NaN or −∞ (or +∞ without `allow_infinity`), [`MeshError::Invalid`] without fields or
/// with a repeated name, [`MeshError::Io`] when the file cannot be staged.
pub fn stage_vtu(
    set: &mut AtomicSet,
    path: &Path,
    positions: &[[f64; 3]],
    cells: Cells<'_>,
    fields: &[(&str, &[f64])],
    allow_infinity: bool,
) -> Result<(), MeshError> {
    super::field::require_fields(path, fields, "a VTU file")?;
    super::field::check_fields(path, positions.len(), fields, None, allow_infinity)?;
    super::field::unique_names(path, fields)?;
    set.stage(path, |w| write_vtu(w, positions, cells, fields))
}

fn write_vtu(
    w: &mut dyn Write,
    positions: &[[f64; 3]],
    cells: Cells<'_>,
    fields: &[(&str, &[f64])],
) -> std::io::Result<()> {
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "  <UnstructuredGrid>")?;
    writeln!(
        w,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        positions.len(),
        cells.len()
    )?;
    writeln!(w, "      <PointData Scalars=\"{}\">", attribute(fields[0].0))?;
    for (name, values) in fields {
        writeln!(
            w,
            "        <DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
            attribute(name)
        )?;
        for chunk in values.chunks(8) {
            let line: Vec<String> = chunk.iter().map(|v| format!("{v:?}")).collect();
            writeln!(w, "          {}", line.join(" "))?;
        }
        writeln!(w, "        </DataArray>")?;
    }
    writeln!(w, "      </PointData>")?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    for p in positions {
        writeln!(w, "          {:?} {:?} {:?}", p[0], p[1], p[2])?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Points>")?;
    writeln!(w, "      <Cells>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    for i in 0..cells.len() {
        let c: Vec<String> = cells.cell(i).iter().map(u32::to_string).collect();
        writeln!(w, "          {}", c.join(" "))?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    let k = cells.corners();
    for chunk in (1..=cells.len()).collect::<Vec<_>>().chunks(16) {
        let line: Vec<String> = chunk.iter().map(|i| (i * k).to_string()).collect();
        writeln!(w, "          {}", line.join(" "))?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">")?;
    let t = cells.vtk_type().to_string();
    for chunk in (0..cells.len()).collect::<Vec<_>>().chunks(32) {
        writeln!(w, "          {}", vec![t.as_str(); chunk.len()].join(" "))?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(w, "      </Cells>")?;
    writeln!(w, "    </Piece>")?;
    writeln!(w, "  </UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")?;
    Ok(())
}
