//! Predicting the outputs of any `.sys` model along measured inputs: the
//! forward model of maximum-likelihood fitting (issue 4) and of the
//! discrepancy workflow (issue 5). The dynamics come from the model file,
//! the single source of truth.

use crate::data::Series;
use obsan_expr::{Tape, Var};
use obsan_model::NormalForm;

/// A compiled model: `S' = f0 + sum_i f_i u_i`, `y = h(S)`.
#[derive(Clone, Debug)]
pub struct Predictor {
    /// Dynamic states (integrated) and params (constant), in model order.
    pub state: Vec<String>,
    pub n_dynamic: usize,
    /// Known constants the model needs a value for (e.g. q), in order.
    pub consts: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// Per output: its values are angles (contains atan/atan2), so residuals wrap.
    pub angular: Vec<bool>,
    /// Roots: for each dynamic state k, f0[k] then f_i[k] for each input.
    dyn_tape: Tape,
    out_tape: Tape,
}

impl Predictor {
    pub fn new(nf: &NormalForm) -> Predictor {
        let n_dynamic = nf.n_dynamic;
        let m = nf.inputs.len();
        let mut roots = Vec::with_capacity(n_dynamic * (m + 1));
        for k in 0..n_dynamic {
            roots.push(nf.f0[k]);
            for f in &nf.fields {
                roots.push(f[k]);
            }
        }
        let consts: Vec<String> = nf
            .consts
            .iter()
            .filter(|c| c.1.is_none())
            .map(|c| c.0.clone())
            .collect();
        let mut vars: Vec<Var> = nf.state_vars.clone();
        vars.extend(
            consts
                .iter()
                .map(|c| nf.ctx.lookup(c).expect("const symbol").var),
        );
        let dyn_tape = Tape::compile(&nf.ctx, &roots, &vars)
            .expect("dynamics use only the state and constants");
        let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let out_tape =
            Tape::compile(&nf.ctx, &outs, &vars).expect("outputs use only the state and constants");
        Predictor {
            state: nf.state.clone(),
            n_dynamic,
            consts,
            inputs: nf.inputs.clone(),
            outputs: nf.outputs.iter().map(|o| o.0.clone()).collect(),
            angular: outs.iter().map(|&h| nf.ctx.is_angle_valued(h)).collect(),
            dyn_tape,
            out_tape,
        }
    }

    fn derivative(
        &self,
        x: &[f64],
        u: &[f64],
        scratch: &mut Vec<f64>,
        vals: &mut [f64],
        dx: &mut [f64],
    ) {
        self.dyn_tape.eval_into(x, scratch, vals);
        let m = self.inputs.len();
        for k in 0..self.n_dynamic {
            let row = &vals[k * (m + 1)..(k + 1) * (m + 1)];
            dx[k] = row[0] + row[1..].iter().zip(u).map(|(f, ui)| f * ui).sum::<f64>();
        }
    }

    /// Outputs at `times`, integrating from `x0` (the whole analysed state:
    /// dynamic states then params) at `inputs.t[0]`, inputs held constant from
    /// each row to the next (classical RK4 on every such interval, split at
    /// the output times). `consts` gives the values of [`Predictor::consts`].
    pub fn predict(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        times: &[f64],
    ) -> Result<Vec<Vec<f64>>, String> {
        if x0.len() != self.state.len() || consts.len() != self.consts.len() {
            return Err(format!(
                "expected {} state values and {} constants",
                self.state.len(),
                self.consts.len()
            ));
        }
        let cols: Vec<usize> = self
            .inputs
            .iter()
            .map(|n| {
                inputs
                    .columns
                    .iter()
                    .position(|c| c == n)
                    .ok_or_else(|| format!("the inputs have no column '{n}'"))
            })
            .collect::<Result<_, _>>()?;
        let mut x: Vec<f64> = x0.iter().chain(consts).copied().collect();
        let nd = self.n_dynamic;
        let mut scratch = Vec::new();
        let mut vals = vec![0.0; self.dyn_tape.n_outputs()];
        let mut out = Vec::with_capacity(times.len());
        let mut yv = vec![0.0; self.outputs.len()];
        let t_start = inputs.t.first().copied().unwrap_or(0.0);
        let mut t = t_start;
        let mut row = 0usize;
        let (mut k1, mut k2, mut k3, mut k4) =
            (vec![0.0; nd], vec![0.0; nd], vec![0.0; nd], vec![0.0; nd]);
        let mut tmp = x.clone();
        for &target in times {
            if target < t - 1e-12 {
                return Err(format!("output time {target} is before {t}: times must not decrease and start at or after the inputs"));
            }
            while t < target - 1e-12 {
                while row + 1 < inputs.len() && inputs.t[row + 1] <= t + 1e-12 {
                    row += 1;
                }
                let next = if row + 1 < inputs.len() {
                    inputs.t[row + 1].min(target)
                } else {
                    target
                };
                let h = next - t;
                let u: Vec<f64> = cols
                    .iter()
                    .map(|&c| inputs.values[c][row].unwrap_or(0.0))
                    .collect();
                self.derivative(&x, &u, &mut scratch, &mut vals, &mut k1);
                for i in 0..nd {
                    tmp[i] = x[i] + h / 2.0 * k1[i];
                }
                self.derivative(&tmp, &u, &mut scratch, &mut vals, &mut k2);
                for i in 0..nd {
                    tmp[i] = x[i] + h / 2.0 * k2[i];
                }
                self.derivative(&tmp, &u, &mut scratch, &mut vals, &mut k3);
                for i in 0..nd {
                    tmp[i] = x[i] + h * k3[i];
                }
                self.derivative(&tmp, &u, &mut scratch, &mut vals, &mut k4);
                for i in 0..nd {
                    x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
                tmp[..nd].copy_from_slice(&x[..nd]);
                if x[..nd].iter().any(|v| !v.is_finite()) {
                    return Err(format!("the state diverged at t = {next}"));
                }
                t = next;
            }
            self.out_tape.eval_into(&x, &mut scratch, &mut yv);
            out.push(yv.clone());
        }
        Ok(out)
    }
}
