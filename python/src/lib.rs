//! `obsan._native`: the obsan CLI's command code in-process. One function,
//! [`run_json`], runs `obsan ARGV... --json` on a worker thread and returns
//! its exit code and JSON text; the pure-Python layer (`obsan/__init__.py`)
//! builds the arguments and converts the value.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::time::Duration;

create_exception!(
    obsan,
    ObsanError,
    PyValueError,
    "An error obsan reports (exit code 2 of the CLI): bad input, with the CLI's file:line:col text, or a limit."
);

/// How often the waiting thread takes the GIL back to look for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);
/// How long a cancelled command is given to stop at the engine's next poll.
const CANCEL_GRACE: Duration = Duration::from_secs(2);

/// Run `obsan ARGV...` (ARGV asks for `--json`) and return (exit code, JSON
/// text). `overlay` = (name, text) is a file held in memory: reading `name`
/// reads `text`. The GIL is released while the command runs; Ctrl-C cancels
/// it and raises KeyboardInterrupt.
#[pyfunction]
#[pyo3(signature = (argv, overlay=None))]
fn run_json(
    py: Python<'_>,
    argv: Vec<String>,
    overlay: Option<(String, String)>,
) -> PyResult<(u8, String)> {
    let overlay = overlay.map(|(name, text)| obsan_cli::Overlay { name, text });
    let fail = |f: obsan_cli::Failure| ObsanError::new_err(f.0);
    let mut job = obsan_cli::spawn_json(&argv, overlay).map_err(fail)?;
    loop {
        // The job moves into the GIL-free closure and back (its receiver is
        // not Sync).
        let (j, r) = py.detach(move || {
            let r = job.wait(SIGNAL_POLL);
            (job, r)
        });
        job = j;
        if let Some(r) = r {
            return r.map(|o| (o.code, o.json)).map_err(fail);
        }
        if let Err(interrupt) = py.check_signals() {
            job.cancel();
            // Every long loop polls the flag (the engine, the rank test, the
            // estimators, Monte Carlo): the command ends with "interrupted",
            // waited for (up to the grace) so that its threads are idle when
            // KeyboardInterrupt is raised.
            py.detach(move || {
                let _ = job.wait(CANCEL_GRACE);
            });
            return Err(interrupt);
        }
    }
}

/// How many commands are still running on their threads (one interrupted
/// by Ctrl-C counts until it has stopped).
#[pyfunction]
fn running_commands() -> usize {
    obsan_cli::running_commands()
}

/// Show (true) or hide (false) the progress lines of long commands.
#[pyfunction]
fn set_progress(enabled: bool) {
    obsan_cli::set_progress(enabled);
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(running_commands, m)?)?;
    m.add_function(wrap_pyfunction!(set_progress, m)?)?;
    m.add("ObsanError", m.py().get_type::<ObsanError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
