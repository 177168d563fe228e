//! SIGINT and SIGTERM for commands that write results: the first signal
//! asks the command to stop at its next safe point (a run's next major
//! step, a sweep's next case) and write what it has; a second ends the
//! process at once, removing its temporaries. Exit code 130 either way.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// The flag the first SIGINT or SIGTERM raises (installs the handler).
pub(crate) fn flag() -> &'static AtomicBool {
    let _ = ctrlc::set_handler(|| {
        if REQUESTED.swap(true, Ordering::Relaxed) {
            ctlgraph::record::remove_temporaries();
            std::process::exit(130);
        }
    });
    &REQUESTED
}

/// Output into a closed pipe (`ctlgraph … | head`) ends the process quietly,
/// as it does for cat, git and grep: SIGPIPE goes back to its default
/// action, which the Rust runtime replaces by an error that `print!`
/// turns into a panic.
pub(crate) fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread exists;
    // setting a signal's disposition to its default has no other effect.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
