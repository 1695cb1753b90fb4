//! Input-output relations: a hand-derived case, and the measurement of the
//! relations' sizes on the SI.jl models the Taylor route cannot do
//! (`cargo test --release -p obsan-analysis --lib io_sizes -- --ignored --nocapture`).

use super::super::model::zmodel;
use super::super::run::Rng;
use super::*;
use obsan_model::System;
use obsan_recon::{Thiele, PRIMES};
use std::time::Instant;

fn model(src: &str, name: &str) -> ZModel {
    let sys = System::parse(src, name).unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    zmodel(&mut nf).unwrap()
}

/// The coefficient of monomial `m` in `r` (0 if absent).
fn coeff(r: &IoRelation, m: &[u32]) -> u64 {
    r.support
        .iter()
        .position(|s| s == m)
        .map_or(0, |i| r.coeffs[i])
}

#[test]
fn decay_with_input() {
    // x' = -a x + u, y = x: y' = -a y + u, so y' + a y - u = 0: order 1,
    // degree 1, in the variables (y, y', u, u'); up to scale, the
    // coefficients of y and u relative to y' are a and -1.
    let m = model(
        "system t\nstate x\nparam a\ninput u\nx' = -a*x + u\noutput y = x\n",
        "t.sys",
    );
    let p = PRIMES[0];
    let mut rng = Rng::new(7);
    let io = IoModel::new(&m, p, &mut rng).unwrap();
    let a = 123_456_789u64;
    let orders = io.orders(&[a], &mut rng).unwrap();
    assert_eq!(orders, vec![1]);
    let r = io.relation(&[a], &orders, 0, 4, 1000, &mut rng).unwrap().unwrap();
    assert_eq!(r.degree, 1);
    assert_eq!(
        r.vars,
        vec![IoVar::Y(0, 0), IoVar::Y(0, 1), IoVar::U(0, 0), IoVar::U(0, 1)]
    );
    assert_eq!(r.support.len(), 3);
    let c1 = coeff(&r, &[0, 1, 0, 0]);
    let inv = fp::inv(c1, p).unwrap();
    assert_eq!(fp::mul(coeff(&r, &[1, 0, 0, 0]), inv, p), a);
    assert_eq!(fp::mul(coeff(&r, &[0, 0, 1, 0]), inv, p), p - 1);
}

#[test]
fn two_outputs_elimination_orders() {
    // x1' = -a x1, x2' = x1 - b x2, y1 = x1, y2 = x2: y1' + a y1 = 0
    // (order 1); y2' = y1 - b y2 is order 1 in y2 with y1 in T_2.
    let m = model(
        "system t\nstate x1, x2\nparam a, b\nx1' = -a*x1\nx2' = x1 - b*x2\noutput y1 = x1\noutput y2 = x2\n",
        "t.sys",
    );
    let p = PRIMES[0];
    let mut rng = Rng::new(9);
    let io = IoModel::new(&m, p, &mut rng).unwrap();
    let th = [5u64, 11];
    let orders = io.orders(&th, &mut rng).unwrap();
    assert_eq!(orders, vec![1, 1]);
    let r = io.relation(&th, &orders, 1, 4, 1000, &mut rng).unwrap().unwrap();
    // Variables (y1, y2, y2'): y2' - y1 + b y2 = 0.
    assert_eq!(r.degree, 1);
    let c = coeff(&r, &[0, 0, 1]);
    let inv = fp::inv(c, p).unwrap();
    assert_eq!(fp::mul(coeff(&r, &[1, 0, 0]), inv, p), p - 1);
    assert_eq!(fp::mul(coeff(&r, &[0, 1, 0]), inv, p), 11);
}

/// Sizes of the relations on the models the Taylor route refuses: orders,
/// degree, ansatz and support sizes, time; then the degree in `t` of each
/// normalised coefficient along a random line `theta = a + t b`.
#[test]
#[ignore]
fn io_sizes() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../systems/benchmarks/si-jl");
    let names = std::env::var("IO_MODELS").unwrap_or_else(|_| {
        "Goodwin HIV SIWR_orig SIWR_multiout Pharm SEAIJRC MAPK_5out".into()
    });
    let max_mono: usize = std::env::var("IO_MAX_MONO")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    for name in names.split_whitespace() {
        let path = format!("{dir}/{name}.sys");
        let src = std::fs::read_to_string(&path).unwrap();
        let m = model(&src, &path);
        let p = PRIMES[0];
        let mut rng = Rng::new(1);
        let io = IoModel::new(&m, p, &mut rng).unwrap();
        let th: Vec<u64> = (0..io.n_params()).map(|_| rng.next() % p).collect();
        let t0 = Instant::now();
        let orders = io.orders(&th, &mut rng).unwrap();
        println!("{name}: nx {} np {} orders {orders:?} ({:.3} s)", m.dyn_vars.len(), io.n_params(), t0.elapsed().as_secs_f64());
        for i in 0..orders.len() {
            let t0 = Instant::now();
            let r = io.relation(&th, &orders, i, 40, max_mono, &mut rng).unwrap();
            let dt = t0.elapsed().as_secs_f64();
            let Some(r) = r else {
                println!("  y{}: no relation within {max_mono} ansatz monomials ({dt:.3} s)", i + 1);
                continue;
            };
            println!(
                "  y{}: {} variables, degree {}, ansatz {} monomials, support {} ({dt:.3} s)",
                i + 1,
                r.vars.len(),
                r.degree,
                r.ansatz,
                r.support.len()
            );
            if std::env::var("IO_LINE").is_err() {
                continue;
            }
            // Degrees along a line: one Thiele per coefficient.
            let a: Vec<u64> = (0..io.n_params()).map(|_| rng.next() % p).collect();
            let b: Vec<u64> = (0..io.n_params()).map(|_| rng.next() % p).collect();
            let mut th_s: Vec<Thiele> = (0..r.support.len()).map(|_| Thiele::new(p, 2)).collect();
            let t1 = Instant::now();
            let mut t = 1u64;
            let mut kernels = 0;
            while th_s.iter().any(|x| !x.done()) {
                let pt: Vec<u64> = a.iter().zip(&b).map(|(&x, &y)| fp::add(x, fp::mul(t, y, p), p)).collect();
                let Some(rt) = io.relation(&pt, &orders, i, r.degree, max_mono, &mut rng).unwrap() else {
                    panic!("no relation at a line point");
                };
                kernels += 1;
                assert_eq!(rt.support, r.support, "support changed along the line");
                for (x, &c) in th_s.iter_mut().zip(&rt.coeffs) {
                    if !x.done() {
                        x.add(t, c);
                    }
                }
                t += 1;
            }
            let degs: Vec<(usize, usize)> = th_s
                .iter()
                .map(|x| {
                    let (n, d) = x.rational();
                    (n.len().saturating_sub(1), d.len().saturating_sub(1))
                })
                .collect();
            let mn = degs.iter().map(|x| x.0).max().unwrap_or(0);
            let md = degs.iter().map(|x| x.1).max().unwrap_or(0);
            println!(
                "    coefficients along a line: max degree num {mn} den {md}; {kernels} kernels, {:.3} s",
                t1.elapsed().as_secs_f64()
            );
        }
    }
}
