//! Where the nominal fit starts. Maximum likelihood needs a start near the
//! optimum; for the models obsan ships there is a data-only initialiser
//! (the paper's DET + LS + section V-C for calib.sys); for any other model
//! the user gives values by name, and params not given start at 0.

use obsan_estimate::{calibrate, CalibrateOptions, Dataset, Method};
use obsan_model::{Kind, System};
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
