//! The heading-free check of a candidate that rewrites a group of angle
//! outputs (found on MRCLAM's Vicon data).
//!
//! Any error common to every member of an angle group at one instant (a
//! heading error enters every bearing additively) can be absorbed by a
//! group scale: on MRCLAM robots 1-3 odometry heading drift was named as a
//! bearing scale of -7 to -9 % that the Vicon truth does not support. The
//! differences of two members measured at the same time cancel any such
//! error. So the candidate's param is estimated a second time from those
//! differences alone, and a candidate whose full-fit estimate disagrees
//! with it by more than `sqrt(crit)` combined cluster-robust sds is not
//! named: its "effect" is a common-mode error, not what it says.
//!
//! The estimate is least squares with a free additive offset per instant
//! (the common mode, one nuisance per time with two or more members): the
//! same as regressing every simultaneous difference, weighted as the
//! projection onto the differences. It is one Gauss-Newton step from the
//! candidate's fit with the fitted states held. The check only applies to
//! effects that rewrite outputs alone, so the states do not depend on the
//! param and the step's sensitivities are exact; every generated angle
//! candidate is linear in its param (`(1 + k) y`, `y + a sin(n y)`), so the
//! step is then the exact minimiser of the within-instant cost at those
//! states. Members are weighed alike: one group has one form and one noise
//! level in expectation, and the cluster-robust sd does not rely on the
//! weights being right.
//!
//! Which candidates it applies to: every output-only effect with one param
//! that rewrites only angle outputs, two or more of them — a scale (yes),
//! the harmonics `sin y`, `cos y`, ... (yes: their differences identify
//! the amplitude, and a common-mode error correlated with the angle could
//! be read as one), a bias (no: it is exactly a common-mode shift, so the
//! differences carry no information about it; found numerically, the
//! differences' sensitivity vanishing, so a user's bias written any way is
//! recognised). Without two members measured at one time (calib.sys: one
//! bearing) the check does not apply and says so.

use crate::error::DiagnoseError;
use crate::model_fit::{ModelFit, OUTLIER_Z};
use crate::options::DiagnoseOptions;
use obsan_data::{wrap, Dataset};
use obsan_fit::{FitTrajectory, Integration, Measured, Predictor};
use obsan_model::{Effect, System};
use serde::Serialize;

/// One measurement of a group member: its time, residual (measured minus
/// predicted, wrapped) and sensitivity to the param at the fit.
#[derive(Clone, Copy, Debug)]
pub struct Member {
    pub t: f64,
    pub residual: f64,
    pub sensitivity: f64,
}

/// The within-instant estimate: the step from the fit, its cluster-robust
/// sd, and what it rests on.
#[derive(Clone, Copy, Debug)]
pub struct DifferenceEstimate {
    /// Param change from the fit's value.
    pub step: f64,
    /// Cluster-robust sd (clusters: the slices passed), NaN with fewer
    /// than two clusters that carry information.
    pub robust_sd: f64,
    /// Instants with two or more members.
    pub instants: usize,
    /// Sum of squared sensitivities about their instant's mean, and the
    /// same without removing the mean (their ratio says whether the
    /// differences carry any information).
    pub within: f64,
    pub total: f64,
}

/// Least squares for the param with a free offset per instant, from the
/// measurements of each cluster (a trajectory): at every time with `m >= 2`
/// members, residuals and sensitivities about their mean; `step` =
/// `sum (g - g_mean)(e - e_mean) / sum (g - g_mean)^2`. The robust variance
/// is `K/(K-1) sum_c u_c^2 / H^2` with `u_c` cluster c's score at the step
/// (as `obsan_fit`'s cluster-robust sds).
pub fn difference_estimate(clusters: &[Vec<Member>]) -> DifferenceEstimate {
    let mut per: Vec<(f64, f64)> = Vec::new();
    let (mut instants, mut total) = (0usize, 0.0);
    for c in clusters {
        let mut ms: Vec<Member> = c.clone();
        ms.sort_by(|a, b| a.t.total_cmp(&b.t));
        let (mut sxy, mut sxx) = (0.0, 0.0);
        let mut i = 0;
        while i < ms.len() {
            let mut j = i + 1;
            while j < ms.len() && ms[j].t == ms[i].t {
                j += 1;
            }
            let at = &ms[i..j];
            if at.len() >= 2 {
                instants += 1;
                let m = at.len() as f64;
                let gm = at.iter().map(|x| x.sensitivity).sum::<f64>() / m;
                let em = at.iter().map(|x| x.residual).sum::<f64>() / m;
                for x in at {
                    sxy += (x.sensitivity - gm) * (x.residual - em);
                    sxx += (x.sensitivity - gm).powi(2);
                    total += x.sensitivity.powi(2);
                }
            }
            i = j;
        }
        per.push((sxy, sxx));
    }
    let h: f64 = per.iter().map(|p| p.1).sum();
    let step = if h > 0.0 {
        per.iter().map(|p| p.0).sum::<f64>() / h
    } else {
        0.0
    };
    let informative = per.iter().filter(|p| p.1 > 0.0).count();
    let robust_sd = if informative >= 2 && h > 0.0 {
        let k = informative as f64;
        let u2: f64 = per
            .iter()
            .map(|(sxy, sxx)| (sxy - step * sxx).powi(2))
            .sum();
        (u2 * k / (k - 1.0)).sqrt() / h
    } else {
        f64::NAN
    };
    DifferenceEstimate {
        step,
        robust_sd,
        instants,
        within: h,
        total,
    }
}

/// Below this ratio of within-instant to total sensitivity the param moves
/// every member alike: a common-mode shift (a bias), not checked.
const COMMON_SHIFT: f64 = 1e-10;

/// The check of one candidate, as `--json` carries it.
#[derive(Clone, Debug, Serialize)]
pub struct CommonModeCheck {
    /// Whether the check applies; when not, `note` says why.
    pub applies: bool,
    pub note: String,
    /// The angle outputs the candidate rewrites.
    pub group: Vec<String>,
    pub param: String,
    /// Instants at which two or more members were measured.
    pub instants: usize,
    /// The full fit's estimate and its cluster-robust sd.
    pub full: f64,
    pub full_robust_sd: f64,
    /// The estimate from simultaneous differences and its robust sd.
    pub differences: f64,
    pub differences_robust_sd: f64,
    /// `|full - differences|` in combined robust sds, and the limit
    /// (`sqrt` of the candidate's critical LR value).
    pub z: f64,
    pub limit: f64,
    /// Not named for it: `z > limit`.
    pub vetoed: bool,
    /// This check is the prediction at the current fit ([`predicted`]):
    /// the candidate was not fitted, its veto being certain (`z > limit +
    /// PREDICTED_MARGIN`); `full` is the Gauss-Newton step's estimate.
    pub predicted: bool,
    /// The z predicted before the fit, when it was (NaN otherwise): beside
    /// `z` it shows how well the prediction held.
    pub predicted_z: f64,
}

impl CommonModeCheck {
    fn not_applicable(group: Vec<String>, param: String, note: String) -> CommonModeCheck {
        CommonModeCheck {
            applies: false,
            note,
            group,
            param,
            instants: 0,
            full: f64::NAN,
            full_robust_sd: f64::NAN,
            differences: f64::NAN,
            differences_robust_sd: f64::NAN,
            z: f64::NAN,
            limit: f64::NAN,
            vetoed: false,
            predicted: false,
            predicted_z: f64::NAN,
        }
    }

    /// A check that could not be computed (`why`): it vetoes nothing.
    pub(crate) fn failed(e: &Effect, why: &str) -> CommonModeCheck {
        let group = e.outputs.iter().map(|o| o.0.clone()).collect();
        let param = e.params.first().cloned().unwrap_or_default();
        CommonModeCheck::not_applicable(group, param, format!("failed: {why}"))
    }

    /// The plain words of a veto, e.g. "b_scale: not supported by
    /// simultaneous b differences (gk_b from differences -0.004 ± 0.006 vs
    /// -0.08 from the full fit, 5.2 combined sds > 3.5): a common-mode
    /// error such as heading drift, not this effect".
    pub fn veto_text(&self, effect: &str) -> String {
        let (how, from, beyond) = if self.predicted {
            (
                "predicted at the current fit, not fitted: ",
                "a Gauss-Newton step",
                format!(" + {PREDICTED_MARGIN}"),
            )
        } else {
            ("", "the full fit", String::new())
        };
        format!(
            "{effect}: not supported by simultaneous differences of its {} angle outputs \
             ({how}{} from differences {:.4} ± {:.4} vs {:.4} from {from}, {:.1} combined \
             robust sds > {:.2}{beyond}): a common-mode error such as heading drift, not this \
             effect",
            self.group.len(),
            self.param,
            self.differences,
            self.differences_robust_sd,
            self.full,
            self.z,
            self.limit
        )
    }
}

/// The rewritten angle outputs and the param when `e` is of the kind the
/// check applies to, else why not.
pub(crate) fn eligible(
    e: &Effect,
    angular: &dyn Fn(&str) -> bool,
) -> Result<(Vec<String>, String), String> {
    let group: Vec<String> = e.outputs.iter().map(|o| o.0.clone()).collect();
    if !e.states.is_empty()
        || !e.substs.is_empty()
        || !e.dynamics.is_empty()
        || !e.compares.is_empty()
        || e.delay.is_some()
        || !e.inputs.is_empty()
    {
        return Err("not an output-only effect".into());
    }
    if e.params.len() != 1 {
        return Err(format!("{} params (the check takes one)", e.params.len()));
    }
    if group.is_empty() || !group.iter().all(|y| angular(y)) {
        return Err("does not rewrite angle outputs only".into());
    }
    if group.len() < 2 {
        return Err("rewrites one angle output: no simultaneous differences".into());
    }
    Ok((group, e.params[0].clone()))
}

/// The check of candidate `e` fitted (`f`) as `ext` to prepared `data`;
/// `crit` is the candidate's critical LR value. The estimate is computed
/// only for a candidate the other tests would name (`significant`): the
/// veto is their last gate.
pub(crate) fn check(
    e: &Effect,
    ext: &System,
    data: &Dataset,
    f: &ModelFit,
    (crit, significant): (f64, bool),
    o: &DiagnoseOptions,
) -> Result<CommonModeCheck, DiagnoseError> {
    let angular = |y: &str| f.series.iter().any(|s| s.output == y && s.angular);
    let (group, param) = match eligible(e, &angular) {
        Ok(x) => x,
        Err(why) => {
            let group = e.outputs.iter().map(|o| o.0.clone()).collect();
            let param = e.params.first().cloned().unwrap_or_default();
            return Ok(CommonModeCheck::not_applicable(group, param, why));
        }
    };
    if !significant {
        let why = "not computed: the candidate is not named by the other tests";
        return Ok(CommonModeCheck::not_applicable(group, param, why.into()));
    }
    let (full, full_robust_sd) = match (f.param(&param), f.robust_sd(&param)) {
        (Some((v, _)), Some(r)) => (v, r),
        _ => (f64::NAN, f64::NAN),
    };
    let nf = ext.normal_form(None, &[]).map_err(DiagnoseError::model)?;
    let p = Predictor::new(&nf);
    let na =
        |note: &str| CommonModeCheck::not_applicable(group.clone(), param.clone(), note.into());
    let cols: Vec<usize> = group
        .iter()
        .filter_map(|y| p.outputs.iter().position(|o| o == y))
        .collect();
    let Some(pi) = p.state.iter().position(|s| *s == param) else {
        return Ok(na("the param is not in the fitted model"));
    };
    // Instants with two or more members, from the data alone: without them
    // nothing is predicted.
    let trajs = FitTrajectory::all(&p, data);
    let simultaneous = trajs.iter().any(|tr| {
        let mut ts: Vec<f64> = cols
            .iter()
            .filter_map(|&c| tr.outputs.column(&p.outputs[c]))
            .flat_map(|col| {
                col.iter()
                    .zip(tr.outputs.t())
                    .filter(|(v, _)| v.is_some())
                    .map(|(_, t)| *t)
                    .collect::<Vec<_>>()
            })
            .collect();
        ts.sort_by(f64::total_cmp);
        ts.windows(2).any(|w| w[0] == w[1])
    });
    if !simultaneous {
        return Ok(na("no two members of the group measured at the same time"));
    }
    let integ = Integration {
        max_step: o.max_step,
        sensitivities: true,
        input_noise: None,
    };
    let pv: Vec<f64> = f.params.iter().map(|x| x.1).collect();
    let n = p.state.len();
    let mut clusters = Vec::with_capacity(trajs.len());
    for (k, tr) in trajs.iter().enumerate() {
        let Some(x0s) = f.initial_states.get(k) else {
            continue;
        };
        let mut x0 = x0s.clone();
        x0.extend_from_slice(&pv);
        // Only the measured cells (values and rows equal predict_with's).
        let cells = Measured::new(&p, tr.outputs);
        let pred = p
            .predict_measured(&x0, &tr.consts, tr.inputs, &cells, &integ)
            .map_err(|source| DiagnoseError::Predict {
                trajectory: tr.name.to_string(),
                source,
            })?;
        let mut members = Vec::new();
        for &c in &cols {
            let Some(col) = tr.outputs.column(&p.outputs[c]) else {
                continue;
            };
            // Gross outliers (misread landmarks) are left out, as by the
            // fit's restart: no Gaussian noise gives them, and a bearing
            // misread across +-pi makes the one-step linearisation void
            // (on MRCLAM robot 3 they tripled the scale's robust sd).
            let rms = f
                .rms
                .iter()
                .find(|r| r.0 == p.outputs[c])
                .map_or(0.0, |r| r.1);
            for (j, (&t, m)) in tr.outputs.t().iter().zip(col).enumerate() {
                let Some(m) = m else { continue };
                let Some(i) = cells.at(j).0.iter().position(|&o| o == c) else {
                    continue;
                };
                let y = pred.outputs[j][i];
                let e = wrap(m - y);
                if rms > 0.0 && e.abs() > OUTLIER_Z * rms {
                    continue;
                }
                members.push(Member {
                    t,
                    residual: e,
                    sensitivity: pred.jacobians[j][i * n + pi],
                });
            }
        }
        clusters.push(members);
    }
    let d = difference_estimate(&clusters);
    Ok(judge(
        group,
        param,
        (full, full_robust_sd),
        &d,
        full + d.step,
        crit,
    ))
}

/// Margin (in combined robust sds) by which a predicted z must exceed the
/// limit for the candidate to be left unfitted. Measured (docs/diagnose.md,
/// "Heading-free check"): over the fitted candidates of MRCLAM robots 1-3
/// and tests/common_mode.rs, the predicted z is within 0.12 of the fitted
/// one for scales and `sin` harmonics, and within 0.52 (at most 0.44 too
/// high) for the `cos` harmonics that scored above the critical value,
/// whose fits move the states more than a Gauss-Newton step does.
pub const PREDICTED_MARGIN: f64 = 0.5;

/// The check predicted at the current fit, before any fit of the candidate
/// (`score` in `screen.rs`): the full fit's estimate as the Gauss-Newton
/// step of every free quantity, `(value, robust sd)` with the sandwich at
/// the step, and `d` the within-instant estimate from the residuals moved
/// by that step (to first order; exact in the param for an effect linear
/// in it). `vetoed` (the fit skipped, this the candidate's check) only
/// when `z > limit + PREDICTED_MARGIN` and the score clears the critical
/// value `crit` (below it the step is less linear: a weak `cos` harmonic
/// on the heading-walk simulation, score below it, was predicted 0.84 too
/// high).
pub(crate) fn predicted(
    (group, param): (Vec<String>, String),
    full: (f64, f64),
    d: &DifferenceEstimate,
    (crit, score): (f64, f64),
) -> CommonModeCheck {
    let mut c = judge(group, param, full, d, full.0 + d.step, crit);
    c.predicted = true;
    c.predicted_z = c.z;
    c.vetoed = c.applies && score >= crit && c.z > c.limit + PREDICTED_MARGIN;
    c
}

/// The check from the full estimate `(value, robust sd)` and the
/// within-instant one (`d`, the estimate `differences`); `crit` is the
/// candidate's critical LR value.
fn judge(
    group: Vec<String>,
    param: String,
    (full, full_robust_sd): (f64, f64),
    d: &DifferenceEstimate,
    differences: f64,
    crit: f64,
) -> CommonModeCheck {
    let na =
        |note: &str| CommonModeCheck::not_applicable(group.clone(), param.clone(), note.into());
    if d.instants == 0 {
        return na("no two members of the group measured at the same time");
    }
    if d.within.is_nan() || d.within <= COMMON_SHIFT * d.total {
        return na(
            "the param shifts every member alike (a common-mode shift): \
             simultaneous differences carry no information about it",
        );
    }
    let limit = crit.sqrt();
    let combined = full_robust_sd.hypot(d.robust_sd);
    if !(combined.is_finite() && combined > 0.0) {
        let mut c = na("no cluster-robust sd (fewer than two trajectories)");
        c.instants = d.instants;
        return c;
    }
    let z = (full - differences).abs() / combined;
    CommonModeCheck {
        applies: true,
        note: String::new(),
        group,
        param,
        instants: d.instants,
        full,
        full_robust_sd,
        differences,
        differences_robust_sd: d.robust_sd,
        z,
        limit,
        vetoed: z > limit,
        predicted: false,
        predicted_z: f64::NAN,
    }
}
