//! The streamed linearisation against the dense one it replaces: every
//! measured cell's Jacobian row built from a kept prediction
//! (`predict_with`, all outputs at every time) placed in the columns of
//! theta, the stack whitened column by column by a whitener built from that
//! prediction's own `M(t)`, and multiplied out with nalgebra.

use super::*;
use crate::fit::fit_with;
use crate::Rng;
use nalgebra::{DMatrix, DVector};
use obsan_data::{Series, Trajectory};
use obsan_model::System;
use proptest::prelude::*;
use std::collections::BTreeMap;

/// Relative tolerance of a sum of products of the same numbers taken in
/// another order (per trajectory, then across them; the dense reference
/// column by column): each of the at most a few hundred terms is exact to
/// one rounding, so the sums agree to about n * 2^-52 of the sum of the
/// terms' magnitudes; 1e-10 leaves a margin of 100 over 200 terms.
const REORDERED: f64 = 1e-10;

/// A damped oscillator driven by a measured input, two outputs (the second
/// measured where `measured_s` says), `n_traj` trajectories of `rows` rows.
fn problem(rng: &mut Rng, n_traj: usize, rows: usize, s_rate: f64) -> (Predictor, Vec<Trajectory>) {
    let src = "system osc\nstate x, v\nparam k, c\ninput u\nx' = v\n\
               v' = -k*x - c*v + u\noutput y = x\noutput s = v\n";
    let sys = System::parse(src, "osc.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let trajs = (0..n_traj)
        .map(|k| {
            let (w, amp, ph) = (0.5 + 2.0 * rng.uniform(), 1.0 + rng.uniform(), rng.normal());
            let mut inputs = Series::new(vec!["u".into()]);
            let mut outputs = Series::new(vec!["y".into(), "s".into()]);
            for i in 0..=rows {
                let t = i as f64 * 0.05;
                inputs.push(t, &[Some((t * w + ph).sin())]);
                if i > 0 {
                    let y = amp * (-0.2 * t).exp() * (1.3 * t).cos() + 0.05 * rng.normal();
                    let s = (rng.uniform() < s_rate).then(|| -0.5 * (1.1 * t).sin());
                    outputs.push(t, &[Some(y), s]);
                }
            }
            Trajectory {
                name: format!("t{k}"),
                inputs,
                outputs,
                meta: BTreeMap::new(),
            }
        })
        .collect();
    (p, trajs)
}

fn fit_trajs(data: &[Trajectory]) -> Vec<FitTrajectory<'_>> {
    data.iter()
        .map(|t| FitTrajectory {
            name: &t.name,
            inputs: &t.inputs,
            outputs: &t.outputs,
            consts: vec![],
        })
        .collect()
}

fn options(noise: bool) -> FitOptions {
    FitOptions {
        max_iterations: 30,
        cost_tolerance: 1e-12,
        step_tolerance: 0.0,
        sigma: vec![0.05, 0.1],
        max_step: 0.0,
        input_noise: noise.then(|| vec![0.02]),
    }
}

/// The dense linearisation at `theta`, whitened (with input noise) by the
/// whitener of the prediction at `w_at`: the stacked Jacobian, the
/// whitened residuals, and per output the sum of squared raw residuals.
fn dense(
    p: &Predictor,
    trajs: &[FitTrajectory],
    lay: &Layout,
    opts: &FitOptions,
    theta: &[f64],
    w_at: &[f64],
) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
    let (ns, nd, n) = (p.state.len(), p.n_dynamic, lay.len());
    let (mut rows, mut res, mut sq) = (Vec::<f64>::new(), Vec::<f64>::new(), vec![0.0; 2]);
    for (k, t) in trajs.iter().enumerate() {
        let integ = Integration {
            max_step: 0.0,
            sensitivities: true,
            input_noise: opts.input_noise.clone(),
        };
        let pred = |th: &[f64]| {
            p.predict_with(&lay.state_of(th, k), &[], t.inputs, t.outputs.t(), &integ)
                .unwrap()
        };
        let (at, wp) = (pred(theta), pred(w_at));
        let (mut rk, mut jk, mut a, mut m) = (vec![], vec![], vec![], vec![]);
        for j in 0..t.outputs.len() {
            for (o, name) in p.outputs.iter().enumerate() {
                let Some(v) = t.outputs.column(name).unwrap()[j] else {
                    continue;
                };
                let d = v - at.outputs[j][o];
                sq[o] += d * d;
                rk.push(d / opts.sigma[o]);
                let own = &at.jacobians[j][o * ns..(o + 1) * ns];
                let w_own = &wp.jacobians[j][o * ns..(o + 1) * ns];
                a.extend(w_own[..nd].iter().map(|x| x / opts.sigma[o]));
                if opts.input_noise.is_some() {
                    m.extend_from_slice(&wp.noise_m[j]);
                }
                let mut full = vec![0.0; n];
                for (c, &col) in lay.columns(k).iter().enumerate() {
                    full[col] = own[c] / opts.sigma[o];
                }
                jk.push(full);
            }
        }
        if opts.input_noise.is_some() {
            let w = Whitener::new(nd, a, m).unwrap();
            w.whiten_in_place(&mut rk);
            for c in 0..n {
                let mut col: Vec<f64> = jk.iter().map(|r| r[c]).collect();
                w.whiten_in_place(&mut col);
                for (r, x) in jk.iter_mut().zip(col) {
                    r[c] = x;
                }
            }
        }
        res.extend(rk);
        rows.extend(jk.into_iter().flatten());
    }
    (
        DMatrix::from_row_slice(res.len(), n, &rows),
        DVector::from_column_slice(&res),
        sq,
    )
}

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= REORDERED * scale.max(f64::MIN_POSITIVE)
}

fn check_vec(got: &[f64], want: &DVector<f64>, what: &str) {
    let scale = want
        .amax()
        .max(got.iter().fold(0.0f64, |m, x| m.max(x.abs())));
    for (i, (g, w)) in got.iter().zip(want.iter()).enumerate() {
        assert!(close(*g, *w, scale), "{what}[{i}]: {g} vs {w}");
    }
}

/// A point near `theta` (every entry moved by up to 10 %).
fn near(rng: &mut Rng, theta: &[f64]) -> Vec<f64> {
    theta
        .iter()
        .map(|x| x + 0.1 * (x.abs() + 0.1) * rng.normal())
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The streamed normal equations, score, cost and raw sums of squares
    /// equal the dense ones; a trial's `J^T r` of the stored rows is the
    /// dense current Jacobian against the trial's residuals, with a spare
    /// and overwriting in place alike; after an accepted trial the stored
    /// rows are the trial's.
    #[test]
    fn streamed_linearisation_equals_the_dense_one(
        seed in any::<u64>(),
        n_traj in 1usize..4,
        rows in 3usize..40,
        s_rate in 0.0f64..1.0,
        noise in any::<bool>(),
        spare in any::<bool>(),
    ) {
        let mut rng = Rng::new(seed);
        let (p, data) = problem(&mut rng, n_traj, rows, s_rate);
        let trajs = fit_trajs(&data);
        let opts = options(noise);
        let params = vec![1.0 + rng.uniform(), 0.2 + 0.5 * rng.uniform()];
        let states: Vec<Vec<f64>> = (0..n_traj).map(|_| vec![1.0 + 0.2 * rng.normal(), 0.2 * rng.normal()]).collect();
        let prob = Problem::new(&p, &trajs, &opts, &params, &states).unwrap();
        let mut theta = params.clone();
        theta.extend(states.iter().flatten());
        let lay = &prob.lay;
        let mut store = JacStore::new(n_traj, spare);
        let lin = prob.normal(&theta, true, Rows::Keep(&store)).unwrap();
        store.valid = true;
        let (j, r, sq) = dense(&p, &trajs, lay, &opts, &theta, &theta);
        let jtj = j.transpose() * &j;
        let jtr = j.transpose() * &r;
        let scale = jtj.amax();
        for a in 0..lay.len() {
            for b in 0..lay.len() {
                prop_assert!(close(lin.jtj[a][b], jtj[(a, b)], scale), "jtj ({a},{b})");
            }
        }
        check_vec(&lin.jtr, &jtr, "jtr");
        prop_assert!(close(lin.cost, r.norm_squared(), r.norm_squared()));
        prop_assert_eq!(lin.n_residuals, r.len());
        check_vec(&lin.sq_sum, &DVector::from_column_slice(&sq), "sq_sum");
        let mut sum = vec![0.0; lay.len()];
        for (k, g) in lin.score.iter().enumerate() {
            for (&col, x) in lay.columns(k).iter().zip(g) {
                sum[col] += x;
            }
        }
        check_vec(&sum, &jtr, "scores");
        // Two trials in a row, both accepted: each one's J^T r is the
        // previous point's Jacobian against its residuals, all whitened
        // by the whitener placed at theta.
        let mut prev = theta.clone();
        for _ in 0..2 {
            let cand = near(&mut rng, &prev);
            let next = prob.normal(&cand, false, Rows::Trial(&store)).unwrap();
            store.settle(true);
            let (jp, _, _) = dense(&p, &trajs, lay, &opts, &prev, &theta);
            let (jc, rc, _) = dense(&p, &trajs, lay, &opts, &cand, &theta);
            check_vec(&next.old_jt, &(jp.transpose() * &rc), "old_jt");
            check_vec(&next.jtr, &(jc.transpose() * &rc), "trial jtr");
            prev = cand;
        }
        // A rejected trial: with a spare the rows stay, without one they
        // are marked stale.
        let cand = near(&mut rng, &prev);
        prob.normal(&cand, false, Rows::Trial(&store)).unwrap();
        store.settle(false);
        prop_assert_eq!(store.valid, spare);
    }

    /// The fit's estimate is the same, number for number, whether the
    /// trial's rows go to a spare or overwrite the current ones (then each
    /// rejected trial re-linearises the current point): the two paths
    /// differ in memory and time only.
    #[test]
    fn the_fit_is_the_same_with_and_without_a_spare_jacobian(
        seed in any::<u64>(),
        noise in any::<bool>(),
    ) {
        let mut rng = Rng::new(seed);
        let (p, data) = problem(&mut rng, 2, 30, 0.4);
        let trajs = fit_trajs(&data);
        let opts = options(noise);
        // Far from the optimum, so that some trials are rejected.
        let params = vec![0.3 + 3.0 * rng.uniform(), 2.0 * rng.uniform()];
        let states = vec![vec![rng.normal(), rng.normal()], vec![rng.normal(), rng.normal()]];
        let run = |spare| fit_with(&p, &trajs, &params, &states, &opts, Some(spare));
        match (run(true), run(false)) {
            (Ok(a), Ok(b)) => {
                prop_assert_eq!(&a.params, &b.params);
                prop_assert_eq!(&a.initial_states, &b.initial_states);
                prop_assert_eq!(a.cost.to_bits(), b.cost.to_bits());
                prop_assert_eq!(a.iterations, b.iterations);
                prop_assert_eq!(&a.params_sd, &b.params_sd);
            }
            (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
            (a, b) => prop_assert!(false, "{:?} vs {:?}", a.map(|r| r.cost), b.map(|r| r.cost)),
        }
    }
}

/// The whitener built residual by residual while the rows are whitened
/// equals the one built from stored `a_i` and `M(t_i)`, and whitens a
/// residual and its row exactly as column by column.
#[test]
fn row_by_row_whitening_is_column_by_column_whitening() {
    let mut rng = Rng::new(5);
    let (n, r, width) = (40, 2, 4);
    let mut acc = vec![0.0; r * r];
    let (mut a, mut m) = (Vec::new(), Vec::new());
    for _ in 0..n {
        a.extend((0..r).map(|_| 3.0 * rng.normal()));
        let b: Vec<f64> = (0..r * r).map(|_| 0.2 * rng.normal()).collect();
        for x in 0..r {
            for y in 0..r {
                acc[x * r + y] += (0..r).map(|k| b[x * r + k] * b[y * r + k]).sum::<f64>();
            }
        }
        m.extend_from_slice(&acc);
    }
    let w = Whitener::new(r, a.clone(), m.clone()).unwrap();
    let cols: Vec<Vec<f64>> = (0..width)
        .map(|_| (0..n).map(|_| rng.normal()).collect())
        .collect();
    let mut b = WhitenerBuilder::new(r, n, true);
    let mut f = RowFilter::new(r, width);
    let mut rows = vec![vec![0.0; width]; n];
    for (i, row) in rows.iter_mut().enumerate() {
        for (c, col) in cols.iter().enumerate() {
            row[c] = col[i];
        }
        let (ai, g, sd) = b
            .push(&a[i * r..(i + 1) * r], &m[i * r * r..(i + 1) * r * r])
            .unwrap();
        f.apply(ai, g, sd, row);
    }
    let built = b.finish().unwrap();
    assert_eq!(built.log_det().to_bits(), w.log_det().to_bits());
    for (c, col) in cols.iter().enumerate() {
        let want = w.whiten(col);
        for (i, x) in want.iter().enumerate() {
            assert_eq!(rows[i][c].to_bits(), x.to_bits(), "row {i} column {c}");
        }
    }
}
