//! Bad input: an error that is the user's (a file, an option, a value), reported as one line naming
//! what and why, with exit code 2 (`cli::main`), never a panic.

/// An error that is the user's input: exit code 2.
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// `msg` as a `BadInput` error.
pub fn bad(msg: impl Into<String>) -> anyhow::Error {
    BadInput(msg.into()).into()
}
