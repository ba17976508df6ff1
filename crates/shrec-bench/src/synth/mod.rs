//! Synthetic SHREC'10-style robustness benchmark (paper Sect. 5; docs/NUMERICS.md §7).
//!
//! The SHREC'10 feature-detection/description data are not available, so we rebuild the
//! protocol on TOSCA null shapes: every base mesh gets 9 synthetic transformation classes plus
//! the real-pose class `pose`, × 5 strengths,
//! each with a ground-truth map from every new vertex to a base vertex.
//!
//! All randomness comes from [`wfem_base::rng::SplitMix64`], seeded from (seed, shape, class) — **not** from
//! the strength — so that the five strengths of a class share their random choices (the
//! same joint, the same hole centres in the same order, the same noise vector, …) and the
//! amount of change grows monotonically with the strength.
//!
//! Parameters (ℓ̄ = mean edge length, D = bounding-box diagonal of the base mesh, s = 1…5):
//!
//! | class | recipe | strength knob |
//! |---|---|---|
//! | `isometry` | skinning bend: weight w = smoothstep of the signed distance to a random joint plane through a random vertex (half-width 5 % D), rotate by w·θ about a random axis in the plane | θ = 15°·s |
//! | `topology` | among pairs with ‖x_i − x_j‖ < 8 % D and edge-graph distance > 10 % D, weld the k closest, skipping a pair whose weld would make a face degenerate (union-find, smallest id survives with its position) | k = 5·2^{s−1} pairs |
//! | `microholes` | delete k random seed vertices and their 1-rings; seeds ≥ 4 hops apart; keep the largest piece | k = 10·2^{s−1} |
//! | `holes` | delete edge-graph geodesic balls around 4 random seeds (≥ 30 % D apart); keep the largest piece | radius = 2.5 %·s·D |
//! | `scale` | x ← βx | β = 1.25, 0.6, 2, 0.4, 4 |
//! | `localscale` | x ← c + (1 + (β−1)w)(x − c), w = exp(−d_g(x,c)²/(2ρ²)), c a random vertex | β = 1 + 0.2s, ρ = 10 % D |
//! | `noise` | x ← x + σz, z ~ N(0, I₃) per vertex | σ = 0.1·s·ℓ̄ |
//! | `shotnoise` | a random fraction p of the vertices moves by ±a·n̂ (random sign) | p = 0.5 %·s, a = 5ℓ̄ |
//! | `pose` | another TOSCA pose of the family (real near-isometry); ground truth from `corres/*.vts`, −1 where unknown | rank round((s−1)(m−1)/4) of the m poses sorted by Kabsch RMS deformation |
//! | `sampling` | QEM half-edge collapse ([`crate::transform::QemDecimator`]); survivors keep positions | keep 80, 60, 40, 20, 10 % |
//!
//! Every output is validated before it is written ([`validate_output`]).

use crate::transform::{bounding_box_diagonal, Transformed};
use crate::BenchError;
use mesh_fem::graph::EdgeGraph;
use mesh_fem::vec3::{dot, sub};
use mesh_fem::{assemble, AssemblyParams, MeshError, TriMesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};
use wfem_base::rng::SplitMix64;

/// The seed of the random stream of one (shape, class): FNV-1a of the names mixed into the
/// global seed. The strength is deliberately left out (see the module documentation).
pub fn stream_seed(seed: u64, shape: &str, class: Class) -> u64 {
    let mut h = crate::Fnv1a::new();
    h.eat(shape.bytes().chain([0u8]).chain(class.name().bytes()));
    SplitMix64::new(seed ^ h.0).next_u64()
}

/// A SHREC'10 transformation class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Class {
    /// Near-isometric bending (skinning-style bend about a joint plane).
    Isometry,
    /// Welding of vertices close in space but far along the surface.
    Topology,
    /// Tubes (handles) between points close in space but far along the surface
    /// ([`crate::handles`]).
    Handles,
    /// Many small holes (a vertex and its 1-ring).
    MicroHoles,
    /// A few big holes (geodesic balls).
    Holes,
    /// Global scaling x ← βx.
    Scale,
    /// Local scaling around a point.
    LocalScale,
    /// Additive Gaussian noise.
    Noise,
    /// Shot noise: a few vertices pushed along the normal.
    ShotNoise,
    /// Down-sampling by QEM half-edge collapse.
    Sampling,
    /// Real near-isometries: the other TOSCA poses of the base shape's family, ordered by
    /// how far they are from a rigid motion, with ground truth from `corres/*.vts`.
    Pose,
}

impl Class {
    /// All classes: the ten [`Class::SYNTHETIC`] ones, then [`Class::Pose`] (needs TOSCA pose
    /// files).
    pub const ALL: [Class; 11] = {
        let mut all = [Class::Pose; 11];
        let mut i = 0;
        while i < Class::SYNTHETIC.len() {
            all[i] = Class::SYNTHETIC[i];
            i += 1;
        }
        all
    };

    /// The ten synthetic classes, in SHREC'10 order (handles after topology); they work on any
    /// mesh.
    pub const SYNTHETIC: [Class; 10] = [
        Class::Isometry,
        Class::Topology,
        Class::Handles,
        Class::MicroHoles,
        Class::Holes,
        Class::Scale,
        Class::LocalScale,
        Class::Noise,
        Class::ShotNoise,
        Class::Sampling,
    ];

    /// The class name used in file names, the manifest and the CLI.
    pub fn name(self) -> &'static str {
        match self {
            Class::Isometry => "isometry",
            Class::Topology => "topology",
            Class::Handles => "handles",
            Class::MicroHoles => "microholes",
            Class::Holes => "holes",
            Class::Scale => "scale",
            Class::LocalScale => "localscale",
            Class::Noise => "noise",
            Class::ShotNoise => "shotnoise",
            Class::Sampling => "sampling",
            Class::Pose => "pose",
        }
    }

    /// Parses a class name (as printed by [`Class::name`]).
    ///
    /// # Errors
    /// [`BenchError::Argument`] listing the known names.
    pub fn from_name(name: &str) -> Result<Class, BenchError> {
        Class::ALL
            .into_iter()
            .find(|c| c.name() == name.trim().to_ascii_lowercase())
            .ok_or_else(|| {
                let names: Vec<_> = Class::ALL.iter().map(|c| c.name()).collect();
                BenchError::Argument(format!("unknown class {name:?}; known: {}", names.join(", ")))
            })
    }
}

/// Bend angle θ (degrees) of the isometry class.
pub fn bend_angle_deg(s: u8) -> f64 {
    15.0 * s as f64
}
/// Half-width of the bend transition band, as a fraction of D.
pub const BEND_HALF_WIDTH: f64 = 0.05;
/// Number of vertex pairs welded by the topology class.
pub fn weld_pair_count(s: u8) -> usize {
    5 << (s - 1)
}
/// Largest Euclidean distance of a welded pair, as a fraction of D.
pub const WELD_MAX_DISTANCE: f64 = 0.08;
/// Minimum edge-graph distance of welded pairs, as a fraction of D.
pub const WELD_MIN_GRAPH_DISTANCE: f64 = 0.10;
/// Number of micro holes requested.
pub fn micro_hole_count(s: u8) -> usize {
    10 << (s - 1)
}
/// Minimum hop distance between micro-hole seeds.
pub const MICRO_HOLE_SEPARATION: u32 = 4;
/// Number of big holes.
pub const BIG_HOLE_COUNT: usize = 4;
/// Radius of the big holes, as a fraction of D.
pub fn big_hole_radius(s: u8) -> f64 {
    0.025 * s as f64
}
/// Minimum edge-graph distance between big-hole seeds, as a fraction of D.
pub const BIG_HOLE_SEPARATION: f64 = 0.30;
/// Global scale factors β for s = 1…5 (|ln β| increases with s).
pub const SCALE_FACTORS: [f64; 5] = [1.25, 0.6, 2.0, 0.4, 4.0];
/// Local scale factor β.
pub fn local_scale_factor(s: u8) -> f64 {
    1.0 + 0.2 * s as f64
}
/// Width ρ of the local scaling, as a fraction of D.
pub const LOCAL_SCALE_WIDTH: f64 = 0.10;
/// Noise standard deviation per coordinate, in mean edge lengths.
pub fn noise_sigma(s: u8) -> f64 {
    0.1 * s as f64
}
/// Fraction of vertices hit by shot noise.
pub fn shot_fraction(s: u8) -> f64 {
    0.005 * s as f64
}
/// Shot amplitude, in mean edge lengths.
pub const SHOT_AMPLITUDE: f64 = 5.0;
/// Fraction of the vertices kept by the sampling class for s = 1…5.
pub const SAMPLING_KEEP: [f64; 5] = [0.8, 0.6, 0.4, 0.2, 0.1];

/// Which of the `m` poses (sorted by increasing deformation) strength s uses: the
/// (s−1)/4 quantile, k = round((s−1)(m−1)/4). With fewer than 5 poses some strengths share
/// a pose.
pub fn pose_index(s: u8, m: usize) -> usize {
    ((s as f64 - 1.0) * (m as f64 - 1.0) / 4.0).round() as usize
}

/// The parameter table (class → strength → parameters) recorded in the manifest.
pub fn parameter_table() -> serde_json::Value {
    let per = |f: &dyn Fn(u8) -> serde_json::Value| (1..=5u8).map(f).collect::<Vec<_>>();
    json!({
        "units": "D = bounding-box diagonal of the base mesh, mean_edge = mean edge length of the base mesh",
        "isometry": {"recipe": "skinning bend about a random joint plane through a random vertex; smoothstep weight over the band |signed distance| < half_width; rotation by w*theta about a random axis in the plane", "half_width_D": BEND_HALF_WIDTH, "theta_deg": per(&|s| json!(bend_angle_deg(s)))},
        "topology": {"recipe": "among vertex pairs closer than max_distance whose edge-graph distance exceeds min_graph_distance, weld the `pairs` closest ones, skipping pairs whose weld would leave a face of area < 1e-6 mean face area (union-find, smallest id survives with its position)", "min_graph_distance_D": WELD_MIN_GRAPH_DISTANCE, "max_distance_D": WELD_MAX_DISTANCE, "pairs": per(&|s| json!(weld_pair_count(s)))},
        "handles": {"recipe": "remove the edge-graph balls of ball_hops hops around two vertices closer than max_distance whose edge-graph distance exceeds min_graph_distance and whose normals face each other; join the two rims by a tube of rings about one mean edge apart (shrec_bench::handles)", "ball_hops": crate::handles::HANDLE_BALL_HOPS, "max_distance_D": crate::handles::HANDLE_MAX_DISTANCE, "min_graph_distance_D": crate::handles::HANDLE_MIN_GRAPH_DISTANCE, "handles": per(&|s| json!(crate::handles::handle_count(s)))},
        "microholes": {"recipe": "delete random seed vertices with their 1-ring vertices (seeds at least `separation_hops` apart), keep the largest connected piece", "separation_hops": MICRO_HOLE_SEPARATION, "holes": per(&|s| json!(micro_hole_count(s)))},
        "holes": {"recipe": "delete edge-graph geodesic balls around random seeds at least separation apart, keep the largest connected piece", "seeds": BIG_HOLE_COUNT, "separation_D": BIG_HOLE_SEPARATION, "radius_D": per(&|s| json!(big_hole_radius(s)))},
        "scale": {"recipe": "x <- beta x", "beta": SCALE_FACTORS},
        "localscale": {"recipe": "x <- c + (1 + (beta-1) w)(x - c), w = exp(-d_g(x,c)^2 / (2 rho^2)), c a random vertex, d_g edge-graph distance", "rho_D": LOCAL_SCALE_WIDTH, "beta": per(&|s| json!(local_scale_factor(s)))},
        "noise": {"recipe": "x <- x + sigma z, z ~ N(0, I3)", "sigma_mean_edge": per(&|s| json!(noise_sigma(s)))},
        "shotnoise": {"recipe": "a random fraction of the vertices moves by +-amplitude along the unit vertex normal", "amplitude_mean_edge": SHOT_AMPLITUDE, "fraction": per(&|s| json!(shot_fraction(s)))},
        "pose": {"recipe": "another TOSCA pose of the same family; poses sorted by deformation = Kabsch-aligned RMS distance of corresponding points / D; strength s takes rank round((s-1)(m-1)/4) of m poses; ground truth from corres/*.vts (row i of two files = same point), -1 where no row names the vertex"},
        "sampling": {"recipe": "QEM half-edge collapse (shrec_bench::transform::QemDecimator, default QemParams); surviving vertices keep position and identity", "keep_fraction": SAMPLING_KEEP},
    })
}

/// A base (null) shape with the quantities every transformation needs.
#[derive(Clone, Debug)]
pub struct BaseShape {
    /// Shape name (file stem).
    pub name: String,
    /// The null mesh.
    pub mesh: TriMesh,
    /// Its edge graph.
    pub graph: EdgeGraph,
    /// D: the bounding-box diagonal.
    pub diameter: f64,
    /// ℓ̄: the mean edge length.
    pub mean_edge: f64,
    /// Other poses of the same family, sorted by increasing [`Pose::deformation`] (empty
    /// unless loaded with [`BaseShape::load_poses`]).
    pub poses: Vec<Pose>,
}

/// Another pose of a base shape's family with its ground truth.
#[derive(Clone, Debug)]
pub struct Pose {
    /// Pose name (file stem), e.g. `cat3`.
    pub name: String,
    /// The pose mesh.
    pub mesh: TriMesh,
    /// For each pose vertex, the base vertex at the same body point (−1: none).
    pub ground_truth: Vec<i64>,
    /// Non-rigidity: RMS distance, after the best rigid alignment (Kabsch), between the
    /// corresponding points of the pose and the base, divided by D.
    pub deformation: f64,
}

/// Reads a `.vts` file: one 1-based vertex index per line.
fn read_vts(path: &Path, n_vertices: usize) -> Result<Vec<u32>, BenchError> {
    let text = std::fs::read_to_string(path).map_err(|source| {
        BenchError::Mesh(MeshError::Io {
            path: path.to_path_buf(),
            source,
        })
    })?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let v: usize = l.trim().parse().map_err(|_| {
                BenchError::Argument(format!("{}:{}: not a vertex index: {l:?}", path.display(), i + 1))
            })?;
            if v == 0 || v > n_vertices {
                return Err(BenchError::Argument(format!(
                    "{}:{}: 1-based index {v} outside 1..={n_vertices}",
                    path.display(),
                    i + 1
                )));
            }
            Ok((v - 1) as u32)
        })
        .collect()
}

/// Best rigid alignment residual: min over rotations R and translations t of
/// sqrt(mean ‖R a_i + t − b_i‖²), via the Kabsch algorithm (3×3 SVD with faer).
fn kabsch_rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let m = a.len() as f64;
    let ca = [0, 1, 2].map(|k| a.iter().map(|p| p[k]).sum::<f64>() / m);
    let cb = [0, 1, 2].map(|k| b.iter().map(|p| p[k]).sum::<f64>() / m);
    let mut h = faer::Mat::<f64>::zeros(3, 3);
    let (mut sa, mut sb) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let x = sub(*p, ca);
        let y = sub(*q, cb);
        sa += dot(x, x);
        sb += dot(y, y);
        for i in 0..3 {
            for j in 0..3 {
                h[(i, j)] += x[i] * y[j];
            }
        }
    }
    // Σ‖R x − y‖² = Σ‖x‖² + Σ‖y‖² − 2 tr(R H) and max_R tr(RH) = σ₁ + σ₂ ± σ₃ (sign of det H).
    let Ok(svd) = h.svd() else {
        return f64::NAN;
    };
    let sigma = svd.S().column_vector();
    let det = h.determinant();
    let trace = sigma[0] + sigma[1] + if det < 0.0 { -sigma[2] } else { sigma[2] };
    ((sa + sb - 2.0 * trace).max(0.0) / m).sqrt()
}

impl BaseShape {
    /// Loads the other poses of the family from the base file's folder: files
    /// `<family><k>.off` with `corres/<family><k>.vts`, where the base file is
    /// `<family><k0>.off` with `corres/<family><k0>.vts`. Row i of two `.vts` files names
    /// the same body point (TOSCA / BCICP convention); a pose vertex named by no row gets −1.
    /// Poses are sorted by increasing deformation.
    ///
    /// # Errors
    /// Unreadable pose or `.vts` files. A base without a `.vts` file simply has no poses.
    pub fn load_poses(&mut self, base_file: &Path) -> Result<(), BenchError> {
        let dir = base_file.parent().unwrap_or(Path::new("."));
        let family = self.name.trim_end_matches(|c: char| c.is_ascii_digit()).to_string();
        let base_vts_path = dir.join("corres").join(format!("{}.vts", self.name));
        if !base_vts_path.is_file() {
            return Ok(());
        }
        let base_vts = read_vts(&base_vts_path, self.mesh.n_vertices())?;
        let entries = std::fs::read_dir(dir).map_err(|source| {
            BenchError::Mesh(MeshError::Io {
                path: dir.to_path_buf(),
                source,
            })
        })?;
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok())
            .filter_map(|e| e.file_name().to_str().map(str::to_string))
            .filter_map(|f| f.strip_suffix(".off").map(str::to_string))
            .filter(|stem| {
                stem.strip_prefix(&family)
                    .is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
                    && *stem != self.name
            })
            .collect();
        names.sort();
        let mut poses = Vec::new();
        for name in names {
            let vts_path = dir.join("corres").join(format!("{name}.vts"));
            if !vts_path.is_file() {
                continue;
            }
            let (mesh, _) =
                mesh_fem::io::load(&dir.join(format!("{name}.off")), &mesh_fem::io::LoadOptions::default())?;
            let vts = read_vts(&vts_path, mesh.n_vertices())?;
            if vts.len() != base_vts.len() {
                return Err(BenchError::Argument(format!(
                    "{} has {} rows but {} has {}",
                    vts_path.display(),
                    vts.len(),
                    base_vts_path.display(),
                    base_vts.len()
                )));
            }
            let mut ground_truth = vec![-1i64; mesh.n_vertices()];
            for (&pv, &bv) in vts.iter().zip(&base_vts) {
                if ground_truth[pv as usize] < 0 {
                    ground_truth[pv as usize] = bv as i64;
                }
            }
            let a: Vec<[f64; 3]> = base_vts.iter().map(|&v| self.mesh.positions()[v as usize]).collect();
            let b: Vec<[f64; 3]> = vts.iter().map(|&v| mesh.positions()[v as usize]).collect();
            let deformation = kabsch_rms(&a, &b) / self.diameter;
            poses.push(Pose {
                name,
                mesh,
                ground_truth,
                deformation,
            });
        }
        poses.sort_by(|x, y| x.deformation.total_cmp(&y.deformation).then(x.name.cmp(&y.name)));
        self.poses = poses;
        Ok(())
    }

    /// Prepares a base shape.
    ///
    /// # Errors
    /// [`BenchError::Argument`] if the mesh has no extent or no edges.
    pub fn new(name: &str, mesh: TriMesh) -> Result<Self, BenchError> {
        let graph = EdgeGraph::new(&mesh);
        let diameter = bounding_box_diagonal(&mesh);
        let mean_edge = graph.mean_edge_length();
        if !(diameter > 0.0 && mean_edge > 0.0) {
            return Err(BenchError::Argument(format!("base shape {name} has no extent")));
        }
        Ok(Self {
            name: name.to_string(),
            mesh,
            graph,
            diameter,
            mean_edge,
            poses: Vec::new(),
        })
    }
}

mod classes;
use classes::{
    holes, identity_gt, isometry, local_scale, micro_holes, noise, pose, sampling, scale, shot_noise, topology,
};

/// Applies one transformation class at strength `s` (1…5) to `base`.
///
/// `seed` is the global seed; the random stream is [`stream_seed`]`(seed, base.name, class)`.
///
/// # Errors
/// [`BenchError::Argument`] for a strength outside 1…5, and mesh errors of the surgery.
pub fn transform(base: &BaseShape, class: Class, s: u8, seed: u64) -> Result<Transformed, BenchError> {
    if !(1..=5).contains(&s) {
        return Err(BenchError::Argument(format!("strength {s} is outside 1..=5")));
    }
    let mut rng = SplitMix64::new(stream_seed(seed, &base.name, class));
    match class {
        Class::Pose => pose(base, s, &mut rng),
        Class::Isometry => isometry(base, s, &mut rng),
        Class::Topology => topology(base, s, &mut rng),
        Class::Handles => crate::handles::add_handles(
            &base.mesh,
            &base.graph,
            base.diameter,
            base.mean_edge,
            crate::handles::handle_count(s),
            &mut rng,
        ),
        Class::MicroHoles => micro_holes(base, s, &mut rng),
        Class::Holes => holes(base, s, &mut rng),
        Class::Scale => scale(base, s, &mut rng),
        Class::LocalScale => local_scale(base, s, &mut rng),
        Class::Noise => noise(base, s, &mut rng),
        Class::ShotNoise => shot_noise(base, s, &mut rng),
        Class::Sampling => sampling(base, s, &mut rng),
    }
}

/// Checks a generated shape before it is written: finite coordinates and indices in range
/// (by construction of [`TriMesh`]), no face repeating a vertex, every face of area above
/// 10⁻¹²·D², a ground truth of one entry per vertex in −1…n_base−1, and a successful FEM
/// assembly (L, B, D) with finite entries and a positive lumped mass.
///
/// # Errors
/// A human-readable reason.
pub fn validate_output(t: &Transformed, n_base: usize, diameter: f64) -> Result<(), String> {
    let m = &t.mesh;
    let min_area = 1e-12 * diameter * diameter;
    for (f, face) in m.faces().iter().enumerate() {
        if face[0] == face[1] || face[1] == face[2] || face[0] == face[2] {
            return Err(format!("face {f} repeats a vertex: {face:?}"));
        }
        let a = m.face_area(f);
        if a.is_nan() || a <= min_area {
            return Err(format!("face {f} {face:?} is degenerate (area {a:e})"));
        }
    }
    if t.ground_truth.len() != m.n_vertices() {
        return Err(format!(
            "ground truth has {} entries for {} vertices",
            t.ground_truth.len(),
            m.n_vertices()
        ));
    }
    if let Some((i, g)) = t
        .ground_truth
        .iter()
        .enumerate()
        .find(|(_, &g)| g < -1 || g >= n_base as i64)
    {
        return Err(format!("ground truth of vertex {i} is {g}, outside -1..{n_base}"));
    }
    let ops = assemble(m, &AssemblyParams::default()).map_err(|e| format!("assembly failed: {e}"))?;
    if ops.lumped_diagonal.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        return Err("lumped mass has a non-positive or non-finite entry".into());
    }
    let finite = |mat: &faer::sparse::SparseColMat<usize, f64>| mat.val().iter().all(|x| x.is_finite());
    if !finite(&ops.stiffness) || !finite(&ops.mass) {
        return Err("stiffness or mass has a non-finite entry".into());
    }
    Ok(())
}

/// Options of [`generate`].
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    /// Folder of the mesh corpus (`cargo xtask shrec`: `wfem_corpus::meshes_dir()` by default).
    pub meshes_dir: PathBuf,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Base shapes: a name `cat` means `cat0` (the null pose); a name ending in a digit is
    /// taken as is. Files are looked up as `tosca-bcicp-5k/TOSCA_Isometric/<name>.off` under
    /// `meshes_dir`, then as `<name>.off` directly in it.
    pub shapes: Vec<String>,
    /// Classes to generate.
    pub classes: Vec<Class>,
    /// Strengths (1…5).
    pub strengths: Vec<u8>,
    /// Global seed.
    pub seed: u64,
}

/// The default base shapes.
pub const DEFAULT_SHAPES: [&str; 8] = ["cat", "centaur", "david", "dog", "horse", "michael", "victoria", "wolf"];

/// One base shape in the manifest.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ManifestBase {
    /// Shape name (with pose number).
    pub shape: String,
    /// Base mesh file read.
    pub file: PathBuf,
    /// Vertex count.
    pub n_vertices: usize,
    /// Face count.
    pub n_faces: usize,
    /// D, the bounding-box diagonal.
    pub diameter: f64,
    /// ℓ̄, the mean edge length.
    pub mean_edge: f64,
    /// The null shape as written (`<shape>/<shape>.null.0.off`, relative to the output folder).
    pub mesh: String,
    /// Its (identity) ground truth file.
    pub ground_truth: String,
}

/// One generated shape in the manifest.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ManifestEntry {
    /// Base shape name.
    pub shape: String,
    /// Class.
    pub class: Class,
    /// Strength 1…5.
    pub strength: u8,
    /// Mesh file, relative to the output folder.
    pub mesh: String,
    /// Ground-truth file (one 0-based base vertex per line, −1 for none), relative.
    pub ground_truth: String,
    /// Vertex count.
    pub n_vertices: usize,
    /// Face count.
    pub n_faces: usize,
    /// Vertices with a ground-truth correspondence.
    pub n_mapped: usize,
    /// Seed of the class's random stream.
    pub stream_seed: u64,
    /// Parameters actually used.
    pub params: serde_json::Value,
}

/// The dataset manifest (`manifest.json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// Generator name and version.
    pub generator: String,
    /// Global seed.
    pub seed: u64,
    /// Corpus folder.
    pub meshes_dir: PathBuf,
    /// The parameter table of every class.
    pub parameters: serde_json::Value,
    /// Base shapes.
    pub bases: Vec<ManifestBase>,
    /// Generated shapes, sorted by shape, class, strength.
    pub outputs: Vec<ManifestEntry>,
}

fn base_file(meshes_dir: &Path, name: &str) -> Result<(String, PathBuf), BenchError> {
    let stem = if name.ends_with(|c: char| c.is_ascii_digit()) {
        name.to_string()
    } else {
        format!("{name}0")
    };
    let candidates = [
        meshes_dir
            .join("tosca-bcicp-5k")
            .join("TOSCA_Isometric")
            .join(format!("{stem}.off")),
        meshes_dir.join(format!("{stem}.off")),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .map(|p| (stem.clone(), p.clone()))
        .ok_or_else(|| BenchError::Argument(format!("no base mesh for {name:?}: tried {candidates:?}")))
}

fn write_gt(path: &Path, gt: &[i64]) -> Result<(), BenchError> {
    mesh_fem::io::write_atomic(path, |w| {
        let mut s = String::with_capacity(gt.len() * 6);
        for g in gt {
            s.push_str(&g.to_string());
            s.push('\n');
        }
        w.write_all(s.as_bytes())
    })?;
    Ok(())
}

fn make_dir(dir: &Path) -> Result<(), BenchError> {
    std::fs::create_dir_all(dir).map_err(|source| {
        BenchError::Mesh(MeshError::Io {
            path: dir.to_path_buf(),
            source,
        })
    })
}

/// Generates the benchmark: for every base shape the null shape, then every requested
/// (class, strength), validated and written atomically, and finally `manifest.json`.
///
/// # Errors
/// The first failure: bad options, unreadable base, failed validation or write error.
pub fn generate(opts: &GenerateOptions) -> Result<Manifest, BenchError> {
    if let Some(&s) = opts.strengths.iter().find(|s| !(1..=5).contains(*s)) {
        return Err(BenchError::Argument(format!("strength {s} is outside 1..=5")));
    }
    make_dir(&opts.out_dir)?;
    let mut bases = Vec::new();
    let mut shapes = Vec::new();
    for name in &opts.shapes {
        let (stem, file) = base_file(&opts.meshes_dir, name)?;
        let (mesh, _) = mesh_fem::io::load(&file, &mesh_fem::io::LoadOptions::default())?;
        let mut shape = BaseShape::new(&stem, mesh)?;
        if opts.classes.contains(&Class::Pose) {
            shape.load_poses(&file)?;
        }
        make_dir(&opts.out_dir.join(&stem))?;
        let null = Transformed {
            ground_truth: identity_gt(shape.mesh.n_vertices()),
            mesh: shape.mesh.clone(),
            params: json!({}),
        };
        validate_output(&null, shape.mesh.n_vertices(), shape.diameter).map_err(|reason| {
            BenchError::InvalidOutput {
                shape: stem.clone(),
                class: "null".into(),
                strength: 0,
                reason,
            }
        })?;
        let mesh_rel = format!("{stem}/{stem}.null.0.off");
        let gt_rel = format!("{stem}/{stem}.null.0.gt");
        mesh_fem::io::write_mesh(&opts.out_dir.join(&mesh_rel), &shape.mesh)?;
        write_gt(&opts.out_dir.join(&gt_rel), &null.ground_truth)?;
        bases.push(ManifestBase {
            shape: stem.clone(),
            file,
            n_vertices: shape.mesh.n_vertices(),
            n_faces: shape.mesh.n_faces(),
            diameter: shape.diameter,
            mean_edge: shape.mean_edge,
            mesh: mesh_rel,
            ground_truth: gt_rel,
        });
        shapes.push(shape);
    }
    let mut tasks = Vec::new();
    for (b, _) in shapes.iter().enumerate() {
        for &c in &opts.classes {
            for &s in &opts.strengths {
                tasks.push((b, c, s));
            }
        }
    }
    let mut outputs = tasks
        .par_iter()
        .map(|&(b, class, s)| -> Result<ManifestEntry, BenchError> {
            let base = &shapes[b];
            let t = transform(base, class, s, opts.seed)?;
            validate_output(&t, base.mesh.n_vertices(), base.diameter).map_err(|reason| BenchError::InvalidOutput {
                shape: base.name.clone(),
                class: class.name().into(),
                strength: s,
                reason,
            })?;
            let stem = &base.name;
            let mesh_rel = format!("{stem}/{stem}.{}.{s}.off", class.name());
            let gt_rel = format!("{stem}/{stem}.{}.{s}.gt", class.name());
            mesh_fem::io::write_mesh(&opts.out_dir.join(&mesh_rel), &t.mesh)?;
            write_gt(&opts.out_dir.join(&gt_rel), &t.ground_truth)?;
            Ok(ManifestEntry {
                shape: stem.clone(),
                class,
                strength: s,
                mesh: mesh_rel,
                ground_truth: gt_rel,
                n_vertices: t.mesh.n_vertices(),
                n_faces: t.mesh.n_faces(),
                n_mapped: t.ground_truth.iter().filter(|&&g| g >= 0).count(),
                stream_seed: stream_seed(opts.seed, stem, class),
                params: t.params,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    outputs.sort_by(|a, b| (&a.shape, a.class, a.strength).cmp(&(&b.shape, b.class, b.strength)));
    let manifest = Manifest {
        generator: format!("wfem shrec-bench {}", env!("CARGO_PKG_VERSION")),
        seed: opts.seed,
        meshes_dir: opts.meshes_dir.clone(),
        parameters: parameter_table(),
        bases,
        outputs,
    };
    let text = serde_json::to_string_pretty(&manifest)?;
    mesh_fem::io::write_atomic(&opts.out_dir.join("manifest.json"), |w| w.write_all(text.as_bytes()))?;
    Ok(manifest)
}
