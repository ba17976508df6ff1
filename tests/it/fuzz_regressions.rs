//! Inputs found during the fuzzing work (issue #8, `docs/FUZZING.md`), kept in `tests/data/fuzz/`
//! (written by `tests/data/fuzz/make.py`; minimised `cargo fuzz tmin` outputs are committed
//! as they are). Every file of the folder must appear in [`CASES`] with its exact outcome
//! through load → validate → assemble, and none may panic.
//!
//! The tetrahedra `tet_<s>.obj` have corners 0, s·e₁, s·e₂, s·e₃. Before the fix a valid
//! triangle with edges above ~1e77 or below ~1e−77 overflowed or underflowed in ‖e₁×e₂‖ and
//! was refused as "zero area". Now the geometry is computed on exactly rescaled edges: the operators
//! follow the scale laws L(s) = L(1), B(s) = s²·B(1) over the whole range where the areas are
//! normal doubles, and beyond it the error names the real culprit.

use mesh_fem::io::{load, LoadOptions};
use mesh_fem::validate::{validate, Problem};
use mesh_fem::{assemble, AssemblyParams, MeshError};
use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

enum Expect {
    /// Loads, validates without errors and assembles to the operators of the unit
    /// tetrahedron scaled by `s` (checked against the closed form, see [`check_tet`]).
    Tet { s: f64 },
    /// Loads; the total area overflows: `Problem::AreaOverflow` and `MeshError::DegenerateMesh`.
    AreaOverflow,
    /// Loads; every face's area underflows: `ZeroAreaFace` for all four faces, and assembly
    /// names face 0.
    AreaUnderflow,
}

struct Case {
    file: &'static str,
    expect: Expect,
}

const CASES: &[Case] = &[
    Case {
        file: "tet_1.obj",
        expect: Expect::Tet { s: 1.0 },
    },
    Case {
        file: "tet_1e100.obj",
        expect: Expect::Tet { s: 1e100 },
    },
    Case {
        file: "tet_1e153.obj",
        expect: Expect::Tet { s: 1e153 },
    },
    Case {
        file: "tet_1e-150.obj",
        expect: Expect::Tet { s: 1e-150 },
    },
    Case {
        file: "tet_1e154.obj",
        expect: Expect::AreaOverflow,
    },
    Case {
        file: "tet_1e200.obj",
        expect: Expect::AreaOverflow,
    },
    Case {
        file: "tet_1e-160.obj",
        expect: Expect::AreaUnderflow,
    },
];

fn folder() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz")
}

fn close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() <= 1e-12 * want.abs(),
        "{what}: got {got:e}, want {want:e}"
    );
}

/// Closed form for the tetrahedron 0, s·e₁, s·e₂, s·e₃ (vertex 0 is the right-angled corner):
/// three right isosceles faces (cotangents 0, 1, 1) and one equilateral face of side s√2
/// (cotangents 1/√3). Hence L₀ⱼ = −1, Lᵢⱼ = −1/(2√3) between the other corners,
/// L₀₀ = 3, Lᵢᵢ = 1 + 1/√3 (independent of s), and the total area is s²·(3/2 + √3/2).
fn check_tet(file: &str, s: f64) {
    let (mesh, _) = load(&folder().join(file), &LoadOptions::default()).unwrap();
    let report = validate(&mesh);
    assert!(report.is_usable(), "{file}: {}", report.summary());
    let ops = assemble(&mesh, &AssemblyParams::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
    let r3 = 3f64.sqrt();
    let l = |i: usize, j: usize| -> f64 {
        match (i, j) {
            (0, 0) => 3.0,
            (i, j) if i == j => 1.0 + 1.0 / r3,
            (0, _) | (_, 0) => -1.0,
            _ => -1.0 / (2.0 * r3),
        }
    };
    let sym = ops.stiffness.symbolic();
    for j in 0..4 {
        let rows = &sym.row_idx()[sym.col_range(j)];
        assert_eq!(rows, &[0, 1, 2, 3], "{file}: column {j} pattern");
        for (k, p) in sym.col_range(j).enumerate() {
            close(ops.stiffness.val()[p], l(k, j), &format!("{file}: L[{k},{j}]"));
        }
    }
    let area = s * s * (1.5 + r3 / 2.0);
    close(ops.area(), area, &format!("{file}: 1ᵀB1"));
    close(ops.lumped_diagonal.iter().sum(), area, &format!("{file}: trace D"));
    // D₀₀ = (three right faces of area s²/2)/3.
    close(ops.lumped_diagonal[0], s * s / 2.0, &format!("{file}: D[0,0]"));
    assert!(ops.mass.val().iter().chain(&ops.lumped_diagonal).all(|v| v.is_finite()));
}

fn run(case: &Case) {
    let path = folder().join(case.file);
    match case.expect {
        Expect::Tet { s } => check_tet(case.file, s),
        Expect::AreaOverflow => {
            let (mesh, _) = load(&path, &LoadOptions::default()).unwrap();
            let report = validate(&mesh);
            assert_eq!(
                report.problems,
                vec![Problem::AreaOverflow { area: f64::INFINITY }],
                "{}",
                case.file
            );
            let e = assemble(&mesh, &AssemblyParams::default()).unwrap_err();
            assert!(
                matches!(e, MeshError::DegenerateMesh { area } if area == f64::INFINITY),
                "{}: {e:?}",
                case.file
            );
            assert!(e.to_string().contains("total area inf"), "{e}");
            assert!(matches!(
                report.into_result(),
                Err(MeshError::DegenerateMesh { area }) if area == f64::INFINITY
            ));
        }
        Expect::AreaUnderflow => {
            let (mesh, _) = load(&path, &LoadOptions::default()).unwrap();
            let report = validate(&mesh);
            let zero: Vec<usize> = report
                .problems
                .iter()
                .filter_map(|p| match p {
                    Problem::ZeroAreaFace { face, .. } => Some(*face),
                    _ => None,
                })
                .collect();
            assert_eq!(zero, vec![0, 1, 2, 3], "{}", case.file);
            let e = assemble(&mesh, &AssemblyParams::default()).unwrap_err();
            assert!(
                matches!(e, MeshError::DegenerateFace { face: 0, .. }),
                "{}: {e:?}",
                case.file
            );
        }
    }
}

#[test]
fn every_fuzz_regression_gives_its_exact_outcome_without_panicking() {
    let mut failures = Vec::new();
    for case in CASES {
        if let Err(panic) = catch_unwind(AssertUnwindSafe(|| run(case))) {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            failures.push(format!("{}: {msg}", case.file));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_file_in_the_fuzz_folder_is_in_the_table() {
    let on_disk: BTreeSet<String> = std::fs::read_dir(folder())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "make.py")
        .collect();
    let in_table: BTreeSet<String> = CASES.iter().map(|c| c.file.to_string()).collect();
    assert_eq!(on_disk, in_table);
}
