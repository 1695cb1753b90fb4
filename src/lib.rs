//! `obsan`'s command code as a library: the `obsan` binary (`src/main.rs`)
//! calls [`main`], and the Python package (`python/`) calls [`spawn_json`],
//! so the two share one renderer and their JSON cannot drift. Thin glue over
//! the library crates: it alone reads files, formats output and chooses exit
//! codes.
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

mod along_cmd;
mod analysis_cmds;
mod cli;
mod clock;
mod design_cmd;
mod diagnose_cmd;
mod diagnose_levels;
mod diagnose_report;
mod diagnose_units;
mod estimate_cmds;
mod experiments_cmd;
mod expr_cmds;
mod figures;
mod fsio;
mod global_cmd;
mod import_cmd;
mod input_table;
pub mod json;
mod modes_cmd;
mod montecarlo_cmd;
mod progress;
mod reduced_text;
mod show;
mod sim_drive;
mod simulate;
mod simulate_sys;
mod unknown_input_cmd;
mod unknown_input_modes_text;

use clap::Parser;
use std::process::ExitCode;

pub use fsio::Overlay;
/// The reader of `simulate MODEL.sys --inputs FILE.csv` (its fuzz target calls it).
pub use input_table::{read_input_table, InputTable};

/// An error to report on stderr with exit code 2.
#[derive(Debug)]
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

/// Panics that follow an exceeded engine budget are reported as the limit
/// (see `run`); any other panic is a bug and prints as usual. Installed once
/// per process, chained to the hook in place.
pub fn install_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default_hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !obsan_expr::limits::budget_tripped() {
                default_hook(info)
            }
        }));
    });
}

/// How long past `--timeout` the watchdog waits before it ends a command. The
/// stages that poll the engine's deadline (set to `--timeout` itself) stop on
/// time and say how far they got; the watchdog is the backstop for work that
/// cannot poll, and firing at the same instant raced them under load.
const WATCHDOG_GRACE: std::time::Duration = std::time::Duration::from_secs(1);

/// The watchdog's wait for a `--timeout` of `secs`.
fn watchdog(secs: f64) -> std::time::Duration {
    // `seconds` in cli.rs bounds the value, so the Duration cannot overflow.
    std::time::Duration::from_secs_f64(secs) + WATCHDOG_GRACE
}

/// The `obsan` program: arguments from the process, output to stdout and
/// stderr, the exit code returned.
pub fn main() -> ExitCode {
    install_panic_hook();
    end_on_signals();
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
    match rx.recv_timeout(watchdog(secs)) {
        Ok(code) => code,
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            // The worker is still running: remove what it was writing.
            fsio::abandon_writes();
            eprintln!("error: timed out after {secs} s (--timeout)");
            ExitCode::from(2)
        }
        // The worker ended without an answer: it panicked, and said so on stderr.
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => ExitCode::from(101),
    }
}

/// On SIGINT or SIGTERM, remove the temporary folders being written (a
/// large `simulate` writes 100 MB) and exit with 128 + the signal's number,
/// as a shell reports a process ended by it. Only the binary does this: the
/// Python package keeps Python's own Ctrl-C handling (it cancels the job).
fn end_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return; // the default handling (the process ends) stays
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            fsio::abandon_writes();
            let name = if sig == SIGINT { "SIGINT" } else { "SIGTERM" };
            eprintln!("error: interrupted ({name})");
            std::process::exit(128 + sig);
        }
    });
}

fn run(command: cli::Command) -> ExitCode {
    match execute(command, false) {
        Ok((code, held)) => {
            if let Some(held) = held {
                emit(format_args!("{held}"), false);
            }
            match code {
                Ok(code) => code,
                Err(Failure(msg)) => {
                    eprintln!("error: {msg}");
                    ExitCode::from(2)
                }
            }
        }
        Err(Failure(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
    }
}

/// The longest canonical form the exact commands print (text, factored or
/// LaTeX, one form at a time). Printed text can be exponentially longer than
/// the form (a leaf is written out wherever it occurs: 77 characters of input
/// print as 19.7 MB), and such text is of no use to a reader, so past this it
/// is an error, exit code 2, as the engine's other limits are.
const MAX_FORM_BYTES: usize = 1 << 20;

/// The command's result, and its stdout if it was held back. The exact
/// commands run under the engine's budget on this thread, for every context
/// they make (normal forms too), with their stdout held back: on a limit
/// (the outer `Err`), what they computed is placeholders and is dropped.
/// `hold` holds back the stdout of the other commands too (the library's
/// callers want it as a value).
#[allow(clippy::type_complexity)]
fn execute(
    command: cli::Command,
    hold: bool,
) -> Result<(Result<ExitCode, Failure>, Option<String>), Failure> {
    // Clear the buffer however this ends, so a later command starts clean.
    struct Release;
    impl Drop for Release {
        fn drop(&mut self) {
            HOLD.with(|h| h.borrow_mut().take());
        }
    }
    let take = || HOLD.with(|h| h.borrow_mut().take());
    let _release = Release;
    match command.max_terms() {
        Some(max_terms) => {
            let budget = obsan_expr::Budget {
                max_terms,
                ..obsan_expr::Budget::default()
            };
            HOLD.with(|h| *h.borrow_mut() = Some(String::new()));
            // A check of a library's on a placeholder may panic once the
            // budget has tripped; that panic is the limit's, caught inside
            // the scope so the limit is still known.
            // Every form printed is capped too: a form past MAX_FORM_BYTES
            // trips the budget like any other limit (never a cut-short form).
            let (r, tripped) = obsan_expr::limits::within_thread_budget_keep(&budget, || {
                obsan_expr::text::within_text_cap(MAX_FORM_BYTES, || {
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| dispatch(command)))
                })
            });
            let r = match (r, tripped) {
                (r, None) => r,
                // An error that names the limit and where in the input it
                // was reached (file:line:col, the argument's column) says
                // more than the limit alone.
                (Ok(Ok(Err(f))), Some(l))
                    if f.0.contains(&l.to_string()) && f.0.len() > l.to_string().len() =>
                {
                    Ok(Ok(Err(f)))
                }
                (_, Some(l)) => Err(l),
            };
            let held = take();
            match r {
                Ok(Ok(r)) => Ok((r, held)),
                Ok(Err(panic)) => std::panic::resume_unwind(panic),
                Err(limit @ obsan_expr::Limit::Text { .. }) => Err(Failure(format!(
                    "a canonical form is too long to print: {limit} (obsan's output limit, {} MiB)",
                    MAX_FORM_BYTES >> 20
                ))),
                Err(limit) => Err(Failure(limit.to_string())),
            }
        }
        None if hold => {
            HOLD.with(|h| *h.borrow_mut() = Some(String::new()));
            let r = dispatch(command);
            Ok((r, take()))
        }
        None => Ok((dispatch(command), None)),
    }
}

/// What a command run through [`spawn_json`] gave: its exit code (0, or 1
/// when a check it performs failed) and its `--json` output, checked to be
/// one JSON value (`null` for a command that prints nothing, e.g. simulate).
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub code: u8,
    pub json: String,
}

/// A command running on its own thread (see [`spawn_json`]).
pub struct Job {
    rx: std::sync::mpsc::Receiver<Result<Outcome, Failure>>,
    cancel: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// The `--timeout` deadline and its seconds, for the message.
    deadline: Option<(std::time::Instant, f64)>,
}

impl Job {
    /// Wait up to `step` for the result; `None` while the command runs. A
    /// passed `--timeout` is the CLI's error (and cancels the command).
    pub fn wait(&self, step: std::time::Duration) -> Option<Result<Outcome, Failure>> {
        use std::sync::mpsc::RecvTimeoutError;
        let now = std::time::Instant::now();
        let step = match self.deadline {
            Some((d, _)) => step.min(d.saturating_duration_since(now)),
            None => step,
        };
        match self.rx.recv_timeout(step) {
            Ok(r) => Some(r),
            Err(RecvTimeoutError::Timeout) => match self.deadline {
                Some((d, secs)) if std::time::Instant::now() >= d => {
                    self.cancel();
                    Some(Err(Failure(format!(
                        "timed out after {secs} s (--timeout)"
                    ))))
                }
                _ => None,
            },
            Err(RecvTimeoutError::Disconnected) => Some(Err(Failure(
                "internal error: the command's thread ended without an answer".into(),
            ))),
        }
    }

    /// Ask the command to stop: the engine's exact work stops where it polls
    /// its budget ([`obsan_expr::with_cancel`]), and the loops outside it
    /// (the F_p rank test, the estimators, Monte Carlo runs on every worker
    /// thread) where they poll [`obsan_expr::cancel_requested`]; the command
    /// then ends with the error "interrupted".
    pub fn cancel(&self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Commands started by [`spawn_json`] whose thread has not ended yet.
static RUNNING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many commands started by [`spawn_json`] are still running (a
/// cancelled one counts until its thread has stopped).
pub fn running_commands() -> usize {
    RUNNING.load(std::sync::atomic::Ordering::SeqCst)
}

/// Show or hide the progress of long commands started afterwards (the Python
/// package hides it by default).
pub fn set_progress(on: bool) {
    progress::set_enabled(on);
}

/// Start `obsan ARGV...` on a worker thread, its stdout held back as the
/// result: the same command code as the binary, so the Python package's
/// values are the CLI's `--json` (ARGV must ask for it where the command
/// has it). Bad arguments are an error at once. `overlay` is a file held in
/// memory (`obsan.loads`).
pub fn spawn_json(argv: &[String], overlay: Option<Overlay>) -> Result<Job, Failure> {
    let args =
        cli::Cli::try_parse_from(std::iter::once("obsan").chain(argv.iter().map(|s| s.as_str())))
            .map_err(|e| {
            let text = e.to_string();
            let text = text.trim_end();
            Failure(text.strip_prefix("error: ").unwrap_or(text).to_string())
        })?;
    let command = args.command;
    let deadline = command
        .timeout()
        .map(|secs| (std::time::Instant::now() + watchdog(secs), secs));
    let cancel = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = cancel.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    install_panic_hook();
    /// Counts the command in [`RUNNING`] until its thread ends, however it ends.
    struct Counted;
    impl Drop for Counted {
        fn drop(&mut self) {
            RUNNING.fetch_sub(1, std::sync::atomic::Ordering::SeqCst);
        }
    }
    RUNNING.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let counted = Counted;
    std::thread::Builder::new()
        .name("obsan".into())
        // As much stack as the binary's main thread has.
        .stack_size(8 << 20)
        .spawn(move || {
            let _counted = counted;
            fsio::set_overlay(overlay);
            let cancelled = flag.clone();
            let r = obsan_expr::with_cancel(flag, || {
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| execute(command, true)))
            });
            fsio::set_overlay(None);
            // Whatever a cancelled command returns was computed from work cut
            // short (a fit stopped early, a candidate skipped): not an answer.
            if cancelled.load(std::sync::atomic::Ordering::Relaxed) {
                let _ = tx.send(Err(Failure("interrupted".into())));
                return;
            }
            let _ = tx.send(match r {
                Ok(Ok((code, held))) => code.and_then(|code| outcome(code, held)),
                Ok(Err(f)) => Err(f),
                Err(panic) => {
                    let what = panic
                        .downcast_ref::<String>()
                        .map(String::as_str)
                        .or_else(|| panic.downcast_ref::<&str>().copied())
                        .unwrap_or("a panic");
                    Err(Failure(format!(
                        "internal error (a bug; please report the input): {what}"
                    )))
                }
            });
        })
        .map_err(|e| Failure(format!("cannot start a thread: {e}")))?;
    Ok(Job {
        rx,
        cancel,
        deadline,
    })
}

/// [`spawn_json`] and wait for the result.
pub fn run_json(argv: &[String], overlay: Option<Overlay>) -> Result<Outcome, Failure> {
    let job = spawn_json(argv, overlay)?;
    loop {
        if let Some(r) = job.wait(std::time::Duration::from_secs(1)) {
            return r;
        }
    }
}

/// A finished command's exit code and held output as an [`Outcome`].
fn outcome(code: ExitCode, held: Option<String>) -> Result<Outcome, Failure> {
    let code = if code == ExitCode::SUCCESS {
        0
    } else if code == ExitCode::from(1) {
        1
    } else {
        return Err(Failure("internal error: an unexpected exit code".into()));
    };
    let held = held.unwrap_or_default();
    let text = held.trim();
    if text.is_empty() {
        return Ok(Outcome {
            code,
            json: "null".into(),
        });
    }
    match serde_json::from_str::<serde_json::Value>(text) {
        Ok(_) => Ok(Outcome {
            code,
            json: text.to_string(),
        }),
        Err(e) => Err(Failure(format!(
            "internal error: the command printed something other than one JSON value ({e}); was --json given?"
        ))),
    }
}

/// The command's name as typed, for refusals that name it (explicit time).
fn command_name(command: &cli::Command) -> &'static str {
    use cli::Command as C;
    match command {
        C::Show(_) => "show",
        C::Simplify(_) => "simplify",
        C::Diff(_) => "diff",
        C::Rank(a) if a.along.is_some() => "rank --along",
        C::Rank(a) if a.sys.experiments.as_deref() == Some("auto") => "rank --experiments auto",
        C::Rank(a) if !a.known.is_empty() || !a.known_generic.is_empty() => "rank --known",
        C::Rank(_) => "rank",
        C::Symmetries(_) => "symmetries",
        C::Lie(_) => "lie",
        C::Check(_) => "check",
        C::Verify(_) => "verify",
        C::Modes(_) => "modes",
        C::Simulate(_) => "simulate",
        C::Calibrate(_) => "calibrate",
        C::Crlb(_) => "crlb",
        C::Montecarlo(_) => "montecarlo",
        C::Diagnose(_) => "diagnose",
        C::Global(_) => "global",
        C::Design(_) => "design",
        C::Import(_) => "import",
        C::Schema(_) => "schema",
    }
}

fn dispatch(command: cli::Command) -> Result<ExitCode, Failure> {
    clock::set_command(command_name(&command));
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
        cli::Command::Montecarlo(a) => montecarlo_cmd::montecarlo_cmd(&a),
        cli::Command::Diagnose(a) => diagnose_cmd::run(&a),
        cli::Command::Import(cli::ImportCommand::Mrclam(a)) => diagnose_cmd::import_mrclam(&a),
        cli::Command::Global(a) => global_cmd::run(&a),
        cli::Command::Design(a) => design_cmd::run(&a),
        cli::Command::Import(cli::ImportCommand::SiJl(a)) => import_cmd::si_jl(&a),
        cli::Command::Import(cli::ImportCommand::Sbml(a)) => import_cmd::sbml(&a),
        cli::Command::Import(cli::ImportCommand::Petab(a)) => import_cmd::petab(&a),
        cli::Command::Import(cli::ImportCommand::StrikeGoldd(a)) => import_cmd::strike_goldd(&a),
        cli::Command::Schema(a) => json::schema_cmd(&a),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn argv(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| s.to_string()).collect()
    }

    const LOCALIZATION: &str = "system localization\nstate D, phiR, thetaR\ninput v, omega\n\
        D' = v*cos(thetaR - phiR)\nphiR' = v*sin(thetaR - phiR)/D\nthetaR' = omega\noutput y = D\n";

    #[test]
    fn a_command_gives_its_json_value() {
        let o = run_json(&argv(&["simplify", "-x^2 + (x+1)^2", "--json"]), None).unwrap();
        assert_eq!(o.code, 0);
        let v: serde_json::Value = serde_json::from_str(&o.json).unwrap();
        assert_eq!(v["canonical"], "2*x + 1");
        assert_eq!(v["is_zero"], false);
    }

    #[test]
    fn an_overlay_is_read_in_place_of_the_file() {
        let src = Some(Overlay {
            name: "<string>".into(),
            text: LOCALIZATION.into(),
        });
        let o = run_json(&argv(&["rank", "<string>", "--json"]), src).unwrap();
        let v: serde_json::Value = serde_json::from_str(&o.json).unwrap();
        // Section II of the paper: rank 2 of 3.
        assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(3)));
        // The overlay was that thread's only: the name is a missing file again.
        let e = run_json(&argv(&["rank", "<string>", "--json"]), None).unwrap_err();
        assert!(e.0.starts_with("cannot read <string>"), "{}", e.0);
    }

    #[test]
    fn errors_keep_the_cli_text_with_line_and_column() {
        let src = Some(Overlay {
            name: "<string>".into(),
            text: "system t\nstate x\noutput y = x\n".into(),
        });
        let e = run_json(&argv(&["rank", "<string>", "--json"]), src).unwrap_err();
        assert!(
            e.0.starts_with("<string>:2:7: state 'x' has no equation"),
            "{}",
            e.0
        );
        let e = run_json(&argv(&["rank", "--no-such-flag"]), None).unwrap_err();
        assert!(e.0.contains("--no-such-flag"), "{}", e.0);
    }

    #[test]
    fn a_failed_check_is_exit_code_1_with_its_value() {
        let src = Some(Overlay {
            name: "<string>".into(),
            text: LOCALIZATION.into(),
        });
        // phiR alone is not invariant under the rotation [0, 1, 1].
        let o = run_json(
            &argv(&["check", "<string>", "--mode", "phiR", "--json"]),
            src,
        )
        .unwrap();
        assert_eq!(o.code, 1);
        let v: serde_json::Value = serde_json::from_str(&o.json).unwrap();
        assert_eq!(v["checks"][0]["observable_mode"], false);
    }

    #[test]
    fn text_output_is_refused_as_not_json() {
        let e = run_json(&argv(&["simplify", "x"]), None).unwrap_err();
        assert!(e.0.contains("other than one JSON value"), "{}", e.0);
    }

    #[test]
    fn cancel_stops_exact_work() {
        // 2^20 terms: many seconds of expansion unless stopped.
        let product: Vec<String> = (0..20).map(|i| format!("(a{i} + b{i})")).collect();
        let job = spawn_json(
            &argv(&[
                "simplify",
                &product.join("*"),
                "--max-terms",
                "100000000",
                "--json",
            ]),
            None,
        )
        .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(200));
        job.cancel();
        let start = std::time::Instant::now();
        let r = loop {
            if let Some(r) = job.wait(std::time::Duration::from_secs(1)) {
                break r;
            }
            assert!(start.elapsed().as_secs() < 60, "the engine did not stop");
        };
        assert_eq!(r.unwrap_err().0, "interrupted");
    }

    #[test]
    fn cancel_stops_monte_carlo_runs_on_their_worker_threads() {
        // 400 runs of five estimators: minutes unless stopped.
        let job = spawn_json(
            &argv(&[
                "montecarlo",
                "--table",
                "5",
                "--cell",
                "1",
                "--runs",
                "400",
                "--json",
            ]),
            None,
        )
        .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(300));
        job.cancel();
        let start = std::time::Instant::now();
        let r = loop {
            if let Some(r) = job.wait(std::time::Duration::from_secs(1)) {
                break r;
            }
            assert!(start.elapsed().as_secs() < 60, "the runs did not stop");
        };
        assert_eq!(r.unwrap_err().0, "interrupted");
    }

    #[test]
    fn a_passed_timeout_is_the_cli_error() {
        let product: Vec<String> = (0..20).map(|i| format!("(a{i} + b{i})")).collect();
        let e = run_json(
            &argv(&[
                "simplify",
                &product.join("*"),
                "--max-terms",
                "100000000",
                "--timeout",
                "0.2",
                "--json",
            ]),
            None,
        )
        .unwrap_err();
        assert_eq!(e.0, "timed out after 0.2 s (--timeout)");
    }
}
