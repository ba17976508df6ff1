//! Long calls: the work runs on its own thread while the caller's thread waits *without the
//! GIL* (other Python threads run) and checks for signals every 50 ms, so Ctrl-C raises
//! `KeyboardInterrupt` at once. The abandoned work is told to stop at its next checkpoint
//! ([`Cancel`], between times or blocks) and its result is dropped. A panic in the work
//! becomes `wfem.InternalError` (a bug); it never crosses into Python as `PanicException`.

use crate::errors::Error;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::time::Duration;
use wfem_base::interrupt::Interrupt;

/// Polling period for signals while the work runs.
const POLL: Duration = Duration::from_millis(50);

/// Set when the caller has given up (Ctrl-C, a raising progress callback): the library's
/// interrupt ([`wfem_base::interrupt`]), installed on the worker thread, so every
/// checkpoint of the library (between poles, Lanczos restarts, shapes) stops the work; the
/// bindings check it too, between their own chunks and before writing a file.
#[derive(Clone, Default)]
pub struct Cancel(Interrupt);

impl Cancel {
    /// `Err` once the caller has given up, so the work can stop early.
    pub fn check(&self) -> Result<(), Error> {
        if self.0.is_raised() {
            Err(Error::Invalid("Cancelled", "the call was interrupted".into()))
        } else {
            Ok(())
        }
    }

    /// `f` of every item, in order, checking before each that the caller has not given up.
    pub fn map<T, U>(
        &self,
        items: impl IntoIterator<Item = T>,
        mut f: impl FnMut(T) -> Result<U, Error>,
    ) -> Result<Vec<U>, Error> {
        items
            .into_iter()
            .map(|item| {
                self.check()?;
                f(item)
            })
            .collect()
    }
}

/// Worker threads of abandoned or running calls still alive (for the tests of cancellation).
static LIVE_WORKERS: AtomicUsize = AtomicUsize::new(0);

/// How many worker threads are alive: 0 soon after an interrupted call when its work stopped.
#[pyfunction]
pub fn _live_workers() -> usize {
    LIVE_WORKERS.load(Ordering::SeqCst)
}

/// Counts a live worker for as long as it exists.
struct Live;

impl Live {
    fn new() -> Self {
        LIVE_WORKERS.fetch_add(1, Ordering::SeqCst);
        Live
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        LIVE_WORKERS.fetch_sub(1, Ordering::SeqCst);
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

/// Progress of a long call: the work reports a step (e.g. the shape it has just described)
/// from any of its threads; the caller's thread passes each one to the Python callback while
/// it waits, so the callback runs on the caller's thread, with the GIL, like any Python code.
#[derive(Clone)]
pub struct Progress(Option<Sender<Report>>);

/// What the work tells the caller's thread.
pub enum Report {
    /// One finished step.
    Step(String),
    /// Every step so far has been passed to the callback: answer on this channel.
    Flush(Sender<()>),
}

impl Progress {
    /// Reports one finished step (nothing without a callback).
    pub fn step(&self, what: &str) {
        if let Some(tx) = &self.0 {
            // The receiver is gone if the caller was interrupted: nothing to do then.
            let _ = tx.send(Report::Step(what.to_string()));
        }
    }

    /// Waits until the callback has seen every step reported so far (so that a callback
    /// that raises stops the call before anything is written). Nothing without a callback.
    pub fn flush(&self) {
        if let Some(tx) = &self.0 {
            let (ack_tx, ack_rx) = channel();
            if tx.send(Report::Flush(ack_tx)).is_ok() {
                // Disconnected: the caller gave up (and raised the interrupt).
                let _ = ack_rx.recv();
            }
        }
    }
}

/// Runs `work` on a worker thread, releasing the GIL, interruptible by signals.
pub fn run<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&Cancel) -> Result<T, Error> + Send + 'static,
{
    run_reporting(py, None, move |cancel, _| work(cancel))
}

/// [`run`] with progress: `callback(step)` is called on the caller's thread for every step the
/// work reports. An exception raised by the callback stops the call (the work is cancelled)
/// and propagates.
pub fn run_reporting<T, F>(py: Python<'_>, callback: Option<Py<PyAny>>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&Cancel, &Progress) -> Result<T, Error> + Send + 'static,
{
    let (progress_tx, progress_rx) = channel::<Report>();
    let progress = Progress(callback.is_some().then_some(progress_tx));
    let cancel = Cancel::default();
    let (tx, rx) = channel::<Result<T, Error>>();
    let worker_cancel = cancel.clone();
    std::thread::Builder::new()
        .name("wfem-worker".into())
        .spawn(move || {
            let _live = Live::new();
            let interrupt = worker_cancel.0.clone();
            let result = catch_unwind(AssertUnwindSafe(|| {
                interrupt.install(|| work(&worker_cancel, &progress))
            }))
            .unwrap_or_else(|payload| Err(Error::Panic(panic_message(payload))));
            // The receiver is gone if the caller was interrupted: nothing to do then.
            let _ = tx.send(result);
        })
        .map_err(|e| Error::Panic(format!("cannot start a worker thread: {e}")).into_py(py))?;
    let mut rx = rx;
    let report = |py: Python<'_>, progress_rx: &Receiver<Report>| -> PyResult<()> {
        if let Some(callback) = &callback {
            for report in progress_rx.try_iter() {
                match report {
                    Report::Step(step) => {
                        callback.call1(py, (step,))?;
                    }
                    Report::Flush(ack) => {
                        let _ = ack.send(());
                    }
                }
            }
        }
        Ok(())
    };
    // An interrupted call returns only once the worker has stopped (it sees the cancel at its
    // next check): whatever it writes — a partial file, a finished one — is in place when the
    // caller continues, and a second call never races the first on the same files. Dropping
    // the progress receiver releases a worker waiting in `Progress::flush`.
    let stop = |py: Python<'_>, rx: Receiver<Result<T, Error>>, progress_rx: Receiver<Report>| {
        cancel.0.raise();
        drop(progress_rx);
        py.detach(move || {
            let _ = rx.recv();
        });
    };
    loop {
        // The receiver moves into the GIL-free closure and back (it is Send, not Sync).
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        if let Err(e) = report(py, &progress_rx) {
            stop(py, rx, progress_rx);
            return Err(e);
        }
        match received {
            Ok(result) => return result.map_err(|e| e.into_py(py)),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    stop(py, rx, progress_rx);
                    return Err(e);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(Error::Panic("the worker thread ended without a result".into()).into_py(py))
            }
        }
    }
}
