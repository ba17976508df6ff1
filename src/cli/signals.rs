//! SIGINT, SIGTERM and SIGHUP end the program without leaving a temporary file (issue #41).
//!
//! [`install`], first thing in `main`, blocks these signals in the main thread, so every
//! thread started later (rayon's workers, the progress bar's) has them blocked too, and one
//! thread waits for them (`sigwait`). When one arrives, that thread removes every temporary of
//! the run ([`wfem_base::tempfiles::remove_all`], which also keeps any temporary from being
//! created or renamed afterwards) and ends the program as the signal would have (its default
//! action: the exit status says which signal). A signal ignored when `wfem` started (`nohup`,
//! a background job of a script) stays ignored. Files SQLite keeps beside an index it has open
//! (`-wal`, `-shm`) are the index's own: the next open folds them in, as after a kill.

/// Waits for the signals that end the program on a thread of its own (see the module docs).
#[cfg(unix)]
#[allow(unsafe_code)]
pub fn install() {
    // SAFETY: plain libc calls on a signal set owned here, before any other thread exists.
    unsafe {
        let mut set: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut set);
        for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            let mut old: libc::sigaction = std::mem::zeroed();
            let ignored = libc::sigaction(signal, std::ptr::null(), &mut old) == 0 && old.sa_sigaction == libc::SIG_IGN;
            if !ignored {
                libc::sigaddset(&mut set, signal);
            }
        }
        if libc::pthread_sigmask(libc::SIG_BLOCK, &set, std::ptr::null_mut()) != 0 {
            return;
        }
        let waiter = std::thread::Builder::new()
            .name("wfem-signals".into())
            .spawn(move || wait(set));
        if waiter.is_err() {
            // No one would answer the signals: leave them to their default action.
            libc::pthread_sigmask(libc::SIG_UNBLOCK, &set, std::ptr::null_mut());
        }
    }
}

/// The signal thread: the first signal of `set` removes the temporaries and ends the process.
#[cfg(unix)]
#[allow(unsafe_code)]
fn wait(set: libc::sigset_t) {
    let mut signal: libc::c_int = 0;
    // SAFETY: sigwait on a set of blocked signals; `signal` is written by it.
    while unsafe { libc::sigwait(&set, &mut signal) } != 0 {}
    wfem_base::tempfiles::remove_all();
    // SAFETY: restore the default action and raise the signal again on this thread, where it
    // is unblocked: the process ends as if it had not been caught.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        let mut only: libc::sigset_t = std::mem::zeroed();
        libc::sigemptyset(&mut only);
        libc::sigaddset(&mut only, signal);
        libc::pthread_sigmask(libc::SIG_UNBLOCK, &only, std::ptr::null_mut());
        libc::raise(signal);
        // Not reached for a terminating signal; the shell's convention otherwise.
        libc::_exit(128 + signal);
    }
}

/// Elsewhere the signals keep their default action.
#[cfg(not(unix))]
pub fn install() {}
