//! `Predictor::predict_measured` visits only the measured cells, and what it
//! computes there is exactly what `predict_with` computes for every output:
//! the same values and the same sensitivity rows (dynamic states and
//! params), bit for bit, with and without sensitivities.

use obsan_data::Series;
use obsan_fit::{Integration, Measured, Predictor, Rng};
use obsan_model::System;

/// A lagged unicycle with a speed scale (params in the dynamics and in an
/// output) observing three landmarks by range and bearing.
const MODEL: &str = "system lagged
state x, y, th, va
param kv, T, kr
input v, omega
x' = (1 + kv)*va*cos(th)
y' = (1 + kv)*va*sin(th)
th' = omega
va' = (v - va)/T
output r1 = (1 + kr)*sqrt((6 - x)^2 + (2 - y)^2)
output b1 = atan2(2 - y, 6 - x) - th
output r2 = (1 + kr)*sqrt((-5 - x)^2 + (5 - y)^2)
output b2 = atan2(5 - y, -5 - x) - th
output r3 = (1 + kr)*sqrt((1 - x)^2 + (-6 - y)^2)
output b3 = atan2(-6 - y, 1 - x) - th
";

fn data(rng: &mut Rng) -> (Series, Series) {
    let mut inputs = Series::new(vec!["v".into(), "omega".into()]);
    for k in 0..1500 {
        let t = k as f64 * 0.02;
        inputs.push(
            t,
            &[
                Some(0.3 + 0.1 * (t / 3.0).sin()),
                Some(0.4 * (t / 5.0).cos()),
            ],
        );
    }
    // Sparse cells as in MRCLAM: each time measures one or two landmark
    // outputs, some times repeat, some measure none; one output column
    // (b3) is absent altogether.
    let cols = ["r1", "b1", "r2", "b2", "r3"];
    let mut outputs = Series::new(cols.iter().map(|c| c.to_string()).collect());
    let mut t = 0.05;
    while t < 29.0 {
        let row: Vec<Option<f64>> = (0..cols.len())
            .map(|_| (rng.uniform() < 0.3).then(|| rng.normal()))
            .collect();
        outputs.push(t, &row);
        if rng.uniform() > 0.2 {
            t += 0.13 * rng.uniform();
        }
    }
    (inputs, outputs)
}

#[test]
fn measured_cells_equal_the_full_prediction_exactly() {
    let sys = System::parse(MODEL, "lagged.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let mut rng = Rng::new(7);
    let (inputs, outputs) = data(&mut rng);
    let cells = Measured::new(&p, &outputs);
    assert!(cells.len() > 100 && cells.len() < outputs.len() * 5 / 2);
    let x0 = [0.2, -0.1, 0.5, 0.25, 0.03, 0.3, -0.01];
    let n = x0.len();
    for sensitivities in [false, true] {
        let integ = Integration {
            max_step: 0.5,
            sensitivities,
            input_noise: None,
        };
        let full = p
            .predict_with(&x0, &[], &inputs, outputs.t(), &integ)
            .unwrap();
        let some = p
            .predict_measured(&x0, &[], &inputs, &cells, &integ)
            .unwrap();
        assert_eq!(cells.n_times(), outputs.len());
        assert_eq!(some.outputs.len(), outputs.len());
        let mut seen = 0;
        for k in 0..outputs.len() {
            let (outs, values) = cells.at(k);
            // The cells are those present in the data, in model order.
            let expected: Vec<(usize, f64)> = p
                .outputs
                .iter()
                .enumerate()
                .filter_map(|(o, name)| outputs.column(name).and_then(|c| c[k]).map(|v| (o, v)))
                .collect();
            let got: Vec<(usize, f64)> = outs.iter().copied().zip(values.iter().copied()).collect();
            assert_eq!(got, expected, "cells at time {k}");
            assert_eq!(some.outputs[k].len(), outs.len());
            for (i, &o) in outs.iter().enumerate() {
                assert_eq!(some.outputs[k][i].to_bits(), full.outputs[k][o].to_bits());
                if sensitivities {
                    let a = &some.jacobians[k][i * n..(i + 1) * n];
                    let b = &full.jacobians[k][o * n..(o + 1) * n];
                    assert_eq!(a, b, "row of output {o} at time {k}");
                    assert!(b.iter().any(|v| *v != 0.0));
                }
                seen += 1;
            }
        }
        assert_eq!(seen, cells.len());
        assert_eq!(some.jacobians.is_empty(), !sensitivities);
    }
}
