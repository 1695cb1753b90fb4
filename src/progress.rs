//! Progress of long commands (montecarlo, diagnose, import) on stderr: the
//! indicatif bar on a terminal; elsewhere (batch jobs, CI logs, pipes) a
//! plain line every few seconds, e.g. `montecarlo: 120/400 runs, 14 s, ~33 s
//! left`, so a log shows the job is alive and how far it got.
//!
//! `OBSAN_PROGRESS_SECS` sets the period of the plain lines (default 5; `0`
//! prints a line at every step, `off` none). stdout is never touched.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const DEFAULT_PERIOD: Duration = Duration::from_secs(5);

/// Whether long commands show progress at all. The CLI leaves it on; the
/// Python package turns it off by default (its stderr is a notebook cell or a
/// log, where a line every few seconds is noise) through [`set_enabled`].
static ENABLED: AtomicBool = AtomicBool::new(true);

/// Turn progress display on or off for every command started afterwards.
pub fn set_enabled(on: bool) {
    ENABLED.store(on, Ordering::Relaxed);
}

struct State {
    label: String,
    unit: &'static str,
    /// 0: a task of unknown length (a message and the elapsed time).
    total: u64,
    pos: AtomicU64,
    msg: Mutex<String>,
    start: Instant,
}

impl State {
    fn line(&self) -> String {
        let secs = self.start.elapsed().as_secs_f64();
        let msg = self.msg.lock().map(|m| m.clone()).unwrap_or_default();
        let mut s = format!("{}: ", self.label);
        if self.total > 0 {
            let pos = self.pos.load(Ordering::Relaxed);
            s.push_str(&format!("{pos}/{} {}, {secs:.0} s", self.total, self.unit));
            if pos > 0 && pos < self.total {
                let left = secs / pos as f64 * (self.total - pos) as f64;
                s.push_str(&format!(", ~{left:.0} s left"));
            }
            if !msg.is_empty() {
                s.push_str(&format!(" ({msg})"));
            }
        } else {
            s.push_str(&format!("{msg}, {secs:.0} s"));
        }
        s
    }

    fn print(&self) {
        let _ = writeln!(std::io::stderr().lock(), "{}", self.line());
    }
}

enum Mode {
    Bar(indicatif::ProgressBar),
    /// Plain lines: every step (period zero), or from a ticker thread.
    Lines {
        every_step: bool,
        stop: Option<mpsc::Sender<()>>,
        ticker: Option<JoinHandle<()>>,
    },
    Off,
}

/// One long task's progress; dropping it ends the display.
pub struct Progress {
    state: Arc<State>,
    mode: Mode,
}

/// The period of plain lines from `OBSAN_PROGRESS_SECS`; `None` for `off`.
fn period() -> Option<Duration> {
    match std::env::var("OBSAN_PROGRESS_SECS") {
        Ok(v) if v.trim() == "off" => None,
        Ok(v) => Some(
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|s| s.is_finite() && *s >= 0.0 && *s < 1e6)
                .map_or(DEFAULT_PERIOD, Duration::from_secs_f64),
        ),
        Err(_) => Some(DEFAULT_PERIOD),
    }
}

impl Progress {
    /// `total` steps counted in `unit` (e.g. 400 "runs"), or `total` 0 for a
    /// task of unknown length shown by its message and elapsed time.
    pub fn new(label: &str, total: u64, unit: &'static str) -> Progress {
        let state = Arc::new(State {
            label: label.to_string(),
            unit,
            total,
            pos: AtomicU64::new(0),
            msg: Mutex::new(String::new()),
            start: Instant::now(),
        });
        let mode = if !ENABLED.load(Ordering::Relaxed) {
            Mode::Off
        } else if std::io::stderr().is_terminal() {
            Mode::Bar(bar(label, total, unit))
        } else {
            match period() {
                None => Mode::Off,
                Some(p) if p.is_zero() => Mode::Lines {
                    every_step: true,
                    stop: None,
                    ticker: None,
                },
                Some(p) => {
                    let (tx, rx) = mpsc::channel::<()>();
                    let st = Arc::clone(&state);
                    // Wakes every period until the sender is dropped.
                    let ticker = std::thread::spawn(move || {
                        while let Err(mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(p) {
                            st.print();
                        }
                    });
                    Mode::Lines {
                        every_step: false,
                        stop: Some(tx),
                        ticker: Some(ticker),
                    }
                }
            }
        };
        Progress { state, mode }
    }

    /// One step done.
    pub fn inc(&self) {
        self.state.pos.fetch_add(1, Ordering::Relaxed);
        match &self.mode {
            Mode::Bar(b) => b.inc(1),
            Mode::Lines {
                every_step: true, ..
            } => self.state.print(),
            _ => {}
        }
    }

    /// Steps done so far, for a task that reports its position (the rank
    /// reached) rather than single steps.
    pub fn set_position(&self, pos: u64) {
        self.state.pos.store(pos, Ordering::Relaxed);
        if let Mode::Bar(b) = &self.mode {
            b.set_position(pos);
        }
    }

    /// What is being done now (a stage, a table).
    pub fn set_message(&self, m: &str) {
        if let Ok(mut g) = self.state.msg.lock() {
            *g = m.to_string();
        }
        match &self.mode {
            Mode::Bar(b) => b.set_message(m.to_string()),
            Mode::Lines {
                every_step: true, ..
            } => self.state.print(),
            _ => {}
        }
    }
}

impl Progress {
    /// A line on stderr that does not tear the bar (none while progress is
    /// turned off by [`set_enabled`]: such lines report progress too).
    pub fn println(&self, line: &str) {
        match &self.mode {
            _ if !ENABLED.load(Ordering::Relaxed) => {}
            Mode::Bar(b) => b.println(line),
            _ => {
                let _ = writeln!(std::io::stderr().lock(), "{line}");
            }
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        match &mut self.mode {
            Mode::Bar(b) => b.finish_and_clear(),
            Mode::Lines { stop, ticker, .. } => {
                drop(stop.take());
                if let Some(t) = ticker.take() {
                    let _ = t.join();
                }
            }
            Mode::Off => {}
        }
    }
}

fn bar(label: &str, total: u64, unit: &str) -> indicatif::ProgressBar {
    if total == 0 {
        let b = indicatif::ProgressBar::new_spinner();
        b.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{spinner}} {label}: {{msg}} {{elapsed}}"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        b.enable_steady_tick(Duration::from_millis(120));
        return b;
    }
    let b = indicatif::ProgressBar::new(total);
    b.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{label} {{bar:30}} {{pos}}/{{len}} {unit}, eta {{eta}} {{msg}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    b
}
