//! `obsan simulate MODEL.sys`: any model integrated from given values
//! (params, initial states, inputs constant, expressions of time or a CSV
//! time course) with obsan-fit's integrator, the states and outputs printed
//! as a CSV at evenly spaced times. Explicit time `t` is the clock state
//! `t' = 1`, exact under RK4.

use crate::cli::SimulateArgs;
use crate::input_table::read_input_table;
use crate::sim_drive::{self, Drive};
use crate::Failure;
use obsan_data::Series;
use obsan_fit::{FitError, Predictor};
use obsan_model::{System, TIME};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

/// The most output rows (`--until` / `--every` + 1): refused, never cut.
pub const MAX_ROWS: usize = 1_000_000;
/// The most RK4 steps of one integration (all doublings together stay
/// under twice this).
pub const MAX_STEPS: usize = 20_000_000;
/// Every printed value `v` has an estimated error within `TOLERANCE (|v| + 1)`:
/// the steps are halved until two runs differ by at most 15 times this, since
/// RK4's error falls by 2^4 = 16 when its step is halved (Richardson: the
/// finer run's error is the difference / 15).
pub const TOLERANCE: f64 = 1e-9;
/// Steps per output interval of the first run.
const FIRST_STEPS: usize = 4;

/// `NAME=VALUE` of `flag`, the value finite.
fn assignment(flag: &str, s: &str) -> Result<(String, f64), Failure> {
    let Some((n, v)) = s.split_once('=') else {
        return Err(Failure(format!("{flag} {s}: expected NAME=VALUE")));
    };
    let v: f64 = v
        .trim()
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .ok_or_else(|| Failure(format!("{flag} {s}: the value must be a finite number")))?;
    Ok((n.trim().to_string(), v))
}

/// A values file: `name = value` a line; `#` starts a comment.
fn read_values(path: &str) -> Result<BTreeMap<String, f64>, Failure> {
    let text = crate::fsio::read_text(path)?;
    let mut out = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        let body = line.split('#').next().unwrap_or_default();
        if body.trim().is_empty() {
            continue;
        }
        let col = body.len() - body.trim_start().len() + 1;
        let at = |m: &str| Failure(format!("{path}:{}:{col}: {m}", i + 1));
        let Some((n, v)) = body.split_once('=') else {
            return Err(at("expected `name = value`"));
        };
        let v: f64 = v
            .trim()
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| {
                at(&format!(
                    "the value of '{}' is not a finite number",
                    n.trim()
                ))
            })?;
        out.insert(n.trim().to_string(), v);
    }
    Ok(out)
}

/// The start of the integration: the whole state (dynamic states, the clock
/// at 0, then params) and the predictor's constants (the model's, in model
/// order, then the drive's, set per step by [`Drive::set_piece`]).
struct Start {
    x0: Vec<f64>,
    consts: Vec<f64>,
}

fn start(p: &Predictor, d: &Drive, a: &SimulateArgs) -> Result<Start, Failure> {
    let f = &a.sys;
    let file = match &f.values {
        Some(path) => read_values(path)?,
        None => BTreeMap::new(),
    };
    let nd = p.n_dynamic;
    let (states, params) = p.state.split_at(nd);
    let users: Vec<&String> = states.iter().filter(|s| *s != TIME).collect();
    let model_consts: Vec<String> = p
        .consts
        .iter()
        .filter(|c| !Drive::is_internal(c))
        .cloned()
        .collect();
    let mut given = file.clone();
    let settable: Vec<&String> = params.iter().chain(&model_consts).collect();
    for (flag, list, names) in [("--set", &f.set, settable), ("--init", &f.init, users)] {
        for s in list {
            let (n, v) = assignment(flag, s)?;
            if !names.contains(&&n) {
                let what = if flag == "--set" {
                    "param or constant"
                } else {
                    "state"
                };
                return Err(Failure(format!(
                    "{flag} {s}: the model has no {what} '{n}'"
                )));
            }
            given.insert(n, v);
        }
    }
    let mut missing = Vec::new();
    let mut take = |kind: &str, names: &[String], from: &BTreeMap<String, f64>| -> Vec<f64> {
        names
            .iter()
            .map(|n| {
                if n == TIME || Drive::is_internal(n) {
                    return 0.0;
                }
                from.get(n).copied().unwrap_or_else(|| {
                    missing.push(format!("{kind} {n}"));
                    0.0
                })
            })
            .collect()
    };
    let mut x0 = take("init", states, &given);
    x0.extend(take("param", params, &given));
    let consts = take("constant", &p.consts, &given);
    missing.extend(d.missing.iter().map(|u| format!("input {u}")));
    if !missing.is_empty() {
        return Err(Failure(format!(
            "missing values: {} (give them with --values FILE, --init NAME=V, --set NAME=V, \
             --input NAME=EXPR, --inputs FILE.csv)",
            missing.join(", ")
        )));
    }
    debug_assert_eq!(x0[d.clock], 0.0);
    Ok(Start { x0, consts })
}

/// The model with its inputs driven as the flags say (see [`sim_drive`])
/// and every dynamic state but the clock also an output (first), so that
/// the predictor reports them.
fn predictor(model: &str, a: &SimulateArgs) -> Result<(Predictor, Drive), Failure> {
    let text = crate::fsio::read_text(model)?;
    let sys = System::parse(&text, model).map_err(|e| Failure(e.to_string()))?;
    crate::clock::refuse_time(&sys)?;
    // Outputs that read inputs stay h(x, u): the drive substitutes u(t).
    let mut nf = sys
        .normal_form_as_written(None, &[])
        .map_err(|e| Failure(format!("{model}: {e}")))?;
    if let Some(w) = nf.unknown_inputs.first() {
        return Err(Failure(format!(
            "{model}: unknown input '{w}' has no value to simulate with"
        )));
    }
    let table = match &a.sim.inputs {
        Some(path) => Some(read_input_table(&crate::fsio::read_text(path)?, path)?),
        None => None,
    };
    let drive = sim_drive::drive(&mut nf, &a.sys.input, table)?;
    let mut outs = Vec::with_capacity(nf.n_dynamic + nf.outputs.len());
    for k in (0..nf.n_dynamic).filter(|&k| k != drive.clock) {
        let s = nf
            .ctx
            .lookup(&nf.state[k])
            .filter(|s| s.var == nf.state_vars[k])
            .ok_or_else(|| Failure(format!("{model}: state '{}' not found", nf.state[k])))?;
        outs.push((nf.state[k].clone(), s.id));
    }
    outs.append(&mut nf.outputs);
    nf.outputs = outs;
    Ok((Predictor::new(&nf), drive))
}

/// The times the integration stops at: every output time and every
/// breakpoint of the inputs, sorted, each with its output row (if any).
fn stops(times: &[f64], breaks: &[f64]) -> Vec<(f64, Option<usize>)> {
    let mut all: Vec<(f64, Option<usize>)> = times
        .iter()
        .enumerate()
        .map(|(k, &t)| (t, Some(k)))
        .chain(breaks.iter().map(|&t| (t, None)))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.is_some().cmp(&a.1.is_some())));
    all.dedup_by(|b, a| a.0 == b.0);
    all
}

/// States and outputs at the output times, at least `n_sub` RK4 steps
/// between consecutive stops (more where the integrator finds the dynamics
/// faster than the steps; it also splits steps itself where they are
/// stiff), and the steps taken. Each interval starts from the state the
/// previous one ended at, the clock set to the interval's start exactly.
fn integrate(
    p: &Predictor,
    d: &Drive,
    s: &Start,
    stops: &[(f64, Option<usize>)],
    n_sub: usize,
) -> Result<(Vec<Vec<f64>>, usize), Failure> {
    let nd = p.n_dynamic;
    let mut x = s.x0.clone();
    let mut consts = s.consts.clone();
    let t0 = stops[0].0;
    // The table's first piece, so that outputs reading an input see u(t0).
    let t1 = stops.get(1).map_or(t0, |s| s.0);
    d.set_piece(p, &mut consts, t0, t1);
    let first = p
        .predict(&x, &consts, &steps_of(t0, t0, 1), &[t0])
        .map_err(Failure::from)?;
    let mut rows = first;
    let mut steps = 0;
    for w in stops.windows(2) {
        let (a, b) = (w[0].0, w[1].0);
        d.set_piece(p, &mut consts, a, b);
        x[d.clock] = a;
        let mut n = n_sub;
        let y = loop {
            match p.predict(&x, &consts, &steps_of(a, b, n), &[b]) {
                Err(FitError::TooStiff {
                    time_scale,
                    spacing,
                }) if time_scale > 0.0 && steps + 2 * n <= MAX_STEPS => {
                    // Steps within the time scale the integrator measured.
                    n = ((n as f64 * spacing / time_scale).ceil() as usize).max(2 * n);
                }
                r => break r.map_err(Failure::from)?,
            }
        };
        steps += n;
        if steps > MAX_STEPS {
            return Err(too_many_steps());
        }
        let y = y.into_iter().next().unwrap_or_default();
        // The outputs open with the dynamic states, the clock left out.
        for (k, v) in (0..nd).filter(|&k| k != d.clock).zip(&y) {
            x[k] = *v;
        }
        if w[1].1.is_some() {
            rows.push(y);
        }
    }
    Ok((rows, steps))
}

fn too_many_steps() -> Failure {
    Failure(format!(
        "the estimated error did not fall within {TOLERANCE:e} (|value| + 1) in {MAX_STEPS} \
         RK4 steps (obsan's limit): the model may be stiff or blow up; try a shorter --until"
    ))
}

/// `n` RK4 steps evenly spread over `[t0, t1)`: the predictor takes one
/// step per row (the inputs are in the drift, so the rows carry no values).
fn steps_of(t0: f64, t1: f64, n: usize) -> Series {
    let mut s = Series::new(Vec::new());
    let h = (t1 - t0) / n as f64;
    for j in 0..n {
        s.push(t0 + j as f64 * h, &[]);
    }
    s
}

/// The largest `|a - b| / (|b| + 1)` over every value.
fn spread(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / (y.abs() + 1.0)))
}

/// Halve the steps until the Richardson estimate meets [`TOLERANCE`].
/// Returns the rows, the RK4 steps of the run printed and the estimated error.
fn converge(
    p: &Predictor,
    d: &Drive,
    s: &Start,
    stops: &[(f64, Option<usize>)],
) -> Result<(Vec<Vec<f64>>, usize, f64), Failure> {
    let intervals = stops.len().saturating_sub(1);
    if intervals == 0 {
        return Ok((integrate(p, d, s, stops, 1)?.0, 0, 0.0));
    }
    let mut n_sub = FIRST_STEPS;
    let mut coarse = integrate(p, d, s, stops, n_sub)?.0;
    loop {
        if 2 * n_sub * intervals > MAX_STEPS {
            return Err(too_many_steps());
        }
        n_sub *= 2;
        let (fine, steps) = integrate(p, d, s, stops, n_sub)?;
        let err = spread(&coarse, &fine) / 15.0;
        if err <= TOLERANCE {
            return Ok((fine, steps, err));
        }
        coarse = fine;
    }
}

/// The output times 0, DT, 2 DT, ... up to T.
fn times(until: f64, every: f64) -> Result<Vec<f64>, Failure> {
    if !(until.is_finite() && until >= 0.0 && every.is_finite() && every > 0.0) {
        return Err(Failure(
            "--until must be a finite number >= 0 and --every one > 0".into(),
        ));
    }
    let n = (until / every * (1.0 + 1e-12)).floor() + 1.0;
    if n > MAX_ROWS as f64 {
        return Err(Failure(format!(
            "--until {until} --every {every} asks for {n} rows: at most {MAX_ROWS} (obsan's limit)"
        )));
    }
    Ok((0..n as usize).map(|k| k as f64 * every).collect())
}

fn csv(columns: &[String], times: &[f64], rows: &[Vec<f64>]) -> String {
    let mut s = columns.join(",") + "\n";
    for (t, r) in times.iter().zip(rows) {
        s += &format!("{t:?}");
        for v in r {
            s += &format!(",{v:?}");
        }
        s.push('\n');
    }
    s
}

pub fn run(model: &str, a: &SimulateArgs) -> Result<ExitCode, Failure> {
    let (Some(until), Some(every)) = (a.sys.until, a.sys.every) else {
        return Err(Failure(
            "obsan simulate MODEL.sys needs --until T and --every DT".into(),
        ));
    };
    let (p, drive) = predictor(model, a)?;
    let s = start(&p, &drive, a)?;
    let times = times(until, every)?;
    let stops = stops(&times, &drive.breakpoints(until)?);
    let (rows, steps, err) = converge(&p, &drive, &s, &stops)?;
    let mut columns = vec!["time".to_string()];
    columns.extend(p.outputs.iter().cloned());
    let text = csv(&columns, &times, &rows);
    if let Some(out) = &a.out {
        let mut reads = vec![model];
        reads.extend(a.sys.values.as_deref());
        reads.extend(a.sim.inputs.as_deref());
        crate::fsio::check_outside(out, &reads)?;
        write_whole(out, &text, a.force)?;
    }
    if a.sys.json {
        let rows: Vec<Vec<f64>> = times
            .iter()
            .zip(&rows)
            .map(|(t, r)| std::iter::once(*t).chain(r.iter().copied()).collect())
            .collect();
        crate::json::print(&crate::json::SimulateSys {
            columns,
            error_estimate: err,
            model: model.to_string(),
            rows,
            steps,
            tolerance: TOLERANCE,
        })?;
    } else if a.out.is_none() {
        out!("{text}");
    } else {
        eprintln!(
            "wrote {} rows ({} RK4 steps, estimated error {err:.1e})",
            times.len(),
            steps
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Write `text` to `out` whole (a sibling temporary file renamed into place).
fn write_whole(out: &str, text: &str, force: bool) -> Result<(), Failure> {
    let p = Path::new(out);
    if p.exists() && !force {
        return Err(Failure(format!("{out} exists (--force replaces it)")));
    }
    if p.is_dir() {
        return Err(Failure(format!("{out} is a folder")));
    }
    let tmp = format!("{out}.tmp-{}", std::process::id());
    std::fs::write(&tmp, text).map_err(|e| Failure(format!("cannot write {tmp}: {e}")))?;
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Failure(format!("cannot write {out}: {e}"))
    })
}
