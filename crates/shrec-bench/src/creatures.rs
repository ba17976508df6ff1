//! Procedural "creatures": closed surfaces with a body and limbs, made by wfem itself, for
//! training a vocabulary on shapes outside every evaluation set (issue #28, point 3).
//!
//! A creature is an icosphere deformed in three steps, all randomness from one seeded
//! [`SplitMix64`] stream:
//!
//! 1. **body**: the unit sphere scaled to an ellipsoid;
//! 2. **limbs**: a limb is a centre d on the sphere, an axis it grows along (d itself unless
//!    aimed), a length ℓ, an angular width w, a profile exponent p ∈ {2, 4} (tapered or blunt)
//!    and a bend β towards a perpendicular t of the axis; a point u of the sphere at angle θ
//!    from d moves by ℓ φ (cos(βφ) axis + sin(βφ) t) with φ = exp(−(θ/w)^p), so the cap around
//!    d is carried out as a whole and the ring around it becomes the limb's side. **Sub-limbs**
//!    (fingers, toes, ears: 2–5 on a limb) are centred on the parent's cap and grow from its
//!    tip, tilted 0.3–1 rad away;
//! 3. **bumps** (0–6): the same displacement with a small length (0.05–0.2) and no bend.
//!
//! The seed chooses the plan (seed mod 3): **random bodies** (axes 1 × [0.45, 1] × [0.3, 1],
//! 2–8 limbs of length 0.3–2.5 and width 0.1–0.4 rad in random directions at least their
//! widths plus 0.25 rad apart, half of them with sub-limbs), **bipeds** (upright; a head, two
//! arms, two legs; hands and ears sometimes) and **quadrupeds** (four legs, a neck and head,
//! a tail). The surfaces may self-intersect where two bent limbs cross in space; the intrinsic
//! geometry the descriptors see is unaffected.

use crate::protocol::ShapeFile;
use crate::BenchError;
use mesh_fem::generate::icosphere;
use mesh_fem::vec3::{add, cross, dot, norm};
use mesh_fem::{MeshError, TriMesh};
use std::path::Path;
use wfem_base::rng::SplitMix64;

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|c| c * s)
}

fn normalized(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / norm(a).max(1e-12))
}

/// One displacement field: a limb or a bump.
#[derive(Clone, Copy, Debug)]
struct Limb {
    direction: [f64; 3],
    axis: [f64; 3],
    perpendicular: [f64; 3],
    length: f64,
    width: f64,
    exponent: i32,
    bend: f64,
}

impl Limb {
    fn random(rng: &mut SplitMix64, length: (f64, f64), width: (f64, f64), bend: f64) -> Self {
        let direction = rng.unit_vector();
        let other = rng.unit_vector();
        let mut perpendicular = cross(direction, other);
        let l = norm(perpendicular).max(1e-12);
        perpendicular = scale(perpendicular, 1.0 / l);
        Self {
            direction,
            axis: direction,
            perpendicular,
            length: length.0 + (length.1 - length.0) * rng.next_f64(),
            width: width.0 + (width.1 - width.0) * rng.next_f64(),
            exponent: if rng.next_f64() < 0.5 { 2 } else { 4 },
            bend: bend * rng.next_f64(),
        }
    }

    /// The displacement of the sphere point `u`.
    fn displacement(&self, u: [f64; 3]) -> [f64; 3] {
        let theta = dot(u, self.direction).clamp(-1.0, 1.0).acos();
        let phi = (-(theta / self.width).powi(self.exponent)).exp();
        if phi < 1e-12 {
            return [0.0; 3];
        }
        let a = self.bend * phi;
        scale(
            add(scale(self.axis, a.cos()), scale(self.perpendicular, a.sin())),
            self.length * phi,
        )
    }
}

/// The creature of `seed` on the icosphere of `level` (10·4^level + 2 vertices).
///
/// # Errors
/// [`MeshError`] if the deformed mesh is invalid (it is not for any seed: the displacement is
/// smooth; the check is the mesh constructor's).
pub fn creature(seed: u64, level: u32) -> Result<TriMesh, MeshError> {
    let mut rng = SplitMix64::new(seed);
    let (axes, mut limbs) = match seed % 3 {
        0 => random_plan(&mut rng),
        1 => biped(&mut rng),
        _ => quadruped(&mut rng),
    };
    let n_bumps = rng.next_below(7);
    for _ in 0..n_bumps {
        limbs.push(Limb::random(&mut rng, (0.05, 0.2), (0.1, 0.3), 0.0));
    }
    deformed_sphere(axes, &limbs, level)
}

/// The icosphere of `level` scaled to the ellipsoid `axes` and displaced by every limb.
fn deformed_sphere(axes: [f64; 3], limbs: &[Limb], level: u32) -> Result<TriMesh, MeshError> {
    let (sphere, faces) = icosphere(level).into_parts();
    let positions = sphere
        .iter()
        .map(|&u| {
            let body = [u[0] * axes[0], u[1] * axes[1], u[2] * axes[2]];
            limbs.iter().fold(body, |x, limb| add(x, limb.displacement(u)))
        })
        .collect();
    TriMesh::new(positions, faces)
}

/// The icosphere level of [`creature_files`]: 10,242 vertices, finer than any refinement needs.
pub const CREATURE_LEVEL: u32 = 5;

/// Creatures 0..count as OFF files in `dir` (written where missing: a file is named by its
/// seed only, so a folder written by an older generator must be emptied first), family
/// `creature`.
///
/// # Errors
/// [`BenchError::Data`] if the folder or a file cannot be written.
pub fn creature_files(dir: &Path, count: u64) -> Result<Vec<ShapeFile>, BenchError> {
    std::fs::create_dir_all(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
    (0..count)
        .map(|seed| {
            let name = format!("creature{seed:03}");
            let path = dir.join(format!("{name}.off"));
            if !path.is_file() {
                let mesh = creature(seed, CREATURE_LEVEL).map_err(|e| BenchError::Data(e.to_string()))?;
                mesh_fem::io::write_mesh(&path, &mesh).map_err(|e| BenchError::Data(e.to_string()))?;
            }
            Ok(ShapeFile {
                path,
                name,
                family: "creature".into(),
                transform: None,
                strength: 0,
                cloud: None,
            })
        })
        .collect()
}

type Plan = ([f64; 3], Vec<Limb>);

/// Individuals of [`people_files`].
pub const PEOPLE_INDIVIDUALS: u64 = 10;
/// Poses per individual of [`people_files`].
pub const PEOPLE_POSES: u64 = 8;
/// The icosphere level of [`people_files`]: 2,562 vertices (enough for 100 eigenpairs).
pub const PEOPLE_LEVEL: u32 = 4;

/// Person `individual` in pose `pose` (issue #42: individuals of one species that differ by
/// build, not by parts): a biped whose **build** — the body's axes, the head's, arms' and
/// legs' lengths, widths and profiles, the same on both sides — comes from the individual's
/// seed, and whose **pose** — where each arm points, how much each limb bends and to which
/// side — from the pose's. A pose bends limbs without stretching them, so the poses of one
/// individual are nearly isometric and two individuals differ by proportions only. `spread`
/// (1: the bipeds of [`creature`]) scales every build range about its middle: 0.5 gives
/// people twice as alike.
///
/// # Errors
/// [`MeshError`] as [`creature`].
pub fn person(individual: u64, pose: u64, level: u32, spread: f64) -> Result<TriMesh, MeshError> {
    let uniform = |rng: &mut SplitMix64, (a, b): (f64, f64)| {
        let mid = 0.5 * (a + b);
        uniform(rng, (mid - spread * (mid - a), mid + spread * (b - mid)))
    };
    let mut build = SplitMix64::new(0x9e37_79b9_7f4a_7c15 ^ individual);
    let mut posing = SplitMix64::new(individual.wrapping_mul(1_000_003).wrapping_add(pose) ^ 0x5bd1_e995);
    let axes = [
        uniform(&mut build, (0.45, 0.65)),
        uniform(&mut build, (0.28, 0.42)),
        1.0,
    ];
    let head = (uniform(&mut build, (0.35, 0.7)), uniform(&mut build, (0.25, 0.35)));
    let arm = (uniform(&mut build, (1.2, 2.2)), uniform(&mut build, (0.13, 0.22)));
    let leg = (uniform(&mut build, (1.5, 2.4)), uniform(&mut build, (0.2, 0.3)));
    let limb = |rng: &mut SplitMix64, direction: [f64; 3], axis: [f64; 3], (length, width): (f64, f64), bend: f64| {
        let axis = near(rng, axis, 0.1);
        Limb {
            direction: normalized(direction),
            axis,
            perpendicular: normalized(cross(axis, rng.unit_vector())),
            length,
            width,
            exponent: 4,
            bend: bend * rng.next_f64(),
        }
    };
    let mut limbs = vec![limb(&mut posing, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], head, 0.3)];
    for side in [-1.0, 1.0] {
        let down = -0.9 + 1.3 * posing.next_f64();
        limbs.push(limb(&mut posing, [side, 0.0, 0.6], [side, 0.0, down], arm, 0.9));
        limbs.push(limb(
            &mut posing,
            [0.35 * side, 0.0, -1.0],
            [0.15 * side, 0.0, -1.0],
            leg,
            0.5,
        ));
    }
    deformed_sphere(axes, &limbs, level)
}

/// [`PEOPLE_INDIVIDUALS`] people in [`PEOPLE_POSES`] poses each ([`person`] of `spread`) as
/// OFF files in `dir` (written where missing: name the folder by the generator's version and
/// the spread, since files already there are reused), family = the
/// individual (`person03`).
///
/// # Errors
/// [`BenchError::Data`] if the folder or a file cannot be written.
pub fn people_files(dir: &Path, spread: f64) -> Result<Vec<ShapeFile>, BenchError> {
    std::fs::create_dir_all(dir).map_err(|e| BenchError::Data(format!("{}: {e}", dir.display())))?;
    let mut out = Vec::new();
    for individual in 0..PEOPLE_INDIVIDUALS {
        for pose in 0..PEOPLE_POSES {
            let family = format!("person{individual:02}");
            let name = format!("{family}-pose{pose}");
            let path = dir.join(format!("{name}.off"));
            if !path.is_file() {
                let mesh =
                    person(individual, pose, PEOPLE_LEVEL, spread).map_err(|e| BenchError::Data(e.to_string()))?;
                mesh_fem::io::write_mesh(&path, &mesh).map_err(|e| BenchError::Data(e.to_string()))?;
            }
            out.push(ShapeFile {
                path,
                name,
                family,
                transform: None,
                strength: 0,
                cloud: None,
            });
        }
    }
    Ok(out)
}

fn uniform(rng: &mut SplitMix64, range: (f64, f64)) -> f64 {
    range.0 + (range.1 - range.0) * rng.next_f64()
}

/// A direction near `v`: `v` plus `jitter` times a random unit vector, normalised.
fn near(rng: &mut SplitMix64, v: [f64; 3], jitter: f64) -> [f64; 3] {
    normalized(add(normalized(v), scale(rng.unit_vector(), jitter)))
}

/// A limb centred at `direction` on the sphere that grows along `axis`.
fn aimed(
    rng: &mut SplitMix64,
    direction: [f64; 3],
    axis: [f64; 3],
    length: (f64, f64),
    width: (f64, f64),
    bend: f64,
) -> Limb {
    let mut limb = Limb::random(rng, length, width, bend);
    limb.direction = near(rng, direction, 0.1);
    limb.axis = near(rng, axis, 0.15);
    limb.perpendicular = normalized(cross(limb.axis, rng.unit_vector()));
    limb.exponent = 4;
    limb
}

/// 2–5 smaller limbs on the cap of `parent`, growing from its tip (fingers, toes, ears).
fn add_sub_limbs(rng: &mut SplitMix64, parent: Limb, limbs: &mut Vec<Limb>) {
    let tip = add(
        scale(parent.axis, parent.bend.cos()),
        scale(parent.perpendicular, parent.bend.sin()),
    );
    for _ in 0..2 + rng.next_below(4) {
        let mut sub = Limb::random(rng, (0.2 * parent.length, 0.7 * parent.length), (0.2, 0.45), 0.8);
        sub.width *= parent.width;
        // Centre: on the parent's cap, 0.3–0.8 of its width away from its centre.
        let side = normalized(cross(parent.direction, rng.unit_vector()));
        let offset = parent.width * (0.3 + 0.5 * rng.next_f64());
        sub.direction = normalized(add(scale(parent.direction, offset.cos()), scale(side, offset.sin())));
        // Axis: the parent's tip direction tilted towards the side by 0.3–1 rad.
        let tilt = 0.3 + 0.7 * rng.next_f64();
        sub.axis = normalized(add(scale(tip, tilt.cos()), scale(side, tilt.sin())));
        sub.perpendicular = normalized(cross(sub.axis, rng.unit_vector()));
        limbs.push(sub);
    }
}

/// Pushes `limb` and, with probability `p`, its sub-limbs ([`add_sub_limbs`]).
fn push_limb(rng: &mut SplitMix64, limb: Limb, p: f64, limbs: &mut Vec<Limb>) {
    limbs.push(limb);
    if rng.next_f64() < p {
        add_sub_limbs(rng, limb, limbs);
    }
}

/// Any body with 2–8 limbs in random directions, half of them with sub-limbs.
fn random_plan(rng: &mut SplitMix64) -> Plan {
    let axes = [1.0, uniform(rng, (0.45, 1.0)), uniform(rng, (0.3, 1.0))];
    let n_limbs = 2 + rng.next_below(7);
    let mut limbs: Vec<Limb> = Vec::with_capacity(n_limbs);
    let mut attempts = 0;
    while limbs.len() < n_limbs && attempts < 200 {
        attempts += 1;
        let limb = Limb::random(rng, (0.3, 2.5), (0.1, 0.4), 1.2);
        let apart = limbs.iter().all(|o| {
            let angle = dot(o.direction, limb.direction).clamp(-1.0, 1.0).acos();
            angle > o.width + limb.width + 0.25
        });
        if apart {
            limbs.push(limb);
        }
    }
    for parent in limbs.clone() {
        if rng.next_f64() < 0.5 {
            add_sub_limbs(rng, parent, &mut limbs);
        }
    }
    (axes, limbs)
}

/// An upright body (z up) with a head, two arms and two legs; hands and ears sometimes.
fn biped(rng: &mut SplitMix64) -> Plan {
    let axes = [uniform(rng, (0.45, 0.65)), uniform(rng, (0.28, 0.42)), 1.0];
    let mut limbs = Vec::new();
    let head = aimed(rng, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], (0.35, 0.7), (0.25, 0.35), 0.3);
    push_limb(rng, head, 0.3, &mut limbs);
    for side in [-1.0, 1.0] {
        let down = uniform(rng, (-0.9, 0.4));
        let arm = aimed(rng, [side, 0.0, 0.6], [side, 0.0, down], (1.2, 2.2), (0.13, 0.22), 0.9);
        push_limb(rng, arm, 0.6, &mut limbs);
        let leg = aimed(
            rng,
            [0.35 * side, 0.0, -1.0],
            [0.15 * side, 0.0, -1.0],
            (1.5, 2.4),
            (0.2, 0.3),
            0.5,
        );
        push_limb(rng, leg, 0.4, &mut limbs);
    }
    (axes, limbs)
}

/// A horizontal body (x forward) with four legs, a neck and head, and a tail.
fn quadruped(rng: &mut SplitMix64) -> Plan {
    let axes = [1.0, uniform(rng, (0.35, 0.55)), uniform(rng, (0.35, 0.55))];
    let mut limbs = Vec::new();
    for (x, y) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let leg = aimed(
            rng,
            [0.6 * x, 0.5 * y, -1.0],
            [0.1 * x, 0.1 * y, -1.0],
            (0.9, 2.0),
            (0.12, 0.2),
            0.6,
        );
        push_limb(rng, leg, 0.3, &mut limbs);
    }
    let lift = uniform(rng, (0.0, 1.2));
    let head = aimed(rng, [1.0, 0.0, 0.5], [1.0, 0.0, lift], (0.6, 1.3), (0.18, 0.3), 1.0);
    push_limb(rng, head, 0.6, &mut limbs);
    let mut tail = aimed(rng, [-1.0, 0.0, 0.2], [-1.0, 0.0, 0.3], (0.4, 1.8), (0.06, 0.12), 1.2);
    tail.exponent = 2;
    limbs.push(tail);
    (axes, limbs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn creatures_are_closed_deterministic_and_differ() {
        let a = creature(1, 3).unwrap();
        let b = creature(1, 3).unwrap();
        let c = creature(2, 3).unwrap();
        assert_eq!(a.positions(), b.positions());
        assert_ne!(a.positions(), c.positions());
        // Euler characteristic of a sphere: the icosphere's connectivity is kept.
        let v = a.n_vertices() as i64;
        let f = a.n_faces() as i64;
        assert_eq!(v - 3 * f / 2 + f, 2);
    }

    #[test]
    fn people_keep_their_build_across_poses() {
        let areas = |individual: u64, spread: f64| -> Vec<f64> {
            (0..8)
                .map(|p| person(individual, p, 3, spread).unwrap().area())
                .collect()
        };
        let mean = |a: &[f64]| a.iter().sum::<f64>() / a.len() as f64;
        assert_eq!(
            person(3, 0, 3, 1.0).unwrap().positions(),
            person(3, 0, 3, 1.0).unwrap().positions()
        );
        assert_ne!(
            person(3, 0, 3, 1.0).unwrap().positions(),
            person(3, 1, 3, 1.0).unwrap().positions()
        );
        // A pose bends limbs and hardly stretches them (area within ±6 % over 8 poses); another
        // build is another body (here 30 % less area).
        let (a, b) = (areas(3, 1.0), areas(4, 1.0));
        for x in &a {
            assert!((x / mean(&a) - 1.0).abs() < 0.06, "{a:?}");
        }
        assert!((mean(&b) / mean(&a) - 1.0).abs() > 0.2, "{a:?} {b:?}");
        // Spread 0 makes every individual the same body: only the poses differ.
        let (c, d) = (areas(3, 0.0), areas(4, 0.0));
        assert!((mean(&c) / mean(&d) - 1.0).abs() < 0.03, "{c:?} {d:?}");
    }

    #[test]
    fn creature_files_are_written_once_and_read_back() {
        let dir = tempfile::tempdir().unwrap();
        let files = creature_files(dir.path(), 3).unwrap();
        assert_eq!(files.len(), 3);
        let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["creature000", "creature001", "creature002"]);
        // Every kind: a random body, a biped, a quadruped; each a valid closed mesh with
        // limbs (its extent is well beyond the unit body's).
        for (seed, f) in files.iter().enumerate() {
            let (read, _) = mesh_fem::io::load(&f.path, &mesh_fem::io::LoadOptions::default()).unwrap();
            let made = creature(seed as u64, CREATURE_LEVEL).unwrap();
            assert_eq!(read.faces(), made.faces());
            assert_eq!(
                read.n_vertices(),
                mesh_fem::generate::icosphere_vertex_count(CREATURE_LEVEL)
            );
            let diagonal = mesh_fem::vec3::bbox_diagonal(read.positions());
            assert!(diagonal > 2.5, "{}: diagonal {diagonal}", f.name);
        }
        // A second call finds the files and does not rewrite them.
        let before = std::fs::metadata(&files[0].path).unwrap().modified().unwrap();
        let again = creature_files(dir.path(), 3).unwrap();
        assert_eq!(again.len(), 3);
        assert_eq!(std::fs::metadata(&files[0].path).unwrap().modified().unwrap(), before);
    }
}
