//! How the process stops when it is told to (SIGINT from Ctrl-C, SIGTERM from `kill`, a job
//! scheduler or a container runtime, SIGHUP from a closed terminal) or when a thread panics (a
//! bug): every temporary file it has open through `vlf_bake::atomic` is removed, so the outputs
//! keep their previous contents and nothing is left beside them; then one line on standard error,
//! and exit 130 (SIGINT), 143 (SIGTERM), 129 (SIGHUP) or 1 (a panic). SIGKILL cannot be caught:
//! its leftover is removed by the next write of the same path (`docs/reliability.md`).
//!
//! SIGXFSZ, which the kernel sends to a write past the file size limit (`ulimit -f`), would kill
//! the process on the spot, leaving its temporary file behind and printing nothing. It is caught
//! and ignored instead, so that the write fails with `EFBIG` ("File too large") and the command
//! fails the ordinary way: its temporary file removed, one line, exit 1.
//!
//! The signal handler itself (signal-hook's) only wakes a thread; that thread removes the files,
//! since removing files and printing are not safe in a signal handler. A panicking thread does
//! the same from the panic hook, so a worker that fails ends the process instead of leaving the
//! others waiting for it.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set once the process has begun to stop: from then on the stopping thread owns the exit.
static STOPPING: AtomicBool = AtomicBool::new(false);

/// Exit code after SIGINT: 128 + 2, as a shell reports a process killed by it.
pub const EXIT_SIGINT: i32 = 130;
/// Exit code after SIGTERM: 128 + 15.
pub const EXIT_SIGTERM: i32 = 143;
/// Exit code after SIGHUP: 128 + 1.
pub const EXIT_SIGHUP: i32 = 129;

/// Starts the thread that waits for SIGINT, SIGTERM and SIGHUP, catches SIGXFSZ, and installs the
/// panic hook.
pub fn install() -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM, SIGXFSZ};
        // Caught, not left to its default action (death): the write that exceeded the file size
        // limit then returns EFBIG, which the writer reports. Nothing else needs to know.
        signal_hook::flag::register(SIGXFSZ, std::sync::Arc::new(AtomicBool::new(false)))?;
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
        std::thread::Builder::new().name("vlf-signals".into()).spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let (name, code) = match signal {
                    SIGINT => ("SIGINT", EXIT_SIGINT),
                    SIGHUP => ("SIGHUP", EXIT_SIGHUP),
                    _ => ("SIGTERM", EXIT_SIGTERM),
                };
                stop(&format!("interrupted by {name}"), code);
            }
        })?;
    }
    std::panic::set_hook(Box::new(|info| {
        let payload = info.payload();
        let what = payload
            .downcast_ref::<&str>()
            .copied()
            .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
            .unwrap_or("unknown cause");
        let place = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
        let thread = std::thread::current();
        let name = thread.name().unwrap_or("unnamed");
        stop(&format!("internal error in thread {name}: {what}{place} (a bug, or the system refused a resource)"), 1);
    }));
    Ok(())
}

/// Removes the live temporary files, prints `error: WHAT; …` and exits with `code`. Only the
/// first caller does so; any other (a second signal, a panic meanwhile) waits for it to exit.
fn stop(what: &str, code: i32) -> ! {
    if STOPPING.swap(true, Ordering::SeqCst) {
        park_forever();
    }
    let removed = vlf_bake::atomic::remove_live_temp_files();
    let cleanup = match removed.as_slice() {
        [] => "no temporary file to remove".to_owned(),
        [one] => format!("removed the temporary file {}", one.display()),
        many => format!("removed {} temporary files", many.len()),
    };
    // Not `eprintln!`, which panics if standard error is closed: nothing may panic here.
    let _ = writeln!(std::io::stderr(), "error: {what}; {cleanup}; the outputs keep their previous contents");
    std::process::exit(code);
}

/// Waits for the stopping thread to end the process, if one has begun to: the main thread calls
/// this before returning, so that the exit code and message are the stopping thread's.
pub fn wait_if_stopping() {
    if STOPPING.load(Ordering::SeqCst) {
        park_forever();
    }
}

fn park_forever() -> ! {
    loop {
        std::thread::park();
    }
}
