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
mod progress;
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

thread_local! {
    /// Output held back while a command runs under the engine's budget.
    static HOLD: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Write to stdout. A reader that went away (broken pipe) has all it wanted:
/// exit 0 without a message, as `head` expects; any other write error is one.
pub fn emit(args: std::fmt::Arguments, newline: bool) {
    use std::io::Write;
    let held = HOLD.with(|h| {
        let mut h = h.borrow_mut();
        let buf = h.as_mut()?;
        use std::fmt::Write as _;
        let _ = buf.write_fmt(args);
        if newline {
            buf.push('\n');
        }
        Some(())
    });
    if held.is_some() {
        return;
    }
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
    // Panics that follow an exceeded engine budget are reported as the limit
    // (see `run`); any other panic is a bug and prints as usual.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !obsan_expr::budget_tripped() {
            default_hook(info)
        }
    }));
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
    // The exact commands run under the engine's budget on this thread, for
    // every context they make (normal forms too), with their stdout held
    // back: on a limit, what they computed is placeholders and is dropped.
    let result = match command.max_terms() {
        Some(max_terms) => {
            let budget = obsan_expr::Budget {
                max_terms,
                ..obsan_expr::Budget::default()
            };
            HOLD.with(|h| *h.borrow_mut() = Some(String::new()));
            // A check of a library's on a placeholder may panic once the
            // budget has tripped; that panic is the limit's, caught inside
            // the scope so the limit is still known.
            let r = obsan_expr::within_thread_budget(&budget, || {
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| dispatch(command)))
            });
            let held = HOLD.with(|h| h.borrow_mut().take()).unwrap_or_default();
            match r {
                Ok(Ok(r)) => {
                    emit(format_args!("{held}"), false);
                    r
                }
                Ok(Err(panic)) => std::panic::resume_unwind(panic),
                Err(limit) => Err(Failure(limit.to_string())),
            }
        }
        None => dispatch(command),
    };
    match result {
        Ok(code) => code,
        Err(Failure(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
    }
}

fn dispatch(command: cli::Command) -> Result<ExitCode, Failure> {
    match command {
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
    }
}
