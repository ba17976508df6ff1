//! Writers round-trip through the readers (ours, and ply-rs-bw for PLY field files); atomic
//! writes leave nothing behind on failure.

use mesh_fem::generate;
use mesh_fem::io::{load, read_field, write_atomic, write_field, write_mesh, LoadOptions};
use mesh_fem::{MeshError, TriMesh};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;

fn dir_entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A mesh with "awkward" coordinates (irrational, tiny, huge) so that round trips test that
/// ASCII output is exact.
fn test_mesh() -> TriMesh {
    let base = generate::irregular_sphere(2, 0.6);
    let (mut p, f) = base.into_parts();
    p[0][0] *= 1e-12;
    p[1][1] *= 1e12;
    p[2][2] = 1.0 / 3.0;
    TriMesh::new(p, f).unwrap()
}

fn field(n: usize, k: usize) -> Vec<f64> {
    (0..n)
        .map(|i| ((i * (k + 3)) as f64).sin() * 10f64.powi(k as i32 - 2))
        .collect()
}

#[test]
fn write_mesh_round_trips_bit_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    for ext in ["off", "obj", "ply", "OFF"] {
        let path = dir.path().join(format!("mesh.{ext}"));
        write_mesh(&path, &mesh).unwrap();
        let (back, report) = load(&path, &LoadOptions::default()).unwrap();
        assert_eq!(back, mesh, "{ext}");
        assert_eq!(report.welded_vertices, 0);
    }
    assert!(matches!(
        write_mesh(&dir.path().join("mesh.stl"), &mesh),
        Err(MeshError::UnknownFormat { .. })
    ));
}

#[test]
fn ply_field_file_reads_back_through_ply_rs_bw_and_our_reader() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    let n = mesh.n_vertices();
    let (heat, hks) = (field(n, 0), field(n, 1));
    let colors: Vec<[u8; 3]> = (0..n).map(|i| [i as u8, (i * 7) as u8, 255 - i as u8]).collect();
    let path = dir.path().join("fields.ply");
    write_field(&path, &mesh, &[("heat", &heat), ("hks_t1", &hks)], Some(&colors)).unwrap();

    // Independent reader: every property by name.
    let mut f = std::fs::File::open(&path).unwrap();
    let ply = Parser::<DefaultElement>::new().read_ply(&mut f).unwrap();
    let vertices = &ply.payload["vertex"];
    assert_eq!(vertices.len(), n);
    let get = |e: &DefaultElement, k: &str| match e.get(k) {
        Some(Property::Double(v)) => *v,
        other => panic!("property {k}: {other:?}"),
    };
    for (i, v) in vertices.iter().enumerate() {
        let p = mesh.positions()[i];
        assert_eq!([get(v, "x"), get(v, "y"), get(v, "z")], p);
        assert_eq!(get(v, "heat"), heat[i]);
        assert_eq!(get(v, "hks_t1"), hks[i]);
        for (k, c) in ["red", "green", "blue"].iter().enumerate() {
            assert_eq!(v.get(*c), Some(&Property::UChar(colors[i][k])));
        }
    }
    let faces = &ply.payload["face"];
    assert_eq!(faces.len(), mesh.n_faces());
    for (face, f) in faces.iter().zip(mesh.faces()) {
        let want: Vec<i32> = f.iter().map(|&i| i as i32).collect();
        assert_eq!(face.get("vertex_indices"), Some(&Property::ListInt(want)));
    }

    // Our reader sees the same mesh (extra properties ignored).
    let (back, _) = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(back, mesh);

    // No fields at all is a valid PLY too.
    let plain = dir.path().join("plain.ply");
    write_field(&plain, &mesh, &[], None).unwrap();
    assert_eq!(load(&plain, &LoadOptions::default()).unwrap().0, mesh);
}

/// Field names as the CLI makes them (`rational_t0.002`, a sign) give a PLY
/// that both readers load: names are reduced to letters, digits and `_`, kept distinct. (The
/// demo's `basis.ply` with `rational_t0.002` could not be read back by `wfem` itself.)
#[test]
fn ply_property_names_are_made_readable_and_distinct() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    let n = mesh.n_vertices();
    let (a, b, d) = (field(n, 0), field(n, 1), field(n, 3));
    let path = dir.path().join("names.ply");
    let fields: [(&str, &[f64]); 3] = [("rational_t0.002", &a), ("t1e+03", &b), ("rational_t0_002", &d)];
    write_field(&path, &mesh, &fields, None).unwrap();
    let (back, _) = load(&path, &LoadOptions::default()).unwrap();
    assert_eq!(back, mesh);
    let mut f = std::fs::File::open(&path).unwrap();
    let ply = Parser::<DefaultElement>::new().read_ply(&mut f).unwrap();
    let v = &ply.payload["vertex"][5];
    let get = |k: &str| match v.get(k) {
        Some(Property::Double(x)) => *x,
        other => panic!("property {k}: {other:?}"),
    };
    assert_eq!(get("rational_t0_002"), a[5]);
    assert_eq!(get("t1e_03"), b[5]);
    assert_eq!(get("rational_t0_002_2"), d[5]);
    assert_eq!(get("x"), mesh.positions()[5][0]);
}

/// Decodes an NPY 1.0 float64 file independently of the library: returns (shape, data).
fn decode_npy(bytes: &[u8]) -> (String, Vec<f64>) {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0, "data must start 64-byte aligned");
    let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    assert!(header.ends_with('\n'));
    assert!(header.contains("'descr': '<f8'") && header.contains("'fortran_order': False"));
    let shape = header[header.find("'shape': ").unwrap() + 9..]
        .split(')')
        .next()
        .unwrap()
        .to_string()
        + ")";
    let data = bytes[10 + len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (shape, data)
}

#[test]
fn npy_fields_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    let n = mesh.n_vertices();
    let (a, b, c) = (field(n, 0), field(n, 1), field(n, 2));

    let one = dir.path().join("one.npy");
    write_field(&one, &mesh, &[("a", &a)], None).unwrap();
    assert_eq!(read_field(&one, n).unwrap(), a);
    let (shape, data) = decode_npy(&std::fs::read(&one).unwrap());
    assert_eq!(shape, format!("({n},)"));
    assert_eq!(data, a);

    let three = dir.path().join("three.npy");
    write_field(&three, &mesh, &[("a", &a), ("b", &b), ("c", &c)], None).unwrap();
    let (shape, data) = decode_npy(&std::fs::read(&three).unwrap());
    assert_eq!(shape, format!("({n}, 3)"));
    for i in 0..n {
        assert_eq!(&data[3 * i..3 * i + 3], &[a[i], b[i], c[i]], "row {i} (C order)");
    }
    // An n × 3 array is not a single field.
    assert!(matches!(read_field(&three, n), Err(MeshError::Parse { .. })));
}

/// Writes an NPY file by hand (for reader tests of variants we never write).
fn npy_bytes(descr: &str, shape: &str, data: &[u8], version: u8) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}\n");
    let pre = if version == 1 { 10 } else { 12 };
    while (pre + header.len()) % 16 != 0 {
        header.insert(header.len() - 1, ' ');
    }
    let mut out = b"\x93NUMPY".to_vec();
    out.extend_from_slice(&[version, 0]);
    if version == 1 {
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

#[test]
fn read_field_accepts_npy_variants_and_rejects_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let values: [f64; 4] = [0.5, -2.25, 0.125, 7.0];
    let write = |name: &str, bytes: Vec<u8>| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    let le8: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let be8: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    let le4: Vec<u8> = values.iter().flat_map(|v| (*v as f32).to_le_bytes()).collect();
    let be4: Vec<u8> = values.iter().flat_map(|v| (*v as f32).to_be_bytes()).collect();
    for (name, bytes) in [
        ("le8.npy", npy_bytes("<f8", "(4,)", &le8, 1)),
        ("be8.npy", npy_bytes(">f8", "(4,)", &be8, 1)),
        ("le4.npy", npy_bytes("<f4", "(4,)", &le4, 1)),
        ("be4.npy", npy_bytes(">f4", "(4, 1)", &be4, 1)),
        ("col.npy", npy_bytes("<f8", "(4, 1)", &le8, 2)),
    ] {
        let p = write(name, bytes);
        assert_eq!(read_field(&p, 4).unwrap(), values, "{name}");
    }
    let p = write("len.npy", npy_bytes("<f8", "(4,)", &le8, 1));
    assert!(matches!(
        read_field(&p, 5),
        Err(MeshError::FieldLength {
            expected: 5,
            found: 4,
            ..
        })
    ));
    let nan: Vec<u8> = [0.0, f64::NAN, 1.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    let p = write("nan.npy", npy_bytes("<f8", "(3,)", &nan, 1));
    assert!(matches!(
        read_field(&p, 3),
        Err(MeshError::NonFiniteValue { vertex: 1, .. })
    ));
    for (name, bytes) in [
        ("int.npy", npy_bytes("<i8", "(4,)", &le8, 1)),
        ("short.npy", npy_bytes("<f8", "(5,)", &le8, 1)),
        ("matrix.npy", npy_bytes("<f8", "(2, 2)", &le8, 1)),
        ("magic.npy", b"NUMPY garbage".to_vec()),
        ("cut.npy", npy_bytes("<f8", "(4,)", &le8, 1)[..20].to_vec()),
    ] {
        let p = write(name, bytes);
        assert!(
            matches!(read_field(&p, 4), Err(MeshError::Parse { line: 0, .. })),
            "{name}"
        );
    }
}

#[test]
fn csv_fields_round_trip_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    let n = mesh.n_vertices();
    let (a, b) = (field(n, 0), field(n, 4));
    let one = dir.path().join("one.csv");
    write_field(&one, &mesh, &[("heat", &a)], None).unwrap();
    assert_eq!(read_field(&one, n).unwrap(), a);

    let two = dir.path().join("two.csv");
    write_field(&two, &mesh, &[("heat", &a), ("hks", &b)], None).unwrap();
    let text = std::fs::read_to_string(&two).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("heat,hks"));
    for (i, line) in lines.enumerate() {
        let (x, y) = line.split_once(',').unwrap();
        assert_eq!((x.parse::<f64>().unwrap(), y.parse::<f64>().unwrap()), (a[i], b[i]));
    }

    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    assert_eq!(
        read_field(&write("plain.csv", "1\r\n2.5\n\n-3e-2\n"), 3).unwrap(),
        [1.0, 2.5, -0.03]
    );
    assert!(matches!(
        read_field(&write("bad.csv", "value\n1\nfoo\n"), 2),
        Err(MeshError::Parse { line: 3, .. })
    ));
    assert!(matches!(
        read_field(&write("wide.csv", "1,2\n"), 1),
        Err(MeshError::Parse { line: 1, .. })
    ));
    assert!(matches!(
        read_field(&write("nan.csv", "1\nNaN\n"), 2),
        Err(MeshError::NonFiniteValue { vertex: 1, .. })
    ));
    assert!(matches!(
        read_field(&write("short.csv", "1\n2\n"), 3),
        Err(MeshError::FieldLength {
            expected: 3,
            found: 2,
            ..
        })
    ));
    assert!(matches!(
        read_field(&write("f.txt", "1\n"), 1),
        Err(MeshError::UnknownFormat { .. })
    ));
}

#[test]
fn write_field_rejects_bad_input_without_creating_files() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = test_mesh();
    let n = mesh.n_vertices();
    let good = field(n, 0);
    let short = vec![1.0; n - 1];
    let mut nan = good.clone();
    nan[5] = f64::NAN;
    let p = |name: &str| dir.path().join(name);
    assert!(matches!(
        write_field(&p("a.npy"), &mesh, &[("f", &short)], None),
        Err(MeshError::FieldLength { found, .. }) if found == n - 1
    ));
    assert!(matches!(
        write_field(&p("a.csv"), &mesh, &[("f", &nan)], None),
        Err(MeshError::NonFiniteValue { vertex: 5, .. })
    ));
    let colors = vec![[0u8; 3]; 2];
    assert!(matches!(
        write_field(&p("a.ply"), &mesh, &[("f", &good)], Some(&colors)),
        Err(MeshError::FieldLength { .. })
    ));
    for bad in ["two words", "x", "red", ""] {
        assert!(matches!(
            write_field(&p("a.ply"), &mesh, &[(bad, &good)], None),
            Err(MeshError::Invalid { .. })
        ));
    }
    assert!(matches!(
        write_field(&p("a.ply"), &mesh, &[("f", &good), ("f", &good)], None),
        Err(MeshError::Invalid { .. })
    ));
    assert!(matches!(
        write_field(&p("a.npy"), &mesh, &[], None),
        Err(MeshError::Invalid { .. })
    ));
    assert!(matches!(
        write_field(&p("a.vtk"), &mesh, &[("f", &good)], None),
        Err(MeshError::UnknownFormat { .. })
    ));
    assert!(dir_entries(dir.path()).is_empty());
}

#[test]
fn failing_writer_leaves_no_file_and_no_temp_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.npy");
    let r = write_atomic(&target, |w| {
        w.write_all(&[7u8; 100_000])?;
        Err(std::io::Error::other("simulated failure half-way"))
    });
    match r {
        Err(MeshError::Io { path, source }) => {
            assert_eq!(path, target);
            assert!(source.to_string().contains("simulated failure"));
        }
        other => panic!("expected Io error, got {other:?}"),
    }
    assert!(dir_entries(dir.path()).is_empty(), "{:?}", dir_entries(dir.path()));

    // An existing file keeps its old content when a rewrite fails, and is replaced on success.
    std::fs::write(&target, b"old").unwrap();
    assert!(write_atomic(&target, |_| Err(std::io::Error::other("no"))).is_err());
    assert_eq!(std::fs::read(&target).unwrap(), b"old");
    assert_eq!(dir_entries(dir.path()), ["out.npy"]);
    write_atomic(&target, |w| w.write_all(b"new")).unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"new");
    assert_eq!(dir_entries(dir.path()), ["out.npy"]);

    // A directory that does not exist is an Io error naming the target.
    let missing = dir.path().join("no/such/dir/f.csv");
    assert!(matches!(
        write_atomic(&missing, |w| w.write_all(b"x")),
        Err(MeshError::Io { .. })
    ));
}
