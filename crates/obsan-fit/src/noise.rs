//! Maximum-likelihood noise levels: each output's white-noise standard
//! deviation and each measured input's noise intensity, from the residuals
//! of a fit (variance components).
//!
//! Linearised about the fitted trajectory, the residuals of one trajectory
//! are `d = A w + v`: `v` white with `sd(v_i) = sigma_o(i)`, `w(t)` the
//! integrated input noise (a random walk with `Cov w(t) = sum_j c_j M_j(t)`,
//! [`crate::Integration::input_noise`] with `c = e_j`) and `A` the
//! residuals' sensitivities to the initial dynamic state. With the
//! sensitivities held at the fit, the restricted likelihood of the levels
//! (each trajectory's initial state profiled out, since it is fitted) is
//!
//! ```text
//! -2 log L(sigma, c) = sum_i [ e_i^2 + log S_i + 2 log sigma_o(i) ]
//!                      - e^T W (W^T W)^-1 W^T e + log det(W^T W) + n log(2 pi)
//! ```
//!
//! where `e_i`, `S_i` are the normalised innovations and variances of the [`Whitener`] (the
//! Cholesky factor `L` of `I + A' M A'^T`, `A' = diag(1/sigma) A`) and
//! `W = L^-1 A'`; one evaluation costs O(n r^2). Holding the initial state
//! at a fit made under other levels instead biases the intensities (an
//! initial-pose error then looks like early drift). It is minimised over
//! `log sigma` and `log c` by BFGS with central-difference gradients, from
//! the best point of a grid. The shared params are held (the caller refits
//! with the new levels and may call again).
//!
//! Linearised about the fitted path, the estimate is consistent while the
//! drift stays small against the geometry (tests/noise.rs: a heading sd of
//! 0.03 rad, ranges of metres); with larger drift (0.1 rad and more) the
//! neglected second-order terms are read as extra input noise, so the
//! intensities come out high (up to twice), which errs towards larger
//! standard deviations, not smaller.

use crate::options::FitTrajectory;
use crate::predict::{Integration, Predictor};
use crate::whiten::Whitener;
use crate::FitError;
use obsan_data::wrap;
use rayon::prelude::*;

/// Options; every tolerance explicit.
#[derive(Clone, Debug)]
pub struct NoiseOptions {
    /// BFGS iterations at most.
    pub max_iterations: usize,
    /// Stop when an iteration lowers `-2 log L` by less than this.
    pub tolerance: f64,
    /// Longest integration step (s), see [`Integration::max_step`].
    pub max_step: f64,
    /// Estimate the output levels too (else they stay at the given ones).
    pub outputs: bool,
    /// Smallest input-noise intensity considered (below it the input is
    /// reported as noiseless: its `c` is set to 0).
    pub min_intensity: f64,
}

impl Default for NoiseOptions {
    fn default() -> Self {
        NoiseOptions {
            max_iterations: 200,
            tolerance: 1e-3,
            max_step: 0.5,
            outputs: true,
            min_intensity: 1e-12,
        }
    }
}

/// The estimated levels.
#[derive(Clone, Debug)]
pub struct NoiseEstimate {
    /// Per output of the predictor (outputs without data keep the given level).
    pub sigma: Vec<f64>,
    /// Per input of the predictor: `c_j` (0 where not estimated).
    pub input_noise: Vec<f64>,
    /// `-2 log L` at the estimate and at the best white-noise model (every
    /// `c = 0`, each estimated `sigma` its output's RMS residual); their
    /// difference is the likelihood-ratio statistic of the input noise.
    pub m2ll: f64,
    pub m2ll_white: f64,
    /// Residuals used.
    pub n: usize,
    pub iterations: usize,
}

/// One trajectory's residuals and the matrices of the likelihood.
struct Parts {
    /// Raw residual, its output, its sensitivity to the initial dynamic state.
    d: Vec<f64>,
    o: Vec<usize>,
    a: Vec<f64>,
    /// Per estimated input: `M_j` at each residual's time (nd x nd each).
    m: Vec<Vec<f64>>,
}

/// A prediction error of trajectory `t`, naming it.
fn named(t: &FitTrajectory, e: FitError) -> FitError {
    FitError::Trajectory {
        name: t.name.to_string(),
        source: Box::new(e),
    }
}

/// Estimate the noise levels at a fit (`params`, `states` per trajectory).
/// `sigma0` starts the output levels; `inputs[j]` says whether input `j`'s
/// intensity is estimated (false for derived inputs, which carry none).
pub fn estimate_noise(
    p: &Predictor,
    trajs: &[FitTrajectory],
    params: &[f64],
    states: &[Vec<f64>],
    sigma0: &[f64],
    inputs: &[bool],
    opts: &NoiseOptions,
) -> Result<NoiseEstimate, FitError> {
    let no = p.outputs.len();
    let nd = p.n_dynamic;
    if sigma0.len() != no || inputs.len() != p.inputs.len() || states.len() != trajs.len() {
        return Err(FitError::NoiseSizes);
    }
    let est_in: Vec<usize> = (0..inputs.len()).filter(|&j| inputs[j]).collect();
    let parts: Vec<Parts> = trajs
        .par_iter()
        .zip(states)
        .map(|(t, x)| Parts::of_trajectory(p, t, x, params, &est_in, opts))
        .collect::<Result<_, FitError>>()?;
    let count: usize = parts.iter().map(|p| p.d.len()).sum();
    let (est_out, white) = white_levels(&parts, sigma0, opts.outputs);

    let dim = est_out.len() + est_in.len();
    let log_min_c = opts.min_intensity.max(1e-300).ln();
    let unpack = |th: &[f64]| -> (Vec<f64>, Vec<f64>) {
        let mut s = sigma0.to_vec();
        for (k, &o) in est_out.iter().enumerate() {
            s[o] = th[k].exp();
        }
        let c: Vec<f64> = th[est_out.len()..].iter().map(|x| x.exp()).collect();
        (s, c)
    };
    let m2ll = |sigma: &[f64], c: &[f64]| -> f64 {
        parts
            .par_iter()
            .map(|pt| pt.m2ll(sigma, c, nd))
            .sum::<f64>()
            + count as f64 * (2.0 * std::f64::consts::PI).ln()
    };
    let m2ll_white = m2ll(&white, &vec![0.0; est_in.len()]);
    if est_in.is_empty() {
        return Ok(NoiseEstimate {
            sigma: white,
            input_noise: vec![0.0; inputs.len()],
            m2ll: m2ll_white,
            m2ll_white,
            n: count,
            iterations: 0,
        });
    }
    let eval = |th: &[f64]| {
        let (s, c) = unpack(th);
        m2ll(&s, &c)
    };
    let start = grid_start(&eval, &white, &est_out, est_in.len(), dim, log_min_c)?;
    let lo: Vec<f64> = est_out
        .iter()
        .map(|&o| (white[o] * 1e-4).ln())
        .chain(std::iter::repeat_n(log_min_c, est_in.len()))
        .collect();
    let hi: Vec<f64> = est_out
        .iter()
        .map(|&o| (white[o] * 10.0).ln())
        .chain(std::iter::repeat_n(1e6f64.ln(), est_in.len()))
        .collect();
    let (th, iterations) = bfgs(&eval, start, &lo, &hi, opts.max_iterations, opts.tolerance);
    let (sigma, c) = unpack(&th);
    let value = m2ll(&sigma, &c);
    let mut input_noise = vec![0.0; inputs.len()];
    for (k, &j) in est_in.iter().enumerate() {
        // At the lower bound the data see no noise on this input.
        input_noise[j] = if th[est_out.len() + k] <= log_min_c + 1e-9 {
            0.0
        } else {
            c[k]
        };
    }
    Ok(NoiseEstimate {
        sigma,
        input_noise,
        m2ll: value,
        m2ll_white,
        n: count,
        iterations,
    })
}

impl Parts {
    /// Trajectory `t`'s residuals at the fit (`x` its states, `params` shared), their
    /// sensitivities to the initial dynamic state and, per estimated input `est_in`, the
    /// covariance shape `M_j` of the integrated input noise at each residual's time.
    fn of_trajectory(
        p: &Predictor,
        t: &FitTrajectory,
        x: &[f64],
        params: &[f64],
        est_in: &[usize],
        opts: &NoiseOptions,
    ) -> Result<Parts, FitError> {
        let (n, nd) = (p.state.len(), p.n_dynamic);
        let mut x0 = x.to_vec();
        x0.extend_from_slice(params);
        let cols: Vec<Option<usize>> = p
            .outputs
            .iter()
            .map(|o| t.outputs.columns().iter().position(|c| c == o))
            .collect();
        let predict = |input_noise: Option<Vec<f64>>| {
            let integ = Integration {
                max_step: opts.max_step,
                sensitivities: true,
                input_noise,
            };
            p.predict_with(&x0, &t.consts, t.inputs, t.outputs.t(), &integ)
                .map_err(|e| named(t, e))
        };
        let mut ms: Vec<Vec<Vec<f64>>> = Vec::new();
        let mut pred = None;
        for &j in est_in {
            let mut c = vec![0.0; p.inputs.len()];
            c[j] = 1.0;
            let pr = predict(Some(c))?;
            ms.push(pr.noise_m.clone());
            pred = Some(pr);
        }
        let pred = match pred {
            Some(p) => p,
            None => predict(None)?,
        };
        let mut parts = Parts {
            d: vec![],
            o: vec![],
            a: vec![],
            m: vec![Vec::new(); est_in.len()],
        };
        for (k, yk) in pred.outputs.iter().enumerate() {
            for (o, c) in cols.iter().enumerate() {
                let Some(v) = c.and_then(|c| t.outputs.values()[c][k]) else {
                    continue;
                };
                let d = v - yk[o];
                parts.d.push(if p.angular[o] { wrap(d) } else { d });
                parts.o.push(o);
                parts
                    .a
                    .extend_from_slice(&pred.jacobians[k][o * n..o * n + nd]);
                for (mj, src) in parts.m.iter_mut().zip(&ms) {
                    mj.extend_from_slice(&src[k]);
                }
            }
        }
        Ok(parts)
    }

    /// This trajectory's terms of `-2 log L` (module docs) at output levels `sigma` and
    /// input intensities `c`, without the `n log(2 pi)` constant; infinite where the
    /// covariance is not positive definite.
    fn m2ll(&self, sigma: &[f64], c: &[f64], nd: usize) -> f64 {
        let len = self.d.len();
        let mut a = Vec::with_capacity(len * nd);
        let mut e = Vec::with_capacity(len);
        let mut logs = 0.0;
        for i in 0..len {
            let s = sigma[self.o[i]];
            e.push(self.d[i] / s);
            a.extend(self.a[i * nd..(i + 1) * nd].iter().map(|v| v / s));
            logs += 2.0 * s.ln();
        }
        let mut m = vec![0.0; len * nd * nd];
        for (cj, mj) in c.iter().zip(&self.m) {
            for (x, y) in m.iter_mut().zip(mj) {
                *x += cj * y;
            }
        }
        let Some(w) = Whitener::new(nd, a.clone(), m) else {
            return f64::INFINITY;
        };
        w.whiten_in_place(&mut e);
        // Each initial state is profiled out (its generalised least-squares correction
        // under this covariance) and its restricted-likelihood term added: the levels are
        // not judged at an initial state fitted under other ones.
        let cols: Vec<Vec<f64>> = (0..nd)
            .map(|c| w.whiten(&(0..len).map(|i| a[i * nd + c]).collect::<Vec<f64>>()))
            .collect();
        let ata = nalgebra::DMatrix::from_fn(nd, nd, |x, y| {
            cols[x]
                .iter()
                .zip(&cols[y])
                .map(|(p, q)| p * q)
                .sum::<f64>()
        });
        let ate = nalgebra::DVector::from_fn(nd, |x, _| {
            cols[x].iter().zip(&e).map(|(p, q)| p * q).sum::<f64>()
        });
        let ee: f64 = e.iter().map(|x| x * x).sum();
        let (fit, logdet) = match ata.clone().cholesky() {
            Some(ch) => {
                let sol = ch.solve(&ate);
                let ld: f64 = ch.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
                (ate.dot(&sol), ld)
            }
            None => (0.0, 0.0),
        };
        ee - fit + logdet + w.log_det() + logs
    }
}

/// The outputs whose level is estimated (those with data, when `outputs` is asked) and
/// the best white-noise levels: each estimated output's RMS residual, the others `sigma0`.
fn white_levels(parts: &[Parts], sigma0: &[f64], outputs: bool) -> (Vec<usize>, Vec<f64>) {
    let no = sigma0.len();
    let mut seen = vec![0usize; no];
    let mut sq = vec![0.0; no];
    for pt in parts {
        for (d, &o) in pt.d.iter().zip(&pt.o) {
            seen[o] += 1;
            sq[o] += d * d;
        }
    }
    let est_out: Vec<usize> = (0..no).filter(|&o| outputs && seen[o] > 0).collect();
    let white: Vec<f64> = (0..no)
        .map(|o| {
            if outputs && seen[o] > 0 {
                (sq[o] / seen[o] as f64).sqrt().max(1e-300)
            } else {
                sigma0[o]
            }
        })
        .collect();
    (est_out, white)
}

/// BFGS's starting point (log levels, estimated outputs first, then `n_in` intensities):
/// the output levels at their white-noise values or half of them (drift taken out of
/// the residuals lowers them) with a common intensity on a half-decade grid; then each
/// intensity on the grid in turn, the others held (the likelihood need not be unimodal
/// in them).
fn grid_start(
    eval: &(dyn Fn(&[f64]) -> f64 + Sync),
    white: &[f64],
    est_out: &[usize],
    n_in: usize,
    dim: usize,
    log_min_c: f64,
) -> Result<Vec<f64>, FitError> {
    let grid: Vec<f64> = (-24..=2)
        .map(|k| (10f64.powf(k as f64 / 2.0)).ln().max(log_min_c))
        .collect();
    let mut best = (f64::INFINITY, vec![0.0; dim]);
    for &lc in &grid {
        for f in [1.0f64, 0.5] {
            let mut th: Vec<f64> = est_out.iter().map(|&o| (white[o] * f).ln()).collect();
            th.extend(std::iter::repeat_n(lc, n_in));
            let v = eval(&th);
            if v < best.0 {
                best = (v, th);
            }
        }
    }
    if !best.0.is_finite() {
        return Err(FitError::NoiseNotCarried);
    }
    if n_in > 1 {
        for _ in 0..2 {
            for k in 0..n_in {
                let i = est_out.len() + k;
                for &lc in &grid {
                    let mut th = best.1.clone();
                    th[i] = lc;
                    let v = eval(&th);
                    if v < best.0 {
                        best = (v, th);
                    }
                }
            }
        }
    }
    Ok(best.1)
}

/// An input-noise intensity read from the measured inputs themselves
/// ([`input_noise_from_samples`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledNoise {
    /// `c` of [`Integration::input_noise`]: white noise of spectral density `c |u|`.
    pub c: f64,
    /// Second differences of block means it was read from (after trimming).
    pub samples: usize,
}

/// The median of a chi-square variable with one degree of freedom.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_7;
/// Normalised squared differences above this many times the median-based
/// level are taken for changes of the true input (a stop, a step), not
/// noise: a chi-square(1) exceeds 25 with probability 6e-7.
const TRIM: f64 = 25.0;
/// Fewer usable differences than this give no estimate.
const MIN_SAMPLES: usize = 30;

/// One intensity `c` shared by the given input columns of every series,
/// under the model of [`Integration::input_noise`]: each measured input
/// carries white noise of spectral density `c |u|` (wheel encoders with the
/// error model of [10]: `c = K^2 / r`), so the mean of a row held over `dt`
/// has noise variance `c |u| / dt`, independent from row to row.
///
/// The rows are averaged in blocks of `block` (a block's mean over its
/// duration `T` has noise variance `c |u| / T`: the same model at a coarser
/// rate, so noise correlated over fewer rows than a block, as from
/// resampling, is not lost), and the second divided differences of the
/// block means (zero on any input linear in time) are normalised by their
/// noise variance per unit `c`: each is then `c` times a chi-square(1)
/// where the true input is smooth. Their median over `CHI2_1_MEDIAN` gives
/// a robust level; differences above `TRIM` times it (a step of the true
/// input, a stop) are dropped and the mean of the rest is the estimate.
/// It errs high, never low, when the true input varies within a few blocks
/// (that variation is read as noise). `None` with fewer than `MIN_SAMPLES`
/// usable differences (missing cells break a block; rows with zero
/// duration or blocks standing still carry nothing).
pub fn input_noise_from_samples(
    series: &[&obsan_data::Series],
    columns: &[&str],
    block: usize,
) -> Option<SampledNoise> {
    let block = block.max(1);
    let mut z = Vec::new();
    for s in series {
        let t = s.t();
        for name in columns {
            let Some(v) = s.column(name) else { continue };
            // Block means (time-weighted), their mid times and sum of |u| dt / T^2.
            let mut means: Vec<Option<(f64, f64, f64)>> = Vec::new();
            let rows = t.len().saturating_sub(1); // the last row has no duration
            for b in 0..rows / block {
                let (mut su, mut sa, mut dur) = (0.0, 0.0, 0.0);
                let mut ok = true;
                for k in b * block..(b + 1) * block {
                    let dt = t[k + 1] - t[k];
                    match v[k] {
                        Some(u) if u.is_finite() && dt > 0.0 && dt.is_finite() => {
                            su += u * dt;
                            sa += u.abs() * dt;
                            dur += dt;
                        }
                        _ => ok = false,
                    }
                }
                means.push(ok.then(|| {
                    let mid = 0.5 * (t[b * block] + t[(b + 1) * block]);
                    (su / dur, mid, sa / (dur * dur))
                }));
            }
            for w in means.windows(3) {
                let (Some(a), Some(b), Some(c)) = (w[0], w[1], w[2]) else {
                    continue;
                };
                // Weights annihilating constants and slopes at uneven spacing.
                let (h1, h2) = (b.1 - a.1, c.1 - b.1);
                let (wa, wb, wc) = (h2, -(h1 + h2), h1);
                let d = wa * a.0 + wb * b.0 + wc * c.0;
                let var = wa * wa * a.2 + wb * wb * b.2 + wc * wc * c.2;
                if var > 0.0 && var.is_finite() && d.is_finite() {
                    z.push(d * d / var);
                }
            }
        }
    }
    if z.len() < MIN_SAMPLES {
        return None;
    }
    let mut sorted = z.clone();
    let mid = sorted.len() / 2;
    let (_, median, _) = sorted.select_nth_unstable_by(mid, f64::total_cmp);
    let level = *median / CHI2_1_MEDIAN;
    let kept: Vec<f64> = z.into_iter().filter(|x| *x <= TRIM * level).collect();
    // (A chi-square(1) truncated at 25 has mean 1 - 2e-5: no correction.)
    let c = kept.iter().sum::<f64>() / kept.len().max(1) as f64;
    (kept.len() >= MIN_SAMPLES && c.is_finite()).then_some(SampledNoise {
        c,
        samples: kept.len(),
    })
}

/// Minimise `f` within the box `[lo, hi]` by BFGS (projected steps,
/// backtracking line search, central-difference gradients). Returns the
/// minimiser and the iterations used.
///
/// Not the least-squares core: the restricted likelihood is not a sum of
/// squares (its log-determinants, module docs), so Levenberg-Marquardt's
/// `J^T J` does not model it. Not argmin: its BFGS and L-BFGS take no box
/// bounds (it has no L-BFGS-B), and the log-levels need them.
fn bfgs(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x0: Vec<f64>,
    lo: &[f64],
    hi: &[f64],
    max_iterations: usize,
    tolerance: f64,
) -> (Vec<f64>, usize) {
    let d = x0.len();
    let clamp = |x: &mut [f64]| {
        for i in 0..d {
            x[i] = x[i].clamp(lo[i], hi[i]);
        }
    };
    let grad = |x: &[f64]| -> Vec<f64> {
        (0..d)
            .map(|i| {
                let h = 1e-4;
                let (mut a, mut b) = (x.to_vec(), x.to_vec());
                a[i] += h;
                b[i] -= h;
                (f(&a) - f(&b)) / (2.0 * h)
            })
            .collect()
    };
    let mut x = x0;
    clamp(&mut x);
    let mut fx = f(&x);
    let mut g = grad(&x);
    // Inverse Hessian approximation, row-major.
    let mut h = vec![0.0; d * d];
    for i in 0..d {
        h[i * d + i] = 1.0;
    }
    let mut it = 0;
    // Small decreases in a row, and whether H was just reset.
    let mut small = 0;
    let mut fresh = true;
    while it < max_iterations {
        it += 1;
        // Bound-active coordinates pushing outwards are frozen this step.
        let free: Vec<bool> = (0..d)
            .map(|i| !((x[i] <= lo[i] && g[i] > 0.0) || (x[i] >= hi[i] && g[i] < 0.0)))
            .collect();
        let mut dir: Vec<f64> = (0..d)
            .map(|i| {
                if !free[i] {
                    return 0.0;
                }
                -(0..d)
                    .filter(|&j| free[j])
                    .map(|j| h[i * d + j] * g[j])
                    .sum::<f64>()
            })
            .collect();
        let mut slope: f64 = dir.iter().zip(&g).map(|(a, b)| a * b).sum();
        if slope >= 0.0 {
            // Not a descent direction: reset to steepest descent.
            for i in 0..d {
                h[i * d..(i + 1) * d].fill(0.0);
                h[i * d + i] = 1.0;
                dir[i] = if free[i] { -g[i] } else { 0.0 };
            }
            slope = dir.iter().zip(&g).map(|(a, b)| a * b).sum();
            if slope >= 0.0 {
                break;
            }
        }
        // Steps in log levels beyond 2 (a factor e^2) are cut.
        let len = dir.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut step = if len > 2.0 { 2.0 / len } else { 1.0 };
        let mut accepted = None;
        for _ in 0..40 {
            let mut xn: Vec<f64> = (0..d).map(|i| x[i] + step * dir[i]).collect();
            clamp(&mut xn);
            let fnew = f(&xn);
            let moved: f64 = (0..d).map(|i| (xn[i] - x[i]) * g[i]).sum();
            if fnew.is_finite() && fnew <= fx + 1e-4 * moved.min(0.0) {
                accepted = Some((xn, fnew));
                break;
            }
            step *= 0.5;
        }
        let Some((xn, fnew)) = accepted else {
            if fresh {
                break;
            }
            // A stale curvature estimate can point nowhere useful: retry
            // once from steepest descent.
            for i in 0..d {
                h[i * d..(i + 1) * d].fill(0.0);
                h[i * d + i] = 1.0;
            }
            fresh = true;
            continue;
        };
        fresh = false;
        let gn = grad(&xn);
        let s: Vec<f64> = (0..d).map(|i| xn[i] - x[i]).collect();
        let y: Vec<f64> = (0..d).map(|i| gn[i] - g[i]).collect();
        let sy: f64 = s.iter().zip(&y).map(|(a, b)| a * b).sum();
        if sy > 1e-12 {
            // H <- (I - rho s y^T) H (I - rho y s^T) + rho s s^T
            let rho = 1.0 / sy;
            let hy: Vec<f64> = (0..d)
                .map(|i| (0..d).map(|j| h[i * d + j] * y[j]).sum())
                .collect();
            let yhy: f64 = y.iter().zip(&hy).map(|(a, b)| a * b).sum();
            for i in 0..d {
                for j in 0..d {
                    h[i * d + j] += -rho * (hy[i] * s[j] + s[i] * hy[j])
                        + (rho * rho * yhy + rho) * s[i] * s[j];
                }
            }
        }
        let drop = fx - fnew;
        x = xn;
        fx = fnew;
        g = gn;
        small = if drop < tolerance { small + 1 } else { 0 };
        if small >= 3 {
            break;
        }
    }
    (x, it)
}

#[cfg(test)]
mod tests {
    use super::{bfgs, input_noise_from_samples};
    use obsan_data::Series;

    /// Encoder-like rows at 50 Hz: a sine speed profile with stops (steps
    /// of the true input), each row's mean carrying noise of variance
    /// `c |u| / dt` (the simulator's error model of [10]).
    fn noisy(c: f64, seed: u64, rows: usize) -> Series {
        let mut rng = crate::Rng::new(seed);
        let dt = 0.02;
        let mut s = Series::new(vec!["wR".into(), "wL".into()]);
        for k in 0..rows {
            let t = k as f64 * dt;
            let run = t.rem_euclid(30.0) < 25.0;
            let u = if run {
                0.5 * (1.0 + 0.3 * (std::f64::consts::TAU * t / 20.0).sin())
            } else {
                0.0
            };
            let mut m = |u: f64| u + (c * u.abs() / dt).sqrt() * rng.normal();
            let (r, l) = (m(u), m(-0.8 * u));
            s.push(t, &[Some(r), Some(l)]);
        }
        s
    }

    #[test]
    fn sampled_intensity_recovers_the_generating_one_through_steps_and_blocks() {
        let c = 0.001f64.powi(2) / 0.3;
        let (a, b) = (noisy(c, 1, 20_000), noisy(c, 2, 20_000));
        for block in [1, 5] {
            let e = input_noise_from_samples(&[&a, &b], &["wR", "wL"], block).unwrap();
            // About 3% relative sd at block 5 (16,000 differences, MA(2)-correlated).
            assert!((e.c / c - 1.0).abs() < 0.1, "block {block}: {} vs {c}", e.c);
            // Only the stops (a sixth of the time) and their steps are left out.
            assert!(e.samples > 2 * 2 * 20_000 / block * 7 / 10, "{e:?}");
        }
        // Noise-free inputs read as (almost) none; a dataset without the
        // columns, or too short, gives no estimate.
        let clean = noisy(0.0, 3, 2_000);
        let e = input_noise_from_samples(&[&clean], &["wR", "wL"], 5).unwrap();
        assert!(e.c < 1e-3 * c, "{e:?}");
        assert!(input_noise_from_samples(&[&a], &["v"], 5).is_none());
        assert!(input_noise_from_samples(&[&noisy(c, 4, 40)], &["wR"], 5).is_none());
    }

    #[test]
    fn bfgs_finds_the_minimum_of_a_quadratic_and_respects_bounds() {
        // f = (x - 1)^2 + 10 (y + 2)^2 + x y: minimum at the solution of the
        // normal equations 2(x-1) + y = 0, 20(y+2) + x = 0.
        let f = |v: &[f64]| (v[0] - 1.0).powi(2) + 10.0 * (v[1] + 2.0).powi(2) + v[0] * v[1];
        let det = 2.0 * 20.0 - 1.0;
        let (x, y) = ((2.0 * 20.0 + 40.0) / det, (2.0 * -40.0 - 2.0) / det);
        let (v, _) = bfgs(&f, vec![0.0, 0.0], &[-9.0, -9.0], &[9.0, 9.0], 100, 1e-14);
        assert!((v[0] - x).abs() < 1e-5 && (v[1] - y).abs() < 1e-5, "{v:?}");
        // With y >= -1 the minimum lies on that bound, x from 2(x-1) + y = 0.
        let (v, _) = bfgs(&f, vec![0.0, 0.0], &[-9.0, -1.0], &[9.0, 9.0], 100, 1e-14);
        assert!(
            (v[1] + 1.0).abs() < 1e-12 && (v[0] - 1.5).abs() < 1e-5,
            "{v:?}"
        );
    }
}
