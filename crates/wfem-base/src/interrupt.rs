//! Cooperative interruption of long computations.
//!
//! A caller that may give up on a computation (a Python call interrupted by Ctrl-C, a server
//! request cancelled) creates an [`Interrupt`], runs the computation inside
//! [`Interrupt::install`] and later calls [`Interrupt::raise`]. The long loops of the library
//! — one pole of a shifted solve, one restart of the Lanczos eigensolver, one time of a series,
//! one block of probe columns, one shape of a collection — call [`checkpoint`] between their
//! steps and stop with [`Interrupted`] (wrapped in each crate's error) once it is raised, so
//! abandoned work stops within one step and releases its threads.
//!
//! The interrupt is per thread: parallel loops carry it to their worker threads with
//! [`current`] and [`within`]. Without an installed interrupt a checkpoint is one
//! thread-local read and never fails, so code that never interrupts pays nothing.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A flag shared between the caller that may give up and the computation it started.
#[derive(Clone, Debug, Default)]
pub struct Interrupt(Arc<AtomicBool>);

/// The computation was interrupted ([`Interrupt::raise`]) before it finished.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error, serde::Serialize)]
#[error("the computation was interrupted")]
pub struct Interrupted;

thread_local! {
    static CURRENT: RefCell<Option<Interrupt>> = const { RefCell::new(None) };
}

impl Interrupt {
    /// A new, not raised, interrupt.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every computation running under this interrupt to stop at its next checkpoint.
    pub fn raise(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Self::raise`] was called.
    pub fn is_raised(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Runs `f` with this interrupt installed on the current thread (the previous one is
    /// restored afterwards, also when `f` panics).
    pub fn install<R>(&self, f: impl FnOnce() -> R) -> R {
        within(Some(self), f)
    }
}

/// The interrupt installed on this thread, if any (to carry into parallel workers).
pub fn current() -> Option<Interrupt> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Runs `f` with `interrupt` installed on the current thread (`None`: none), restoring the
/// previous one afterwards — how a parallel loop carries its caller's interrupt.
pub fn within<R>(interrupt: Option<&Interrupt>, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Interrupt>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            CURRENT.with(|c| *c.borrow_mut() = previous);
        }
    }
    let previous = CURRENT.with(|c| std::mem::replace(&mut *c.borrow_mut(), interrupt.cloned()));
    let _restore = Restore(previous);
    f()
}

/// `Err(Interrupted)` when the interrupt installed on this thread has been raised.
///
/// # Errors
/// [`Interrupted`].
pub fn checkpoint() -> Result<(), Interrupted> {
    CURRENT.with(|c| match &*c.borrow() {
        Some(i) if i.is_raised() => Err(Interrupted),
        _ => Ok(()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn a_checkpoint_fails_only_under_a_raised_interrupt() {
        assert_eq!(checkpoint(), Ok(()));
        let i = Interrupt::new();
        i.install(|| {
            assert_eq!(checkpoint(), Ok(()));
            i.raise();
            assert_eq!(checkpoint(), Err(Interrupted));
        });
        // Uninstalled again: the raised flag no longer concerns this thread.
        assert_eq!(checkpoint(), Ok(()));
        assert!(current().is_none());
    }

    #[test]
    fn installs_nest_and_restore_after_a_panic() {
        let outer = Interrupt::new();
        let inner = Interrupt::new();
        inner.raise();
        outer.install(|| {
            let caught = std::panic::catch_unwind(|| inner.install(|| panic!("boom")));
            assert!(caught.is_err());
            // The outer one is back, not raised.
            assert_eq!(checkpoint(), Ok(()));
            assert!(current().is_some_and(|c| !c.is_raised()));
        });
    }

    #[test]
    fn parallel_workers_see_the_callers_interrupt_through_within() {
        let i = Interrupt::new();
        i.raise();
        let seen: Vec<bool> = i.install(|| {
            let carried = current();
            (0..64)
                .into_par_iter()
                .map(|_| within(carried.as_ref(), || checkpoint().is_err()))
                .collect()
        });
        assert!(seen.iter().all(|&s| s));
    }
}
