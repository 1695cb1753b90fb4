//! Step 4's first half: can these data reveal an effect's parameter? The
//! rank test (Hermann–Krener, exact modulo a prime) of the model *on this
//! data's input class*, over all trajectories at once.
//!
//! The input class is read from the data: per trajectory, the measured
//! inputs (and the model's derived inputs computed from them, e.g. `rate`)
//! are averaged over 1 s blocks; if no measured input varies by more than
//! [`VARYING`] of its size the trajectory is driven by one constant input
//! vector, else by the affine span of the block means (principal directions
//! above [`DIRECTION`] of the largest, at most three). For an input-affine
//! model the fields `F(u) = f0 + sum_i f_i u_i` at sample inputs that span
//! that class generate the same observability codistribution as every input
//! of the class, so the test uses them as the fields of a drift-free
//! system. The trajectories are stacked: one copy of the dynamic states per
//! trajectory (each started anew), the params shared, each copy's known
//! constants set to its values. The test is then exact for that stacked
//! system; what is approximate is only the reading of the class from noisy
//! data (a derived input such as `rate(u)` counts as free when `u` varies).

use crate::error::DiagnoseError;
use obsan_analysis::RankReport;
use obsan_data::Dataset;
use obsan_model::{EffectLibrary, Kind, NormalForm, System};
use serde::Serialize;

/// A measured input varies when the standard deviation of its 1 s block
/// means exceeds this fraction of their root mean square.
pub const VARYING: f64 = 0.02;
/// A principal direction of a varying input class counts when its singular
/// value exceeds this fraction of the largest.
pub const DIRECTION: f64 = 0.03;

/// The inputs that drive each trajectory.
#[derive(Clone, Debug, Serialize)]
pub struct InputClass {
    /// Per trajectory: sample input vectors (in the model's input order)
    /// whose affine span is the class.
    pub samples: Vec<Vec<Vec<f64>>>,
    /// Per trajectory: whether some measured input varies.
    pub varying: Vec<bool>,
}

impl InputClass {
    pub fn describe(&self) -> String {
        let c = self.varying.iter().filter(|v| !**v).count();
        match (c, self.varying.len()) {
            (0, _) => "varying inputs on every trajectory".into(),
            (c, n) if c == n => {
                "constant inputs on every trajectory (e.g. constant-speed circles)".into()
            }
            (c, n) => format!("constant inputs on {c} of {n} trajectories"),
        }
    }
}

fn block_means(t: &[f64], v: &[Option<f64>], block: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let (mut s, mut n, mut start) = (0.0, 0usize, t.first().copied().unwrap_or(0.0));
    for (ti, vi) in t.iter().zip(v) {
        if *ti >= start + block && n > 0 {
            out.push(s / n as f64);
            s = 0.0;
            n = 0;
            start = *ti;
        }
        if let Some(x) = vi {
            s += x;
            n += 1;
        }
    }
    if n > 0 {
        out.push(s / n as f64);
    }
    out
}

/// Read the input class of every trajectory of `data` (which must hold a
/// column for each of `inputs`; `derived[i]` marks the model's derived ones).
pub fn input_class(
    inputs: &[String],
    derived: &[Option<String>],
    data: &Dataset,
) -> Result<InputClass, DiagnoseError> {
    let mut samples = Vec::new();
    let mut varying = Vec::new();
    for tr in &data.trajectories {
        let cols: Vec<Vec<f64>> = inputs
            .iter()
            .map(|n| {
                tr.inputs
                    .column(n)
                    .map(|c| block_means(tr.inputs.t(), c, 1.0))
                    .ok_or_else(|| DiagnoseError::NoInputColumn {
                        trajectory: tr.name.clone(),
                        column: n.clone(),
                    })
            })
            .collect::<Result<_, _>>()?;
        let nb = cols.iter().map(Vec::len).min().unwrap_or(0);
        if nb == 0 {
            return Err(DiagnoseError::NoInputRows {
                trajectory: tr.name.clone(),
            });
        }
        let mean: Vec<f64> = cols
            .iter()
            .map(|c| c[..nb].iter().sum::<f64>() / nb as f64)
            .collect();
        let varies = cols
            .iter()
            .zip(derived)
            .filter(|(_, d)| d.is_none())
            .any(|(c, _)| {
                let m = c[..nb].iter().sum::<f64>() / nb as f64;
                let rms = (c[..nb].iter().map(|x| x * x).sum::<f64>() / nb as f64).sqrt();
                let sd = (c[..nb].iter().map(|x| (x - m).powi(2)).sum::<f64>() / nb as f64).sqrt();
                rms > 0.0 && sd > VARYING * rms
            });
        varying.push(varies);
        if !varies {
            // One constant input: rates are exactly zero, not noise.
            let s: Vec<f64> = mean
                .iter()
                .zip(derived)
                .map(|(m, d)| match d {
                    Some(d) if d.trim_start().starts_with("rate(") => 0.0,
                    _ => *m,
                })
                .collect();
            samples.push(vec![s]);
            continue;
        }
        // Principal directions of the centred block means, each column scaled
        // by its own spread so that units do not matter.
        let scale: Vec<f64> = cols
            .iter()
            .zip(&mean)
            .map(|(c, m)| {
                (c[..nb].iter().map(|x| (x - m).powi(2)).sum::<f64>() / nb as f64)
                    .sqrt()
                    .max(1e-300)
            })
            .collect();
        let a =
            nalgebra::DMatrix::from_fn(nb, inputs.len(), |r, c| (cols[c][r] - mean[c]) / scale[c]);
        if a.iter().any(|x| !x.is_finite()) {
            return Err(DiagnoseError::NonFiniteInputs {
                trajectory: tr.name.clone(),
            });
        }
        let svd = nalgebra::SVD::try_new(a, false, true, 1e-14, 10_000).ok_or_else(|| {
            DiagnoseError::InputClassNotConverged {
                trajectory: tr.name.clone(),
            }
        })?;
        let Some(vt) = svd.v_t else {
            return Err(DiagnoseError::NoSingularVectors);
        };
        let smax = svd.singular_values.max();
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&i, &j| svd.singular_values[j].total_cmp(&svd.singular_values[i]));
        let mut s = vec![mean.clone()];
        for &i in order.iter().take(3) {
            let sv = svd.singular_values[i];
            if sv <= DIRECTION * smax || sv == 0.0 {
                continue;
            }
            let amp = sv / (nb as f64).sqrt();
            s.push(
                (0..inputs.len())
                    .map(|c| mean[c] + amp * vt[(i, c)] * scale[c])
                    .collect(),
            );
        }
        samples.push(s);
    }
    Ok(InputClass { samples, varying })
}

/// The stacked system's rank test.
#[derive(Clone, Debug, Serialize)]
pub struct Identifiability {
    pub rank: usize,
    pub n: usize,
    /// Per unknown of the stacked system (states named `x[trajectory]`, then
    /// params): identifiable on its own.
    pub observable: Vec<(String, bool)>,
    /// Probability that the rank is too low (never too high).
    pub error_bound: f64,
    /// Per param that is not identifiable: a null vector of the stacked
    /// codistribution at the given point (numeric), as (name, coefficient),
    /// the param's own coefficient 1.
    pub symmetries: Vec<(String, Vec<(String, f64)>)>,
}

impl Identifiability {
    pub fn param_observable(&self, name: &str) -> bool {
        self.observable.iter().any(|(n, o)| n == name && *o)
    }
}

fn num(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.6e}")
    }
}

/// Most variables the rank test's basis functions may reach for the null
/// vectors of the hidden params: their SVD is dense in this number squared
/// (1,000: 8 MB, about a second).
pub const MAX_NULL_COLUMNS: usize = 1_000;

/// Refuse, before anything is built, an effect of `lib` whose expressions
/// use more than [`MAX_NULL_COLUMNS`] of its new params (the screen, the
/// rank test and the fits are dense in their number squared). Params it
/// declares and never uses are not counted: they cost nothing.
pub fn check_effect_sizes(lib: &EffectLibrary) -> Result<(), DiagnoseError> {
    for e in &lib.effects {
        let mut used = std::collections::HashSet::new();
        let texts = e
            .outputs
            .iter()
            .chain(&e.dynamics)
            .chain(&e.substs)
            .chain(&e.compares)
            .map(|(_, x)| x.as_str())
            .chain(e.delay.as_deref());
        for text in texts {
            used.extend(text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')));
        }
        let params = e
            .params
            .iter()
            .filter(|p| used.contains(p.as_str()))
            .count();
        if params > MAX_NULL_COLUMNS {
            return Err(DiagnoseError::EffectTooLarge {
                params,
                limit: MAX_NULL_COLUMNS,
                at: format!("{}:{}: effect '{}'", lib.origin, e.line, e.name),
            });
        }
    }
    Ok(())
}

/// The rank test of `sys` on the class of `data` over the trajectories
/// `which` (at most a few: each adds a copy of the state). `consts[k]` are
/// trajectory k's constant values; `point` (params, then per chosen
/// trajectory its dynamic state) is where null vectors are evaluated.
pub fn stacked_rank(
    sys: &System,
    class: &InputClass,
    consts: &[Vec<(String, f64)>],
    outputs_seen: &[Vec<bool>],
    which: &[usize],
    point: (&[f64], &[Vec<f64>]),
) -> Result<Identifiability, DiagnoseError> {
    let text = stacked_text(sys, class, consts, outputs_seen, which)?;
    let stacked =
        System::parse(&text, "stacked").map_err(|e| DiagnoseError::Stacking(Box::new(e)))?;
    let mut nf = stacked
        .normal_form(None, &[])
        .map_err(DiagnoseError::model)?;
    let report = obsan_analysis::rank(&mut nf, Default::default()).map_err(DiagnoseError::Rank)?;
    let observable: Vec<(String, bool)> = nf
        .state
        .iter()
        .zip(&report.observable)
        .map(|(n, o)| (pretty(n, which), *o))
        .collect();
    // Numeric null vectors at the point, for the params that are not identifiable.
    let hidden: Vec<usize> = (nf.n_dynamic..nf.state.len())
        .filter(|&i| !report.observable[i])
        .collect();
    let symmetries = if hidden.is_empty() {
        Vec::new()
    } else {
        let n_states = sys.decls_of(Kind::State).count();
        hidden_symmetries(&mut nf, &report, &hidden, which, n_states, point)?
    };
    Ok(Identifiability {
        rank: report.rank,
        n: report.n,
        observable,
        error_bound: report.error_bound,
        symmetries,
    })
}

/// A stacked variable's name for the reader: `x__t1` is trajectory `which[1]`'s `x`,
/// written `x[k]`; a param keeps its name.
fn pretty(n: &str, which: &[usize]) -> String {
    match n.rsplit_once("__t") {
        Some((s, c)) => {
            let k = c.parse::<usize>().map(|c| which[c]).unwrap_or(0);
            format!("{s}[{k}]")
        }
        None => n.to_string(),
    }
}

/// The `.sys` text of the stacked drift-free system: per chosen trajectory `c`, a copy
/// `x__t{c}` of each state driven by one input `v__t{c}_{a}` per sample of its input
/// class (the field `F(u_a)` with that trajectory's constants), the params shared, and
/// the outputs that trajectory measured.
fn stacked_text(
    sys: &System,
    class: &InputClass,
    consts: &[Vec<(String, f64)>],
    outputs_seen: &[Vec<bool>],
    which: &[usize],
) -> Result<String, DiagnoseError> {
    let states: Vec<String> = sys.decls_of(Kind::State).map(|d| d.name.clone()).collect();
    let params: Vec<String> = sys.decls_of(Kind::Param).map(|d| d.name.clone()).collect();
    let outputs: Vec<String> = sys.output_names().iter().map(|s| s.to_string()).collect();
    let mut text = String::from("system stacked\n");
    let mut st_names = Vec::new();
    let mut in_names = Vec::new();
    for (c, &k) in which.iter().enumerate() {
        for s in &states {
            st_names.push(format!("{s}__t{c}"));
        }
        for a in 0..class.samples[k].len() {
            in_names.push(format!("v__t{c}_{a}"));
        }
    }
    text.push_str(&format!("state {}\n", st_names.join(", ")));
    if !params.is_empty() {
        text.push_str(&format!("param {}\n", params.join(", ")));
    }
    text.push_str(&format!("input {}\n", in_names.join(", ")));
    let mut any_output = false;
    for (c, &k) in which.iter().enumerate() {
        let mut base: Vec<(String, String)> = states
            .iter()
            .map(|s| (s.clone(), format!("{s}__t{c}")))
            .collect();
        for (n, v) in &consts[k] {
            base.push((n.clone(), num(*v)));
        }
        for s in &states {
            let terms = sampled_fields(sys, s, &class.samples[k], &base, c)?;
            text.push_str(&format!("{s}__t{c}' = {}\n", terms.join(" + ")));
        }
        for (o, y) in outputs.iter().enumerate() {
            if !outputs_seen[k].get(o).copied().unwrap_or(false) {
                continue;
            }
            any_output = true;
            let h = sys
                .rhs_text(y)
                .ok_or(DiagnoseError::Incomplete("output without expression"))?;
            text.push_str(&format!("output {y}__t{c} = {}\n", substitute(h, &base)));
        }
    }
    if !any_output {
        return Err(DiagnoseError::NoOutputMeasured);
    }
    Ok(text)
}

/// State `s`'s equation in copy `c`: one term `v__t{c}_{a} * rhs(u_a)` per sample input
/// `u_a` of the class, the states renamed and the constants set by `base`.
fn sampled_fields(
    sys: &System,
    s: &str,
    samples: &[Vec<f64>],
    base: &[(String, String)],
    c: usize,
) -> Result<Vec<String>, DiagnoseError> {
    let inputs: Vec<String> = sys.decls_of(Kind::Input).map(|d| d.name.clone()).collect();
    let rhs = sys
        .rhs_text(s)
        .ok_or(DiagnoseError::Incomplete("state without equation"))?;
    Ok(samples
        .iter()
        .enumerate()
        .map(|(a, u)| {
            let mut m = base.to_vec();
            // With a delay the class also holds each input's rate
            // (after the inputs): u(t - tau) ~ u - tau du/dt.
            for (i, n) in inputs.iter().enumerate() {
                let val = match (&sys.delay, u.get(inputs.len() + i)) {
                    (Some(tau), Some(du)) => {
                        format!("{} - {tau}*({})", num(u[i]), num(*du))
                    }
                    _ => num(u[i]),
                };
                m.push((n.clone(), val));
            }
            format!("v__t{c}_{a}*({})", substitute(rhs, &m))
        })
        .collect())
}

/// Per hidden param (`hidden`, indices into the stacked state): a numeric null vector of
/// the stacked codistribution at `point` (params, then per chosen trajectory its dynamic
/// state; `n_states` per copy), scaled so the param's own coefficient is 1. Empty where
/// the gradients at the point are not finite.
fn hidden_symmetries(
    nf: &mut NormalForm,
    report: &RankReport,
    hidden: &[usize],
    which: &[usize],
    n_states: usize,
    point: (&[f64], &[Vec<f64>]),
) -> Result<Vec<HiddenSymmetry>, DiagnoseError> {
    let (pv, sv) = point;
    let mut x = Vec::with_capacity(nf.state.len());
    for &k in which {
        x.extend(sv.get(k).cloned().unwrap_or_else(|| vec![0.1; n_states]));
    }
    x.extend(pv.iter().copied());
    x.resize(nf.state.len(), 0.0);
    // Only the variables the basis functions reach have a non-zero
    // gradient column: each other one is a null direction on its own
    // (d/dx_j, exactly), so the gradients and the SVD are sized by what
    // the outputs reach, not by the number of params (an
    // effect with 6,000 params made a 6,000^2 SVD).
    let ids = report.basis_functions(nf).map_err(DiagnoseError::Rank)?;
    let reached = obsan_expr::lie::reached_states(&nf.ctx, &nf.state_vars, &[], &ids);
    if reached.len() > MAX_NULL_COLUMNS {
        return Err(DiagnoseError::TooManyReached {
            reached: reached.len(),
            limit: MAX_NULL_COLUMNS,
            at: String::new(),
        });
    }
    let vars: Vec<_> = reached.iter().map(|&j| nf.state_vars[j]).collect();
    let x: Vec<f64> = reached.iter().map(|&j| x[j]).collect();
    let mut grads = Vec::new();
    for &id in &ids {
        for &v in &vars {
            grads.push(nf.ctx.diff(id, v));
        }
    }
    let tape = obsan_expr::Tape::compile(&nf.ctx, &grads, &vars)
        .map_err(|_| DiagnoseError::GradientTape)?;
    let g = tape.eval(&x);
    let n = vars.len();
    let r = report.basis.len();
    // Null space of the r x n gradient matrix: right singular vectors.
    let mut m = nalgebra::DMatrix::zeros(r.max(n), n);
    for i in 0..r {
        for j in 0..n {
            m[(i, j)] = g[i * n + j];
        }
    }
    // A point where the gradients are not finite gives no null vector.
    let svd = if m.iter().all(|x| x.is_finite()) {
        nalgebra::SVD::try_new(m, false, true, 1e-14, 10_000)
    } else {
        None
    };
    let Some(svd) = svd else {
        return Ok(Vec::new());
    };
    let Some(vt) = svd.v_t else {
        return Err(DiagnoseError::NoSingularVectors);
    };
    let smax = svd.singular_values.max().max(1e-300);
    let null: Vec<Vec<f64>> = (0..n)
        .filter(|&i| svd.singular_values[i] < 1e-8 * smax)
        .map(|i| (0..n).map(|j| vt[(i, j)]).collect())
        .collect();
    let mut symmetries = Vec::new();
    for &hv in hidden {
        let Ok(h) = reached.binary_search(&hv) else {
            // Not reached: its own symmetry.
            symmetries.push((
                nf.state[hv].clone(),
                vec![(pretty(&nf.state[hv], which), 1.0)],
            ));
            continue;
        };
        // The null vector (in the span) with the largest weight on h.
        let mut best: Option<Vec<f64>> = None;
        for v in &null {
            if best.as_ref().is_none_or(|b| v[h].abs() > b[h].abs()) {
                best = Some(v.clone());
            }
        }
        let Some(v) = best.filter(|v| v[h].abs() > 1e-9) else {
            continue;
        };
        let terms: Vec<(String, f64)> = (0..n)
            .filter(|&j| (v[j] / v[h]).abs() > 1e-6)
            .map(|j| (pretty(&nf.state[reached[j]], which), v[j] / v[h]))
            .collect();
        symmetries.push((nf.state[hv].clone(), terms));
    }
    Ok(symmetries)
}

/// A hidden param and its null vector, as in [`Identifiability::symmetries`].
type HiddenSymmetry = (String, Vec<(String, f64)>);

/// Whole-identifier substitution (see obsan-model's effect patches).
fn substitute(text: &str, map: &[(String, String)]) -> String {
    obsan_model::substitute_names(text, map)
}
