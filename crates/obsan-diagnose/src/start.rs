//! Where the nominal fit starts. Maximum likelihood needs a start near the
//! optimum; for the models obsan ships there is a data-only initialiser
//! (the paper's DET + LS + section V-C for calib.sys); for any other model
//! the user gives values by name; otherwise a declaration's start value
//! (`param T = 0.2`, `state va = v`) is used, and params without one start
//! at 0.

use obsan_calib::{calibrate, CalibrateOptions, Method};
use obsan_data::{add_derived_inputs, Dataset, Trajectory};
use obsan_model::{Decl, Kind, Start, System};
use std::collections::BTreeMap;

/// Start values (params, per trajectory the dynamic state) for `sys` on
/// `data`; `given` overrides by name (a state's value applies to every
/// trajectory).
pub fn start_values(
    sys: &System,
    data: &Dataset,
    given: &BTreeMap<String, f64>,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), String> {
    let params: Vec<String> = sys.decls_of(Kind::Param).map(|d| d.name.clone()).collect();
    let states: Vec<String> = sys.decls_of(Kind::State).map(|d| d.name.clone()).collect();
    let mut p: BTreeMap<String, f64> = BTreeMap::new();
    let mut s: Vec<BTreeMap<String, f64>> = vec![BTreeMap::new(); data.trajectories.len()];
    let calib = ["phi", "psi", "eta", "delta", "xi"];
    if states == ["mu", "gamma"] && calib.iter().all(|c| params.iter().any(|x| x == c)) {
        // The paper's pipeline: DET, LS per circle, section V-C.
        let opts = CalibrateOptions::for_dataset(data, Method::Ls);
        let r = calibrate(data, None, &opts).map_err(|e| {
            format!(
                "the calib start (DET + LS) failed: {e}; give start values with --init NAME=VALUE"
            )
        })?;
        for (n, v) in calib.iter().zip(r.calibration.values()) {
            p.insert(n.to_string(), v);
        }
        for (k, t) in r.trajectories.iter().enumerate() {
            s[k].insert("mu".into(), t.start.0);
            s[k].insert("gamma".into(), t.start.1);
        }
    }
    if states.starts_with(&["x".to_string(), "y".to_string(), "th".to_string()]) {
        for (k, t) in data.trajectories.iter().enumerate() {
            if let Some(x0) = unicycle_start(t) {
                s[k].insert("x".into(), x0[0]);
                s[k].insert("y".into(), x0[1]);
                s[k].insert("th".into(), x0[2]);
            }
        }
    }
    // A state measured directly (`output px = x`, or its angle
    // `atan2(sin(th), cos(th))`) starts at its first measurement.
    for (k, t) in data.trajectories.iter().enumerate() {
        for n in &states {
            if s[k].contains_key(n) {
                continue;
            }
            let direct = [n.clone(), format!("atan2(sin({n}), cos({n}))")];
            let first = sys
                .output_names()
                .iter()
                .filter(|o| {
                    sys.rhs_text(o)
                        .is_some_and(|r| direct.iter().any(|d| d == r))
                })
                .find_map(|o| t.outputs.column(o)?.iter().flatten().next().copied());
            if let Some(v) = first {
                s[k].insert(n.clone(), v);
            }
        }
    }
    // Declared starts where nothing better is known.
    for d in sys.decls_of(Kind::Param) {
        if let Some(v) = declared_number(d) {
            p.entry(d.name.clone()).or_insert(v);
        }
    }
    for (k, t) in data.trajectories.iter().enumerate() {
        for d in sys.decls_of(Kind::State) {
            if let Some(Start::Inputs(e)) = &d.start {
                if !s[k].contains_key(&d.name) {
                    s[k].insert(d.name.clone(), state_start(&d.name, e, t)?);
                }
            }
        }
    }
    for (n, v) in given {
        if params.contains(n) {
            p.insert(n.clone(), *v);
        } else if states.contains(n) {
            for sk in &mut s {
                sk.insert(n.clone(), *v);
            }
        } else {
            return Err(format!(
                "--init {n}: '{n}' is neither a param nor a state of {}",
                sys.name
            ));
        }
    }
    let pv = params
        .iter()
        .map(|n| p.get(n).copied().unwrap_or(0.0))
        .collect();
    let mut sv = Vec::new();
    for (k, sk) in s.iter().enumerate() {
        let mut v = Vec::new();
        for n in &states {
            match sk.get(n) {
                Some(x) => v.push(*x),
                None => {
                    return Err(format!(
                        "no start value for state '{n}' of {} on trajectory {}: give one with --init {n}=VALUE",
                        sys.name, data.trajectories[k].name
                    ))
                }
            }
        }
        sv.push(v);
    }
    Ok((pv, sv))
}

/// The start pose of a unicycle window observing known landmarks (outputs
/// `r<c>`, `b<c>`, constants `lx<c>`, `ly<c>`): dead-reckon the window from
/// the origin with the commanded (v, omega), turn every range-bearing
/// measurement into the landmark's position in that frame, and register
/// those points onto the known landmarks (2-D Procrustes, closed form).
fn unicycle_start(t: &obsan_data::Trajectory) -> Option<[f64; 3]> {
    let (v, w) = (t.inputs.column("v")?, t.inputs.column("omega")?);
    // Relative poses at the input rows.
    let mut pose = vec![(0.0f64, 0.0f64, 0.0f64)];
    for k in 0..t.inputs.len().saturating_sub(1) {
        let dt = t.inputs.t[k + 1] - t.inputs.t[k];
        let (x, y, th) = pose[k];
        let (vk, wk) = (v[k].unwrap_or(0.0), w[k].unwrap_or(0.0));
        let thm = th + 0.5 * wk * dt;
        pose.push((
            x + vk * dt * thm.cos(),
            y + vk * dt * thm.sin(),
            th + wk * dt,
        ));
    }
    let mut q = Vec::new();
    let mut l = Vec::new();
    for (ci, name) in t.outputs.columns.iter().enumerate() {
        let Some(code) = name.strip_prefix('r') else {
            continue;
        };
        let Some(bi) = t
            .outputs
            .columns
            .iter()
            .position(|c| c == &format!("b{code}"))
        else {
            continue;
        };
        let (Some(lx), Some(ly)) = (
            t.meta.get(&format!("lx{code}")),
            t.meta.get(&format!("ly{code}")),
        ) else {
            continue;
        };
        for (j, &tj) in t.outputs.t.iter().enumerate() {
            let (Some(r), Some(b)) = (t.outputs.values[ci][j], t.outputs.values[bi][j]) else {
                continue;
            };
            let k = t
                .inputs
                .t
                .partition_point(|&x| x <= tj)
                .saturating_sub(1)
                .min(pose.len() - 1);
            let (px, py, pth) = pose[k];
            q.push((px + r * (pth + b).cos(), py + r * (pth + b).sin()));
            l.push((*lx, *ly));
        }
    }
    if q.len() < 2 {
        return None;
    }
    let n = q.len() as f64;
    let qc = (
        q.iter().map(|p| p.0).sum::<f64>() / n,
        q.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let lc = (
        l.iter().map(|p| p.0).sum::<f64>() / n,
        l.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let (mut sc, mut ss) = (0.0, 0.0);
    for (a, b) in q.iter().zip(&l) {
        let (ax, ay, bx, by) = (a.0 - qc.0, a.1 - qc.1, b.0 - lc.0, b.1 - lc.1);
        sc += ax * bx + ay * by;
        ss += ax * by - ay * bx;
    }
    let th0 = ss.atan2(sc);
    let (c, s) = (th0.cos(), th0.sin());
    let x0 = lc.0 - (c * qc.0 - s * qc.1);
    let y0 = lc.1 - (s * qc.0 + c * qc.1);
    Some([x0, y0, th0])
}

/// A param's declared start value (`param T = 0.2`).
fn declared_number(d: &Decl) -> Option<f64> {
    match &d.start {
        Some(Start::Number(q)) => Some(q.to_f64()),
        _ => None,
    }
}

/// A state's declared start on one trajectory: `expr` evaluated at the
/// inputs' first row (with the trajectory's constants).
fn state_start(name: &str, expr: &str, t: &Trajectory) -> Result<f64, String> {
    let mut head = t.inputs.clone();
    head.t.truncate(2);
    for c in &mut head.values {
        c.truncate(2);
    }
    let key = format!("{name}__start");
    add_derived_inputs(&mut head, &[(key.clone(), expr.to_string())], &t.meta)
        .map_err(|e| format!("start of state {name} on trajectory {}: {e}", t.name))?;
    head.column(&key)
        .and_then(|c| c.first().copied().flatten())
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            format!(
                "start of state {name} = {expr} on trajectory {}: no value at the first input row",
                t.name
            )
        })
}

/// Start values of `ext`, a model extended from one whose fit gave
/// `params` and `states` (per trajectory): those first, then each new
/// param's declared start (else 0) and each new state's declared start.
pub fn extended_start(
    ext: &System,
    params: &[f64],
    states: &[Vec<f64>],
    data: &Dataset,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), String> {
    let mut pv = params.to_vec();
    for d in ext.decls_of(Kind::Param).skip(params.len()) {
        pv.push(declared_number(d).unwrap_or(0.0));
    }
    let mut sv = Vec::with_capacity(states.len());
    for (k, (x0, t)) in states.iter().zip(&data.trajectories).enumerate() {
        let mut x = x0.clone();
        for d in ext.decls_of(Kind::State).skip(x0.len()) {
            match &d.start {
                Some(Start::Inputs(e)) => x.push(state_start(&d.name, e, t)?),
                _ => {
                    return Err(format!(
                        "the new state {} has no start value on trajectory {k} (declare it as state {} = EXPR)",
                        d.name, d.name
                    ))
                }
            }
        }
        sv.push(x);
    }
    Ok((pv, sv))
}
