//! Renders a smooth field with iso-lines on the generated `bumpy(4)` mesh and writes a PNG;
//! with `--splats`, the same field on the vertices of `bumpy(5)` taken as a point cloud without
//! faces, drawn as splats.
//!
//! ```text
//! cargo run --release -p wfem-render --example render -- /tmp/wfem-render.png
//! cargo run --release -p wfem-render --example render -- --splats /tmp/wfem-splats.png
//! ```
//! The field is a smooth "distance-like" bump exp(−|p − p₀|²/σ²) centred at one vertex, which
//! is marked with a red dot, like the basis functions K_t e_i in the paper's figures. The
//! splats' normals are the cloud's estimated tangent planes (arbitrary signs) and their radii
//! come from its neighbourhood triangles, as in `wfem heat cloud.xyz … -o x.png`: the picture
//! should look like the mesh's (a closed surface, smooth colours and iso-lines).

use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::generate::bumpy;
use mesh_fem::AssemblyParams;
use std::time::Instant;
use wfem_render::{render_png, render_splats_png, RenderParams, Splats};

/// The bump exp(−|p − p₀|²/0.8) around the point with the largest x + y + z (visible from the
/// front and oblique views), and that point.
fn bump(positions: &[[f64; 3]]) -> Result<(Vec<f64>, usize), &'static str> {
    let anchor = (0..positions.len())
        .max_by(|&a, &b| {
            let s = |i: usize| positions[i][0] + positions[i][1] + positions[i][2];
            s(a).total_cmp(&s(b))
        })
        .ok_or("no points")?;
    let p0 = positions[anchor];
    let field = positions
        .iter()
        .map(|p| {
            let d2 = (0..3).map(|k| (p[k] - p0[k]).powi(2)).sum::<f64>();
            (-d2 / 0.8).exp()
        })
        .collect();
    Ok((field, anchor))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let splats = args.iter().any(|a| a == "--splats");
    let path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| format!("/tmp/wfem-{}.png", if splats { "splats" } else { "render" }));
    let start;
    let (png, params) = if splats {
        let points = bumpy(5).positions().to_vec();
        let cloud = PointCloud::new(points.clone(), None)?;
        let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default())?;
        let splats = Splats::from_triangles(points, ops.normals, ops.neighbourhood.faces())?;
        let (field, anchor) = bump(splats.positions())?;
        let params = RenderParams {
            title: Some(format!(
                "bumpy(5) as a cloud of {} points, splats: exp(-|p - p0|^2 / 0.8)",
                splats.len()
            )),
            highlight: vec![anchor as u32],
            ..RenderParams::default()
        };
        start = Instant::now();
        (render_splats_png(&splats, &field, &params)?, params)
    } else {
        let mesh = bumpy(4);
        let (field, anchor) = bump(mesh.positions())?;
        let params = RenderParams {
            title: Some(format!(
                "bumpy(4), {} vertices: exp(-|p - p0|^2 / 0.8)",
                mesh.n_vertices()
            )),
            highlight: vec![anchor as u32],
            ..RenderParams::default()
        };
        start = Instant::now();
        (render_png(&mesh, &field, &params)?, params)
    };
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
