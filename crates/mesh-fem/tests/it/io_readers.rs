//! Reader tests on small in-memory files: every format, its variants and its failure modes.

use mesh_fem::io::{load, load_bytes, read_obj, read_off, read_ply, read_stl, LoadOptions, MeshFormat};
use mesh_fem::MeshError;
use std::path::Path;

fn name() -> &'static Path {
    Path::new("<test>")
}

fn strict() -> LoadOptions {
    LoadOptions::default()
}

fn tri() -> LoadOptions {
    LoadOptions::with_triangulation(true)
}

/// The unit square split into two triangles, as positions and faces.
const SQUARE_POSITIONS: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];

fn expect_parse_line(r: Result<impl std::fmt::Debug, MeshError>, want_line: usize) -> String {
    match r {
        Err(MeshError::Parse { line, message, .. }) => {
            assert_eq!(line, want_line, "wrong line for error {message:?}");
            message
        }
        other => panic!("expected a parse error at line {want_line}, got {other:?}"),
    }
}

// ---------------------------------------------------------------- OBJ

#[test]
fn obj_reads_all_corner_forms_comments_and_crlf() {
    let src = "# a comment\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n\r\nvt 0 0\r\nvt 1 0\r\nvt 1 1\r\n\
               vn 0 0 1\r\nf 1/1/1 2/2/1 3/3/1\r\nf 1//1 3//1 4//1 # trailing comment\r\nf 1/1 2/2 4/3\r\nf 2 3 4\r\n";
    let (mesh, report) = read_obj(src.as_bytes(), name(), &strict()).unwrap();
    assert_eq!(mesh.positions(), &SQUARE_POSITIONS);
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3], [0, 1, 3], [1, 2, 3]]);
    assert_eq!(report.format, MeshFormat::Obj);
    assert_eq!(report.welded_vertices, 0);
    assert_eq!(report.triangulated_polygons, 0);
}

#[test]
fn obj_groups_share_vertices_and_file_order_is_kept() {
    // The second group uses vertices 3 and 4 first; the file order must survive and the two
    // groups must share the diagonal (no duplicated vertices), unreferenced vertex 5 stays.
    let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 9 9 9\no first\ng a\nf 1 2 3\no second\ng b\nf 4 1 3\n";
    let (mesh, report) = read_obj(src.as_bytes(), name(), &strict()).unwrap();
    assert_eq!(mesh.n_vertices(), 5);
    assert_eq!(&mesh.positions()[..4], &SQUARE_POSITIONS);
    assert_eq!(mesh.faces(), &[[0, 1, 2], [3, 0, 2]]);
    assert_eq!(report.welded_vertices, 0);
}

#[test]
fn obj_negative_indices_count_back_from_the_last_vertex() {
    let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf -4 -2 -1\n";
    let (mesh, _) = read_obj(src.as_bytes(), name(), &strict()).unwrap();
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
}

#[test]
fn obj_polygons_fail_by_default_and_fan_on_request() {
    let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3\nf 1 3 5 4\n";
    match read_obj(src.as_bytes(), name(), &strict()) {
        Err(MeshError::Polygon { face, corners, .. }) => assert_eq!((face, corners), (1, 4)),
        other => panic!("expected Polygon, got {other:?}"),
    }
    let (mesh, report) = read_obj(src.as_bytes(), name(), &tri()).unwrap();
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 4], [0, 4, 3]]);
    assert_eq!(report.triangulated_polygons, 1);
}

#[test]
fn obj_bad_data_gives_typed_errors_with_lines() {
    let m = expect_parse_line(read_obj(b"v 0 0 0\nv 1 x 0\n", name(), &strict()), 2);
    assert!(m.contains("\"x\""), "{m}");
    expect_parse_line(read_obj(b"v 0 0\n", name(), &strict()), 1);
    expect_parse_line(read_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", name(), &strict()), 4);
    expect_parse_line(
        read_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 a\n", name(), &strict()),
        5,
    );
    expect_parse_line(read_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", name(), &strict()), 4);
    match read_obj(b"v 0 0 0\nv 1 0 0\nf 1 2 -3\n", name(), &strict()) {
        Err(MeshError::NegativeIndex { line, face, index, .. }) => {
            assert_eq!((line, face, index), (3, 0, -1))
        }
        other => panic!("expected NegativeIndex, got {other:?}"),
    }
    match read_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n", name(), &strict()) {
        Err(MeshError::IndexOutOfRange {
            face,
            index,
            n_vertices,
        }) => {
            assert_eq!((face, index, n_vertices), (1, 6, 3))
        }
        other => panic!("expected IndexOutOfRange, got {other:?}"),
    }
    match read_obj(b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", name(), &strict()) {
        Err(MeshError::NonFiniteCoordinate { vertex, .. }) => assert_eq!(vertex, 1),
        other => panic!("expected NonFiniteCoordinate, got {other:?}"),
    }
    assert!(matches!(
        read_obj(b"# nothing\n", name(), &strict()),
        Err(MeshError::Empty { .. })
    ));
}

// ---------------------------------------------------------------- OFF

#[test]
fn off_with_comments_blank_lines_edges_and_colors() {
    let src = "OFF # header comment\n# comment line\n\n4 2 5\n0 0 0\n1 0 0 # c\n1 1 0\n\n0 1 0\n3 0 1 2 255 0 0\n3 0 2 3 0.1 0.2 0.3 1.0\n";
    let (mesh, report) = read_off(src.as_bytes(), name(), &strict()).unwrap();
    assert_eq!(mesh.positions(), &SQUARE_POSITIONS);
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
    assert_eq!(report.format, MeshFormat::Off);
}

#[test]
fn off_header_variants_and_crlf() {
    for header in [
        "OFF\r\n4 2 0",
        "OFF 4 2 0",
        "COFF\r\n4 2 0",
        "NOFF\r\n4 2 0",
        "CNOFF\r\n4 2 0",
        "STOFF\n4 2 0",
        "4 2 0",
    ] {
        let extra = if header.contains("C") || header.contains("N") || header.contains("ST") {
            " 0.5 0.5 0.5 1"
        } else {
            ""
        };
        let mut src = format!("{header}\r\n");
        for p in SQUARE_POSITIONS {
            src.push_str(&format!("{} {} {}{extra}\r\n", p[0], p[1], p[2]));
        }
        src.push_str("3 0 1 2\r\n3 0 2 3\r\n");
        let (mesh, _) =
            read_off(src.as_bytes(), name(), &strict()).unwrap_or_else(|e| panic!("header {header:?}: {e}"));
        assert_eq!(mesh.positions(), &SQUARE_POSITIONS, "header {header:?}");
        assert_eq!(mesh.n_faces(), 2);
    }
}

#[test]
fn off_polygons_and_errors() {
    let quad = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    assert!(matches!(
        read_off(quad.as_bytes(), name(), &strict()),
        Err(MeshError::Polygon {
            face: 0,
            corners: 4,
            ..
        })
    ));
    let (mesh, report) = read_off(quad.as_bytes(), name(), &tri()).unwrap();
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
    assert_eq!(report.triangulated_polygons, 1);

    // Truncated: the second face is missing (error at the last line read).
    expect_parse_line(
        read_off(b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", name(), &strict()),
        6,
    );
    // Garbage coordinate, short face, garbage header.
    expect_parse_line(
        read_off(b"OFF\n3 1 0\n0 0 0\n1 zz 0\n0 1 0\n3 0 1 2\n", name(), &strict()),
        4,
    );
    expect_parse_line(
        read_off(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", name(), &strict()),
        6,
    );
    expect_parse_line(read_off(b"PLY\n3 1 0\n", name(), &strict()), 1);
    let m = expect_parse_line(read_off(b"4OFF\n3 1 0\n", name(), &strict()), 1);
    assert!(m.contains("not a 3-D OFF variant"), "{m}");
    expect_parse_line(read_off(b"OFF BINARY\n", name(), &strict()), 1);
    expect_parse_line(read_off(b"OFF\n-3 1 0\n", name(), &strict()), 2);
    match read_off(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", name(), &strict()) {
        Err(MeshError::NegativeIndex { line, face, index, .. }) => {
            assert_eq!((line, face, index), (6, 0, -1))
        }
        other => panic!("expected NegativeIndex, got {other:?}"),
    }
    assert!(matches!(
        read_off(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", name(), &strict()),
        Err(MeshError::IndexOutOfRange {
            face: 0,
            index: 3,
            n_vertices: 3
        })
    ));
    assert!(matches!(
        read_off(b"OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n", name(), &strict()),
        Err(MeshError::NonFiniteCoordinate { vertex: 1, .. })
    ));
}

#[test]
fn off_huge_declared_counts_do_not_allocate_up_front() {
    // 2^62 vertices declared in a 30-byte file: must fail cleanly at end of file rather than
    // try to reserve exabytes.
    let src = b"OFF\n4611686018427387904 4611686018427387904 0\n0 0 0\n";
    expect_parse_line(read_off(src, name(), &strict()), 3);
}

// ---------------------------------------------------------------- PLY

#[test]
fn ply_huge_declared_counts_fail_cleanly() {
    for format in ["ascii", "binary_little_endian"] {
        let src = format!(
            "ply\nformat {format} 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n\
             element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n"
        );
        assert!(
            matches!(
                read_ply(src.as_bytes(), name(), &strict()),
                Err(MeshError::Parse { .. })
            ),
            "{format}"
        );
    }
}

fn ascii_ply(face_prop: &str, crlf: bool) -> Vec<u8> {
    let mut s = String::from("ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n");
    s.push_str(&format!("element face 2\nproperty {face_prop}\nend_header\n"));
    for p in SQUARE_POSITIONS {
        s.push_str(&format!("{} {} {} 200\n", p[0], p[1], p[2]));
    }
    s.push_str("3 0 1 2\n3 0 2 3\n");
    if crlf {
        s = s.replace('\n', "\r\n");
    }
    s.into_bytes()
}

#[test]
fn ply_ascii_index_names_and_list_types() {
    for prop in [
        "list uchar int vertex_indices",
        "list uchar uint vertex_index",
        "list int int vertex_indices",
        "list uchar uchar vertex_indices",
        "list ushort short vertex_index",
    ] {
        for crlf in [false, true] {
            let (mesh, report) = read_ply(&ascii_ply(prop, crlf), name(), &strict())
                .unwrap_or_else(|e| panic!("{prop} crlf={crlf}: {e}"));
            assert_eq!(mesh.positions(), &SQUARE_POSITIONS);
            assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
            assert_eq!(report.format, MeshFormat::Ply);
        }
    }
}

/// Scalar types usable in the binary builder below.
#[derive(Clone, Copy)]
enum Num {
    F32,
    F64,
    U8,
    I32,
    U32,
    U16,
}

impl Num {
    fn name(self) -> &'static str {
        match self {
            Num::F32 => "float",
            Num::F64 => "double",
            Num::U8 => "uchar",
            Num::I32 => "int",
            Num::U32 => "uint",
            Num::U16 => "ushort",
        }
    }
    fn put(self, out: &mut Vec<u8>, v: f64, big: bool) {
        macro_rules! put {
            ($x:expr) => {
                if big {
                    out.extend_from_slice(&$x.to_be_bytes())
                } else {
                    out.extend_from_slice(&$x.to_le_bytes())
                }
            };
        }
        match self {
            Num::F32 => put!(v as f32),
            Num::F64 => put!(v),
            Num::U8 => put!(v as u8),
            Num::I32 => put!(v as i32),
            Num::U32 => put!(v as u32),
            Num::U16 => put!(v as u16),
        }
    }
}

/// A binary PLY of `positions`/`faces` with an extra `nx` vertex property and an extra
/// `edge` element, in the given byte order, coordinate type and list types.
fn binary_ply(
    positions: &[[f64; 3]],
    faces: &[Vec<i64>],
    big: bool,
    coord: Num,
    count_t: Num,
    index_t: Num,
    index_name: &str,
) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_{}_endian 1.0\nelement vertex {}\nproperty {c} x\nproperty {c} nx\nproperty {c} y\nproperty {c} z\n\
         element face {}\nproperty list {} {} {index_name}\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        if big { "big" } else { "little" },
        positions.len(),
        faces.len(),
        count_t.name(),
        index_t.name(),
        c = coord.name(),
    )
    .into_bytes();
    for p in positions {
        coord.put(&mut out, p[0], big);
        coord.put(&mut out, 7.0, big);
        coord.put(&mut out, p[1], big);
        coord.put(&mut out, p[2], big);
    }
    for f in faces {
        count_t.put(&mut out, f.len() as f64, big);
        for &i in f {
            index_t.put(&mut out, i as f64, big);
        }
    }
    Num::I32.put(&mut out, 0.0, big);
    Num::I32.put(&mut out, 1.0, big);
    out
}

#[test]
fn ply_binary_both_endiannesses_types_and_names() {
    let positions = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.25], [1.0, 1.0, -3.0], [0.0, 1.0, 0.0]];
    let faces = vec![vec![0, 1, 2], vec![0, 2, 3]];
    for big in [false, true] {
        for coord in [Num::F32, Num::F64] {
            for (count_t, index_t) in [
                (Num::U8, Num::I32),
                (Num::U8, Num::U32),
                (Num::I32, Num::I32),
                (Num::U8, Num::U16),
                (Num::U8, Num::U8),
            ] {
                for index_name in ["vertex_indices", "vertex_index"] {
                    let bytes = binary_ply(&positions, &faces, big, coord, count_t, index_t, index_name);
                    let (mesh, report) = read_ply(&bytes, name(), &strict()).unwrap_or_else(|e| {
                        panic!("big={big} {} {} {}: {e}", coord.name(), index_t.name(), index_name)
                    });
                    assert_eq!(mesh.positions(), &positions);
                    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
                    assert!(report.notes.iter().any(|n| n.contains("edge")), "{:?}", report.notes);
                }
            }
        }
    }
}

#[test]
fn ply_double_coordinates_keep_full_precision() {
    let positions = [[0.1, 0.2, 0.3], [1.0 / 3.0, 0.0, 0.0], [0.0, std::f64::consts::PI, 0.0]];
    let bytes = binary_ply(
        &positions,
        &[vec![0, 1, 2]],
        false,
        Num::F64,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    let (mesh, _) = read_ply(&bytes, name(), &strict()).unwrap();
    assert_eq!(mesh.positions(), &positions);
}

#[test]
fn ply_polygons_and_bad_data() {
    let quad = binary_ply(
        &SQUARE_POSITIONS,
        &[vec![0, 1, 2, 3]],
        false,
        Num::F32,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    assert!(matches!(
        read_ply(&quad, name(), &strict()),
        Err(MeshError::Polygon {
            face: 0,
            corners: 4,
            ..
        })
    ));
    let (mesh, report) = read_ply(&quad, name(), &tri()).unwrap();
    assert_eq!(mesh.faces(), &[[0, 1, 2], [0, 2, 3]]);
    assert_eq!(report.triangulated_polygons, 1);

    let negative = binary_ply(
        &SQUARE_POSITIONS,
        &[vec![0, -2, 3]],
        true,
        Num::F32,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    assert!(matches!(
        read_ply(&negative, name(), &strict()),
        Err(MeshError::NegativeIndex {
            face: 0,
            index: -2,
            line: 0,
            ..
        })
    ));
    let out_of_range = binary_ply(
        &SQUARE_POSITIONS,
        &[vec![0, 1, 4]],
        false,
        Num::F32,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    assert!(matches!(
        read_ply(&out_of_range, name(), &strict()),
        Err(MeshError::IndexOutOfRange { face: 0, index: 4, .. })
    ));
    let nan = binary_ply(
        &[[0.0, 0.0, 0.0], [f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[vec![0, 1, 2]],
        false,
        Num::F64,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    assert!(matches!(
        read_ply(&nan, name(), &strict()),
        Err(MeshError::NonFiniteCoordinate { vertex: 1, .. })
    ));
    // Truncated binary payload: line 0.
    let full = binary_ply(
        &SQUARE_POSITIONS,
        &[vec![0, 1, 2]],
        false,
        Num::F32,
        Num::U8,
        Num::I32,
        "vertex_indices",
    );
    for cut in [full.len() - 9, full.len() - 30, full.len() - 60] {
        expect_parse_line(read_ply(&full[..cut], name(), &strict()), 0);
    }
    // Missing face element / properties.
    let no_face = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    let m = expect_parse_line(read_ply(no_face, name(), &strict()), 0);
    assert!(m.contains("face"), "{m}");
    let no_z = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0\n";
    let m = expect_parse_line(read_ply(no_z, name(), &strict()), 0);
    assert!(m.contains("\"z\""), "{m}");
    // ASCII garbage in the payload names its line (line 11 = second vertex).
    let mut bad = ascii_ply("list uchar int vertex_indices", false);
    let text = String::from_utf8(bad.clone())
        .unwrap()
        .replacen("1 0 0 200", "1 oops 0 200", 1);
    bad = text.into_bytes();
    match read_ply(&bad, name(), &strict()) {
        Err(MeshError::Parse { line, .. }) => assert!(line > 0, "ASCII PLY errors carry a line"),
        other => panic!("expected a parse error, got {other:?}"),
    }
    expect_parse_line(read_ply(b"not a ply file\n", name(), &strict()), 1);
}

// ---------------------------------------------------------------- STL

const TETRA: [[[f64; 3]; 3]; 4] = [
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]],
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
];

fn ascii_stl(tris: &[[[f64; 3]; 3]]) -> String {
    let mut s = String::from("solid tetra\n");
    for t in tris {
        s.push_str("  facet normal 0 0 0\n    outer loop\n");
        for p in t {
            s.push_str(&format!("      vertex {:e} {:e} {:e}\n", p[0], p[1], p[2]));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    s.push_str("endsolid tetra\n");
    s
}

fn binary_stl(tris: &[[[f64; 3]; 3]], header_start: &[u8]) -> Vec<u8> {
    let mut out = vec![b' '; 80];
    out[..header_start.len()].copy_from_slice(header_start);
    out.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        out.extend_from_slice(&[0u8; 12]);
        for p in t {
            for c in p {
                out.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

fn check_tetra(mesh: &mesh_fem::TriMesh, report: &mesh_fem::io::LoadReport) {
    assert_eq!(mesh.n_vertices(), 4);
    assert_eq!(mesh.n_faces(), 4);
    assert_eq!(report.welded_vertices, 8);
    assert_eq!(report.format, MeshFormat::Stl);
    for (f, t) in mesh.faces().iter().zip(TETRA) {
        for (i, p) in f.iter().zip(t) {
            assert_eq!(mesh.positions()[*i as usize], p);
        }
    }
}

#[test]
fn stl_ascii_and_binary_weld_to_the_same_tetrahedron() {
    let (m, r) = read_stl(ascii_stl(&TETRA).as_bytes(), name(), &strict()).unwrap();
    check_tetra(&m, &r);
    let (m, r) = read_stl(ascii_stl(&TETRA).replace('\n', "\r\n").as_bytes(), name(), &strict()).unwrap();
    check_tetra(&m, &r);
    // A binary file whose header starts with "solid" must still be read as binary.
    for header in [&b"solid but binary"[..], b"exported by a CAD tool"] {
        let (m, r) = read_stl(&binary_stl(&TETRA, header), name(), &strict()).unwrap();
        check_tetra(&m, &r);
        assert!(r.notes.iter().any(|n| n.contains("binary")));
    }
}

#[test]
fn stl_binary_with_solid_header_and_trailing_bytes_is_read_as_binary() {
    let mut bytes = binary_stl(&TETRA, b"solid exported");
    bytes.extend_from_slice(b"\0\0trailing");
    let (m, r) = read_stl(&bytes, name(), &strict()).unwrap();
    check_tetra(&m, &r);
    assert!(r.notes.iter().any(|n| n.contains("binary")), "{:?}", r.notes);
    // Garbage that starts with "solid" is neither: the ASCII error is reported.
    expect_parse_line(read_stl(b"solid x\nfacet normal 0 0 0\nbogus\n", name(), &strict()), 3);
}

#[test]
fn stl_welds_signed_zeros_but_not_distinct_points() {
    let mut t = TETRA;
    t[1][0] = [-0.0, 0.0, -0.0];
    let (m, r) = read_stl(ascii_stl(&t).as_bytes(), name(), &strict()).unwrap();
    assert_eq!((m.n_vertices(), r.welded_vertices), (4, 8));
    t[1][0] = [1e-300, 0.0, 0.0];
    let (m, r) = read_stl(ascii_stl(&t).as_bytes(), name(), &strict()).unwrap();
    assert_eq!((m.n_vertices(), r.welded_vertices), (5, 7));
}

#[test]
fn stl_bad_data() {
    let full = binary_stl(&TETRA, b"binary");
    expect_parse_line(read_stl(&full[..full.len() - 10], name(), &strict()), 0);
    expect_parse_line(read_stl(&full[..50], name(), &strict()), 0);
    let four = ascii_stl(&TETRA).replacen("    endloop", "      vertex 1 1 1\n    endloop", 1);
    expect_parse_line(read_stl(four.as_bytes(), name(), &strict()), 7);
    let two = ascii_stl(&TETRA).replacen("      vertex 0e0 1e0 0e0\n", "", 1);
    expect_parse_line(read_stl(two.as_bytes(), name(), &strict()), 6);
    let garbage = ascii_stl(&TETRA).replacen("vertex 0e0 1e0 0e0", "vertex 0 one 0", 1);
    expect_parse_line(read_stl(garbage.as_bytes(), name(), &strict()), 5);
    let truncated = &ascii_stl(&TETRA)[..60];
    assert!(matches!(
        read_stl(truncated.as_bytes(), name(), &strict()),
        Err(MeshError::Parse { .. })
    ));
    let nan = ascii_stl(&TETRA).replacen("vertex 0e0 1e0 0e0", "vertex 0 NaN 0", 1);
    assert!(matches!(
        read_stl(nan.as_bytes(), name(), &strict()),
        Err(MeshError::NonFiniteCoordinate { .. })
    ));
}

// ---------------------------------------------------------------- load() and robustness

#[test]
fn load_picks_the_format_by_case_insensitive_extension() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("square.OBJ");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
    let (mesh, report) = load(&obj, &strict()).unwrap();
    assert_eq!((mesh.n_vertices(), report.format), (3, MeshFormat::Obj));

    let unknown = dir.path().join("square.xyz");
    std::fs::write(&unknown, "").unwrap();
    match load(&unknown, &strict()) {
        Err(MeshError::UnknownFormat { extension, .. }) => assert_eq!(extension, "xyz"),
        other => panic!("expected UnknownFormat, got {other:?}"),
    }
    assert!(matches!(
        load(&dir.path().join("none"), &strict()),
        Err(MeshError::UnknownFormat { .. })
    ));
    assert!(matches!(
        load(&dir.path().join("missing.off"), &strict()),
        Err(MeshError::Io { .. })
    ));
}

/// Every prefix of small valid files, and single corrupted bytes, must give `Ok` or `Err`,
/// never a panic (a cheap stand-in for fuzzing each parser).
#[test]
fn truncated_and_corrupted_inputs_never_panic() {
    let samples: Vec<(MeshFormat, Vec<u8>)> = vec![
        (
            MeshFormat::Obj,
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2//2 3\nf -4 -2 -1\n".to_vec(),
        ),
        (
            MeshFormat::Off,
            b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 2 3 1\n".to_vec(),
        ),
        (MeshFormat::Ply, ascii_ply("list uchar int vertex_indices", false)),
        (
            MeshFormat::Ply,
            binary_ply(
                &SQUARE_POSITIONS,
                &[vec![0, 1, 2], vec![0, 2, 3]],
                false,
                Num::F32,
                Num::U8,
                Num::I32,
                "vertex_indices",
            ),
        ),
        (
            MeshFormat::Ply,
            binary_ply(
                &SQUARE_POSITIONS,
                &[vec![0, 1, 2]],
                true,
                Num::F64,
                Num::I32,
                Num::U32,
                "vertex_index",
            ),
        ),
        (MeshFormat::Stl, ascii_stl(&TETRA).into_bytes()),
        (MeshFormat::Stl, binary_stl(&TETRA, b"solid")),
    ];
    for opts in [strict(), tri()] {
        for (format, bytes) in &samples {
            for cut in 0..bytes.len() {
                let _ = load_bytes(&bytes[..cut], *format, name(), &opts);
            }
            for i in 0..bytes.len() {
                for replacement in [0u8, 0xff, b'-', b'9', b'\n'] {
                    let mut b = bytes.clone();
                    b[i] = replacement;
                    let _ = load_bytes(&b, *format, name(), &opts);
                }
            }
        }
    }
}
