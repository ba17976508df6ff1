//! A store on read-only media or in a read-only folder (issue #41): its write-ahead log may
//! hold committed shapes that the main file lacks (copied while a writer had it open, or left
//! by a killed writer), and no shared-memory file can be created there. Such a store used to
//! be opened as immutable, which ignores the log: queries silently left those shapes out.
//!
//! The test runs this test binary again as a child (`readonly::reader_child`, selected by an
//! environment variable; without it that test does nothing) which, when it runs as root, first
//! drops the capabilities that let root write anywhere (root ignores permission bits, so
//! without this a read-only folder is writable to it), checks that the folder is really
//! unwritable, then opens the store read-only and prints what it sees.
#![cfg(unix)]

use retrieval_store::metric::StandardMetric;
use retrieval_store::{Entry, Store, StoreParams};
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::Command;

const CHILD_ENV: &str = "RETRIEVAL_STORE_READONLY_CHILD";
const DIM: usize = 6;

/// Drops CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH and CAP_FOWNER from this thread's effective
/// set (threads it starts later inherit that): a root process then obeys permission bits.
#[allow(unsafe_code)]
fn obey_permission_bits() {
    #[repr(C)]
    struct Header {
        version: u32,
        pid: i32,
    }
    #[repr(C)]
    #[derive(Clone, Copy, Default)]
    struct Data {
        effective: u32,
        permitted: u32,
        inheritable: u32,
    }
    const VERSION_3: u32 = 0x2008_0522;
    let mut header = Header {
        version: VERSION_3,
        pid: 0,
    };
    let mut data = [Data::default(); 2];
    // SAFETY: capget/capset with a version 3 header and two data words, as the kernel expects.
    unsafe {
        assert_eq!(
            libc::syscall(libc::SYS_capget, &mut header as *mut Header, data.as_mut_ptr()),
            0
        );
        data[0].effective &= !((1 << 1) | (1 << 2) | (1 << 3));
        assert_eq!(
            libc::syscall(libc::SYS_capset, &header as *const Header, data.as_ptr()),
            0
        );
    }
}

#[test]
fn reader_child() {
    let Some(path) = std::env::var_os(CHILD_ENV) else {
        return;
    };
    let path = PathBuf::from(path);
    obey_permission_bits();
    let folder = path.parent().unwrap();
    assert!(
        std::fs::File::create(folder.join("probe")).is_err(),
        "the folder is writable to the reader: the test would not exercise a read-only store"
    );
    match Store::open_readonly(&path) {
        Ok(store) => {
            let last = store.len().unwrap().saturating_sub(1);
            let hits = store
                .search_metric(&super::store::vector(last, DIM), 1, &StandardMetric::L1)
                .unwrap();
            println!("@@len {} nearest {}", store.len().unwrap(), hits[0].name);
            println!("@@vectors {}", store.vectors().unwrap().len() / DIM);
        }
        Err(e) => println!("@@error {e}"),
    }
}

/// What the child saw of the store at `path`.
fn read_in_child(path: &Path) -> Vec<String> {
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["readonly::reader_child", "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
        .lines()
        // The harness's "test … ... " may precede the first line on the same line.
        .filter_map(|l| l.find("@@").map(|at| l[at + 2..].to_owned()))
        .collect()
}

fn add(store: &mut Store, range: std::ops::Range<usize>) {
    let names: Vec<String> = range.clone().map(|i| format!("shape-{i}")).collect();
    let vectors: Vec<Vec<f64>> = range.map(|i| super::store::vector(i, DIM)).collect();
    let entries: Vec<Entry<'_>> = names.iter().zip(&vectors).map(|(n, v)| Entry::new(n, "", v)).collect();
    store.add(&entries).unwrap();
}

#[test]
fn issue_41_a_read_only_store_is_read_with_its_log() {
    let dir = tempfile::tempdir().unwrap();
    let written = dir.path().join("index.sqlite");
    let params = StoreParams {
        dimension: DIM,
        chunk_rows: 4,
    };
    // Five shapes folded into the file (the writer closed), then three more committed by a
    // writer still open: they are in the log only.
    add(&mut Store::create(&written, &params, false).unwrap(), 0..5);
    let mut writer = Store::open(&written).unwrap();
    add(&mut writer, 5..8);
    let wal = dir.path().join("index.sqlite-wal");
    assert!(std::fs::metadata(&wal).unwrap().len() > 0);
    // The files as they are, onto "read-only media": the store and its log, no shared memory.
    let media = dir.path().join("media");
    std::fs::create_dir(&media).unwrap();
    for name in ["index.sqlite", "index.sqlite-wal"] {
        std::fs::copy(dir.path().join(name), media.join(name)).unwrap();
    }
    drop(writer);
    // And a copy whose log is empty: read as immutable, as before.
    let folded = dir.path().join("folded");
    std::fs::create_dir(&folded).unwrap();
    std::fs::copy(&written, folded.join("index.sqlite")).unwrap();
    for d in [&media, &folded] {
        std::fs::set_permissions(d, std::fs::Permissions::from_mode(0o555)).unwrap();
    }
    let seen = read_in_child(&media.join("index.sqlite"));
    let folded_seen = read_in_child(&folded.join("index.sqlite"));
    for d in [&media, &folded] {
        std::fs::set_permissions(d, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    // Immutable, the old reading, saw 5 shapes and answered shape-4.
    assert_eq!(
        seen,
        ["len 8 nearest shape-7", "vectors 8"],
        "the log's shapes were left out"
    );
    assert_eq!(folded_seen, ["len 8 nearest shape-7", "vectors 8"]);
    // Nothing was written beside the store on the media.
    let mut left: Vec<String> = std::fs::read_dir(&media)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["index.sqlite", "index.sqlite-wal"]);
}
