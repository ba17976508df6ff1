//! Issue #16: special files given as a mesh or a field are refused instead of blocking, and
//! a CSV field with a UTF-8 byte order mark is read whole.

use mesh_fem::io::{load, read_field, read_regular_file, LoadOptions};
use mesh_fem::MeshError;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// Runs `f` on its own thread and fails the test if it has not returned after 20 s (a FIFO
/// opened for reading blocks until a writer appears; the old reader hung here forever).
fn within_timeout<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(20))
        .expect("reading a special file blocked (no answer after 20 s)")
}

fn assert_refused(result: Result<impl std::fmt::Debug, MeshError>, path: &Path, kind: &str) {
    match result {
        Err(MeshError::Io { path: p, source }) => {
            assert_eq!(p, path);
            assert_eq!(source.kind(), std::io::ErrorKind::InvalidInput, "{source}");
            let text = source.to_string();
            assert!(text.contains(kind) && text.contains("not a regular file"), "{text}");
        }
        other => panic!("{}: expected an Io error, got {other:?}", path.display()),
    }
}

#[cfg(unix)]
fn mkfifo(path: &Path) -> bool {
    std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .is_ok_and(|s| s.success())
}

#[cfg(unix)]
#[test]
fn issue_16_fifo_as_mesh_or_field_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let mesh: PathBuf = dir.path().join("pipe.off");
    let field: PathBuf = dir.path().join("pipe.csv");
    if !(mkfifo(&mesh) && mkfifo(&field)) {
        eprintln!("skipped: mkfifo is not available");
        return;
    }
    let m = mesh.clone();
    assert_refused(within_timeout(move || load(&m, &LoadOptions::default())), &mesh, "FIFO");
    let f = field.clone();
    assert_refused(within_timeout(move || read_field(&f, 3)), &field, "FIFO");
}

#[test]
fn issue_16_directories_and_devices_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir(&folder).unwrap();
    assert_refused(load(&folder, &LoadOptions::default()), &folder, "directory");
    let folder_csv = dir.path().join("folder.csv");
    std::fs::create_dir(&folder_csv).unwrap();
    assert_refused(read_field(&folder_csv, 3), &folder_csv, "directory");
    #[cfg(unix)]
    {
        let null = Path::new("/dev/null");
        if null.exists() {
            let n = null.to_path_buf();
            assert_refused(within_timeout(move || read_regular_file(&n)), null, "device");
        }
    }
    // A missing file keeps the operating system's error.
    let missing = dir.path().join("missing.obj");
    match load(&missing, &LoadOptions::default()) {
        Err(MeshError::Io { source, .. }) => assert_eq!(source.kind(), std::io::ErrorKind::NotFound),
        other => panic!("{other:?}"),
    }
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_to_a_regular_file_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("f.csv");
    std::fs::write(&target, "1\n2\n3\n").unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    assert_eq!(read_field(&link, 3).unwrap(), vec![1.0, 2.0, 3.0]);
}

#[test]
fn issue_16_csv_field_with_a_byte_order_mark() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bom.csv");
    std::fs::write(&p, b"\xef\xbb\xbf1.5\r\n2\r\n-3\r\n").unwrap();
    assert_eq!(read_field(&p, 3).unwrap(), vec![1.5, 2.0, -3.0]);
    // With a header line after the mark, the header is still skipped.
    std::fs::write(&p, b"\xef\xbb\xbfvalue\n1.5\n2\n-3\n").unwrap();
    assert_eq!(read_field(&p, 3).unwrap(), vec![1.5, 2.0, -3.0]);
    // Values near the largest double are read exactly.
    std::fs::write(&p, "1e308\n-1.7976931348623157e308\n0\n").unwrap();
    assert_eq!(read_field(&p, 3).unwrap(), vec![1e308, -f64::MAX, 0.0]);
}
