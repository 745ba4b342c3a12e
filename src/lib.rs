//! fuzzy-vpl, the application: the command line (`cli`), the viewer (`app`) and the bench
//! (`bench`), on the core crate `fuzzy_vpl_core` (scene, BVH, GPU passes, methods, renderer,
//! metrics, settings), which this crate re-exports whole: `fuzzy_vpl::render` is
//! `fuzzy_vpl_core::render`. A program that embeds the renderer depends on the core alone
//! (`crates/core/examples/embed.rs`).

// First, so that the crate's `println!`, `print!`, `eprintln!` and `eprint!` are these macros,
// which never panic on a full or closed stream.
#[macro_use]
pub mod stdio;

pub use fuzzy_vpl_core::*;

pub mod app;
pub mod bench;
pub mod cli;
