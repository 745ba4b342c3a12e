//! Standard error that never panics: `eprintln!` and `eprint!` in this crate are the macros below
//! (they shadow the standard ones from `lib.rs`), so a closed or full stderr cannot end a render in
//! a panic: a failed write of a diagnostic (progress, a warning) is ignored. The library writes
//! nothing to stdout; the application's `stdio` adds stdout's results.

use std::io::Write;

/// Writes `args` to stderr, ignoring a failure (nothing is left to tell it on).
pub fn err(args: std::fmt::Arguments) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

macro_rules! eprintln {
    () => { $crate::stdio::err(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::stdio::err(format_args!("{}\n", format_args!($($arg)*))) };
}

macro_rules! eprint {
    ($($arg:tt)*) => { $crate::stdio::err(format_args!($($arg)*)) };
}
