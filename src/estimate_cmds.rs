//! `obsan calibrate | crlb`: reading datasets, formatting. `obsan
//! montecarlo` is in montecarlo_cmd.rs, the figures of `--plot` in figures.rs.

use crate::cli::{CalibrateArgs, CrlbArgs};
use crate::figures::write_figures;
use crate::simulate::sim_options;
use crate::{json, Failure};
use obsan_calib::{
    calib_predictor, calibrate, simulate, CalibrateOptions, EncoderNoise, Method, Table, PARAMS,
};
use obsan_data::{DataFile, Dataset, DatasetReader, TrajectoryFiles};
use std::path::Path;
use std::process::ExitCode;

fn read(path: &Path) -> Result<Option<DataFile>, Failure> {
    if !path.exists() {
        return Ok(None);
    }
    let bytes =
        std::fs::read(path).map_err(|e| Failure(format!("cannot read {}: {e}", path.display())))?;
    Ok(Some(DataFile {
        path: path.display().to_string(),
        bytes,
    }))
}

/// `calibrate --json`: the report in the binary's own types.
fn calibrate_json(m: Method, r: &obsan_calib::CalibrationReport) -> json::Calibrate {
    let sd = r.calibration.sd();
    let estimates = |names: &[&str], v: &[f64], sd: Option<&[f64]>| {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let e = json::Estimate {
                    sd: sd.map(|s| s[i]),
                    value: v[i],
                };
                (n.to_string(), e)
            })
            .collect()
    };
    let trajectories = r
        .trajectories
        .iter()
        .map(|t| json::Trajectory {
            l: t.closed.l,
            c: t.closed.c(),
            gamma0: json::finite(t.start.1),
            k: t.closed.k(),
            mu0: json::finite(t.start.0),
            name: t.name.clone(),
            period_from_others: t.period_from_others,
            q: t.q,
            residual_rms: t.rms,
            sd: t.modes_sd().map(|s| json::ModesSd {
                l: s[1],
                xi_q: s[0],
            }),
            xi_q: t.closed.xi_q,
        })
        .collect();
    json::Calibrate {
        // Which encoder noise ML's sds include; null for the other methods.
        encoder_noise: (m == Method::Ml).then_some(match r.encoder_noise {
            EncoderNoise::Stated { k, c } => json::EncoderNoise::Stated { c, k },
            EncoderNoise::Estimated { k, c, samples } => {
                json::EncoderNoise::Estimated { c, k, samples }
            }
            EncoderNoise::BearingsOnly => json::EncoderNoise::BearingsOnly,
        }),
        exact: false,
        method: m.name().to_string(),
        metric: r.metric.as_ref().map(|(mm, msd)| {
            let names = ["rho", "r_right", "r_left", "B"];
            estimates(&names, &mm.values(), msd.as_ref().map(|s| &s[..]))
        }),
        ml: r.ml.as_ref().map(|f| json::MlFit {
            cost: f.cost,
            iterations: f.iterations,
            residuals: f.n_residuals,
        }),
        params: estimates(
            &PARAMS,
            &r.calibration.values(),
            sd.as_ref().map(|s| &s[..]),
        ),
        sigma_beta: r.sigma_beta,
        sigma_beta_estimated: r.sigma_estimated,
        trajectories,
    }
}

/// Read a dataset folder (docs/data-format.md): dataset.json (optional), one
/// folder per trajectory with inputs.csv, outputs.csv, meta.json (optional).
/// The files are read here and checked by the library, one trajectory at a
/// time (its file bytes dropped once parsed: a large dataset's text is never
/// held whole beside its values); its warnings (e.g. an ignored text
/// column) are printed once each.
pub fn read_dataset(dir: &str, inputs: &[&str], outputs: &[&str]) -> Result<Dataset, Failure> {
    let root = Path::new(dir);
    if !root.is_dir() {
        return Err(Failure(format!("{dir}: not a dataset folder")));
    }
    let mut names: Vec<String> = std::fs::read_dir(root)
        .map_err(|e| Failure(format!("cannot list {dir}: {e}")))?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let meta = read(&root.join("dataset.json"))?;
    let mut reader = DatasetReader::new(meta.as_ref(), inputs, outputs)?;
    let mut any = false;
    for name in names {
        let tdir = root.join(&name);
        let (ipath, opath) = (tdir.join("inputs.csv"), tdir.join("outputs.csv"));
        if !ipath.exists() && !opath.exists() {
            continue; // not a trajectory
        }
        any = true;
        reader.add(&TrajectoryFiles {
            name,
            inputs: read(&ipath)?,
            outputs: read(&opath)?,
            meta: read(&tdir.join("meta.json"))?,
        })?;
    }
    if !any {
        return Err(Failure(format!(
            "{dir}: no trajectory folder (with inputs.csv and outputs.csv)"
        )));
    }
    let r = reader.finish()?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    Ok(r.dataset)
}

/// `calibrate` is the paper's estimator: a dataset of another model lacks its columns, and the
/// user needs to hear which command fits any model, not only which column is missing.
fn calib_only(f: Failure) -> Failure {
    if f.0.contains("missing column") {
        Failure(format!(
            "{}\n(calibrate is the paper's estimator, for data of systems/calib.sys: inputs wR, \
             wL and output beta; for another model use `obsan diagnose --model M.sys --data DIR`)",
            f.0
        ))
    } else {
        f
    }
}

fn method(s: &str) -> Result<Method, Failure> {
    Ok(match s {
        "det" => Method::Det,
        "ls" => Method::Ls,
        "cekf" => Method::Cekf,
        "ml" => Method::Ml,
        _ => {
            return Err(Failure(format!(
                "--method {s}: expected det, ls, cekf or ml"
            )))
        }
    })
}

/// Units of display: angles in degrees, the rest as is.
fn shown(i: usize, v: f64) -> f64 {
    if i < 2 {
        v.to_degrees()
    } else {
        v
    }
}

pub fn calibrate_cmd(a: &CalibrateArgs) -> Result<ExitCode, Failure> {
    let m = method(&a.method)?;
    if let Some(dir) = &a.plot {
        crate::fsio::check_outside(dir, &[&a.dataset])?;
    }
    let data = read_dataset(&a.dataset, &["wR", "wL"], &["beta"]).map_err(calib_only)?;
    let mut o = CalibrateOptions::for_dataset(&data, m);
    if let Some(d0) = a.d0 {
        if !(d0.is_finite() && d0 > 0.0) {
            return Err(Failure(format!(
                "--d0 must be a positive distance in metres, got {d0}"
            )));
        }
        o.d0 = Some(d0);
    }
    if let Some(s) = a.sigma_beta_deg {
        if !(s.is_finite() && s > 0.0) {
            return Err(Failure(format!(
                "--sigma-beta-deg must be positive, got {s}"
            )));
        }
        o.sigma_beta = Some(s.to_radians());
    }
    let p = calib_predictor();
    let r = calibrate(&data, Some(&p), &o).map_err(|e| Failure(format!("{}: {e}", a.dataset)))?;
    if let Some(dir) = &a.plot {
        let n = write_figures(dir, a.force, &[&a.dataset], &data, &p, &o, &r)?;
        eprintln!("wrote {n} figures (PNG and SVG) to {dir}");
    }
    if a.json {
        crate::json::print(&calibrate_json(m, &r))?;
        return Ok(ExitCode::SUCCESS);
    }
    let sd = r.calibration.sd();
    outln!(
        "method {} on {} ({} trajectories); bearing noise {:.3} deg{}",
        m.name(),
        a.dataset,
        r.trajectories.len(),
        r.sigma_beta.to_degrees(),
        if r.sigma_estimated {
            " (estimated from the LS residuals)"
        } else {
            " (from dataset.json)"
        }
    );
    outln!(
        "{:<10} {:>7} {:>22} {:>22} {:>10} {:>11} {:>9}",
        "trajectory",
        "q",
        "xi_q",
        "L (deg)",
        "c (deg)",
        "k",
        "rms (deg)"
    );
    for t in &r.trajectories {
        let s = t.modes_sd();
        let pm = |v: f64, e: Option<f64>| match e {
            Some(e) => format!("{v:.6} ± {e:.6}"),
            None => format!("{v:.6}"),
        };
        outln!(
            "{:<10} {:>7} {:>22} {:>22} {:>10.4} {:>11.6} {:>9.3}",
            t.name,
            t.q,
            pm(t.closed.xi_q, s.map(|s| s[0])),
            pm(t.closed.l.to_degrees(), s.map(|s| s[1].to_degrees())),
            t.closed.c().to_degrees(),
            t.closed.k(),
            t.rms.to_degrees()
        );
    }
    for t in r.trajectories.iter().filter(|t| t.period_from_others) {
        outln!(
            "note: {}: DET misread the period (LS fitted far worse than on the other circles); xi_q was started from the other circles' eq. (18) line",
            t.name
        );
    }
    outln!();
    let units = ["deg", "deg", "", "", ""];
    for (i, name) in PARAMS.iter().enumerate() {
        let v = shown(i, r.calibration.values()[i]);
        match sd {
            Some(s) => outln!("{name:<6} = {v:>12.6} ± {:.6} {}", shown(i, s[i]), units[i]),
            None => outln!("{name:<6} = {v:>12.6} {}", units[i]),
        }
    }
    if sd.is_none() {
        outln!("(det gives no standard deviations; use ls or ml)");
    }
    // Which encoder noise ML's sds include.
    if sd.is_some() && matches!(m, Method::Ml) {
        match r.encoder_noise {
            EncoderNoise::Stated { k, .. } => outln!(
                "(sds include the wheel-encoder noise stated in dataset.json: K = {k} m^1/2)"
            ),
            EncoderNoise::Estimated { k, c, samples } => outln!(
                "(sds include the wheel-encoder noise estimated from the wheel speeds, as dataset.json states none: K = {k:.3e} m^1/2, c = K^2/r = {c:.3e}, from {samples} differences; see docs/accuracy.md)"
            ),
            EncoderNoise::BearingsOnly => outln!(
                "(no wheel-encoder noise stated in dataset.json or read from the wheel speeds: these sds are the bearings' alone and leave it out, so they are too small if the encoders are noisy; see docs/accuracy.md)"
            ),
        }
    }
    match &r.metric {
        Some((mm, msd)) => {
            outln!();
            for (i, n) in ["rho", "rR", "rL", "B"].iter().enumerate() {
                match msd {
                    Some(s) => outln!("{n:<6} = {:>12.6} ± {:.6} m", mm.values()[i], s[i]),
                    None => outln!("{n:<6} = {:>12.6} m", mm.values()[i]),
                }
            }
            outln!("(metric from d0 = {} m on trajectory {})", o.d0.unwrap_or(0.0), r.trajectories[0].name);
        }
        None => outln!("\nrho, rR, rL, B need one metric distance: --d0 METRES (initial distance to the feature, first trajectory)"),
    }
    Ok(ExitCode::SUCCESS)
}

pub fn crlb_cmd(a: &CrlbArgs) -> Result<ExitCode, Failure> {
    let p = calib_predictor();
    // (set-up text, bearing-only sd, sd with encoder noise) in table units.
    let (setup, bearing, full, counts) = match &a.dataset {
        Some(dir) => {
            let data = read_dataset(dir, &["wR", "wL"], &["beta"])?;
            let o = CalibrateOptions::for_dataset(&data, Method::Ml);
            let fail = |e: obsan_calib::CalibError| Failure(format!("{dir}: {e}"));
            let run = calibrate(&data, Some(&p), &o).map_err(fail)?;
            let (b, f) = run.crlb(&data, &p, &o).map_err(fail)?;
            let v = run.calibration.values();
            let units = |s: [f64; 5]| -> Vec<f64> {
                vec![
                    s[0].to_degrees(),
                    s[1].to_degrees(),
                    100.0 * s[2] / v[2].abs(),
                    100.0 * s[3] / v[3].abs(),
                    100.0 * s[4] / v[4].abs(),
                ]
            };
            let k = match run.encoder_noise {
                EncoderNoise::Stated { k, .. } => format!("encoder K {k} m^1/2"),
                EncoderNoise::Estimated { k, .. } => {
                    format!("encoder K {k:.4e} m^1/2 read from the wheel speeds")
                }
                EncoderNoise::BearingsOnly => "no encoder noise stated or read".into(),
            };
            (
                format!("dataset {dir}, at its ML estimate; {k}"),
                units(b),
                f.map(units),
                data.trajectories
                    .iter()
                    .map(|t| format!("{} {}", t.name, t.outputs.len()))
                    .collect::<Vec<_>>(),
            )
        }
        None => {
            let o = sim_options(&a.sim, &a.set)?;
            let b = o.crlb_sd(&p, false)?;
            let f = (o.k_encoder > 0.0)
                .then(|| o.crlb_sd(&p, true))
                .transpose()?;
            let (data, _) = simulate(&o)?;
            (
                format!(
                    "simulated set-up, bearing noise {} deg, encoder K {} m^1/2",
                    a.sim.sigma_beta_deg, o.k_encoder
                ),
                b,
                f,
                data.trajectories
                    .iter()
                    .map(|t| format!("{} {}", t.name, t.outputs.len()))
                    .collect(),
            )
        }
    };
    if a.json {
        let obj = |sd: &[f64]| {
            Table::PARAM_COLUMNS
                .iter()
                .zip(sd)
                .map(|(c, v)| (c.to_string(), *v))
                .collect()
        };
        crate::json::print(&json::Crlb {
            bearings: counts,
            crlb_sd: obj(&bearing),
            crlb_sd_with_encoder_noise: full.as_ref().map(|f| obj(f)),
            setup,
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    outln!("Cramér–Rao bound: {setup}; bearings: {}", counts.join(", "));
    outln!(
        "  {:<15} {:>14} {:>22}",
        "",
        "bearing noise",
        "+ encoder noise"
    );
    for (i, c) in Table::PARAM_COLUMNS.iter().enumerate() {
        let f = full
            .as_ref()
            .map_or("-".to_string(), |f| format!("{:.4}", f[i]));
        outln!("  sd {c:<9} >= {:>14.4} {:>22}", bearing[i], f);
    }
    outln!(
        "(the encoder-noise bound is for estimators driven by the measured wheel speeds, as ml;
 one that knows the circle exactly, as ls with the commanded q, is bounded by the first column)"
    );
    Ok(ExitCode::SUCCESS)
}
