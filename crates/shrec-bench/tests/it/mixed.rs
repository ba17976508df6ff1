//! The generated mixed collection (`shrec_bench::mixed`, issue #42): its classes, and members
//! that are deterministic, in the vertex range and of their own triangulation.

use shrec_bench::mixed::{member, mixed_files_of, MIXED_CLASSES, MIXED_MEMBERS, MIXED_VERTICES};
use std::collections::BTreeSet;
use wfem_base::rng::SplitMix64;

#[test]
fn the_mixed_classes_are_twenty_distinct_corpus_objects() {
    let meshes = wfem_corpus::meshes_dir().expect("the mesh corpus is required (or set WFEM_MESHES)");
    let names: BTreeSet<&str> = MIXED_CLASSES.iter().map(|(n, _)| *n).collect();
    let files: BTreeSet<&str> = MIXED_CLASSES.iter().map(|(_, f)| *f).collect();
    assert_eq!((names.len(), files.len()), (20, 20));
    for (_, file) in MIXED_CLASSES {
        assert!(meshes.join(file).is_file(), "{file} is not in the corpus");
    }
    assert_eq!(MIXED_CLASSES.len() * MIXED_MEMBERS, 160);
}

#[test]
fn a_member_is_deterministic_by_its_generator_and_in_the_vertex_range() {
    let mesh = mesh_fem::generate::bumpy(3);
    let a = member(&mesh, &mut SplitMix64::new(7)).unwrap();
    assert_eq!(member(&mesh, &mut SplitMix64::new(7)).unwrap(), a);
    let b = member(&mesh, &mut SplitMix64::new(8)).unwrap();
    assert_ne!(a.positions(), b.positions());
    let (lo, hi) = MIXED_VERTICES;
    for m in [&a, &b] {
        // The remeshing reaches its target within a few vertices (QEM may stop short of it
        // only by refusing a fold).
        assert!(
            m.n_vertices() <= hi && m.n_vertices() + lo / 50 >= lo,
            "{}",
            m.n_vertices()
        );
        assert!(mesh_fem::assemble(m, &Default::default()).is_ok());
    }
}

#[test]
fn mixed_files_are_written_once_one_family_per_class_and_reproducible() {
    let meshes = wfem_corpus::meshes_dir().expect("the mesh corpus is required (or set WFEM_MESHES)");
    // Two of the smaller objects, two members each: the same generator as the 20 × 8.
    let classes = [MIXED_CLASSES[12], MIXED_CLASSES[10]];
    let (one, two) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let files = mixed_files_of(&meshes, one.path(), &classes, 2).unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["spot-0", "spot-1", "goathead-0", "goathead-1"]);
    let families: BTreeSet<&str> = files.iter().map(|f| f.family.as_str()).collect();
    assert_eq!(families, BTreeSet::from(["goathead", "spot"]));
    // Made again elsewhere: the same bytes; a file already there is reused, not remade.
    let again = mixed_files_of(&meshes, two.path(), &classes, 2).unwrap();
    for (a, b) in files.iter().zip(&again) {
        assert_eq!(
            std::fs::read(&a.path).unwrap(),
            std::fs::read(&b.path).unwrap(),
            "{}",
            a.name
        );
    }
    std::fs::write(&files[0].path, b"kept").unwrap();
    let reused = mixed_files_of(&meshes, one.path(), &classes, 2).unwrap();
    assert_eq!(std::fs::read(&reused[0].path).unwrap(), b"kept");
    // Two members of one class differ (their own stretch, bumps and triangulation).
    assert_ne!(
        std::fs::read(&again[0].path).unwrap(),
        std::fs::read(&again[1].path).unwrap()
    );
}
