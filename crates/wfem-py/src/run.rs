//! Long calls: the work runs on its own thread while the caller's thread waits *without the
//! GIL* (other Python threads run) and checks for signals every 50 ms, so Ctrl-C raises
//! `KeyboardInterrupt` at once. The abandoned work is told to stop at its next checkpoint
//! ([`Cancel`], between times or blocks) and its result is dropped. A panic in the work
//! becomes `wfem.InternalError` (a bug); it never crosses into Python as `PanicException`.

use crate::errors::Error;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;

/// Polling period for signals while the work runs.
const POLL: Duration = Duration::from_millis(50);

/// Set when the caller has given up (Ctrl-C); checked by the work between chunks.
#[derive(Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// `Err` once the caller has given up, so the work can stop early.
    pub fn check(&self) -> Result<(), Error> {
        if self.0.load(Ordering::Relaxed) {
            Err(Error::Invalid("Cancelled", "the call was interrupted".into()))
        } else {
            Ok(())
        }
    }
}

fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".into()
    }
}

/// Runs `work` on a worker thread, releasing the GIL, interruptible by signals.
pub fn run<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&Cancel) -> Result<T, Error> + Send + 'static,
{
    let cancel = Cancel::default();
    let (tx, rx) = channel::<Result<T, Error>>();
    let worker_cancel = cancel.clone();
    std::thread::Builder::new()
        .name("wfem-worker".into())
        .spawn(move || {
            let result = catch_unwind(AssertUnwindSafe(|| work(&worker_cancel)))
                .unwrap_or_else(|payload| Err(Error::Panic(panic_message(payload))));
            // The receiver is gone if the caller was interrupted: nothing to do then.
            let _ = tx.send(result);
        })
        .map_err(|e| Error::Panic(format!("cannot start a worker thread: {e}")).into_py(py))?;
    let mut rx = rx;
    loop {
        // The receiver moves into the GIL-free closure and back (it is Send, not Sync).
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match received {
            Ok(result) => return result.map_err(|e| e.into_py(py)),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    cancel.0.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Error::Panic("the worker thread ended without a result".into()).into_py(py))
            }
        }
    }
}
