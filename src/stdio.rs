//! Standard output and standard error that never panic. `println!`, `print!`, `eprintln!` and
//! `eprint!` in this crate are the macros below (they shadow the standard ones from `lib.rs`), so a
//! full disk, `>/dev/full` or a closed stream cannot end a run in a panic:
//!
//! - a failed write to stderr (progress, warnings, errors: diagnostics) is ignored;
//! - a failed write to stdout (what `info`, `bench-table` and `raybench` print: results) is
//!   remembered, the first one only, and `cli::main` ends the run with exit code 2 naming stdout
//!   and the reason ([`stdout_failure`]).

use std::io::Write;
use std::sync::Mutex;

/// The first failed write to stdout, as its reason.
static STDOUT_FAILED: Mutex<Option<String>> = Mutex::new(None);

/// Writes `args` to stdout; a failure is remembered for [`stdout_failure`].
pub fn out(args: std::fmt::Arguments) {
    if let Err(e) = std::io::stdout().lock().write_fmt(args) {
        note_stdout_error(e);
    }
}

/// Writes `args` to stderr, ignoring a failure (the core's).
pub use fuzzy_vpl_core::stdio::err;

fn note_stdout_error(e: std::io::Error) {
    let mut first = STDOUT_FAILED.lock().unwrap_or_else(|p| p.into_inner());
    if first.is_none() {
        *first = Some(e.to_string());
    }
}

/// Flushes stdout and returns the reason of the first write to it that failed, if one did.
pub fn stdout_failure() -> Option<String> {
    if let Err(e) = std::io::stdout().lock().flush() {
        note_stdout_error(e);
    }
    STDOUT_FAILED
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .clone()
}

macro_rules! println {
    () => { $crate::stdio::out(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::stdio::out(format_args!("{}\n", format_args!($($arg)*))) };
}

macro_rules! print {
    ($($arg:tt)*) => { $crate::stdio::out(format_args!($($arg)*)) };
}

macro_rules! eprintln {
    () => { $crate::stdio::err(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::stdio::err(format_args!("{}\n", format_args!($($arg)*))) };
}

// Unused today; here so that an `eprint!` added later cannot panic either.
#[allow(unused_macros)]
macro_rules! eprint {
    ($($arg:tt)*) => { $crate::stdio::err(format_args!($($arg)*)) };
}
