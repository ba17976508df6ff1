//! Tests of the headless renderer: geometry of the picture (where high values land, where the
//! iso-lines are), the legend, the colormaps against published reference colours and CIE L*,
//! and every error variant.

use mesh_fem::generate::{bumpy, grid, icosphere, torus};
use mesh_fem::TriMesh;
use wfem_render::{
    layout, render_png, render_rgb, symmetric_range, Colormap, RenderError, RenderParams, RgbImage, UpAxis, View,
};

/// Front view only (camera at −y, z up), no legend, small.
pub(crate) fn front_params(n_isolines: usize) -> RenderParams {
    RenderParams {
        width: 240,
        height: 240,
        views: vec![View::standard(UpAxis::Z)[0]],
        n_isolines,
        legend: false,
        ..RenderParams::default()
    }
}

fn z_field(mesh: &TriMesh) -> Vec<f64> {
    mesh.positions().iter().map(|p| p[2]).collect()
}

pub(crate) fn luminance(c: [u8; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// The t whose colormap colour, times the best shading factor s, is closest to `c`.
pub(crate) fn best_t(map: Colormap, c: [u8; 3]) -> f64 {
    let p = c.map(|v| v as f64);
    let mut best = (f64::INFINITY, 0.0);
    for k in 0..=255 {
        let t = k as f64 / 255.0;
        let m = map.map(t).map(|v| v as f64);
        let s = (p[0] * m[0] + p[1] * m[1] + p[2] * m[2]) / (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        let r = (0..3).map(|i| (p[i] - s * m[i]).powi(2)).sum::<f64>();
        if r < best.0 {
            best = (r, t);
        }
    }
    best.1
}

/// CIE L* of an sRGB colour (D65), written out independently of the renderer's colour code.
fn lightness(c: [u8; 3]) -> f64 {
    let lin = |v: u8| {
        let v = v as f64 / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let y = 0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2]);
    if y > 216.0 / 24389.0 {
        116.0 * y.cbrt() - 16.0
    } else {
        y * 24389.0 / 27.0
    }
}

fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
    (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= tol)
}

#[test]
fn default_layout_matches_image_and_corners_are_white() {
    let mesh = icosphere(3);
    let field = z_field(&mesh);
    let params = RenderParams {
        width: 200,
        height: 160,
        title: Some("z on a sphere".into()),
        ..RenderParams::default()
    };
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let lay = layout(&params, (-1.0, 1.0)).unwrap();
    assert_eq!((img.width, img.height), (lay.width, lay.height));
    assert_eq!(lay.views.len(), 4);
    assert!(img.width > 4 * 200 && img.height > 160, "legend and title add space");
    assert_eq!(img.data.len(), 3 * img.width as usize * img.height as usize);
    for v in &lay.views {
        for (x, y) in [
            (v.x, v.y),
            (v.x + v.width - 1, v.y),
            (v.x, v.y + v.height - 1),
            (v.x + v.width - 1, v.y + v.height - 1),
        ] {
            assert_eq!(img.pixel(x, y), [255; 3], "corner ({x}, {y}) of a view");
        }
        // The object is drawn: the centre of each view is not background.
        assert_ne!(img.pixel(v.x + v.width / 2, v.y + v.height / 2), [255; 3]);
    }
    // The title is dark text on white.
    let t = lay.title.unwrap();
    let dark = (0..t.width)
        .flat_map(|x| (0..t.height).map(move |y| (x, y)))
        .filter(|&(x, y)| luminance(img.pixel(x, y)) < 60.0)
        .count();
    assert!(dark > 50, "{dark} title pixels");
}

#[test]
fn high_values_appear_at_the_top_of_the_front_view() {
    let mesh = icosphere(4);
    let field = z_field(&mesh);
    let params = front_params(0);
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let (w, h) = (params.width, params.height);
    let upper = best_t(Colormap::Viridis, img.pixel(w / 2, h / 5));
    let middle = best_t(Colormap::Viridis, img.pixel(w / 2, h / 2));
    let lower = best_t(Colormap::Viridis, img.pixel(w / 2, 4 * h / 5));
    // In the orthographic front view screen height is z, and the sphere fills 90% of the
    // view: the three rows sit at z ≈ 0.67, 0, −0.67, i.e. t ≈ 0.83, 0.5, 0.17.
    assert!((upper - 0.83).abs() < 0.08, "upper t = {upper}");
    assert!((middle - 0.5).abs() < 0.08, "middle t = {middle}");
    assert!((lower - 0.17).abs() < 0.08, "lower t = {lower}");
}

#[test]
fn isolines_are_dark_and_equally_spaced_level_sets() {
    let mesh = icosphere(4);
    let field = z_field(&mesh);
    let n = 12;
    let with = render_rgb(&mesh, &field, &front_params(n)).unwrap();
    let without = render_rgb(&mesh, &field, &front_params(0)).unwrap();
    // Iso-lines only ever darken.
    let mut darkened = 0;
    let mut darkest: f64 = 255.0;
    for (a, b) in with.data.chunks(3).zip(without.data.chunks(3)) {
        let (la, lb) = (luminance([a[0], a[1], a[2]]), luminance([b[0], b[1], b[2]]));
        assert!(la <= lb + 1.0, "an iso-line brightened a pixel: {la} > {lb}");
        if lb - la > 30.0 {
            darkened += 1;
            darkest = darkest.min(la);
        }
    }
    assert!(darkened > 500, "{darkened} iso-line pixels");
    assert!(darkest < 40.0, "iso-lines are dark: {darkest}");

    // Along the centre column of the front view, z is linear in the screen row, so the n level
    // sets z = −1 + 2k/(n+1) are n evenly spaced runs of darkened pixels.
    let x = with.width / 2;
    let mut centres = Vec::new();
    let mut run: Vec<u32> = Vec::new();
    for y in 0..with.height {
        let dark = luminance(with.pixel(x, y)) < 0.6 * luminance(without.pixel(x, y));
        if dark {
            run.push(y);
        } else if !run.is_empty() {
            centres.push(run.iter().sum::<u32>() as f64 / run.len() as f64);
            run.clear();
        }
    }
    assert_eq!(centres.len(), n, "runs at {centres:?}");
    let gaps: Vec<f64> = centres.windows(2).map(|w| w[1] - w[0]).collect();
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    for g in &gaps {
        assert!((g - mean).abs() < 1.5, "uneven iso-line spacing {gaps:?}");
    }
    // Spacing: 2/(n+1) in z, times the scale 0.9·height/2 of a unit sphere.
    let expected = 2.0 / (n + 1) as f64 * 0.45 * with.height as f64;
    assert!(
        (mean - expected).abs() < 0.05 * expected,
        "spacing {mean} vs {expected}"
    );
}

#[test]
fn legend_gradient_is_monotone_in_the_colormap() {
    let mesh = icosphere(2);
    let field = z_field(&mesh);
    for map in [Colormap::Viridis, Colormap::Coolwarm] {
        let params = RenderParams {
            width: 160,
            height: 240,
            colormap: map,
            ..RenderParams::default()
        };
        let img = render_rgb(&mesh, &field, &params).unwrap();
        let lo = field.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = field.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let bar = layout(&params, (lo, hi)).unwrap().legend_bar.unwrap();
        let x = bar.x + bar.width / 2;
        let ts: Vec<f64> = (bar.y..bar.y + bar.height)
            .map(|y| best_t(map, img.pixel(x, y)))
            .collect();
        assert!(
            ts[0] > 0.99 && *ts.last().unwrap() < 0.01,
            "{map:?}: {} .. {}",
            ts[0],
            ts.last().unwrap()
        );
        for w in ts.windows(2) {
            assert!(w[1] <= w[0] + 1e-12, "{map:?}: legend not monotone");
        }
        // Tick labels: dark text right of the bar.
        let label_ink = (bar.x + bar.width + 2..img.width)
            .flat_map(|x| (bar.y..bar.y + bar.height).map(move |y| (x, y)))
            .filter(|&(x, y)| luminance(img.pixel(x, y)) < 60.0)
            .count();
        assert!(label_ink > 40, "{label_ink}");
    }
}

#[test]
fn constant_field_renders_in_the_middle_colour() {
    let mesh = icosphere(3);
    let field = vec![2.5; mesh.n_vertices()];
    let params = front_params(12);
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let c = img.pixel(params.width / 2, params.height / 2);
    assert!((best_t(Colormap::Viridis, c) - 0.5).abs() < 0.05, "{c:?}");
    // With a legend too (a single label).
    let with_legend = RenderParams { legend: true, ..params };
    render_rgb(&mesh, &field, &with_legend).unwrap();
}

#[test]
fn explicit_range_clamps_values() {
    let mesh = icosphere(3);
    let field = z_field(&mesh);
    // Everything above −0.9 is at or beyond the top of the range: the centre is the top colour.
    let params = RenderParams {
        range: Some((-2.0, -0.9)),
        ..front_params(0)
    };
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let t = best_t(Colormap::Viridis, img.pixel(params.width / 2, params.height / 2));
    assert!(t > 0.97, "{t}");
}

#[test]
fn png_decodes_to_the_rgb_image() {
    let mesh = torus(1.0, 0.35, 48, 24);
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0] * p[1]).collect();
    let params = RenderParams {
        width: 120,
        height: 100,
        colormap: Colormap::Coolwarm,
        title: Some("x*y".into()),
        ..RenderParams::default()
    };
    let png_bytes = render_png(&mesh, &field, &params).unwrap();
    let rgb = render_rgb(&mesh, &field, &params).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (rgb.width, rgb.height));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(&buf[..info.buffer_size()], &rgb.data[..]);
}

pub(crate) fn count_red(img: &RgbImage) -> usize {
    img.data
        .chunks(3)
        .filter(|c| c[0] > 200 && c[1] < 60 && c[2] < 60)
        .count()
}

#[test]
fn highlighted_vertex_is_a_red_dot_only_when_visible() {
    let mesh = icosphere(3);
    let field = z_field(&mesh);
    let ys: Vec<f64> = mesh.positions().iter().map(|p| p[1]).collect();
    // The front camera sits at −y: the vertex with the smallest y faces it, the largest is hidden.
    let facing = (0..ys.len()).min_by(|&a, &b| ys[a].total_cmp(&ys[b])).unwrap() as u32;
    let hidden = (0..ys.len()).max_by(|&a, &b| ys[a].total_cmp(&ys[b])).unwrap() as u32;
    let render = |v: u32| {
        let params = RenderParams {
            highlight: vec![v],
            ..front_params(0)
        };
        render_rgb(&mesh, &field, &params).unwrap()
    };
    assert!(count_red(&render(facing)) > 10);
    assert_eq!(count_red(&render(hidden)), 0);
}

#[test]
fn open_mesh_is_lit_from_both_sides() {
    let mesh = grid(20, 20); // unit square in z = 0
    let field: Vec<f64> = mesh.positions().iter().map(|p| p[0]).collect();
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
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let mean = |x0: u32| {
        let mut s = 0.0;
        let mut n = 0;
        for y in 0..100 {
            for x in x0..x0 + 100 {
                let c = img.pixel(x, y);
                if c != [255; 3] {
                    s += luminance(c);
                    n += 1;
                }
            }
        }
        assert!(n > 3000, "{n} mesh pixels");
        s / n as f64
    };
    let (front, back) = (mean(0), mean(100));
    assert!((front - back).abs() < 0.05 * front, "front {front}, back {back}");
}

#[test]
fn degenerate_geometry_does_not_panic() {
    // Zero-area faces (collinear and repeated vertices) next to a proper triangle.
    let mesh = TriMesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2], [0, 0, 1], [0, 1, 3]],
    )
    .unwrap();
    let field = vec![0.0, 1.0, 2.0, 3.0];
    let params = RenderParams {
        width: 64,
        height: 48,
        highlight: vec![2],
        ..RenderParams::default()
    };
    render_png(&mesh, &field, &params).unwrap();
    // Coordinates so large that the projection overflows.
    let huge = TriMesh::new(
        vec![[1e308, 0.0, 0.0], [-1e308, 1e308, 0.0], [0.0, -1e308, 1e308]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    render_png(&huge, &[0.0, 1.0, 2.0], &params).unwrap();
    // Tiny images with every decoration still render.
    for (width, height) in [(1, 1), (2, 7), (9, 2)] {
        let tiny = RenderParams {
            width,
            height,
            supersample: 4,
            title: Some("tiny".into()),
            ..params.clone()
        };
        let img = render_rgb(&mesh, &field, &tiny).unwrap();
        assert!(img.width >= width && img.height >= height);
    }
    // A mesh collapsed to one point, and a flat grid seen edge-on.
    let point = TriMesh::new(vec![[1.0, 2.0, 3.0]; 3], vec![[0, 1, 2]]).unwrap();
    render_png(&point, &[1.0, 2.0, 3.0], &params).unwrap();
    let flat = grid(4, 4);
    let edge_on = RenderParams {
        views: vec![View::new([1.0, 0.0, 0.0], [0.0, 0.0, 1.0])],
        legend: false,
        highlight: vec![],
        ..params
    };
    let img = render_rgb(&flat, &vec![0.0; flat.n_vertices()], &edge_on).unwrap();
    // Every face projects to a segment: nothing but background.
    assert!(img.data.iter().all(|&c| c == 255));
}

#[test]
fn errors_name_the_culprit() {
    let mesh = icosphere(1);
    let n = mesh.n_vertices();
    let field = z_field(&mesh);
    let p = RenderParams {
        width: 32,
        height: 32,
        ..RenderParams::default()
    };

    let err = render_rgb(&mesh, &field[..n - 1], &p).unwrap_err();
    assert!(
        matches!(err, RenderError::FieldLength { expected, got } if expected == n && got == n - 1),
        "{err}"
    );

    let mut bad = field.clone();
    bad[7] = f64::NAN;
    let err = render_rgb(&mesh, &bad, &p).unwrap_err();
    assert!(matches!(err, RenderError::NonFiniteValue { vertex: 7, .. }), "{err}");
    assert!(err.to_string().contains("vertex 7"));
    bad[7] = f64::NEG_INFINITY;
    assert!(matches!(
        render_png(&mesh, &bad, &p),
        Err(RenderError::NonFiniteValue { vertex: 7, .. })
    ));

    let no_views = RenderParams {
        views: vec![],
        ..p.clone()
    };
    assert!(matches!(
        render_rgb(&mesh, &field, &no_views),
        Err(RenderError::NoViews)
    ));

    let parallel = RenderParams {
        views: vec![
            View::standard(UpAxis::Y)[0],
            View::new([0.0, 2.0, 0.0], [0.0, 1.0, 0.0]),
        ],
        ..p.clone()
    };
    assert!(matches!(
        render_rgb(&mesh, &field, &parallel),
        Err(RenderError::DegenerateView { index: 1, .. })
    ));
    let zero = RenderParams {
        views: vec![View::new([0.0; 3], [0.0, 1.0, 0.0])],
        ..p.clone()
    };
    assert!(matches!(
        render_rgb(&mesh, &field, &zero),
        Err(RenderError::DegenerateView { index: 0, .. })
    ));
    let nan_view = RenderParams {
        views: vec![View::new([f64::NAN, 0.0, 1.0], [0.0, 1.0, 0.0])],
        ..p.clone()
    };
    assert!(matches!(
        render_rgb(&mesh, &field, &nan_view),
        Err(RenderError::DegenerateView { .. })
    ));

    for (width, height, supersample) in [
        (0, 32, 2),
        (32, 0, 2),
        (32, 32, 0),
        (32, 32, 9),
        (100_000, 32, 1),
        (8192, 8192, 1),
    ] {
        let q = RenderParams {
            width,
            height,
            supersample,
            ..p.clone()
        };
        assert!(
            matches!(render_rgb(&mesh, &field, &q), Err(RenderError::InvalidSize { .. })),
            "{width}×{height}×{supersample}"
        );
    }

    for range in [(1.0, 1.0), (2.0, 1.0), (f64::NAN, 1.0), (0.0, f64::INFINITY)] {
        let q = RenderParams {
            range: Some(range),
            ..p.clone()
        };
        assert!(
            matches!(render_rgb(&mesh, &field, &q), Err(RenderError::InvalidRange(..))),
            "{range:?}"
        );
    }

    let q = RenderParams {
        highlight: vec![0, n as u32],
        ..p.clone()
    };
    let err = render_rgb(&mesh, &field, &q).unwrap_err();
    assert!(
        matches!(err, RenderError::HighlightOutOfRange { vertex, n_vertices } if vertex == n as u32 && n_vertices == n)
    );
}

#[test]
fn viridis_matches_reference_colours_and_lightness_increases() {
    // matplotlib's viridis: #440154 at 0, #21918c at 0.5, #fde725 at 1 (the polynomial fit is
    // within 5/255 per channel).
    assert!(
        close(Colormap::Viridis.map(0.0), [0x44, 0x01, 0x54], 5),
        "{:?}",
        Colormap::Viridis.map(0.0)
    );
    assert!(
        close(Colormap::Viridis.map(0.5), [0x21, 0x91, 0x8c], 5),
        "{:?}",
        Colormap::Viridis.map(0.5)
    );
    assert!(
        close(Colormap::Viridis.map(1.0), [0xfd, 0xe7, 0x25], 5),
        "{:?}",
        Colormap::Viridis.map(1.0)
    );
    let l: Vec<f64> = (0..=64)
        .map(|k| lightness(Colormap::Viridis.map(k as f64 / 64.0)))
        .collect();
    for w in l.windows(2) {
        assert!(w[1] > w[0], "L* not increasing: {l:?}");
    }
    // Nearly uniform: L* rises from ≈ 16 to ≈ 91 with steps within a factor 2 of the mean.
    assert!(l[0] < 20.0 && l[64] > 88.0);
    let mean = (l[64] - l[0]) / 64.0;
    for w in l.windows(2) {
        assert!((w[1] - w[0]) > 0.5 * mean && (w[1] - w[0]) < 2.0 * mean);
    }
    // Clamping and NaN never panic.
    assert_eq!(Colormap::Viridis.map(-3.0), Colormap::Viridis.map(0.0));
    assert_eq!(Colormap::Viridis.map(7.0), Colormap::Viridis.map(1.0));
    assert_eq!(Colormap::Viridis.map(f64::NAN), Colormap::Viridis.map(0.0));
}

#[test]
fn coolwarm_matches_moreland_and_is_diverging() {
    assert!(close(Colormap::Coolwarm.map(0.0), [59, 76, 192], 1));
    assert!(close(Colormap::Coolwarm.map(1.0), [180, 4, 38], 1));
    // Lightness rises to the white-ish centre and falls again, symmetric within a few units.
    let l: Vec<f64> = (0..=64)
        .map(|k| lightness(Colormap::Coolwarm.map(k as f64 / 64.0)))
        .collect();
    for k in 0..32 {
        assert!(l[k + 1] > l[k] && l[64 - k - 1] > l[64 - k], "{l:?}");
        assert!((l[k] - l[64 - k]).abs() < 6.0, "{k}: {} vs {}", l[k], l[64 - k]);
    }
    // The centre is grey (no hue): Moreland's table gives (221, 221, 221).
    let mid = Colormap::Coolwarm.map(0.5);
    assert!(close(mid, [221, 221, 221], 3), "{mid:?}");
}

#[test]
fn bumpy_render_with_everything() {
    // The demo scene: views, legend, title, highlight, iso-lines; checks that the picture has
    // both ends of the colormap and that the anchor is marked.
    let mesh = bumpy(3);
    let pos = mesh.positions();
    let anchor = 5usize;
    let field: Vec<f64> = pos
        .iter()
        .map(|p| (-(0..3).map(|k| (p[k] - pos[anchor][k]).powi(2)).sum::<f64>()).exp())
        .collect();
    let params = RenderParams {
        width: 160,
        height: 160,
        title: Some("K_t e_i, t = 0.1".into()),
        highlight: vec![anchor as u32],
        ..RenderParams::default()
    };
    let img = render_rgb(&mesh, &field, &params).unwrap();
    assert!(count_red(&img) > 5, "anchor visible in at least one view");
}

#[test]
fn symmetric_range_centres_zero() {
    assert_eq!(symmetric_range(&[-0.5, 2.0, 1.0]), Some((-2.0, 2.0)));
    assert_eq!(symmetric_range(&[0.0, 0.0]), None);
    assert_eq!(symmetric_range(&[]), None);
    assert_eq!(symmetric_range(&[1.0, f64::NAN]), None);
    // With Coolwarm, a zero value is drawn in the map's grey centre.
    let mesh = icosphere(3);
    let field = z_field(&mesh);
    let params = RenderParams {
        colormap: Colormap::Coolwarm,
        range: symmetric_range(&field),
        ..front_params(0)
    };
    let img = render_rgb(&mesh, &field, &params).unwrap();
    let t = best_t(Colormap::Coolwarm, img.pixel(params.width / 2, params.height / 2));
    assert!((t - 0.5).abs() < 0.04, "{t}");
}

#[test]
fn layout_snapshot() {
    // Integer geometry only (stable across platforms): view rectangles, legend bar, title band.
    let cases = [
        ("default", RenderParams::default(), (-1.53, 1.72)),
        (
            "titled_small",
            RenderParams {
                width: 200,
                height: 150,
                title: Some("K_t e_i, t = 0.1".into()),
                ..RenderParams::default()
            },
            (0.0, 1.0e-5),
        ),
        (
            "no_legend_two_views",
            RenderParams {
                width: 320,
                height: 240,
                views: View::standard(UpAxis::Z)[..2].to_vec(),
                legend: false,
                ..RenderParams::default()
            },
            (0.0, 1.0),
        ),
    ];
    let summary: Vec<String> = cases
        .iter()
        .map(|(name, params, range)| format!("{name}: {:?}", layout(params, *range).unwrap()))
        .collect();
    insta::assert_snapshot!(summary.join("\n"));
}
