//! Tests of point clouds drawn as splats, against the rendered mesh of the same surface: the
//! silhouette, no holes, the colours and iso-lines, the z-order, two-sided lighting of normals
//! with arbitrary signs, and every error variant of [`Splats`].

use crate::render::{best_t, count_red, front_params, luminance};
use mesh_fem::cloud::{assemble_cloud, CloudParams, PointCloud};
use mesh_fem::generate::icosphere;
use mesh_fem::AssemblyParams;
use wfem_render::{
    render_rgb, render_splats_png, render_splats_rgb, Colormap, RenderError, RenderParams, RgbImage, Splats, View,
};

/// SplitMix64 uniforms in (0, 1) (test-local).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        (((z ^ (z >> 31)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gauss(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
}

/// n uniformly random points on the unit sphere as splats, the way the CLI draws a cloud:
/// normals estimated by the cloud's assembly (arbitrary signs), radii from its neighbourhood
/// triangles.
fn sphere_splats(n: usize, seed: u64) -> Splats {
    let (points, normals, triangles) = sphere_cloud(n, seed);
    Splats::from_triangles(points, normals, &triangles).unwrap()
}

/// Points, normals and triangles.
type Cloud = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[u32; 3]>);

/// n uniformly random points on the unit sphere, the normals estimated by the cloud's
/// assembly, and its neighbourhood triangles.
fn sphere_cloud(n: usize, seed: u64) -> Cloud {
    let mut rng = Rng(seed);
    let points: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let p = [rng.gauss(), rng.gauss(), rng.gauss()];
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            p.map(|c| c / r)
        })
        .collect();
    let cloud = PointCloud::new(points.clone(), None).unwrap();
    let ops = assemble_cloud(&cloud, &CloudParams::default(), &AssemblyParams::default()).unwrap();
    (points, ops.normals, ops.neighbourhood.faces().to_vec())
}

fn z_of(points: &[[f64; 3]]) -> Vec<f64> {
    points.iter().map(|p| p[2]).collect()
}

fn covered(img: &RgbImage, x: u32, y: u32) -> bool {
    img.pixel(x, y) != [255; 3]
}

/// Pixels covered in one image and not in the other, and pixels of `inner` covered in
/// `reference` at distance ≥ 2 from its background but not covered in `inner` (holes).
fn coverage_difference(reference: &RgbImage, other: &RgbImage) -> (usize, usize, usize) {
    let (w, h) = (reference.width, reference.height);
    let (mut area, mut differ, mut holes) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let a = covered(reference, x, y);
            area += a as usize;
            differ += (a != covered(other, x, y)) as usize;
            let interior = (y.saturating_sub(2)..(y + 3).min(h))
                .all(|yy| (x.saturating_sub(2)..(x + 3).min(w)).all(|xx| covered(reference, xx, yy)));
            holes += (interior && !covered(other, x, y)) as usize;
        }
    }
    (area, differ, holes)
}

#[test]
fn splatted_sphere_covers_the_mesh_silhouette_without_holes() {
    let mesh = icosphere(5);
    let params = front_params(0);
    let reference = render_rgb(&mesh, &z_of(mesh.positions()), &params).unwrap();
    // From sparse (≈ 13 px between points in the 240 px view) to dense. Tangent discs stick
    // out of a curved silhouette by about r²/2R (r ≈ 0.1 at 2K points on the unit sphere):
    // measured 2.4 %, 1.1 %, 0.23 % of the silhouette's pixels.
    for (n, seed, tol) in [(2_000, 1, 0.03), (5_000, 2, 0.015), (20_000, 3, 0.005)] {
        let splats = sphere_splats(n, seed);
        let img = render_splats_rgb(&splats, &z_of(splats.positions()), &params).unwrap();
        let (area, differ, holes) = coverage_difference(&reference, &img);
        eprintln!("{n} points: {differ} of {area} silhouette pixels differ, {holes} holes");
        assert_eq!(holes, 0, "{n} points");
        assert!((differ as f64) < tol * area as f64, "{n} points: {differ} of {area}");
    }
}

#[test]
fn splatted_sphere_has_the_colours_and_shading_of_the_mesh() {
    let mesh = icosphere(5);
    let params = front_params(0);
    let reference = render_rgb(&mesh, &z_of(mesh.positions()), &params).unwrap();
    let splats = sphere_splats(20_000, 4);
    let img = render_splats_rgb(&splats, &z_of(splats.positions()), &params).unwrap();
    let (mut sum_t, mut sum_l, mut n) = (0.0, 0.0, 0);
    let mut worst_t: f64 = 0.0;
    for y in 0..img.height {
        for x in 0..img.width {
            let (a, b) = (reference.pixel(x, y), img.pixel(x, y));
            if a == [255; 3] || b == [255; 3] {
                continue;
            }
            let dt = (best_t(Colormap::Viridis, a) - best_t(Colormap::Viridis, b)).abs();
            worst_t = worst_t.max(dt);
            sum_t += dt;
            sum_l += (luminance(a) - luminance(b)).abs();
            n += 1;
        }
    }
    let (mean_t, mean_l) = (sum_t / n as f64, sum_l / n as f64);
    eprintln!("mean |Δt| {mean_t:.4}, worst {worst_t:.3}, mean |Δ luminance| {mean_l:.2}");
    // The field is blended from the points' values (exact at each point, z varies by ≈ 0.015
    // between neighbours), the normals are PCA estimates; the mesh's are interpolated.
    assert!(mean_t < 0.01, "mean |Δt| {mean_t}");
    assert!(mean_l < 2.0, "mean |Δ luminance| {mean_l}");
}

#[test]
fn isolines_on_splats_are_where_the_mesh_has_them() {
    let mesh = icosphere(5);
    let n = 12;
    let splats = sphere_splats(20_000, 5);
    let (mesh_field, splat_field) = (z_of(mesh.positions()), z_of(splats.positions()));
    let dark_rows = |with: &RgbImage, without: &RgbImage| -> Vec<f64> {
        // Centres of the runs of darkened pixels down the centre column.
        let x = with.width / 2;
        let (mut centres, mut run) = (Vec::new(), Vec::new());
        for y in 0..with.height {
            if luminance(with.pixel(x, y)) < 0.6 * luminance(without.pixel(x, y)) {
                run.push(y as f64);
            } else if !run.is_empty() {
                centres.push(run.iter().sum::<f64>() / run.len() as f64);
                run.clear();
            }
        }
        centres
    };
    let mesh_rows = dark_rows(
        &render_rgb(&mesh, &mesh_field, &front_params(n)).unwrap(),
        &render_rgb(&mesh, &mesh_field, &front_params(0)).unwrap(),
    );
    let with = render_splats_rgb(&splats, &splat_field, &front_params(n)).unwrap();
    let without = render_splats_rgb(&splats, &splat_field, &front_params(0)).unwrap();
    let splat_rows = dark_rows(&with, &without);
    assert_eq!(mesh_rows.len(), n, "{mesh_rows:?}");
    assert_eq!(splat_rows.len(), n, "{splat_rows:?}");
    for (a, b) in mesh_rows.iter().zip(&splat_rows) {
        assert!(
            (a - b).abs() < 1.5,
            "iso-lines at rows {mesh_rows:?} (mesh) and {splat_rows:?} (splats)"
        );
    }
    // Comparable line widths: the number of darkened pixels in the whole view.
    let darkened = |with: &RgbImage, without: &RgbImage| {
        with.data
            .chunks(3)
            .zip(without.data.chunks(3))
            .filter(|(a, b)| luminance([a[0], a[1], a[2]]) < luminance([b[0], b[1], b[2]]) - 30.0)
            .count() as f64
    };
    let mesh_dark = darkened(
        &render_rgb(&mesh, &mesh_field, &front_params(n)).unwrap(),
        &render_rgb(&mesh, &mesh_field, &front_params(0)).unwrap(),
    );
    let splat_dark = darkened(&with, &without);
    assert!(
        (splat_dark / mesh_dark - 1.0).abs() < 0.25,
        "{splat_dark} iso-line pixels on splats, {mesh_dark} on the mesh"
    );
}

/// Two parallel square sheets of points, z = 0 (field 0) and z = `gap` (field 1), the second
/// smaller (|x|, |y| ≤ 0.5 instead of 1).
fn two_sheets(gap: f64) -> (Splats, Vec<f64>) {
    let (mut points, mut field) = (Vec::new(), Vec::new());
    let m = 41;
    for (z, half, value) in [(0.0, 1.0, 0.0), (gap, 0.5, 1.0)] {
        for i in 0..m {
            for j in 0..m {
                let s = |k: usize| half * (2.0 * k as f64 / (m - 1) as f64 - 1.0);
                points.push([s(i), s(j), z]);
                field.push(value);
            }
        }
    }
    let n = points.len();
    let spacing = 2.0 / (m - 1) as f64;
    let radii = (0..n)
        .map(|i| if i < m * m { spacing } else { spacing / 2.0 })
        .collect();
    (Splats::new(points, vec![[0.0, 0.0, 1.0]; n], radii).unwrap(), field)
}

#[test]
fn nearer_splats_hide_farther_ones() {
    let (splats, field) = two_sheets(0.3);
    let params = |direction: [f64; 3]| RenderParams {
        width: 120,
        height: 120,
        views: vec![View::new(direction, [0.0, 1.0, 0.0])],
        n_isolines: 0,
        legend: false,
        ..RenderParams::default()
    };
    let t_at = |img: &RgbImage, x: u32, y: u32| best_t(Colormap::Viridis, img.pixel(x, y));
    // From +z the small sheet (field 1) is in front in the middle, the big one around it.
    let above = render_splats_rgb(&splats, &field, &params([0.0, 0.0, 1.0])).unwrap();
    assert!(t_at(&above, 60, 60) > 0.97, "{}", t_at(&above, 60, 60));
    assert!(t_at(&above, 12, 60) < 0.03, "{}", t_at(&above, 12, 60));
    // From −z the big sheet hides the small one everywhere.
    let below = render_splats_rgb(&splats, &field, &params([0.0, 0.0, -1.0])).unwrap();
    for (x, y) in [(60, 60), (12, 60), (50, 70)] {
        assert!(t_at(&below, x, y) < 0.03, "({x}, {y}): {}", t_at(&below, x, y));
    }
    // Obliquely from above, still no blending of the two sheets in the middle.
    let oblique = render_splats_rgb(&splats, &field, &params([0.3, 0.2, 1.0])).unwrap();
    let t = t_at(&oblique, 60, 60);
    assert!(t > 0.97, "{t}");
}

#[test]
fn normal_signs_do_not_matter() {
    let (points, normals, triangles) = sphere_cloud(3_000, 6);
    let field = z_of(&points);
    let flipped: Vec<[f64; 3]> = normals
        .iter()
        .enumerate()
        .map(|(i, n)| if i % 3 == 0 { n.map(|c| -c) } else { *n })
        .collect();
    let splats = Splats::from_triangles(points.clone(), normals, &triangles).unwrap();
    let other = Splats::from_triangles(points, flipped, &triangles).unwrap();
    let params = RenderParams {
        width: 160,
        height: 160,
        legend: false,
        ..RenderParams::default()
    };
    let a = render_splats_rgb(&splats, &field, &params).unwrap();
    let b = render_splats_rgb(&other, &field, &params).unwrap();
    // Equal up to the last bits of the sums of the blended normals and slopes.
    let max_diff = a.data.iter().zip(&b.data).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    assert!(max_diff <= 1, "{max_diff}");
}

#[test]
fn open_sheet_is_lit_from_both_sides() {
    let (splats, _) = two_sheets(0.3);
    // Only the big sheet: the first 41² points.
    let m2 = 41 * 41;
    let sheet = Splats::new(
        splats.positions()[..m2].to_vec(),
        splats.normals()[..m2].to_vec(),
        splats.radii()[..m2].to_vec(),
    )
    .unwrap();
    let field: Vec<f64> = sheet.positions().iter().map(|p| p[0]).collect();
    let params = RenderParams {
        width: 100,
        height: 100,
        views: vec![
            View::new([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
            View::new([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
        ],
        n_isolines: 0,
        legend: false,
        ..RenderParams::default()
    };
    let img = render_splats_rgb(&sheet, &field, &params).unwrap();
    let mean = |x0: u32| {
        let (mut s, mut n) = (0.0, 0);
        for y in 0..100 {
            for x in x0..x0 + 100 {
                if covered(&img, x, y) {
                    s += luminance(img.pixel(x, y));
                    n += 1;
                }
            }
        }
        assert!(n > 7000, "{n} covered pixels");
        s / n as f64
    };
    let (front, back) = (mean(0), mean(100));
    assert!((front - back).abs() < 0.05 * front, "front {front}, back {back}");
}

#[test]
fn highlighted_point_is_a_red_dot_only_when_visible() {
    let splats = sphere_splats(3_000, 7);
    let field = z_of(splats.positions());
    let ys: Vec<f64> = splats.positions().iter().map(|p| p[1]).collect();
    // The front camera sits at −y.
    let facing = (0..ys.len()).min_by(|&a, &b| ys[a].total_cmp(&ys[b])).unwrap() as u32;
    let hidden = (0..ys.len()).max_by(|&a, &b| ys[a].total_cmp(&ys[b])).unwrap() as u32;
    let render = |v: u32| {
        let params = RenderParams {
            highlight: vec![v],
            ..front_params(0)
        };
        render_splats_rgb(&splats, &field, &params).unwrap()
    };
    assert!(count_red(&render(facing)) > 10);
    assert_eq!(count_red(&render(hidden)), 0);
}

#[test]
fn splat_errors_name_the_culprit() {
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let n = vec![[0.0, 0.0, 1.0]; 3];
    let r = vec![0.5; 3];
    assert!(matches!(
        Splats::new(vec![], vec![], vec![]),
        Err(RenderError::NoPoints)
    ));
    assert!(matches!(
        Splats::new(p.clone(), n[..2].to_vec(), r.clone()),
        Err(RenderError::SplatLength {
            what: "normals",
            expected: 3,
            got: 2
        })
    ));
    assert!(matches!(
        Splats::new(p.clone(), n.clone(), vec![0.5; 4]),
        Err(RenderError::SplatLength { what: "radii", .. })
    ));
    let err = Splats::from_triangles(p.clone(), n.clone(), &[[0, 1, 3]]).unwrap_err();
    assert!(
        matches!(
            err,
            RenderError::TriangleOutOfRange {
                triangle: 0,
                index: 3,
                n_points: 3
            }
        ),
        "{err}"
    );
    let mut four = p.clone();
    four.push([1.0, 1.0, 0.0]);
    let err = Splats::from_triangles(four, vec![[0.0, 0.0, 1.0]; 4], &[[0, 1, 2]]).unwrap_err();
    assert!(err.to_string().contains("splat 3: it is in no triangle"), "{err}");
    let mut bad = p.clone();
    bad[1][2] = f64::NAN;
    let err = Splats::new(bad, n.clone(), r.clone()).unwrap_err();
    assert!(matches!(err, RenderError::InvalidSplat { point: 1, .. }), "{err}");
    assert!(err.to_string().contains("position"), "{err}");
    let mut bad = n.clone();
    bad[2] = [0.0; 3];
    let err = Splats::new(p.clone(), bad, r.clone()).unwrap_err();
    assert!(err.to_string().contains("splat 2: its normal"), "{err}");
    for radius in [0.0, -1.0, f64::INFINITY] {
        let err = Splats::new(p.clone(), n.clone(), vec![0.5, radius, 0.5]).unwrap_err();
        assert!(err.to_string().contains("splat 1: its radius"), "{err}");
    }

    // The render errors count points.
    let splats = Splats::new(p, n, r).unwrap();
    let params = RenderParams {
        width: 32,
        height: 32,
        ..RenderParams::default()
    };
    let err = render_splats_rgb(&splats, &[0.0; 2], &params).unwrap_err();
    assert!(matches!(err, RenderError::FieldLength { expected: 3, got: 2 }), "{err}");
    let err = render_splats_png(
        &splats,
        &[0.0; 3],
        &RenderParams {
            highlight: vec![3],
            ..params.clone()
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            RenderError::HighlightOutOfRange {
                vertex: 3,
                n_vertices: 3
            }
        ),
        "{err}"
    );
    let err = render_splats_rgb(&splats, &[0.0, f64::NAN, 0.0], &params).unwrap_err();
    assert!(matches!(err, RenderError::NonFiniteValue { vertex: 1, .. }), "{err}");
    assert!(render_splats_png(&splats, &[0.0, 1.0, 2.0], &params).is_ok());
}

#[test]
fn mesh_vertices_as_splats_cover_the_mesh() {
    // The vertices of a mesh drawn as splats with their triangles (radii and linear splats
    // from the faces), with the exact normals of the sphere, cover its silhouette and give
    // the colours of the mesh.
    let mesh = icosphere(4);
    let normals = mesh.positions().to_vec();
    let splats = Splats::from_triangles(mesh.positions().to_vec(), normals, mesh.faces()).unwrap();
    let params = front_params(0);
    let field = z_of(mesh.positions());
    let reference = render_rgb(&mesh, &field, &params).unwrap();
    let img = render_splats_rgb(&splats, &field, &params).unwrap();
    let (area, differ, holes) = coverage_difference(&reference, &img);
    assert_eq!(holes, 0);
    assert!((differ as f64) < 0.02 * area as f64, "{differ} of {area}");
}

#[test]
fn linear_splats_follow_a_linear_field_better_than_constant_ones() {
    // The same sphere splats with and without their neighbours (Splats::new keeps none):
    // the linear splats reproduce the colours of the mesh more closely.
    let splats = sphere_splats(5_000, 8);
    let constant = Splats::new(
        splats.positions().to_vec(),
        splats.normals().to_vec(),
        splats.radii().to_vec(),
    )
    .unwrap();
    let mesh = icosphere(5);
    let params = front_params(0);
    let reference = render_rgb(&mesh, &z_of(mesh.positions()), &params).unwrap();
    let error = |s: &Splats| {
        let img = render_splats_rgb(s, &z_of(s.positions()), &params).unwrap();
        let (mut sum, mut n) = (0.0, 0);
        for y in 0..img.height {
            for x in 0..img.width {
                let (a, b) = (reference.pixel(x, y), img.pixel(x, y));
                if a != [255; 3] && b != [255; 3] {
                    sum += (best_t(Colormap::Viridis, a) - best_t(Colormap::Viridis, b)).abs();
                    n += 1;
                }
            }
        }
        sum / n as f64
    };
    let (linear, flat) = (error(&splats), error(&constant));
    eprintln!("mean |Δt|: linear splats {linear:.4}, constant splats {flat:.4}");
    assert!(linear < 0.7 * flat, "linear {linear}, constant {flat}");
}
