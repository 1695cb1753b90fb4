//! `obsan simulate`: the paper's simulator, written atomically as a dataset.

use crate::cli::{SimFlags, SimulateArgs};
use crate::fsio::write_folder_atomically;
use crate::Failure;
use obsan_calib::{simulate, SimOptions};
use obsan_data::{Dataset, Series};
use std::path::PathBuf;
use std::process::ExitCode;

/// The files of a dataset, relative to its folder.
pub fn dataset_files(
    data: &Dataset,
    extra: &[(&str, String)],
) -> Result<Vec<(PathBuf, String)>, Failure> {
    let mut files = vec![(
        PathBuf::from("dataset.json"),
        serde_json::to_string_pretty(&data.meta)? + "\n",
    )];
    for (name, content) in extra {
        files.push((PathBuf::from(name), content.clone()));
    }
    for tr in &data.trajectories {
        let dir = PathBuf::from(&tr.name);
        files.push((dir.join("inputs.csv"), tr.inputs.to_csv()));
        files.push((dir.join("outputs.csv"), tr.outputs.to_csv()));
        files.push((
            dir.join("meta.json"),
            serde_json::to_string_pretty(&tr.meta)? + "\n",
        ));
    }
    Ok(files)
}

/// The most bearings per trajectory `--bearings` may ask for (the paper's
/// tables use at most a few hundred). Refused before anything is allocated:
/// memory grows with bearings x trajectories.
pub const MAX_BEARINGS: usize = 1_000_000;
/// The most trajectories (`--set q=RATIOS`) of one simulation.
pub const MAX_TRAJECTORIES: usize = 100;
/// The most bearings of all trajectories together (`--bearings` x ratios):
/// 3 x 10^6 is a 97 MB dataset (crlb on it peaks at 704 MB).
pub const MAX_TOTAL_BEARINGS: usize = 3_000_000;

/// The wheel-speed ratios of the simulated circles (eq. 17), spelled as the model's constant:
/// `--set q=0.9,0,-1`, one trajectory each; `--q 0.9,0,-1` is the old spelling, still read.
pub fn ratios(old: &[f64], set: &[String]) -> Result<Vec<f64>, Failure> {
    let mut q: Option<Vec<f64>> = None;
    for s in set {
        let Some(("q", list)) = s.split_once('=').map(|(n, v)| (n.trim(), v)) else {
            return Err(Failure(format!(
                "--set {s}: without a MODEL.sys the simulated set-up has one constant, q (the wheel-speed ratios), e.g. --set q=0.9,0,-1"
            )));
        };
        let values: Result<Vec<f64>, _> = list.split(',').map(|x| x.trim().parse()).collect();
        let values = values.map_err(|_| {
            Failure(format!(
                "--set {s}: q needs one or more finite ratios, e.g. --set q=0.9,0,-1"
            ))
        })?;
        if q.replace(values).is_some() {
            return Err(Failure("q is given twice: one --set q=RATIOS".into()));
        }
    }
    match (q, old.is_empty()) {
        (Some(_), false) => Err(Failure(
            "q is given twice: --set q=RATIOS (--q is its old spelling)".into(),
        )),
        (Some(q), true) => Ok(q),
        (None, false) => Ok(old.to_vec()),
        (None, true) => Ok(vec![0.9, 0.0, -1.0]),
    }
}

/// The simulator's options from the command line, checked; `set` holds `--set q=RATIOS`.
pub fn sim_options(a: &SimFlags, set: &[String]) -> Result<SimOptions, Failure> {
    let q = ratios(&a.q, set)?;
    let mut o = SimOptions {
        q: q.clone(),
        sigma_beta: a.sigma_beta_deg.to_radians(),
        k_encoder: a.k,
        iota: a.iota,
        dq: a.dq,
        nu: a.nu,
        profile: a
            .speed_profile
            .parse()
            .map_err(|e| Failure(format!("--speed-profile {e}")))?,
        bearing_rate: a.bearing_rate,
        bearings: a.bearings,
        d0: a.d0,
        seed: a.seed,
        ..SimOptions::default()
    };
    for (flag, v) in [
        ("--sigma-beta-deg", a.sigma_beta_deg),
        ("--k", a.k),
        ("--iota", a.iota),
        ("--nu", a.nu),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Failure(format!(
                "{flag} must be a finite number >= 0, got {v}"
            )));
        }
    }
    if q.is_empty() || q.iter().any(|q| !q.is_finite()) {
        return Err(Failure(
            "q needs one or more finite ratios, e.g. --set q=0.9,0,-1".into(),
        ));
    }
    if q.len() > MAX_TRAJECTORIES {
        return Err(Failure(format!(
            "q gives {} ratios: at most {MAX_TRAJECTORIES} trajectories (obsan's limit)",
            q.len()
        )));
    }
    if let Some(n) = a.bearings.filter(|n| *n > MAX_BEARINGS) {
        return Err(Failure(format!(
            "--bearings {n}: at most {MAX_BEARINGS} per trajectory (obsan's limit)"
        )));
    }
    if let Some(n) = a.bearings.filter(|n| n * q.len() > MAX_TOTAL_BEARINGS) {
        return Err(Failure(format!(
            "--bearings {n} on {} trajectories: at most {MAX_TOTAL_BEARINGS} bearings in all (obsan's limit)",
            q.len()
        )));
    }
    for e in &a.effects {
        let Some((n, v)) = e.split_once('=') else {
            return Err(Failure(format!("--effect {e}: expected NAME=VALUE")));
        };
        let v: f64 = v
            .trim()
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| Failure(format!("--effect {e}: the value must be a finite number")))?;
        o.effects
            .set(n.trim(), v)
            .map_err(|m| Failure(format!("--effect {e}: {m}")))?;
    }
    if let Some(path) = &a.inputs {
        let bytes = std::fs::read(path).map_err(|e| Failure(format!("cannot read {path}: {e}")))?;
        let (s, warnings) = Series::parse_csv_bytes(&bytes, path, &["wR", "wL"], false)?;
        for w in warnings {
            eprintln!("warning: {w}");
        }
        if s.len() < 2 {
            return Err(Failure(format!(
                "{path}: at least two rows of wheel speeds are needed"
            )));
        }
        o.inputs = Some(s);
    }
    if a.bearings
        .is_some_and(|n| n < obsan_data::MIN_OUTPUT_SAMPLES)
    {
        return Err(Failure(format!(
            "--bearings must be at least {}",
            obsan_data::MIN_OUTPUT_SAMPLES
        )));
    }
    Ok(o)
}

/// The watchdog's message when the deadline has passed.
fn past(deadline: Option<std::time::Instant>, secs: Option<f64>) -> Result<(), Failure> {
    match (deadline, secs) {
        (Some(d), Some(s)) if std::time::Instant::now() > d => {
            Err(Failure(format!("timed out after {s} s (--timeout)")))
        }
        _ => Ok(()),
    }
}

pub fn run(a: &SimulateArgs) -> Result<ExitCode, Failure> {
    if let Some(model) = &a.model {
        return crate::simulate_sys::run(model, a);
    }
    let out = a.out.as_deref().unwrap_or_default();
    if a.sys.until.is_some() || !(a.sys.init.is_empty() && a.sys.input.is_empty()) {
        return Err(Failure(
            "--until, --every, --init and --input need a MODEL.sys".into(),
        ));
    }
    let reads: Vec<&str> = a.sim.inputs.iter().map(String::as_str).collect();
    crate::fsio::check_outside(out, &reads)?;
    let o = sim_options(&a.sim, &a.sys.set)?;
    // The simulation and the CSV text do not poll a clock; between them the
    // deadline is checked, so a short --timeout stops before anything is
    // written instead of finishing within the watchdog's grace.
    let deadline = crate::cli::deadline_after(std::time::Instant::now(), a.timeout);
    let (data, truth) = simulate(&o).map_err(Failure::from)?;
    past(deadline, a.timeout)?;
    let truth_json = serde_json::to_string_pretty(&truth)? + "\n";
    let files = dataset_files(&data, &[("truth.json", truth_json)])?;
    past(deadline, a.timeout)?;
    write_folder_atomically(out, a.force, &reads, &files)?;
    let summary: Vec<String> = data
        .trajectories
        .iter()
        .map(|t| {
            format!(
                "{} ({} bearings, {:.1} s)",
                t.name,
                t.outputs.len(),
                t.inputs.t().last().copied().unwrap_or(0.0)
            )
        })
        .collect();
    eprintln!("wrote {}: {}", out, summary.join(", "));
    Ok(ExitCode::SUCCESS)
}
