//! Malformed and hostile mesh files (`tests/data/bad/`, written by `tests/data/bad/make.py`)
//! must give the exact typed outcome recorded in [`CASES`]: a [`MeshError`] from `load` whose
//! message names the culprit, or a loaded mesh with an exact validation verdict, assembly
//! outcome and (optionally) repair result. No file may panic, and every file of the folder
//! must appear in the table.

use mesh_fem::io::{load, LoadOptions};
use mesh_fem::validate::{repair, validate, RepairOptions};
use mesh_fem::{assemble, AssemblyParams, MeshError};
use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

/// Whether the error is the expected variant (with the expected fields).
type ErrIs = fn(&MeshError) -> bool;

/// What `validate(&mesh).into_result()` or `assemble` must return.
#[derive(Clone, Copy)]
enum Verdict {
    /// `Ok`.
    Ok,
    /// `Err` matching the predicate.
    Err(ErrIs),
}

/// The exact outcome for one file.
enum Expect {
    /// `load` fails with this error; its `Display` contains every listed fragment.
    Fails(ErrIs, &'static [&'static str]),
    /// `load` succeeds.
    Loads {
        /// Vertices and faces of the loaded mesh.
        counts: (usize, usize),
        /// `LoadReport::triangulated_polygons` and `LoadReport::welded_vertices`.
        triangulated: usize,
        welded: usize,
        /// `LoadReport::notes`, exactly.
        notes: &'static [&'static str],
        /// Every problem found by `validate`, as `Debug` strings, in order.
        problems: &'static [&'static str],
        /// `validate(&mesh).into_result()`.
        validation: Verdict,
        /// `assemble(&mesh, &AssemblyParams::default())`.
        assembly: Verdict,
    },
    /// `load` succeeds, and `repair` with these options succeeds with these results.
    Repairs {
        opts: RepairOptions,
        /// Vertices and faces after repair.
        counts: (usize, usize),
        vertex_map: &'static [Option<u32>],
        dropped_faces: &'static [usize],
        dropped_degenerate_faces: &'static [usize],
        dropped_vertices: usize,
        /// `validate(&repaired).into_result()` and `assemble(&repaired, …)`.
        validation: Verdict,
        assembly: Verdict,
    },
}

struct Case {
    file: &'static str,
    triangulate: bool,
    expect: Expect,
}

const fn fails(file: &'static str, is: ErrIs, names: &'static [&'static str]) -> Case {
    Case {
        file,
        triangulate: false,
        expect: Expect::Fails(is, names),
    }
}

const DROP_DEGENERATE: RepairOptions = RepairOptions {
    merge_duplicate_vertices: None,
    drop_degenerate_faces: true,
    drop_duplicate_faces: false,
    orient_faces: false,
    drop_unreferenced_vertices: false,
};
const DROP_DEGENERATE_AND_UNREFERENCED: RepairOptions = RepairOptions {
    drop_unreferenced_vertices: true,
    ..DROP_DEGENERATE
};
const DROP_UNREFERENCED: RepairOptions = RepairOptions {
    drop_degenerate_faces: false,
    ..DROP_DEGENERATE_AND_UNREFERENCED
};

/// A closed tetrahedron that loads, validates without a single problem and assembles.
const fn clean_tet(file: &'static str, welded: usize, notes: &'static [&'static str]) -> Case {
    Case {
        file,
        triangulate: false,
        expect: Expect::Loads {
            counts: (4, 4),
            triangulated: 0,
            welded,
            notes,
            problems: &[],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    }
}

fn parse_at(e: &MeshError, want_line: usize, fragment: &str) -> bool {
    matches!(e, MeshError::Parse { line, message, .. } if *line == want_line && message.contains(fragment))
}

const CASES: &[Case] = &[
    // ---------------------------------------------------------------- empty files
    fails(
        "empty.obj",
        |e| {
            matches!(
                e,
                MeshError::Empty {
                    n_vertices: 0,
                    n_faces: 0
                }
            )
        },
        &["0 vertices, 0 faces"],
    ),
    fails(
        "empty.off",
        |e| parse_at(e, 0, "end of file while reading the header"),
        &["empty.off:0:"],
    ),
    fails(
        "empty.ply",
        |e| parse_at(e, 0, "end of file while reading magic number"),
        &["empty.ply:0:"],
    ),
    fails(
        "empty.stl",
        |e| parse_at(e, 0, "at least 84 bytes, the file has 0"),
        &["empty.stl:0:"],
    ),
    // ---------------------------------------------------------------- garbage bytes
    // Binary data is not skipped record by record (which ended in a misleading "empty
    // mesh"): the first line whose keyword is not an OBJ keyword is named. Line 1 is the
    // garbage's leading lone CR.
    fails(
        "garbage.obj",
        |e| parse_at(e, 2, "is not an OBJ record keyword"),
        &["garbage.obj:2:", "\\xcf"],
    ),
    fails(
        "garbage.off",
        |e| parse_at(e, 2, "expected an OFF header"),
        &["garbage.off:2:"],
    ),
    fails(
        "garbage.ply",
        |e| parse_at(e, 0, "valid UTF-8"),
        &["garbage.ply:0:", "PLY header"],
    ),
    // The garbage's bytes 80..84 read as a triangle count of 2149563997: refused from the
    // file size, without allocating for the count.
    fails(
        "garbage.stl",
        |e| parse_at(e, 0, "declares 2149563997 triangles but holds only 8"),
        &["garbage.stl:0:"],
    ),
    // ---------------------------------------------------------------- no / unknown format
    fails(
        "unknown_extension.xyz",
        |e| matches!(e, MeshError::UnknownFormat { extension, .. } if extension == "xyz"),
        &["unknown_extension.xyz", "\"xyz\""],
    ),
    fails(
        "no_extension",
        |e| matches!(e, MeshError::UnknownFormat { extension, .. } if extension.is_empty()),
        &["no_extension"],
    ),
    // The generator itself lives in the folder; it is not a mesh.
    fails(
        "make.py",
        |e| matches!(e, MeshError::UnknownFormat { extension, .. } if extension == "py"),
        &["make.py", "\"py\""],
    ),
    // ---------------------------------------------------------------- OBJ
    fails(
        "obj_truncated.obj",
        |e| parse_at(e, 8, "face 3 has 2 corners"),
        &["obj_truncated.obj:8:"],
    ),
    fails(
        "obj_vertices_only.obj",
        |e| {
            matches!(
                e,
                MeshError::Empty {
                    n_vertices: 4,
                    n_faces: 0
                }
            )
        },
        &["4 vertices, 0 faces"],
    ),
    fails(
        "obj_bad_number.obj",
        |e| parse_at(e, 2, "\"zero\""),
        &["obj_bad_number.obj:2:"],
    ),
    fails(
        "obj_face_two_corners.obj",
        |e| parse_at(e, 8, "face 3 has 2 corners"),
        &["obj_face_two_corners.obj:8:"],
    ),
    fails(
        "obj_nan.obj",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 2, position } if position[0].is_nan() && position[1] == 1.0),
        &["vertex 2", "NaN"],
    ),
    fails(
        "obj_inf.obj",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 3, position } if position[2] == f64::INFINITY),
        &["vertex 3", "inf"],
    ),
    fails(
        "obj_index_out_of_range.obj",
        |e| {
            matches!(
                e,
                MeshError::IndexOutOfRange {
                    face: 3,
                    index: 4,
                    n_vertices: 4
                }
            )
        },
        &["face 3", "vertex 4", "4 vertices"],
    ),
    // OBJ counts from 1, so 0 is no vertex at all.
    fails(
        "obj_zero_index.obj",
        |e| parse_at(e, 5, "index 0"),
        &["obj_zero_index.obj:5:", "start at 1"],
    ),
    // `f -1 -2 -9` after 4 vertices: -9 points before the first vertex (reported as 4-9 = -5).
    fails(
        "obj_negative_before_first.obj",
        |e| {
            matches!(
                e,
                MeshError::NegativeIndex {
                    line: 7,
                    face: 2,
                    index: -5,
                    ..
                }
            )
        },
        &["obj_negative_before_first.obj:7:", "face 2", "-5"],
    ),
    fails(
        "obj_mixed_polygons.obj",
        |e| {
            matches!(
                e,
                MeshError::Polygon {
                    face: 1,
                    corners: 4,
                    ..
                }
            )
        },
        &["face 1 has 4 corners", "triangulate_polygons"],
    ),
    Case {
        file: "obj_mixed_polygons.obj",
        triangulate: true,
        expect: Expect::Loads {
            counts: (8, 5),
            triangulated: 2,
            welded: 0,
            notes: &[],
            problems: &["NonManifoldVertex { vertex: 1 }", "Boundary { loops: 2, edges: 9 }"],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    clean_tet("obj_crlf.obj", 0, &[]),
    // A UTF-8 byte order mark before the first record is skipped, not an unknown keyword.
    clean_tet("obj_utf8_bom.obj", 0, &[]),
    clean_tet("obj_negative_relative_ok.obj", 0, &[]),
    Case {
        file: "obj_repeated_vertex.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (4, 4),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "RepeatedIndex { face: 3, vertices: [1, 1, 3] }",
                "NonManifoldEdge { edge: [1, 3], n_faces: 3 }",
                "Boundary { loops: 1, edges: 2 }",
            ],
            validation: Verdict::Err(
                |e| matches!(e, MeshError::RepeatedIndex { face: 3, vertices } if vertices == &[1, 1, 3]),
            ),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 3,
                        vertices: [1, 1, 3]
                    }
                )
            }),
        },
    },
    Case {
        file: "obj_zero_area_face.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 5),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "ZeroAreaFace { face: 4, vertices: [0, 4, 1] }",
                "NonManifoldEdge { edge: [0, 1], n_faces: 3 }",
                "Boundary { loops: 1, edges: 2 }",
            ],
            validation: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 4,
                        vertices: [0, 4, 1]
                    }
                )
            }),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 4,
                        vertices: [0, 4, 1]
                    }
                )
            }),
        },
    },
    // Dropping the zero-area face leaves its midpoint vertex 4 unreferenced; dropping that
    // too gives back the clean tetrahedron.
    Case {
        file: "obj_zero_area_face.obj",
        triangulate: false,
        expect: Expect::Repairs {
            opts: DROP_DEGENERATE_AND_UNREFERENCED,
            counts: (4, 4),
            vertex_map: &[Some(0), Some(1), Some(2), Some(3), None],
            dropped_faces: &[4],
            dropped_degenerate_faces: &[4],
            dropped_vertices: 1,
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // A needle with area/ℓ² = 5e-10: thin but above the 1e-14 threshold, so it is kept.
    Case {
        file: "obj_needle_face.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 5),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "NonManifoldEdge { edge: [0, 1], n_faces: 3 }",
                // Issue #16: the needle itself is now reported (a warning naming the face).
                "NeedleFace { face: 4, vertices: [0, 1, 4], cotangent: 353553390.59327376 }",
                "Boundary { loops: 1, edges: 2 }",
            ],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // A needle 1e-16 off its edge: numerically zero area.
    Case {
        file: "obj_needle_degenerate.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 5),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "ZeroAreaFace { face: 4, vertices: [0, 1, 4] }",
                "NonManifoldEdge { edge: [0, 1], n_faces: 3 }",
                "Boundary { loops: 1, edges: 2 }",
            ],
            validation: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 4,
                        vertices: [0, 1, 4]
                    }
                )
            }),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 4,
                        vertices: [0, 1, 4]
                    }
                )
            }),
        },
    },
    Case {
        file: "obj_needle_degenerate.obj",
        triangulate: false,
        expect: Expect::Repairs {
            opts: DROP_DEGENERATE,
            counts: (5, 4),
            vertex_map: &[Some(0), Some(1), Some(2), Some(3), Some(4)],
            dropped_faces: &[4],
            dropped_degenerate_faces: &[4],
            dropped_vertices: 0,
            // Dropping only the needle leaves its apex (vertex 4) unreferenced.
            validation: Verdict::Err(|e| matches!(e, MeshError::UnreferencedVertex { vertex: 4 })),
            assembly: Verdict::Err(|e| matches!(e, MeshError::UnreferencedVertex { vertex: 4 })),
        },
    },
    Case {
        file: "obj_isolated_vertex.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 4),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &["UnreferencedVertex { vertex: 2 }"],
            validation: Verdict::Err(|e| matches!(e, MeshError::UnreferencedVertex { vertex: 2 })),
            assembly: Verdict::Err(|e| matches!(e, MeshError::UnreferencedVertex { vertex: 2 })),
        },
    },
    Case {
        file: "obj_isolated_vertex.obj",
        triangulate: false,
        expect: Expect::Repairs {
            opts: DROP_UNREFERENCED,
            counts: (4, 4),
            vertex_map: &[Some(0), Some(1), None, Some(2), Some(3)],
            dropped_faces: &[],
            dropped_degenerate_faces: &[],
            dropped_vertices: 1,
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // Three triangles on the edge (0, 1): loads and assembles, with a non-manifold warning.
    Case {
        file: "obj_nonmanifold_fan.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 3),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "NonManifoldEdge { edge: [0, 1], n_faces: 3 }",
                "Boundary { loops: 1, edges: 6 }",
            ],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    Case {
        file: "obj_collinear.obj",
        triangulate: false,
        expect: Expect::Loads {
            counts: (4, 2),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "ZeroAreaFace { face: 0, vertices: [0, 1, 2] }",
                "ZeroAreaFace { face: 1, vertices: [1, 2, 3] }",
                "InconsistentOrientation { edge: [1, 2] }",
                "Boundary { loops: 1, edges: 4 }",
            ],
            validation: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 0,
                        vertices: [0, 1, 2]
                    }
                )
            }),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 0,
                        vertices: [0, 1, 2]
                    }
                )
            }),
        },
    },
    // ---------------------------------------------------------------- OFF
    fails(
        "off_truncated.off",
        |e| parse_at(e, 10, "face 3 declares 3 corners but lists 0"),
        &["off_truncated.off:10:"],
    ),
    fails(
        "off_header_only.off",
        |e| parse_at(e, 1, "while reading the element counts"),
        &["off_header_only.off:1:"],
    ),
    fails(
        "off_counts_too_large.off",
        |e| parse_at(e, 10, "reading face 2 of 4"),
        &["off_counts_too_large.off:10:"],
    ),
    // Declares 999999999 vertices and faces but holds 3: refused at the end of the data.
    fails(
        "off_huge_counts.off",
        |e| parse_at(e, 6, "vertex 4 of 999999999"),
        &["off_huge_counts.off:6:"],
    ),
    fails(
        "off_binary.off",
        |e| parse_at(e, 1, "binary OFF is not supported"),
        &["off_binary.off:1:"],
    ),
    fails(
        "off_negative_index.off",
        |e| {
            matches!(
                e,
                MeshError::NegativeIndex {
                    line: 10,
                    face: 3,
                    index: -1,
                    ..
                }
            )
        },
        &["off_negative_index.off:10:", "face 3", "-1"],
    ),
    fails(
        "off_index_out_of_range.off",
        |e| {
            matches!(
                e,
                MeshError::IndexOutOfRange {
                    face: 1,
                    index: 4,
                    n_vertices: 4
                }
            )
        },
        &["face 1", "vertex 4"],
    ),
    fails(
        "off_inf.off",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 1, position } if position[0] == f64::NEG_INFINITY),
        &["vertex 1", "-inf"],
    ),
    fails(
        "off_nan.off",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 3, position } if position[2].is_nan()),
        &["vertex 3", "NaN"],
    ),
    fails(
        "off_mixed_polygons.off",
        |e| {
            matches!(
                e,
                MeshError::Polygon {
                    face: 1,
                    corners: 4,
                    ..
                }
            )
        },
        &["off_mixed_polygons.off", "face 1 has 4 corners"],
    ),
    Case {
        file: "off_mixed_polygons.off",
        triangulate: true,
        expect: Expect::Loads {
            counts: (6, 3),
            triangulated: 1,
            welded: 0,
            notes: &[],
            problems: &["NonManifoldVertex { vertex: 1 }", "Boundary { loops: 2, edges: 7 }"],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // Fewer faces declared than present: the extra faces are ignored, with a note.
    Case {
        file: "off_counts_too_small.off",
        triangulate: false,
        expect: Expect::Loads {
            counts: (4, 2),
            triangulated: 0,
            welded: 0,
            notes: &["ignored content after the declared faces"],
            problems: &["Boundary { loops: 1, edges: 4 }"],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    clean_tet("off_crlf.off", 0, &[]),
    // The OFF magic is optional (as in libigl and other readers).
    clean_tet("off_no_magic.off", 0, &[]),
    Case {
        file: "off_repeated_vertex.off",
        triangulate: false,
        expect: Expect::Loads {
            counts: (4, 4),
            triangulated: 0,
            welded: 0,
            notes: &[],
            problems: &[
                "RepeatedIndex { face: 0, vertices: [0, 0, 1] }",
                "NonManifoldEdge { edge: [0, 1], n_faces: 3 }",
                "Boundary { loops: 1, edges: 2 }",
            ],
            validation: Verdict::Err(
                |e| matches!(e, MeshError::RepeatedIndex { face: 0, vertices } if vertices == &[0, 0, 1]),
            ),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 0,
                        vertices: [0, 0, 1]
                    }
                )
            }),
        },
    },
    // Dropping the repeated-index face leaves an open tetrahedron (3 faces, all 4 vertices used).
    Case {
        file: "off_repeated_vertex.off",
        triangulate: false,
        expect: Expect::Repairs {
            opts: DROP_DEGENERATE_AND_UNREFERENCED,
            counts: (4, 3),
            vertex_map: &[Some(0), Some(1), Some(2), Some(3)],
            dropped_faces: &[0],
            dropped_degenerate_faces: &[0],
            dropped_vertices: 0,
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // ---------------------------------------------------------------- PLY
    fails(
        "ply_ascii_truncated.ply",
        |e| parse_at(e, 17, "element 'face' (expected 4, got 3)"),
        &["ply_ascii_truncated.ply:17:"],
    ),
    fails(
        "ply_binary_truncated.ply",
        |e| parse_at(e, 0, "binary element 'face' (expected 4, got 3)"),
        &["ply_binary_truncated.ply:0:"],
    ),
    fails(
        "ply_header_truncated.ply",
        |e| parse_at(e, 5, "missing 'end_header'"),
        &["ply_header_truncated.ply:5:"],
    ),
    // One vertex too many declared: the first face line is read as vertex 4, so the faces run short.
    fails(
        "ply_ascii_counts_too_large.ply",
        |e| parse_at(e, 18, "element 'face' (expected 4, got 3)"),
        &["ply_ascii_counts_too_large.ply:18:"],
    ),
    fails(
        "ply_ascii_huge_vertex_count.ply",
        |e| parse_at(e, 18, "element 'vertex' (expected 4000000000, got 8)"),
        &["ply_ascii_huge_vertex_count.ply:18:"],
    ),
    fails(
        "ply_binary_huge_vertex_count.ply",
        |e| parse_at(e, 0, "binary element 'vertex' (expected 4000000000, got 8)"),
        &["ply_binary_huge_vertex_count.ply:0:"],
    ),
    fails(
        "ply_binary_huge_face_count.ply",
        |e| parse_at(e, 0, "binary element 'face' (expected 4294967295, got 4)"),
        &["ply_binary_huge_face_count.ply:0:"],
    ),
    fails(
        "ply_binary_negative_index.ply",
        |e| {
            matches!(
                e,
                MeshError::NegativeIndex {
                    line: 0,
                    face: 2,
                    index: -7,
                    ..
                }
            )
        },
        &["ply_binary_negative_index.ply:0:", "face 2", "-7"],
    ),
    fails(
        "ply_binary_index_out_of_range.ply",
        |e| {
            matches!(
                e,
                MeshError::IndexOutOfRange {
                    face: 3,
                    index: 1000,
                    n_vertices: 4
                }
            )
        },
        &["face 3", "vertex 1000"],
    ),
    fails(
        "ply_binary_nan.ply",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 1, position } if position[0].is_nan()),
        &["vertex 1", "NaN"],
    ),
    fails(
        "ply_ascii_mixed_polygons.ply",
        |e| {
            matches!(
                e,
                MeshError::Polygon {
                    face: 1,
                    corners: 4,
                    ..
                }
            )
        },
        &["ply_ascii_mixed_polygons.ply", "face 1 has 4 corners"],
    ),
    Case {
        file: "ply_ascii_mixed_polygons.ply",
        triangulate: true,
        expect: Expect::Loads {
            counts: (6, 3),
            triangulated: 1,
            welded: 0,
            notes: &["ASCII PLY"],
            problems: &["NonManifoldVertex { vertex: 1 }", "Boundary { loops: 2, edges: 7 }"],
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    fails(
        "ply_no_xyz.ply",
        |e| parse_at(e, 0, "no property \"x\""),
        &["ply_no_xyz.ply:0:", "'vertex'"],
    ),
    fails(
        "ply_unknown_format.ply",
        |e| parse_at(e, 2, "binary_middle_endian"),
        &["ply_unknown_format.ply:2:"],
    ),
    fails(
        "ply_bad_magic.ply",
        |e| parse_at(e, 1, "magic number 'ply'"),
        &["ply_bad_magic.ply:1:"],
    ),
    // One face fewer declared than present: the extra face line (17: 9 header lines, 4
    // vertices, 3 declared faces) is an error naming the line, not silently dropped.
    fails(
        "ply_ascii_counts_too_small.ply",
        |e| parse_at(e, 17, "data after the last declared element"),
        &["ply_ascii_counts_too_small.ply:17:", "too few elements"],
    ),
    clean_tet("ply_ascii_crlf.ply", 0, &["ASCII PLY"]),
    // CRLF header lines followed by binary data.
    clean_tet("ply_binary_crlf_header.ply", 0, &["binary little-endian PLY"]),
    // ---------------------------------------------------------------- STL
    fails(
        "stl_ascii_truncated.stl",
        |e| parse_at(e, 24, "end of file inside a facet"),
        &["stl_ascii_truncated.stl:24:"],
    ),
    fails(
        "stl_binary_truncated.stl",
        |e| parse_at(e, 0, "declares 4 triangles but holds only 3 (264 bytes)"),
        &["stl_binary_truncated.stl:0:"],
    ),
    // Count 2^32 − 1 with 4 triangles of data: refused from the file size, no allocation.
    fails(
        "stl_binary_huge_count.stl",
        |e| parse_at(e, 0, "declares 4294967295 triangles but holds only 4 (284 bytes)"),
        &["stl_binary_huge_count.stl:0:"],
    ),
    fails(
        "stl_binary_header_only.stl",
        |e| {
            matches!(
                e,
                MeshError::Empty {
                    n_vertices: 0,
                    n_faces: 0
                }
            )
        },
        &["0 vertices, 0 faces"],
    ),
    fails(
        "stl_ascii_nan.stl",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 2, position } if position[1].is_nan()),
        &["vertex 2", "NaN"],
    ),
    fails(
        "stl_binary_inf.stl",
        |e| matches!(e, MeshError::NonFiniteCoordinate { vertex: 1, position } if position[0] == f64::INFINITY),
        &["vertex 1", "inf"],
    ),
    // 12 corners weld into 4 vertices (8 welded).
    clean_tet("stl_ascii_crlf.stl", 8, &["ASCII STL"]),
    // A tetrahedron plus a triangle whose three corners are one point: welding turns it into
    // the face [4, 4, 4].
    Case {
        file: "stl_binary_point_triangle.stl",
        triangulate: false,
        expect: Expect::Loads {
            counts: (5, 5),
            triangulated: 0,
            welded: 10,
            notes: &["binary STL"],
            problems: &[
                "RepeatedIndex { face: 4, vertices: [4, 4, 4] }",
                "SeveralComponents { count: 2 }",
            ],
            validation: Verdict::Err(
                |e| matches!(e, MeshError::RepeatedIndex { face: 4, vertices } if vertices == &[4, 4, 4]),
            ),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 4,
                        vertices: [4, 4, 4]
                    }
                )
            }),
        },
    },
    Case {
        file: "stl_binary_point_triangle.stl",
        triangulate: false,
        expect: Expect::Repairs {
            opts: DROP_DEGENERATE_AND_UNREFERENCED,
            counts: (4, 4),
            vertex_map: &[Some(0), Some(1), Some(2), Some(3), None],
            dropped_faces: &[4],
            dropped_degenerate_faces: &[4],
            dropped_vertices: 1,
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
    // ---------------------------------------------------------------- more hostile cases
    // A 32-bit list length of 2^31 − 1 corners with 3 present: refused, no giant allocation.
    fails(
        "ply_binary_huge_list_count.ply",
        |e| parse_at(e, 0, "binary element 'face' (expected 1, got 0)"),
        &["ply_binary_huge_list_count.ply:0:"],
    ),
    fails(
        "ply_binary_two_corner_face.ply",
        |e| parse_at(e, 0, "face 3 has 2 corners"),
        &["ply_binary_two_corner_face.ply:0:"],
    ),
    // `nan` is no PLY number: the ASCII PLY grammar refuses the line.
    fails(
        "ply_ascii_nan.ply",
        |e| parse_at(e, 12, "Couldn't read element line"),
        &["ply_ascii_nan.ply:12:", "0 nan 0"],
    ),
    // Big-endian doubles with unsigned indices: the binary baseline that must load.
    clean_tet("ply_binary_big_endian.ply", 0, &["binary big-endian PLY"]),
    fails(
        "off_huge_corner_count.off",
        |e| parse_at(e, 10, "face 3 declares 1000000000 corners but lists 3"),
        &["off_huge_corner_count.off:10:"],
    ),
    fails(
        "off_negative_counts.off",
        |e| parse_at(e, 2, "vertex count \"-1\""),
        &["off_negative_counts.off:2:"],
    ),
    fails(
        "obj_index_overflow.obj",
        |e| parse_at(e, 8, "\"99999999999999999999\" as a vertex index"),
        &["obj_index_overflow.obj:8:"],
    ),
    // A binary STL whose header starts with "solid" (as many exporters write it) is still binary.
    clean_tet("stl_binary_starts_with_solid.stl", 8, &["binary STL"]),
    // A quad that repeats a corner: refused by default; fan triangulation makes the
    // repeated-index triangle [1, 2, 2] (which counts edge 1–2 twice), and dropping it gives
    // back the closed tetrahedron.
    fails(
        "obj_polygon_repeated_corner.obj",
        |e| {
            matches!(
                e,
                MeshError::Polygon {
                    face: 3,
                    corners: 4,
                    ..
                }
            )
        },
        &["obj_polygon_repeated_corner.obj", "face 3 has 4 corners"],
    ),
    Case {
        file: "obj_polygon_repeated_corner.obj",
        triangulate: true,
        expect: Expect::Loads {
            counts: (4, 5),
            triangulated: 1,
            welded: 0,
            notes: &[],
            problems: &[
                "RepeatedIndex { face: 3, vertices: [1, 2, 2] }",
                "NonManifoldEdge { edge: [1, 2], n_faces: 4 }",
            ],
            validation: Verdict::Err(
                |e| matches!(e, MeshError::RepeatedIndex { face: 3, vertices } if vertices == &[1, 2, 2]),
            ),
            assembly: Verdict::Err(|e| {
                matches!(
                    e,
                    MeshError::DegenerateFace {
                        face: 3,
                        vertices: [1, 2, 2]
                    }
                )
            }),
        },
    },
    Case {
        file: "obj_polygon_repeated_corner.obj",
        triangulate: true,
        expect: Expect::Repairs {
            opts: DROP_DEGENERATE,
            counts: (4, 4),
            vertex_map: &[Some(0), Some(1), Some(2), Some(3)],
            dropped_faces: &[3],
            dropped_degenerate_faces: &[3],
            dropped_vertices: 0,
            validation: Verdict::Ok,
            assembly: Verdict::Ok,
        },
    },
];

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

fn check_verdict(what: &str, got: Result<(), MeshError>, want: Verdict) -> Result<(), String> {
    match (got, want) {
        (Ok(()), Verdict::Ok) => Ok(()),
        (Err(e), Verdict::Err(is)) if is(&e) => Ok(()),
        (Err(e), Verdict::Err(_)) => Err(format!("{what}: unexpected error {e:?}")),
        (Err(e), Verdict::Ok) => Err(format!("{what}: expected Ok, got {e:?}")),
        (Ok(()), Verdict::Err(_)) => Err(format!("{what}: expected an error, got Ok")),
    }
}

/// Runs one case; `Err` describes the mismatch.
fn run(case: &Case) -> Result<(), String> {
    let path = bad_dir().join(case.file);
    let loaded = load(&path, &LoadOptions::with_triangulation(case.triangulate));
    match (&case.expect, loaded) {
        (Expect::Fails(is, names), Err(e)) => {
            if !is(&e) {
                return Err(format!("wrong error {e:?}"));
            }
            let msg = e.to_string();
            for name in *names {
                if !msg.contains(name) {
                    return Err(format!("message {msg:?} does not name {name:?}"));
                }
            }
            Ok(())
        }
        (Expect::Fails(..), Ok((mesh, _))) => Err(format!(
            "expected a load error, but it loaded {} vertices and {} faces",
            mesh.n_vertices(),
            mesh.faces().len()
        )),
        (_, Err(e)) => Err(format!("expected the file to load, got {e:?}")),
        (
            Expect::Loads {
                counts,
                triangulated,
                welded,
                notes,
                problems,
                validation,
                assembly,
            },
            Ok((mesh, report)),
        ) => {
            let got_counts = (mesh.n_vertices(), mesh.faces().len());
            if got_counts != *counts {
                return Err(format!("counts {got_counts:?}, expected {counts:?}"));
            }
            if (report.triangulated_polygons, report.welded_vertices) != (*triangulated, *welded) {
                return Err(format!(
                    "report {report:?}: expected {triangulated} triangulated, {welded} welded"
                ));
            }
            if report.notes != *notes {
                return Err(format!("notes {:?}, expected {notes:?}", report.notes));
            }
            let got: Vec<String> = validate(&mesh).problems.iter().map(|p| format!("{p:?}")).collect();
            if got != *problems {
                return Err(format!("problems {got:?}, expected {problems:?}"));
            }
            check_verdict("validation", validate(&mesh).into_result().map(|_| ()), *validation)?;
            check_verdict(
                "assembly",
                assemble(&mesh, &AssemblyParams::default()).map(|_| ()),
                *assembly,
            )
        }
        (
            Expect::Repairs {
                opts,
                counts,
                vertex_map,
                dropped_faces,
                dropped_degenerate_faces,
                dropped_vertices,
                validation,
                assembly,
            },
            Ok((mesh, _)),
        ) => {
            let (fixed, rep) = repair(&mesh, opts).map_err(|e| format!("repair failed: {e:?}"))?;
            let got_counts = (fixed.n_vertices(), fixed.faces().len());
            if got_counts != *counts {
                return Err(format!("repaired counts {got_counts:?}, expected {counts:?}"));
            }
            if rep.vertex_map != *vertex_map
                || rep.dropped_faces != *dropped_faces
                || rep.dropped_degenerate_faces != *dropped_degenerate_faces
                || rep.dropped_vertices != *dropped_vertices
            {
                return Err(format!("repair report {rep:?}"));
            }
            // Every kept face is an old face renumbered through the vertex map.
            let mut kept = 0;
            for (old, new) in rep.face_map.iter().enumerate() {
                if let Some(new) = new {
                    let renumbered =
                        mesh.faces()[old].map(|v| vertex_map[v as usize].expect("kept face uses kept vertex"));
                    if fixed.faces()[*new as usize] != renumbered {
                        return Err(format!("face {old} was not renumbered through the vertex map"));
                    }
                    kept += 1;
                }
            }
            if kept != counts.1 {
                return Err(format!("face map keeps {kept} faces"));
            }
            check_verdict(
                "validation after repair",
                validate(&fixed).into_result().map(|_| ()),
                *validation,
            )?;
            check_verdict(
                "assembly after repair",
                assemble(&fixed, &AssemblyParams::default()).map(|_| ()),
                *assembly,
            )
        }
    }
}

#[test]
fn every_file_in_the_bad_folder_is_in_the_table() {
    let on_disk: BTreeSet<String> = std::fs::read_dir(bad_dir())
        .expect("tests/data/bad exists")
        .map(|e| {
            e.expect("readable entry")
                .file_name()
                .into_string()
                .expect("UTF-8 name")
        })
        .collect();
    let in_table: BTreeSet<String> = CASES.iter().map(|c| c.file.to_string()).collect();
    let untested: Vec<_> = on_disk.difference(&in_table).collect();
    let missing: Vec<_> = in_table.difference(&on_disk).collect();
    assert!(untested.is_empty(), "files with no entry in CASES: {untested:?}");
    assert!(missing.is_empty(), "CASES names files that do not exist: {missing:?}");
    assert!(on_disk.len() >= 40, "the corpus has only {} files", on_disk.len());
}

#[test]
fn every_bad_file_gives_its_exact_outcome_without_panicking() {
    let mut panicked = Vec::new();
    let mut wrong = Vec::new();
    for case in CASES {
        match catch_unwind(AssertUnwindSafe(|| run(case))) {
            Err(_) => panicked.push(case.file),
            Ok(Err(why)) => wrong.push(format!("{} (triangulate={}): {why}", case.file, case.triangulate)),
            Ok(Ok(())) => {}
        }
    }
    assert!(panicked.is_empty(), "panicked on: {panicked:?}");
    assert!(wrong.is_empty(), "wrong outcomes:\n{}", wrong.join("\n"));
}
