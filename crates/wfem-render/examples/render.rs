//! Renders a smooth field with iso-lines on the generated `bumpy(4)` mesh and writes a PNG.
//!
//! ```text
//! cargo run --release -p wfem-render --example render -- /tmp/wfem-render.png
//! ```
//! The field is a smooth "distance-like" bump exp(−|p − p₀|²/σ²) centred at one vertex, which
//! is marked with a red dot, like the basis functions K_t e_i in the paper's figures.

use mesh_fem::generate::bumpy;
use std::time::Instant;
use wfem_render::{render_png, RenderParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/wfem-render.png".to_string());
    let mesh = bumpy(4);
    let positions = mesh.positions();
    // Anchor: the vertex with the largest x + y + z, visible from the front and oblique views.
    let anchor = (0..positions.len())
        .max_by(|&a, &b| {
            let s = |i: usize| positions[i][0] + positions[i][1] + positions[i][2];
            s(a).total_cmp(&s(b))
        })
        .ok_or("empty mesh")?;
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
            "bumpy(4), {} vertices: exp(-|p - p0|^2 / 0.8)",
            mesh.n_vertices()
        )),
        highlight: vec![anchor as u32],
        ..RenderParams::default()
    };
    let start = Instant::now();
    let png = render_png(&mesh, &field, &params)?;
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
