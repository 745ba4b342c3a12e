//! `fuzzy-vpl`: the command line lives in `fuzzy_vpl::cli` (docs/design.md, "CLI").

fn main() -> std::process::ExitCode {
    fuzzy_vpl::cli::main()
}
