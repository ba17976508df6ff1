//! The demo's volume (issue #39): the heat K_t e_i from a point inside a generated solid (the
//! demo's bumpy shape, filled with tetrahedra), drawn on its boundary and on a cut through it,
//! and written as a `.vtu` that ParaView opens.

use super::heat::{negative_note, prepare_kernel};
use super::output::{figure_params, short_label, volume_cut, with_cut};
use super::CliError;
use mesh_fem::io::vtu::{stage_vtu, Cells};
use mesh_fem::io::AtomicSet;
use mesh_fem::volume::assemble_volume;
use mesh_fem::AssemblyParams;
use std::fmt::Write as _;
use std::path::Path;
use wfem_heat::HeatParams;
use wfem_render::{Frame, View};

/// The generated solid: shells of the level-3 icosphere (8 × 642 + 1 = 5,137 vertices,
/// 28,160 tetrahedra).
const LEVEL: u32 = 3;
const SHELLS: usize = 8;

/// The diffusion times on the solid (its radius is about 1).
const TIMES: [f64; 2] = [0.01, 0.05];

/// The files of the section.
pub fn files() -> Vec<String> {
    let mut files = vec!["volume.vtu".to_string()];
    files.extend(TIMES.iter().map(|t| format!("volume_t{}.png", short_label(*t))));
    files
}

/// Computes the heat from a point inside the generated solid at [`TIMES`], stages the `.vtu` and
/// the figures (boundary above, the cut through the centre below) in `set`, and returns the
/// report's section.
///
/// # Errors
/// Assembly, heat and rendering errors (none expected on the generated solid).
pub fn section(out: &Path, set: &mut AtomicSet) -> Result<String, CliError> {
    let solid = mesh_fem::generate::tet_bumpy(LEVEL, SHELLS);
    let boundary = solid.boundary_mesh()?;
    let fem = assemble_volume(&solid, &AssemblyParams::default())?;
    let n = solid.n_vertices();
    let kernel = prepare_kernel(&fem, HeatParams::default(), n)?;
    // The source: the vertex nearest to a point halfway out along screen-right, in the plane of
    // the default cut (through the centre, facing the front view), so the cut shows it.
    let frame = Frame::auto(&boundary);
    let (lo, hi) = mesh_fem::vec3::bounding_box(solid.positions());
    let target = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]) + 0.25 * (hi[k] - lo[k]) * frame.right[k]);
    let source = (0..n)
        .min_by(|&a, &b| {
            let d = |v: usize| mesh_fem::vec3::norm(mesh_fem::vec3::sub(solid.positions()[v], target));
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    let mut e = vec![0.0; n];
    e[source] = 1.0;
    let cut = volume_cut(&solid, None, &frame)?;
    let views = View::standard_in(&frame);
    let mut fields: Vec<(String, Vec<f64>)> = Vec::new();
    let mut rows = Vec::new();
    for &t in &TIMES {
        let g = kernel.apply(&e, t)?;
        // Heat is conserved: 1ᵀB K_t e_i = 1ᵀB e_i = D_ii (D holds the row sums of B).
        let total: f64 = g.iter().zip(&fem.lumped_diagonal).map(|(x, d)| x * d).sum();
        let conservation = (total - fem.lumped_diagonal[source]).abs() / fem.lumped_diagonal[source];
        let on_boundary = boundary
            .faces()
            .iter()
            .flatten()
            .map(|&v| g[v as usize])
            .fold(0.0f64, f64::max);
        let peak = g.iter().fold(0.0f64, |m, &x| m.max(x));
        rows.push((t, peak, on_boundary, conservation));
        let title = format!(
            "demo: heat K_t e_{source} from a point inside a solid, t = {t} ({n} vertices){}",
            negative_note(&e, &g)
        );
        let params = figure_params(&title, &g, &[], views.clone());
        let png = with_cut(&boundary, &cut, &g, params, &frame)?;
        let path = out.join(format!("volume_t{}.png", short_label(t)));
        set.stage(&path, |w| w.write_all(&png))?;
        fields.push((format!("heat_t{t}"), g));
    }
    let refs: Vec<(&str, &[f64])> = fields.iter().map(|(n, v)| (n.as_str(), v.as_slice())).collect();
    stage_vtu(
        set,
        &out.join("volume.vtu"),
        solid.positions(),
        Cells::Tetrahedra(solid.tets()),
        &refs,
        false,
    )?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## A volume\n\nThe heat K_t e_{source} of the wFEM kernel on a generated solid (the bumpy shape filled \
         with {} tetrahedra, {n} vertices, volume {:.4}): linear FEM on tetrahedra, the exact default method. \
         The source lies inside; `volume_t*.png` show the boundary above and the cut through the centre below \
         (one colour scale), `volume.vtu` holds the tetrahedra and both fields (ParaView).\n",
        solid.n_tets(),
        solid.volume()
    );
    let _ = writeln!(
        s,
        "| t | max K_t e_i | max on the boundary | heat lost, \\|1ᵀB(K_t e_i − e_i)\\| / D_ii |"
    );
    let _ = writeln!(s, "|---:|---:|---:|---:|");
    for (t, peak, on_boundary, conservation) in rows {
        let _ = writeln!(s, "| {t} | {peak:.3e} | {on_boundary:.3e} | {conservation:.1e} |");
    }
    Ok(s)
}
