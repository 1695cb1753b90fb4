//! `obsan`: the command-line front end. Thin glue over the library crates:
//! it alone reads files, formats output and chooses exit codes.
//!
//! Exit codes: 0 success; 1 the command ran but a check it performs failed;
//! 2 bad input (a malformed file, an unknown symbol, a bad flag) or an error.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

/// `print!` to stdout; a closed pipe (`obsan ... | head`) ends the program
/// quietly instead of panicking.
macro_rules! out {
    ($($t:tt)*) => { $crate::emit(format_args!($($t)*), false) };
}
/// `println!`, with [`out!`]'s handling of a closed pipe.
macro_rules! outln {
    () => { $crate::emit(format_args!(""), true) };
    ($($t:tt)*) => { $crate::emit(format_args!($($t)*), true) };
}

mod analysis_cmds;
mod cli;
mod diagnose_cmd;
mod estimate_cmds;
mod expr_cmds;
mod fsio;
mod modes_cmd;
mod plot;
mod show;
mod simulate;

use clap::Parser;
use std::process::ExitCode;

/// An error to report on stderr with exit code 2.
pub struct Failure(pub String);

impl<E: std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Failure {
        Failure(e.to_string())
    }
}

/// Write to stdout. A reader that went away (broken pipe) has all it wanted:
/// exit 0 without a message, as `head` expects; any other write error is one.
pub fn emit(args: std::fmt::Arguments, newline: bool) {
    use std::io::Write;
    let mut o = std::io::stdout().lock();
    let r = o
        .write_fmt(args)
        .and_then(|_| if newline { o.write_all(b"\n") } else { Ok(()) });
    if let Err(e) = r {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: cannot write the output: {e}");
        std::process::exit(2);
    }
}

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    let Some(secs) = args.command.timeout() else {
        return run(args.command);
    };
    // The whole command runs on a worker; the deadline covers every stage,
    // including long exact computations that cannot poll a clock themselves.
    let (tx, rx) = std::sync::mpsc::channel();
    let command = args.command;
    std::thread::spawn(move || {
        let _ = tx.send(run(command));
    });
    // `seconds` in cli.rs bounds the value, so the Duration cannot overflow.
    match rx.recv_timeout(std::time::Duration::from_secs_f64(secs)) {
        Ok(code) => code,
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            eprintln!("error: timed out after {secs} s (--timeout)");
            ExitCode::from(2)
        }
        // The worker ended without an answer: it panicked, and said so on stderr.
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => ExitCode::from(101),
    }
}

fn run(command: cli::Command) -> ExitCode {
    let result = match command {
        cli::Command::Show(a) => show::run(&a),
        cli::Command::Simplify(a) => expr_cmds::simplify(&a),
        cli::Command::Diff(a) => expr_cmds::diff(&a),
        cli::Command::Rank(a) => analysis_cmds::rank(&a),
        cli::Command::Symmetries(a) => analysis_cmds::symmetries(&a),
        cli::Command::Lie(a) => analysis_cmds::lie(&a),
        cli::Command::Check(a) => analysis_cmds::check(&a),
        cli::Command::Verify(a) => analysis_cmds::verify(&a),
        cli::Command::Modes(a) => modes_cmd::run(&a),
        cli::Command::Simulate(a) => simulate::run(&a),
        cli::Command::Calibrate(a) => estimate_cmds::calibrate_cmd(&a),
        cli::Command::Crlb(a) => estimate_cmds::crlb_cmd(&a),
        cli::Command::Montecarlo(a) => estimate_cmds::montecarlo_cmd(&a),
        cli::Command::Diagnose(a) => diagnose_cmd::run(&a),
        cli::Command::Import(cli::ImportCommand::Mrclam(a)) => diagnose_cmd::import_mrclam(&a),
    };
    match result {
        Ok(code) => code,
        Err(Failure(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
    }
}
