//! `TimeScales` (which diffusion times mean something on a mesh) against the dense
//! generalized eigendecomposition and against the kernel itself: a time called "past the time
//! at infinity" gives a constant K_t e_i, a "negligible" one gives back e_i.
use crate::common::*;
use mesh_fem::{assemble, generate, AssemblyParams, Mass, TriMesh};
use wfem_heat::spectral::Eigenbasis;
use wfem_heat::times::{TimeScales, TimeWarning, SETTLED};
use wfem_heat::{HeatError, HeatKernel, HeatParams, Operators};

fn context(mesh: &TriMesh) -> Operators {
    let fem = assemble(mesh, &AssemblyParams::default()).unwrap();
    Operators::new(&fem, Mass::Consistent).unwrap()
}

/// Two disjoint copies: `mesh` and `mesh` scaled by `alpha`, shifted away.
fn two_components(mesh: &TriMesh, alpha: f64) -> TriMesh {
    let other = mesh.scaled(alpha).unwrap();
    let n = mesh.n_vertices() as u32;
    let mut positions = mesh.positions().to_vec();
    positions.extend(other.positions().iter().map(|p| [p[0] + 10.0, p[1], p[2]]));
    let mut faces = mesh.faces().to_vec();
    faces.extend(other.faces().iter().map(|f| [f[0] + n, f[1] + n, f[2] + n]));
    TriMesh::new(positions, faces).unwrap()
}

/// λ₂ of the smallest non-zero eigenvalue of the dense reference.
fn dense_first_nonzero(ops: &Operators) -> f64 {
    let dense = Eigenbasis::dense_of(ops).unwrap();
    let floor = 1e-8 * ops.mean_rayleigh_quotient();
    dense.values.iter().copied().find(|&l| l > floor).unwrap()
}

#[test]
fn first_nonzero_eigenvalue_and_its_bound_against_the_dense_spectrum() {
    let torus = generate::torus(3.0, 0.5, 40, 10);
    let sphere = generate::irregular_sphere(3, 5.6);
    for mesh in [torus.clone(), sphere.clone(), two_components(&sphere, 2.0)] {
        let ops = context(&mesh);
        let scales = TimeScales::new(&ops, Some(mesh.positions())).unwrap();
        let exact = dense_first_nonzero(&ops);
        let first = scales.first_nonzero().unwrap().unwrap();
        assert!((first - exact).abs() <= 1e-6 * exact, "λ₂ {first} vs dense {exact}");
        let bound = scales.first_nonzero_bound();
        // An upper bound (min-max), and a tight one on these shapes.
        assert!(
            bound >= exact * (1.0 - 1e-9) && bound <= 3.0 * exact,
            "bound {bound} vs λ₂ {exact}"
        );
    }
}

#[test]
fn warnings_say_what_the_kernel_does() {
    let mesh = generate::icosphere(3).with_area(0.057).unwrap();
    let fem = assemble(&mesh, &AssemblyParams::default()).unwrap();
    let kernel = HeatKernel::new(&fem, HeatParams::default()).unwrap();
    let ops = kernel.operators();
    let scales = TimeScales::new(ops, Some(mesh.positions())).unwrap();
    let n = mesh.n_vertices();
    let e = unit(n, 5);
    let spread = |g: &[f64]| {
        let max = g.iter().fold(f64::MIN, |m, &x| m.max(x));
        let min = g.iter().fold(f64::MAX, |m, &x| m.min(x));
        (max - min) / max.abs()
    };
    // The bunny's case of issue #25 (area 0.057): t = 0.1 is far past infinity.
    let warning = scales.check(0.1).unwrap();
    let Some(TimeWarning::PastInfinity { infinity, sensible, .. }) = warning else {
        panic!("t = 0.1 not flagged: {warning:?}");
    };
    assert!(spread(&kernel.apply(&e, 0.1).unwrap()) <= 10.0 * SETTLED);
    assert!(spread(&kernel.apply(&e, 1.01 * infinity).unwrap()) <= 10.0 * SETTLED);
    // Below the time at infinity, no warning, and the result is not constant.
    assert_eq!(scales.check(0.5 * infinity).unwrap(), None);
    assert!(spread(&kernel.apply(&e, 0.5 * infinity).unwrap()) > 1e-7);
    // The sensible range is inside and gives visible results at both ends.
    let (lo, hi) = sensible;
    assert!(lo < hi && hi < infinity);
    for t in [lo, hi] {
        assert_eq!(scales.check(t).unwrap(), None);
        assert!(spread(&kernel.apply(&e, t).unwrap()) > 1e-5);
    }
    // A negligible time gives back the input to ε; a thousand times more changes it.
    let tiny = 0.5 * SETTLED / scales.mean_eigenvalue();
    assert!(matches!(
        scales.check(tiny).unwrap(),
        Some(TimeWarning::Negligible { .. })
    ));
    let g = kernel.apply(&e, tiny).unwrap();
    assert!(max_abs_diff(&g, &e) <= 10.0 * SETTLED);
    assert_eq!(scales.check(1e3 * tiny).unwrap(), None);
    // Values that are not times are left to the kernel, which refuses them.
    for bad in [0.0, -1.0, f64::INFINITY, f64::NAN] {
        assert_eq!(scales.check(bad).unwrap(), None);
    }
    // Without positions (operators given directly): negligible times only, the same λ₂.
    let bare = TimeScales::new(ops, None).unwrap();
    assert_eq!(bare.check(0.1).unwrap(), None);
    assert!(matches!(
        bare.check(tiny).unwrap(),
        Some(TimeWarning::Negligible { .. })
    ));
    assert_eq!(bare.first_nonzero().unwrap(), scales.first_nonzero().unwrap());
    let g = kernel.apply(&e, 1e4 * tiny).unwrap();
    assert!(max_abs_diff(&g, &e) > 100.0 * SETTLED);
}

#[test]
fn warnings_in_a_unit_and_their_text() {
    let w = TimeWarning::PastInfinity {
        t: 0.1,
        infinity: 0.05,
        sensible: (1e-6, 0.02),
    };
    let area = w.in_unit(0.057);
    assert_eq!(area.sensible(), (1e-6 / 0.057, 0.02 / 0.057));
    insta::assert_snapshot!(area.to_string(), @"t = 1.75 is past the time at infinity of this mesh (0.877): the heat has spread to its mean to 1e-12, so the result is constant; sensible times for this mesh are about 1.75e-5 to 0.351");
}

#[test]
fn positions_of_another_mesh_are_refused() {
    let mesh = generate::icosphere(2);
    let ops = context(&mesh);
    let err = TimeScales::new(&ops, Some(&mesh.positions()[1..])).unwrap_err();
    assert!(matches!(err, HeatError::LengthMismatch { .. }), "{err}");
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}
