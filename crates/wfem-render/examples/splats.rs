//! Renders the field of the `render` example on the vertices of the generated `bumpy(5)` mesh
//! taken as a point cloud without faces, drawn as splats, and writes a PNG.
//!
//! ```text
//! cargo run --release -p wfem-render --example splats -- /tmp/wfem-splats.png
//! ```
//! The normals are the cloud's estimated tangent planes (arbitrary signs) and the radii come
//! from its neighbourhood triangles, as in `wfem heat cloud.xyz … -o x.png`; the picture should look like
//! the mesh's (`--example render`): a closed surface, smooth colours and iso-lines.

use mesh_fem::generate::bumpy;
use mesh_fem::{assemble_cloud, AssemblyParams, CloudParams, PointCloud};
use std::time::Instant;
use wfem_render::{render_splats_png, RenderParams, Splats};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/wfem-splats.png".to_string());
    let points = bumpy(5).positions().to_vec();
    let cloud = PointCloud::new(points.clone(), None)?;
    let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())?;
    let splats = Splats::from_triangles(points, ops.normals, ops.neighbourhood.faces())?;
    let positions = splats.positions();
    // Anchor: the point with the largest x + y + z, visible from the front and oblique views.
    let anchor = (0..positions.len())
        .max_by(|&a, &b| {
            let s = |i: usize| positions[i][0] + positions[i][1] + positions[i][2];
            s(a).total_cmp(&s(b))
        })
        .ok_or("empty cloud")?;
    let p0 = positions[anchor];
    let field: Vec<f64> = positions
        .iter()
        .map(|p| {
            let d2 = (0..3).map(|k| (p[k] - p0[k]).powi(2)).sum::<f64>();
            (-d2 / 0.8).exp()
        })
        .collect();
    let params = RenderParams {
        title: Some(format!(
            "bumpy(5) as a cloud of {} points, splats: exp(-|p - p0|^2 / 0.8)",
            splats.len()
        )),
        highlight: vec![anchor as u32],
        ..RenderParams::default()
    };
    let start = Instant::now();
    let png = render_splats_png(&splats, &field, &params)?;
    let elapsed = start.elapsed();
    std::fs::write(&path, &png)?;
    println!(
        "wrote {path}: {} bytes, {} views of {}x{}, rendered in {:.3} s",
        png.len(),
        params.views.len(),
        params.width,
        params.height,
        elapsed.as_secs_f64()
    );
    Ok(())
}
