//! `WFEM_MESHES` overrides the corpus folder. This file holds a single test because it sets a
//! process-wide environment variable (each integration test file is its own process).

use mesh_fem::MeshError;
use wfem_corpus::{all_mesh_files, mesh_path, meshes_dir};

#[test]
fn wfem_meshes_overrides_the_folder_and_the_walk_is_sorted_and_filtered() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    std::fs::create_dir_all(root.join("b/deeper")).unwrap();
    std::fs::create_dir_all(root.join("a")).unwrap();
    for f in [
        "b/deeper/z.OFF",
        "b/m.stl",
        "a/x.obj",
        "a/y.Ply",
        "a/readme.md",
        "a/x.obj.bak",
        "top.off",
    ] {
        std::fs::write(root.join(f), "").unwrap();
    }
    std::env::set_var("WFEM_MESHES", root);
    assert_eq!(meshes_dir().unwrap(), root);
    let rel: Vec<String> = all_mesh_files()
        .unwrap()
        .iter()
        .map(|p| p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/"))
        .collect();
    assert_eq!(rel, ["a/x.obj", "a/y.Ply", "b/deeper/z.OFF", "b/m.stl", "top.off"]);
    assert_eq!(mesh_path("a/x.obj").unwrap(), root.join("a/x.obj"));
    assert!(matches!(mesh_path("a/none.obj"), Err(MeshError::Io { .. })));

    std::env::set_var("WFEM_MESHES", root.join("missing"));
    match meshes_dir() {
        Err(MeshError::Io { path, source }) => {
            assert_eq!(path, root.join("missing"));
            assert!(source.to_string().contains("WFEM_MESHES"));
        }
        other => panic!("expected Io error, got {other:?}"),
    }
    assert!(all_mesh_files().is_err());
}
