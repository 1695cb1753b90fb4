//! `obsan`: the command-line front end; the command code is the library
//! (`src/lib.rs`), shared with the Python package.

fn main() -> std::process::ExitCode {
    obsan_cli::main()
}
