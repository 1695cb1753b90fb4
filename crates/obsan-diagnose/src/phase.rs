//! Where a diagnosis's time goes: with `OBSAN_DIAG_PHASES` set, each phase
//! of the workflow adds its process CPU (all threads, from /proc/self/stat)
//! and wall time to a tally printed on stderr when the diagnosis ends. Off,
//! a phase costs one cached env read. Phases are timed on the workflow's own
//! thread and never nested, so their CPU adds up to the run's.
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

/// Per phase: name, CPU seconds, wall seconds, calls.
static TALLY: Mutex<Vec<(&'static str, f64, f64, usize)>> = Mutex::new(Vec::new());

fn on() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("OBSAN_DIAG_PHASES").is_some())
}

/// The process's user + system CPU seconds (Linux; 0 elsewhere). The clock
/// tick is taken as 100 Hz, the kernel's USER_HZ on every Linux ABI.
fn cpu() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which may hold spaces): state is
    // field 3, utime 14 and stime 15.
    let rest = s.rsplit_once(')').map_or("", |r| r.1);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|x| x.parse().ok())
        .collect();
    f.iter().sum::<f64>() / 100.0
}

/// Run `f`, tallied under `name` when timing is on.
pub(crate) fn time<T>(name: &'static str, f: impl FnOnce() -> T) -> T {
    if !on() {
        return f();
    }
    let (c0, w0) = (cpu(), Instant::now());
    let out = f();
    let (dc, dw) = (cpu() - c0, w0.elapsed().as_secs_f64());
    let mut t = TALLY.lock().unwrap_or_else(|e| e.into_inner());
    match t.iter_mut().find(|e| e.0 == name) {
        Some(e) => (e.1, e.2, e.3) = (e.1 + dc, e.2 + dw, e.3 + 1),
        None => t.push((name, dc, dw, 1)),
    }
    out
}

/// Print the tally (when timing is on) and clear it.
pub(crate) fn report() {
    if !on() {
        return;
    }
    let mut t = TALLY.lock().unwrap_or_else(|e| e.into_inner());
    let (c, w) = t.iter().fold((0.0, 0.0), |a, e| (a.0 + e.1, a.1 + e.2));
    for e in t.iter() {
        eprintln!(
            "phase {:<22} cpu {:7.2} s  wall {:7.2} s  calls {}",
            e.0, e.1, e.2, e.3
        );
    }
    eprintln!(
        "phase {:<22} cpu {c:7.2} s  wall {w:7.2} s",
        "(timed total)"
    );
    t.clear();
}
