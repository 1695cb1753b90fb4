//! `obsan rank M.sys --along DATASET` (docs/experiments.md, "Observability
//! along data"): reads the dataset and its truth (simulated truth, Vicon
//! ground truth, or a fit's values in the same shape), calls the analysis,
//! prints the windows and the degenerate stretches.

use crate::cli::deadline_after;
use crate::cli::RankArgs;
use crate::json;
use crate::show::load_normal_form;
use crate::Failure;
use obsan_analysis::{
    trajectory::along, trajectory::generic_consts, trajectory::AlongOptions,
    trajectory::AlongReport, trajectory::AlongTrajectory, trajectory::INPUT_REL_TOL,
    trajectory::ROUNDING_FLOOR, trajectory::TOL_SAFETY,
};
use obsan_data::Dataset;
use obsan_model::NormalForm;
use serde_json::Value;
use std::process::ExitCode;
use std::time::Instant;

pub fn run(a: &RankArgs) -> Result<ExitCode, Failure> {
    let dir = a.along.as_deref().unwrap_or_default();
    if !a.sys.experiment.is_empty() || a.sys.experiments.is_some() {
        return Err(Failure(
            "--along reads its experiments from the dataset: drop --experiment/--experiments"
                .into(),
        ));
    }
    if !a.known.is_empty() || !a.known_generic.is_empty() {
        return Err(Failure(
            "--along starts from the dataset's truth: drop --known/--known-generic".into(),
        ));
    }
    let (_, mut nf) = load_normal_form(&a.sys)?;
    let ins: Vec<&str> = nf.inputs.iter().map(String::as_str).collect();
    let outs: Vec<&str> = nf.outputs.iter().map(|o| o.0.as_str()).collect();
    let data = crate::estimate_cmds::read_dataset(dir, &ins, &outs)?;
    let truth_path = a
        .truth
        .clone()
        .unwrap_or_else(|| format!("{}/truth.json", dir.trim_end_matches('/')));
    if !std::path::Path::new(&truth_path).exists() {
        return Err(Failure(format!(
            "{truth_path}: not found. --along evaluates at known states: a simulated dataset's \
             truth.json, MRCLAM's Vicon truth, or a fit's values in that shape (--truth FILE)"
        )));
    }
    let truth: Value = serde_json::from_str(&crate::fsio::read_text(&truth_path)?)
        .map_err(|e| Failure(format!("{truth_path}:{}:{}: {e}", e.line(), e.column())))?;
    let trajs = trajectories(&nf, &data, &truth, &truth_path)?;
    let opts = AlongOptions {
        window: a.window,
        deadline: deadline_after(Instant::now(), a.an.timeout),
    };
    let r = along(&mut nf, &trajs, &opts).map_err(|e| Failure(e.to_string()))?;
    if a.out.json {
        json::print(&to_json(&nf, dir, a.window, &trajs, &r))?;
    } else {
        print_text(&nf, &trajs, &r);
    }
    Ok(ExitCode::SUCCESS)
}

/// The value of `name` for trajectory `entry`: its key `name0` or `name`,
/// its `start` array (dynamic states, in order), else the top level's `name`.
fn lookup(entry: Option<&Value>, top: &Value, name: &str, index: Option<usize>) -> Option<f64> {
    if let Some(e) = entry {
        for k in [format!("{name}0"), name.to_string()] {
            if let Some(x) = e.get(&k).and_then(Value::as_f64) {
                return Some(x);
            }
        }
        if let (Some(i), Some(s)) = (index, e.get("start").and_then(Value::as_array)) {
            if let Some(x) = s.get(i).and_then(Value::as_f64) {
                return Some(x);
            }
        }
    }
    top.get(name).and_then(Value::as_f64)
}

fn trajectories(
    nf: &NormalForm,
    data: &Dataset,
    truth: &Value,
    path: &str,
) -> Result<Vec<AlongTrajectory>, Failure> {
    let entries: Vec<&Value> = ["trajectories", "windows"]
        .iter()
        .filter_map(|k| truth.get(*k).and_then(Value::as_array))
        .flatten()
        .collect();
    let consts = generic_consts(nf);
    let mut out = Vec::new();
    for t in &data.trajectories {
        let entry = entries
            .iter()
            .find(|e| e.get("name").and_then(Value::as_str) == Some(t.name.as_str()))
            .copied();
        let mut start = Vec::new();
        for (i, s) in nf.state.iter().enumerate() {
            let idx = (i < nf.n_dynamic).then_some(i);
            start.push(lookup(entry, truth, s, idx).ok_or_else(|| {
                Failure(format!(
                    "{path}: no value of '{s}' for trajectory '{}' (keys '{s}0', '{s}', 'start', or a top-level '{s}')",
                    t.name
                ))
            })?);
        }
        let mut cv = Vec::new();
        for c in &consts {
            cv.push(*t.meta.get(c).ok_or_else(|| {
                Failure(format!(
                    "{}/meta.json: no value of the constant '{c}' (or give it with --set {c}=VALUE)",
                    t.name
                ))
            })?);
        }
        let cols = |names: &[String], s: &obsan_data::Series| -> Vec<usize> {
            names
                .iter()
                .map(|n| {
                    s.columns()
                        .iter()
                        .position(|c| c == n)
                        .unwrap_or(usize::MAX)
                })
                .collect()
        };
        let ic = cols(&nf.inputs, &t.inputs);
        let onames: Vec<String> = nf.outputs.iter().map(|o| o.0.clone()).collect();
        let oc = cols(&onames, &t.outputs);
        let iv = t.inputs.values();
        let inputs = (0..t.inputs.len())
            .map(|k| {
                ic.iter()
                    .map(|&c| iv.get(c).and_then(|col| col[k]).unwrap_or(0.0))
                    .collect()
            })
            .collect();
        let ov = t.outputs.values();
        let measured = (0..t.outputs.len())
            .map(|k| {
                oc.iter()
                    .map(|&c| ov.get(c).is_some_and(|col| col[k].is_some()))
                    .collect()
            })
            .collect();
        out.push(AlongTrajectory {
            name: t.name.clone(),
            input_t: t.inputs.t().to_vec(),
            inputs,
            output_t: t.outputs.t().to_vec(),
            measured,
            start,
            consts: cv,
        });
    }
    Ok(out)
}

/// A number to about 6 significant digits, without noise digits.
fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{}", if x == 0.0 { 0.0 } else { x });
    }
    let p = 10f64.powi(5 - x.abs().log10().floor() as i32);
    format!("{}", (x * p).round() / p)
}

/// A number to 4 significant digits (printed directions).
fn num4(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return num(x);
    }
    let p = 10f64.powi(3 - x.abs().log10().floor() as i32);
    format!("{}", (x * p).round() / p)
}

/// `c_0 + sum c_i u_i = 0` as `u_k = ...` (u_k its last input).
fn relation_text(nf: &NormalForm, c: &[f64]) -> String {
    let Some(k) = (1..c.len()).rev().find(|&i| c[i] != 0.0) else {
        return format!("{} = 0", num(c[0]));
    };
    let mut rhs = Vec::new();
    for i in 1..k {
        if c[i] != 0.0 {
            let x = -c[i] / c[k];
            let name = &nf.inputs[i - 1];
            rhs.push(match num(x).as_str() {
                "1" => name.clone(),
                "-1" => format!("-{name}"),
                t => format!("{t}*{name}"),
            });
        }
    }
    if c[0] != 0.0 || rhs.is_empty() {
        rhs.push(num(-c[0] / c[k]));
    }
    format!(
        "{} = {}",
        nf.inputs[k - 1],
        rhs.join(" + ").replace("+ -", "- ")
    )
}

/// A direction as `0.71 mu - 0.7 gamma` (components below 1e-6 dropped).
fn vector_text(names: &[String], v: &[f64]) -> String {
    let mut s = String::new();
    for (n, &x) in names.iter().zip(v) {
        if x.abs() < 1e-6 {
            continue;
        }
        let t = num4(x.abs());
        if s.is_empty() {
            s = format!("{}{t} {n}", if x < 0.0 { "-" } else { "" });
        } else {
            s.push_str(&format!(" {} {t} {n}", if x < 0.0 { "-" } else { "+" }));
        }
    }
    if s.is_empty() {
        "0".into()
    } else {
        s
    }
}

/// A basis of span(`vs`) in reduced echelon form (pivots in the variables'
/// order): unique for the subspace, so the printed lost directions do not
/// depend on the SVD's choice of basis. Entries below 1e-9 are zero.
fn echelon(vs: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut rows = vs.to_vec();
    let n = rows.first().map_or(0, Vec::len);
    let mut r = 0;
    for c in 0..n {
        if r == rows.len() {
            break;
        }
        let p = (r..rows.len())
            .max_by(|&a, &b| rows[a][c].abs().total_cmp(&rows[b][c].abs()))
            .unwrap_or(r);
        if rows[p][c].abs() < 1e-6 {
            continue;
        }
        rows.swap(r, p);
        let piv = rows[r][c];
        rows[r].iter_mut().for_each(|x| *x /= piv);
        for i in 0..rows.len() {
            let f = rows[i][c];
            if i != r && f != 0.0 {
                let pr = rows[r].clone();
                rows[i].iter_mut().zip(&pr).for_each(|(x, y)| *x -= f * y);
            }
        }
        r += 1;
    }
    rows.iter_mut()
        .flat_map(|row| row.iter_mut())
        .filter(|x| x.abs() < 1e-9)
        .for_each(|x| *x = 0.0);
    rows
}

fn relations(nf: &NormalForm, r: &AlongReport, w: usize) -> Vec<String> {
    r.inputs[w]
        .relations
        .iter()
        .map(|c| relation_text(nf, c))
        .collect()
}

fn deg(x: f64) -> f64 {
    x.to_degrees()
}

fn nums(v: &[f64]) -> Vec<json::Num> {
    v.iter().map(|x| json::finite(*x)).collect()
}

fn rows(v: &[Vec<f64>]) -> Vec<Vec<json::Num>> {
    v.iter().map(|r| nums(r)).collect()
}

fn to_json(
    nf: &NormalForm,
    dir: &str,
    window: f64,
    trajs: &[AlongTrajectory],
    r: &AlongReport,
) -> json::Along {
    let finite = json::finite;
    let windows = r
        .windows
        .iter()
        .enumerate()
        .map(|(i, w)| json::AlongWindow {
            condition: finite(w.condition),
            input_relations: relations(nf, r, i),
            kernel: rows(&w.kernel),
            rank: w.rank,
            rows: w.rows,
            singular_values: nums(&w.singular_values),
            t0: finite(w.t0),
            t1: finite(w.t1),
            tolerance: finite(w.tolerance),
            trajectory: trajs[w.trajectory].name.clone(),
            weakest: nums(&w.weakest),
        })
        .collect();
    let stretches = r
        .stretches
        .iter()
        .map(|s| {
            let m = &s.symmetry;
            json::AlongStretch {
                input_relations: relations(nf, r, s.windows[0]),
                lost: rows(&echelon(&s.kernel)),
                rank: s.rank,
                symmetry: json::AlongSymmetry {
                    angle_bound_deg: finite(deg(m.angle_bound)),
                    angles_deg: m.angles.iter().map(|a| finite(deg(*a))).collect(),
                    exact: m.exact,
                    kernel_to_symmetries_deg: finite(deg(m.kernel_to_symmetries)),
                    matches: m.matches,
                    restricted_rank: m.restricted_rank,
                    symmetries_to_kernel_deg: finite(deg(m.symmetries_to_kernel)),
                    vectors: rows(&m.vectors),
                },
                t0: finite(s.t0),
                t1: finite(s.t1),
                trajectory: trajs[s.trajectory].name.clone(),
                windows: s.windows.len(),
            }
        })
        .collect();
    let d = &r.dataset;
    json::Along {
        along: dir.to_string(),
        dataset: json::AlongDataset {
            columns: d.columns.clone(),
            kernel: rows(&d.kernel),
            n: d.columns.len(),
            rank: d.rank,
            singular_values: nums(&d.singular_values),
            tolerance: finite(d.tolerance),
        },
        input_rel_tol: finite(INPUT_REL_TOL),
        n: r.n,
        rounding_floor: finite(ROUNDING_FLOOR),
        state: nf.state.clone(),
        stretches,
        system: nf.name.clone(),
        tolerance_safety: finite(TOL_SAFETY),
        window: finite(window),
        windows,
    }
}

fn print_text(nf: &NormalForm, trajs: &[AlongTrajectory], r: &AlongReport) {
    let n = r.n;
    outln!(
        "system {}: observability along the data ({} variables: {})",
        nf.name,
        n,
        nf.state.join(", ")
    );
    for (ti, t) in trajs.iter().enumerate() {
        let ws: Vec<_> = r.windows.iter().filter(|w| w.trajectory == ti).collect();
        let full = ws.iter().filter(|w| w.rank == n).count();
        let worst = ws
            .iter()
            .filter(|w| w.rank == n)
            .map(|w| w.condition)
            .fold(0.0, f64::max);
        let cond = if full > 0 {
            format!(" (largest condition number {worst:.1e})")
        } else {
            String::new()
        };
        let plural = if ws.len() == 1 { "" } else { "s" };
        outln!(
            "{}: {} window{plural}, {full} of full rank{cond}",
            t.name,
            ws.len()
        );
    }
    if r.stretches.is_empty() {
        outln!("no degenerate stretch");
    }
    for s in &r.stretches {
        let m = &s.symmetry;
        outln!(
            "{} {}-{} s: rank {} of {n}; inputs: {}",
            trajs[s.trajectory].name,
            num(s.t0),
            num(s.t1),
            s.rank,
            {
                let rel = relations(nf, r, s.windows[0]);
                if rel.is_empty() {
                    "no relation".to_string()
                } else {
                    rel.join(", ")
                }
            }
        );
        for k in echelon(&s.kernel) {
            outln!("  lost: {}", vector_text(&nf.state, &k));
        }
        let angle = m.kernel_to_symmetries.max(m.symmetries_to_kernel);
        outln!(
            "  {} the {} symmetries of the model restricted to these inputs and outputs (rank {}){}",
            if m.matches { "matches" } else { "does not match" },
            m.vectors.len(),
            m.restricted_rank,
            if m.matches {
                String::from(": principal angles within the kernel's error bound")
            } else {
                format!(": largest principal angle {} deg", num4(deg(angle)))
            }
        );
    }
    let d = &r.dataset;
    outln!(
        "whole dataset (params shared, each trajectory its own start): rank {} of {}",
        d.rank,
        d.columns.len()
    );
    for k in echelon(&d.kernel) {
        outln!("  lost: {}", vector_text(&d.columns, &k));
    }
}
