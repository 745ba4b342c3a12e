//! Panics turned into one-line errors, quietly. A scene load (a hostile file can still reach a
//! dependency's panic) and the viewer's frame worker (a wgpu validation error is a panic) run their
//! work through [`quietly`]: a panic inside prints nothing on stderr and comes back as its message,
//! so the user sees one clear line instead of a Rust panic report. Panics elsewhere go to the hook
//! that was installed before (Rust's default report).

use std::cell::{Cell, RefCell};

thread_local! {
    /// Set while `quietly` runs on this thread: the panic hook then records instead of printing.
    static QUIET: Cell<bool> = const { Cell::new(false) };
    static MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Installs (once) the hook that stays silent inside `quietly` on the current thread and defers to
/// the previously installed hook for everything else.
fn install_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) {
                let msg = info.payload_as_str().unwrap_or("unknown panic");
                let at = info
                    .location()
                    .map(|l| format!(" at {}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                MESSAGE.with(|m| *m.borrow_mut() = Some(one_line(&format!("{msg}{at}"))));
            } else {
                previous(info)
            }
        }));
    });
}

/// Runs `f`; a panic inside it prints nothing and returns as `Err(message at file:line)`, on one
/// line. Nests: an inner `quietly` catches its own panics and leaves the outer one quiet.
pub fn quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install_hook();
    let was_quiet = QUIET.with(|q| q.replace(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was_quiet));
    result.map_err(|_| {
        MESSAGE
            .with(|m| m.borrow_mut().take())
            .unwrap_or_else(|| "unknown panic".into())
    })
}

/// Whether a panic on this thread would be caught quietly now (outside `quietly`: false).
pub fn is_quiet() -> bool {
    QUIET.with(Cell::get)
}

/// Collapses all whitespace (newlines included) to single spaces.
pub fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_its_message_on_one_line() {
        let e = quietly(|| -> u32 { panic!("first\nsecond {}", 2) }).unwrap_err();
        assert!(e.starts_with("first second 2 at "), "{e}");
        assert!(e.contains("panic_guard.rs"), "{e}");
        assert_eq!(quietly(|| 7), Ok(7));
        assert!(!is_quiet());
    }

    #[test]
    fn nested_guards_keep_the_outer_one_quiet() {
        let outer = quietly(|| {
            let inner = quietly(|| -> () { panic!("inner") });
            assert!(inner.unwrap_err().starts_with("inner at "));
            assert!(is_quiet());
            panic!("outer")
        });
        assert!(outer.unwrap_err().starts_with("outer at "));
        assert!(!is_quiet());
    }
}
