//! Temporary files and folders that do not outlive their process (issue #41).
//!
//! Every temporary of the workspace's writers — mesh-fem's `AtomicSet`, retrieval-store's
//! builds, the CLI's folder probe — is a [`TempPath`]: a file or folder named
//! `.NAME.tmp-PID-N` beside its target `NAME`, registered here for as long as it exists.
//!
//! * **A signal**: a program that stops on a signal calls [`remove_all`] before it ends (the
//!   `wfem` binary does on SIGINT, SIGTERM and SIGHUP). It takes the registry's lock, which
//!   every creation of a temporary and every commit ([`while_locked`]: the renames onto the
//!   targets) holds, removes every registered path and never releases the lock: nothing is
//!   created or renamed after it, and a target is its old file or its new one. A folder is
//!   removed until it is gone, so that a file someone was creating in it (SQLite's journal)
//!   has nowhere to go.
//! * **A kill** (SIGKILL, a crash, a power cut) leaves the temporaries; the next writer of the
//!   same target removes those whose process no longer runs ([`sweep`], called by
//!   [`TempPath::file`] and [`TempPath::dir`]), including the names of earlier versions
//!   (`.NAME.PID.build…`, `.NAME.PID.tmp…`, `.wfem-probe-PID`). A process id is only compared
//!   on this machine: a folder shared with another machine or PID namespace keeps its files.
//!
//! Without a signal handler (a library user, Python) the registry only keeps the list.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

/// The live temporaries of this process, and the targets whose folder was swept.
struct Registry {
    live: Vec<(u64, PathBuf)>,
    /// Targets swept already (a handful per run: one read of each folder).
    swept: Vec<PathBuf>,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    live: Vec::new(),
    swept: Vec::new(),
});

fn lock() -> MutexGuard<'static, Registry> {
    // A panic while the lock was held leaves the list as it was: still usable.
    REGISTRY.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A registered temporary file or folder beside a target; removed when dropped (after a
/// commit has renamed it away there is nothing left to remove).
#[derive(Debug)]
pub struct TempPath {
    id: u64,
    path: PathBuf,
}

static NEXT: AtomicU64 = AtomicU64::new(0);

/// `.NAME.tmp-PID-N` beside `target` (`N` unique in this process).
fn temp_name(target: &Path) -> std::io::Result<(PathBuf, u64)> {
    let name = target
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file"))?;
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    let name = format!(".{}.tmp-{}-{id}", name.to_string_lossy(), std::process::id());
    Ok((folder_of(target).join(name), id))
}

/// The folder a path lives in (`.` for a bare file name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

impl TempPath {
    /// Creates a new, empty temporary file beside `target`, after removing what dead
    /// processes left for the same target.
    ///
    /// # Errors
    /// The error of creating the file (a missing or read-only folder, …).
    pub fn file(target: &Path) -> std::io::Result<(Self, File)> {
        let (path, id) = temp_name(target)?;
        let mut registry = lock();
        sweep_once(&mut registry, target);
        let file = OpenOptions::new().write(true).create_new(true).open(&path)?;
        registry.live.push((id, path.clone()));
        Ok((Self { id, path }, file))
    }

    /// Creates a new, empty private folder beside `target` (e.g. for an SQLite file and its
    /// journals), after removing what dead processes left for the same target.
    ///
    /// # Errors
    /// The error of creating the folder.
    pub fn dir(target: &Path) -> std::io::Result<Self> {
        let (path, id) = temp_name(target)?;
        let mut registry = lock();
        sweep_once(&mut registry, target);
        std::fs::create_dir(&path)?;
        registry.live.push((id, path.clone()));
        Ok(Self { id, path })
    }

    /// The temporary file or folder.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempPath {
    fn drop(&mut self) {
        let mut registry = lock();
        remove(&self.path);
        registry.live.retain(|(id, _)| *id != self.id);
    }
}

/// Runs `f` — the renames of temporaries onto their targets — under the registry's lock, so
/// that a signal's [`remove_all`] runs before or after all of them, never between. `f` must
/// not create or drop a [`TempPath`] (the lock is not reentrant).
pub fn while_locked<R>(f: impl FnOnce() -> R) -> R {
    let _registry = lock();
    f()
}

/// Removes every registered temporary and keeps the registry locked for good: what a program
/// ending on a signal calls last (nothing is created or committed after it).
pub fn remove_all() {
    let registry = lock();
    for (_, path) in &registry.live {
        remove(path);
    }
    std::mem::forget(registry);
}

/// Removes a file, or a folder with everything in it; a folder is removed again while another
/// thread creates files in it (at most a few times), so that it ends up gone.
fn remove(path: &Path) {
    for _ in 0..100 {
        let removed = match std::fs::symlink_metadata(path) {
            Err(_) => return,
            Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
            Ok(_) => std::fs::remove_file(path),
        };
        if removed.is_ok() {
            return;
        }
    }
}

/// Removes the temporaries of `target` that processes no longer running left beside it:
/// `.NAME.tmp-PID-N` (files or folders) and the names earlier versions used. Files of running
/// processes, and of this one, stay.
pub fn sweep(target: &Path) {
    let Some(name) = target.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let Ok(entries) = std::fs::read_dir(folder_of(target)) else {
        return;
    };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let owner = match file.strip_prefix(&prefix) {
            Some(rest) => owner_of(rest),
            // The folder probe of earlier versions (`.wfem-probe-PID`).
            None if name == "wfem-probe" => file.strip_prefix(".wfem-probe-").and_then(|p| p.parse().ok()),
            None => None,
        };
        if let Some(pid) = owner {
            if pid != std::process::id() && !is_running(pid) {
                remove(&entry.path());
            }
        }
    }
}

fn sweep_once(registry: &mut Registry, target: &Path) {
    let key = folder_of(target).join(target.file_name().unwrap_or_default());
    if !registry.swept.contains(&key) {
        registry.swept.push(key);
        sweep(target);
    }
}

/// The process id in the rest of a temporary's name after `.NAME.`: `tmp-PID-N`, or the
/// earlier `PID.build…` (an index build and its inner files) and `PID.tmp…` (a store and its
/// SQLite journals).
fn owner_of(rest: &str) -> Option<u32> {
    if let Some(tail) = rest.strip_prefix("tmp-") {
        let (pid, n) = tail.split_once('-')?;
        return (n.bytes().all(|b| b.is_ascii_digit()) && !n.is_empty())
            .then(|| pid.parse().ok())
            .flatten();
    }
    let (pid, tail) = rest.split_once('.')?;
    (tail.starts_with("build") || tail.starts_with("tmp"))
        .then(|| pid.parse().ok())
        .flatten()
}

/// Whether a process with this id runs on this machine (a process of another user counts).
#[cfg(unix)]
#[allow(unsafe_code)]
fn is_running(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: kill with signal 0 sends nothing; it only checks that the process exists.
    let alive = unsafe { libc::kill(pid, 0) } == 0;
    alive || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

/// Without a way to ask, every process counts as running (nothing is removed).
#[cfg(not(unix))]
fn is_running(_pid: u32) -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_are_read_from_every_form_of_name() {
        assert_eq!(owner_of("tmp-123-0"), Some(123));
        assert_eq!(owner_of("tmp-123-45"), Some(123));
        assert_eq!(owner_of("123.build"), Some(123));
        assert_eq!(owner_of("123.build.123.tmp-journal"), Some(123));
        assert_eq!(owner_of("123.tmp-wal"), Some(123));
        assert_eq!(owner_of("tmp-123-"), None);
        assert_eq!(owner_of("tmp-abc-1"), None);
        assert_eq!(owner_of("partial"), None);
        assert_eq!(owner_of("partial.json"), None);
        assert_eq!(owner_of("123.json"), None);
    }

    #[test]
    fn a_temporary_is_removed_when_dropped_and_dead_owners_are_swept() {
        let dir = std::env::temp_dir().join(format!("wfem-tempfiles-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.npy");
        // A dead process (ids this high are not handed out) and a live one (this test's parent
        // or init: pid 1 always runs).
        let dead = dir.join(".out.npy.tmp-2147483000-0");
        let dead_dir = dir.join(".out.npy.2147483001.build");
        let live = dir.join(".out.npy.tmp-1-0");
        let other = dir.join(".other.npy.tmp-2147483000-0");
        std::fs::write(&dead, b"x").unwrap();
        std::fs::create_dir(&dead_dir).unwrap();
        std::fs::write(dead_dir.join("index.sqlite-journal"), b"x").unwrap();
        std::fs::write(&live, b"x").unwrap();
        std::fs::write(&other, b"x").unwrap();
        let (temp, _file) = TempPath::file(&target).unwrap();
        assert!(temp.path().exists());
        assert!(!dead.exists() && !dead_dir.exists(), "a dead process's files stay");
        assert!(
            live.exists() && other.exists(),
            "a running process's or another target's file went"
        );
        let folder = TempPath::dir(&target).unwrap();
        std::fs::write(folder.path().join("a"), b"x").unwrap();
        let (kept, removed) = (temp.path().to_path_buf(), folder.path().to_path_buf());
        drop(temp);
        drop(folder);
        assert!(!kept.exists() && !removed.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
