//! Tests of the SHREC'10-style generator: every class on small generated meshes, geometric
//! checks of the ground truth, monotone strengths, determinism, and one end-to-end run on a
//! real TOSCA shape.

use mesh_fem::generate::bumpy;
use mesh_fem::graph::EdgeGraph;
use mesh_fem::TriMesh;
use shrec_bench::synth::*;
use shrec_bench::transform::Transformed;
use wfem_base::rng::SplitMix64;

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn base() -> BaseShape {
    BaseShape::new("bumpy", bumpy(3)).unwrap()
}

/// An almost closed open cylinder: the two sides of the seam are 0.1 apart in space but
/// about 2π apart along the surface, the configuration the topology class welds.
fn seam_cylinder() -> BaseShape {
    let (nu, nv) = (40usize, 8usize);
    let mut positions = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let phi = i as f64 / (nu - 1) as f64 * (2.0 * std::f64::consts::PI - 0.1);
            positions.push([phi.cos(), phi.sin(), j as f64 / (nv - 1) as f64]);
        }
    }
    let mut faces = Vec::new();
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let (a, b, c, d) = (j * nu + i, j * nu + i + 1, (j + 1) * nu + i + 1, (j + 1) * nu + i);
            faces.push([a as u32, b as u32, c as u32]);
            faces.push([a as u32, c as u32, d as u32]);
        }
    }
    BaseShape::new("seam", TriMesh::new(positions, faces).unwrap()).unwrap()
}

fn run(b: &BaseShape, class: Class, s: u8, seed: u64) -> Transformed {
    let t = transform(b, class, s, seed).unwrap();
    validate_output(&t, b.mesh.n_vertices(), b.diameter).unwrap_or_else(|e| panic!("{class:?} {s}: {e}"));
    t
}

fn gt_positions_equal(b: &BaseShape, t: &Transformed) {
    for (i, &g) in t.ground_truth.iter().enumerate() {
        assert!(g >= 0);
        assert_eq!(t.mesh.positions()[i], b.mesh.positions()[g as usize], "vertex {i}");
    }
}

fn rms_displacement(b: &BaseShape, t: &Transformed) -> f64 {
    let p = b.mesh.positions();
    let q = t.mesh.positions();
    (p.iter().zip(q).map(|(a, c)| dist(*a, *c).powi(2)).sum::<f64>() / p.len() as f64).sqrt()
}

#[test]
fn every_class_and_strength_gives_a_valid_mesh() {
    let b = base();
    for class in Class::SYNTHETIC {
        for s in 1..=5 {
            let t = run(&b, class, s, 7);
            // Only the tubes of the handles class are new vertices (no ground truth).
            assert!(t
                .ground_truth
                .iter()
                .all(|&g| (g >= 0 || (class == Class::Handles && g == -1)) && g < b.mesh.n_vertices() as i64));
        }
    }
    assert!(transform(&b, Class::Pose, 1, 7).is_err(), "no poses loaded");
    assert!(transform(&b, Class::Noise, 0, 7).is_err());
    assert!(transform(&b, Class::Noise, 6, 7).is_err());
}

#[test]
fn global_scale_is_exact() {
    let b = base();
    for s in 1..=5u8 {
        let t = run(&b, Class::Scale, s, 1);
        let beta = SCALE_FACTORS[s as usize - 1];
        assert_eq!(t.mesh.faces(), b.mesh.faces());
        for (q, p) in t.mesh.positions().iter().zip(b.mesh.positions()) {
            assert_eq!(*q, p.map(|c| beta * c));
        }
    }
    let logs: Vec<f64> = SCALE_FACTORS.iter().map(|b: &f64| b.ln().abs()).collect();
    assert!(logs.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn noise_has_the_requested_standard_deviation() {
    let b = base();
    for s in [1u8, 5] {
        let t = run(&b, Class::Noise, s, 3);
        let sigma = noise_sigma(s) * b.mean_edge;
        let d: Vec<f64> = t
            .mesh
            .positions()
            .iter()
            .zip(b.mesh.positions())
            .flat_map(|(q, p)| [q[0] - p[0], q[1] - p[1], q[2] - p[2]])
            .collect();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let std = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
        // 3·642 samples: the standard error of the sample std is about 1.6 %.
        assert!((std / sigma - 1.0).abs() < 0.06, "s={s}: std {std} vs sigma {sigma}");
        assert!(mean.abs() < 0.1 * sigma);
    }
}

#[test]
fn shot_noise_moves_the_requested_vertices_along_the_normal() {
    let b = base();
    let normals = shrec_bench::transform::vertex_normals(&b.mesh);
    for s in 1..=5u8 {
        let t = run(&b, Class::ShotNoise, s, 3);
        let a = SHOT_AMPLITUDE * b.mean_edge;
        let expected = (shot_fraction(s) * b.mesh.n_vertices() as f64).round().max(1.0) as usize;
        let mut moved = 0;
        for (v, (q, p)) in t.mesh.positions().iter().zip(b.mesh.positions()).enumerate() {
            if q != p {
                moved += 1;
                let delta = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                let along: f64 = delta.iter().zip(&normals[v]).map(|(x, y)| x * y).sum();
                assert!((along.abs() - a).abs() < 1e-9 * a, "vertex {v}");
                assert!((dist(*q, *p) - a).abs() < 1e-9 * a);
            }
        }
        assert_eq!(moved, expected, "strength {s}");
    }
}

#[test]
fn isometry_bend_is_near_isometric_and_grows_with_strength() {
    let b = base();
    let mut last = 0.0;
    for s in 1..=5u8 {
        let t = run(&b, Class::Isometry, s, 5);
        assert_eq!(t.ground_truth, (0..b.mesh.n_vertices() as i64).collect::<Vec<_>>());
        // Edge-length distortion stays small (the bend is rigid outside a thin band).
        let mut rel = Vec::new();
        for f in b.mesh.faces() {
            for k in 0..3 {
                let (i, j) = (f[k] as usize, f[(k + 1) % 3] as usize);
                let l0 = dist(b.mesh.positions()[i], b.mesh.positions()[j]);
                let l1 = dist(t.mesh.positions()[i], t.mesh.positions()[j]);
                rel.push((l1 / l0 - 1.0).abs());
            }
        }
        let mean = rel.iter().sum::<f64>() / rel.len() as f64;
        rel.sort_by(f64::total_cmp);
        assert!(
            rel[rel.len() / 2] < 1e-9,
            "s={s}: median edge distortion {}",
            rel[rel.len() / 2]
        );
        assert!(mean < 0.1, "s={s}: mean edge distortion {mean}");
        let disp = rms_displacement(&b, &t);
        assert!(disp > last, "s={s}: displacement {disp} not above {last}");
        last = disp;
    }
}

#[test]
fn local_scale_fixes_the_centre_and_grows_with_strength() {
    let b = base();
    let mut last = 0.0;
    for s in 1..=5u8 {
        let t = run(&b, Class::LocalScale, s, 5);
        let c = t.params["center_vertex"].as_u64().unwrap() as usize;
        assert_eq!(t.mesh.positions()[c], b.mesh.positions()[c]);
        let disp = rms_displacement(&b, &t);
        assert!(disp > last);
        last = disp;
    }
}

#[test]
fn holes_remove_balls_and_keep_the_rest_with_correct_ids() {
    let b = base();
    let mut last_removed = 0;
    for s in 1..=5u8 {
        let t = run(&b, Class::Holes, s, 11);
        gt_positions_equal(&b, &t);
        let seeds: Vec<u32> = t.params["seeds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as u32)
            .collect();
        let radius = t.params["radius"].as_f64().unwrap();
        assert!((radius - big_hole_radius(s) * b.diameter).abs() < 1e-12);
        let d = b.graph.distances(&seeds, f64::INFINITY).unwrap();
        // Every survivor lies outside the balls; every base vertex outside the balls that is
        // lost was cut off with a smaller piece.
        for &g in &t.ground_truth {
            assert!(d[g as usize] >= radius);
        }
        let inside = d.iter().filter(|&&x| x < radius).count();
        let removed = b.mesh.n_vertices() - t.mesh.n_vertices();
        assert!(removed >= inside && inside > 0);
        assert!(removed > last_removed, "s={s}");
        last_removed = removed;
        // Ground truth is injective.
        let mut g = t.ground_truth.clone();
        g.sort_unstable();
        g.dedup();
        assert_eq!(g.len(), t.ground_truth.len());
    }
}

#[test]
fn micro_holes_remove_one_rings_and_grow_with_strength() {
    let b = base();
    let (mut last_removed, mut last_holes) = (0, 0);
    for s in 1..=5u8 {
        let t = run(&b, Class::MicroHoles, s, 13);
        gt_positions_equal(&b, &t);
        let seeds: Vec<u32> = t.params["seeds"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as u32)
            .collect();
        let hop = b.graph.hops(&seeds, 1).unwrap();
        for &g in &t.ground_truth {
            assert_eq!(hop[g as usize], u32::MAX, "a vertex of a hole survived");
        }
        // Seeds are at least MICRO_HOLE_SEPARATION hops apart.
        for (k, &a) in seeds.iter().enumerate() {
            let h = b.graph.hops(&[a], MICRO_HOLE_SEPARATION).unwrap();
            for &c in &seeds[k + 1..] {
                assert!(h[c as usize] == u32::MAX || h[c as usize] >= MICRO_HOLE_SEPARATION);
            }
        }
        // Nested seeds: more holes remove strictly more; a small mesh saturates.
        let removed = b.mesh.n_vertices() - t.mesh.n_vertices();
        assert!(seeds.len() >= last_holes && removed >= last_removed);
        if seeds.len() > last_holes {
            assert!(removed > last_removed, "s={s}");
        }
        assert!(seeds.len() <= micro_hole_count(s));
        (last_removed, last_holes) = (removed, seeds.len());
    }
    assert!(last_holes > 20);
}

#[test]
fn sampling_keeps_the_requested_fraction_and_positions() {
    let b = base();
    let n = b.mesh.n_vertices();
    let mut last = n;
    for s in 1..=5u8 {
        let t = run(&b, Class::Sampling, s, 0);
        gt_positions_equal(&b, &t);
        let want = SAMPLING_KEEP[s as usize - 1] * n as f64;
        assert!(
            (t.mesh.n_vertices() as f64 - want).abs() <= 0.02 * n as f64,
            "s={s}: {}",
            t.mesh.n_vertices()
        );
        assert!(t.mesh.n_vertices() < last);
        last = t.mesh.n_vertices();
    }
    assert!((last as f64) < 0.2 * n as f64);
}

#[test]
fn welding_merges_only_close_pairs_far_apart_on_the_surface() {
    let b = seam_cylinder();
    let mut last = 0;
    for s in 1..=5u8 {
        let t = run(&b, Class::Topology, s, 0);
        gt_positions_equal(&b, &t);
        let pairs = t.params["welded_pairs"].as_array().unwrap();
        assert!(!pairs.is_empty() && pairs.len() <= weld_pair_count(s));
        let eps = WELD_MAX_DISTANCE * b.diameter;
        let min_graph = WELD_MIN_GRAPH_DISTANCE * b.diameter;
        for pr in pairs {
            let (i, j) = (pr[0].as_u64().unwrap() as usize, pr[1].as_u64().unwrap() as usize);
            assert!(dist(b.mesh.positions()[i], b.mesh.positions()[j]) < eps);
            let d = b.graph.distances(&[i as u32], f64::INFINITY).unwrap();
            assert!(d[j] > min_graph, "pair ({i},{j}) is only {} apart on the surface", d[j]);
            // The larger index is gone, the smaller one survives.
            assert!(!t.ground_truth.contains(&(i.max(j) as i64)));
        }
        let merged = b.mesh.n_vertices() - t.mesh.n_vertices();
        assert!(merged >= 1 && merged >= last, "s={s}: merged {merged}");
        last = merged;
        // The weld closed the seam: the new mesh has an edge across it.
        let g = EdgeGraph::new(&t.mesh);
        assert!(g.n_edges() > 0);
    }
    // No weld on a shape without such pairs.
    let t = run(&base(), Class::Topology, 5, 0);
    assert_eq!(
        t.mesh.n_vertices() + t.params["vertices_merged"].as_u64().unwrap() as usize,
        642
    );
}

#[test]
fn same_seed_same_output_different_seed_different_output() {
    let b = base();
    for class in [
        Class::Isometry,
        Class::MicroHoles,
        Class::Holes,
        Class::LocalScale,
        Class::Noise,
        Class::ShotNoise,
    ] {
        let a = run(&b, class, 3, 1);
        let a2 = run(&b, class, 3, 1);
        let c = run(&b, class, 3, 2);
        assert_eq!(a.mesh, a2.mesh, "{class:?}");
        assert_eq!(a.ground_truth, a2.ground_truth);
        assert_eq!(a.params, a2.params);
        assert_ne!(a.mesh, c.mesh, "{class:?} ignores the seed");
    }
    // Streams differ between shapes and classes.
    assert_ne!(
        stream_seed(1, "cat0", Class::Noise),
        stream_seed(1, "dog0", Class::Noise)
    );
    assert_ne!(
        stream_seed(1, "cat0", Class::Noise),
        stream_seed(1, "cat0", Class::ShotNoise)
    );
}

#[test]
fn validation_rejects_bad_outputs() {
    let b = base();
    let mut t = run(&b, Class::Noise, 1, 1);
    t.ground_truth[3] = b.mesh.n_vertices() as i64;
    assert!(validate_output(&t, b.mesh.n_vertices(), b.diameter).is_err());
    t.ground_truth.pop();
    assert!(validate_output(&t, b.mesh.n_vertices(), b.diameter).is_err());
    // A collapsed face.
    let (mut p, f) = b.mesh.clone().into_parts();
    let [x, y, _] = f[0];
    p[y as usize] = p[x as usize];
    let bad = Transformed {
        mesh: TriMesh::new(p, f).unwrap(),
        ground_truth: (0..b.mesh.n_vertices() as i64).collect(),
        params: serde_json::json!({}),
    };
    assert!(validate_output(&bad, b.mesh.n_vertices(), b.diameter).is_err());
}

#[test]
fn generator_on_a_real_shape_writes_files_and_manifest() {
    let meshes_dir = wfem_corpus::meshes_dir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let opts = GenerateOptions {
        meshes_dir,
        out_dir: out.path().to_path_buf(),
        shapes: vec!["wolf".into()],
        classes: Class::ALL.to_vec(),
        strengths: vec![5],
        seed: 2010,
    };
    let manifest = generate(&opts).unwrap();
    let text = std::fs::read_to_string(out.path().join("manifest.json")).unwrap();
    let parsed: Manifest = serde_json::from_str(&text).unwrap();
    assert_eq!(parsed, manifest);
    assert_eq!(manifest.seed, 2010);
    assert_eq!(manifest.bases.len(), 1);
    let base = &manifest.bases[0];
    assert_eq!(base.shape, "wolf0");
    assert_eq!(base.n_vertices, 4344);
    assert_eq!(manifest.outputs.len(), Class::ALL.len());
    for class in Class::ALL {
        assert!(
            manifest.parameters.get(class.name()).is_some(),
            "{class:?} missing from the table"
        );
    }
    for e in &manifest.outputs {
        assert_eq!(e.strength, 5);
        let (mesh, _) = mesh_fem::io::load(&out.path().join(&e.mesh), &mesh_fem::io::LoadOptions::default()).unwrap();
        assert_eq!(
            (mesh.n_vertices(), mesh.n_faces()),
            (e.n_vertices, e.n_faces),
            "{}",
            e.mesh
        );
        let gt: Vec<i64> = std::fs::read_to_string(out.path().join(&e.ground_truth))
            .unwrap()
            .lines()
            .map(|l| l.parse().unwrap())
            .collect();
        assert_eq!(gt.len(), e.n_vertices);
        assert!(gt.iter().all(|&g| (-1..base.n_vertices as i64).contains(&g)));
        assert_eq!(gt.iter().filter(|&&g| g >= 0).count(), e.n_mapped);
    }
    let sampling = manifest.outputs.iter().find(|e| e.class == Class::Sampling).unwrap();
    assert!((sampling.n_vertices as f64) < 0.2 * base.n_vertices as f64);
    let topo = manifest.outputs.iter().find(|e| e.class == Class::Topology).unwrap();
    assert!(topo.n_vertices < base.n_vertices, "no weld on wolf0");
    // Same seed again: identical manifest.
    let again = generate(&opts).unwrap();
    assert_eq!(again, manifest);
}

/// A synthetic family in a temporary folder: fam0 = base, fam1 = rigidly moved copy,
/// fam2 = rigidly moved copy with known noise; identity `.vts` files.
#[test]
fn poses_are_ranked_by_kabsch_deformation_with_vts_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("corres")).unwrap();
    let m = bumpy(2);
    let n = m.n_vertices();
    let (c, s) = (0.6f64.cos(), 0.6f64.sin());
    let rigid = |p: [f64; 3]| [c * p[0] - s * p[1] + 3.0, s * p[0] + c * p[1] - 1.0, p[2] + 0.5];
    let moved: Vec<[f64; 3]> = m.positions().iter().map(|&p| rigid(p)).collect();
    let mut rng = SplitMix64::new(9);
    let sigma = 0.01;
    let noisy: Vec<[f64; 3]> = moved
        .iter()
        .map(|p| {
            [
                p[0] + sigma * rng.next_normal(),
                p[1] + sigma * rng.next_normal(),
                p[2] + sigma * rng.next_normal(),
            ]
        })
        .collect();
    let noise_rms = (moved.iter().zip(&noisy).map(|(a, b)| dist(*a, *b).powi(2)).sum::<f64>() / n as f64).sqrt();
    // The pose files list vertices in reverse order to exercise the .vts mapping.
    let rev = |p: &[[f64; 3]]| p.iter().rev().copied().collect::<Vec<_>>();
    let rev_faces: Vec<[u32; 3]> = m.faces().iter().map(|f| f.map(|v| (n - 1) as u32 - v)).collect();
    let ids: String = (1..=n).map(|i| format!("{i}\n")).collect();
    let rev_ids: String = (1..=n).map(|i| format!("{}\n", n + 1 - i)).collect();
    mesh_fem::io::write_mesh(&dir.path().join("fam0.off"), &m).unwrap();
    mesh_fem::io::write_mesh(
        &dir.path().join("fam1.off"),
        &TriMesh::new(rev(&noisy), rev_faces.clone()).unwrap(),
    )
    .unwrap();
    mesh_fem::io::write_mesh(
        &dir.path().join("fam2.off"),
        &TriMesh::new(rev(&moved), rev_faces).unwrap(),
    )
    .unwrap();
    std::fs::write(dir.path().join("corres/fam0.vts"), &ids).unwrap();
    std::fs::write(dir.path().join("corres/fam1.vts"), &rev_ids).unwrap();
    std::fs::write(dir.path().join("corres/fam2.vts"), &rev_ids).unwrap();
    let mut b = BaseShape::new("fam0", m.clone()).unwrap();
    b.load_poses(&dir.path().join("fam0.off")).unwrap();
    assert_eq!(b.poses.len(), 2);
    assert_eq!(b.poses[0].name, "fam2", "the rigid copy has the smallest deformation");
    assert!(b.poses[0].deformation < 1e-12, "{}", b.poses[0].deformation);
    // Kabsch residual of noise is at most its RMS (the identity alignment), and close to it.
    let d1 = b.poses[1].deformation * b.diameter;
    assert!(
        d1 <= noise_rms * (1.0 + 1e-12) && d1 > 0.95 * noise_rms,
        "{d1} vs {noise_rms}"
    );
    for s in 1..=5u8 {
        let t = run(&b, Class::Pose, s, 0);
        // Ground truth through the reversed .vts: pose vertex i is base vertex n−1−i, and the
        // positions agree up to the rigid motion (and the noise for fam1).
        for (i, &g) in t.ground_truth.iter().enumerate() {
            assert_eq!(g as usize, n - 1 - i);
            let want = rigid(m.positions()[g as usize]);
            assert!(dist(t.mesh.positions()[i], want) < 6.0 * sigma);
        }
    }
    assert_eq!(pose_index(1, 2), 0);
    assert_eq!(pose_index(5, 2), 1);
    assert_eq!(pose_index(3, 9), 4);
}

#[test]
fn tosca_cat_poses_have_ground_truth() {
    let file = wfem_corpus::mesh_path("tosca-bcicp-5k/TOSCA_Isometric/cat0.off").unwrap();
    let (mesh, _) = mesh_fem::io::load(&file, &mesh_fem::io::LoadOptions::default()).unwrap();
    let mut b = BaseShape::new("cat0", mesh).unwrap();
    b.load_poses(&file).unwrap();
    assert_eq!(b.poses.len(), 10);
    assert!(b.poses.windows(2).all(|w| w[0].deformation <= w[1].deformation));
    for s in [1u8, 5] {
        let t = run(&b, Class::Pose, s, 0);
        let mapped = t.ground_truth.iter().filter(|&&g| g >= 0).count();
        assert!(mapped as f64 > 0.5 * t.mesh.n_vertices() as f64, "only {mapped} mapped");
        // Neighbours map to nearby base points: mean base distance of the images of the
        // ends of a pose edge is a few base edge lengths.
        let (mut sum, mut count) = (0.0, 0.0);
        for f in t.mesh.faces() {
            for k in 0..3 {
                let (gi, gj) = (t.ground_truth[f[k] as usize], t.ground_truth[f[(k + 1) % 3] as usize]);
                if gi >= 0 && gj >= 0 {
                    sum += dist(b.mesh.positions()[gi as usize], b.mesh.positions()[gj as usize]);
                    count += 1.0;
                }
            }
        }
        assert!(sum / count < 3.0 * b.mean_edge, "s={s}: {}", sum / count / b.mean_edge);
    }
}
