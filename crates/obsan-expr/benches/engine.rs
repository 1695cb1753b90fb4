//! Engine benchmark on the paper's calibration system (eq. 16), with only
//! this crate: Lie derivatives of the bearing output along both input fields
//! up to order K, then every gradient entry, on canonical forms and on the
//! graph (canonicalised at the end). Prints the median of REPS runs.
//!
//! Run: `cargo bench -p obsan-expr --bench engine` (optionally `-- K REPS`).

use obsan_expr::{Ctx, Id, RatFun, Var};
use std::time::{Duration, Instant};

struct Calib {
    ctx: Ctx,
    states: Vec<Var>,
    fields: Vec<Vec<Id>>,
    h: Id,
}

fn calib() -> Calib {
    let mut ctx = Ctx::new();
    let names = ["mu", "gamma", "phi", "psi", "eta", "delta", "xi"];
    let states: Vec<Var> = names.iter().map(|n| ctx.symbol(n).var).collect();
    let mut p = |s: &str| ctx.parse(s).expect("benchmark expression parses");
    let f_r = vec![
        p("-mu^2*eta*cos(gamma - phi)"),
        p("xi - mu*eta*sin(gamma - phi)"),
    ];
    let f_l = vec![
        p("-mu^2*eta*delta*cos(gamma - phi)"),
        p("-xi*delta - mu*eta*delta*sin(gamma - phi)"),
    ];
    let h = p("atan2(sin(gamma), -mu - cos(gamma)) - psi");
    let zero = p("0");
    let pad = |f: Vec<Id>| {
        let mut f = f;
        f.resize(7, zero);
        f
    };
    Calib {
        ctx,
        states,
        fields: vec![pad(f_r), pad(f_l)],
        h,
    }
}

/// Canonical route: Lie derivatives and gradients on canonical forms.
fn canonical(order: usize) -> (Duration, usize) {
    let mut c = calib();
    let t0 = Instant::now();
    let fields: Vec<Vec<RatFun>> = c
        .fields
        .clone()
        .iter()
        .map(|f| f.iter().map(|&x| c.ctx.canon(x)).collect())
        .collect();
    let h = c.ctx.canon(c.h);
    let mut level = vec![h];
    let mut all = level.clone();
    for _ in 0..order {
        let mut next = Vec::new();
        for g in &level {
            for f in &fields {
                next.push(c.ctx.rf_lie_derivative(g, &c.states, f));
            }
        }
        all.extend(next.iter().cloned());
        level = next;
    }
    let mut terms = 0;
    for l in &all {
        for &x in &c.states {
            terms += c.ctx.rf_diff(l, x).term_count();
        }
    }
    (t0.elapsed(), terms)
}

/// Graph route: Lie derivatives and gradients on the graph, then canonical forms.
fn graph(order: usize) -> (Duration, usize) {
    let mut c = calib();
    let t0 = Instant::now();
    let mut level = vec![c.h];
    let mut all = level.clone();
    for _ in 0..order {
        let mut next = Vec::new();
        for &g in &level {
            for f in &c.fields {
                next.push(c.ctx.lie_derivative(g, &c.states, f));
            }
        }
        all.extend(&next);
        level = next;
    }
    let mut terms = 0;
    for &l in &all {
        for &x in &c.states.clone() {
            let d = c.ctx.diff(l, x);
            terms += c.ctx.canon(d).term_count();
        }
    }
    (t0.elapsed(), terms)
}

fn median(f: &dyn Fn() -> (Duration, usize), reps: usize) -> (f64, f64, usize) {
    let mut runs: Vec<(Duration, usize)> = (0..reps).map(|_| f()).collect();
    runs.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    (ms(runs[reps / 2].0), ms(runs[0].0), runs[0].1)
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let k: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(4);
    let reps: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5).max(1);
    println!("calib (eq. 16): Lie derivatives and gradients, median (min) of {reps} runs");
    println!("order | canonical route ms | graph route ms | terms");
    for order in 1..=k {
        let (cm, cmin, t1) = median(&|| canonical(order), reps);
        let (gm, gmin, t2) = median(&|| graph(order), reps);
        assert_eq!(t1, t2, "both routes give the same canonical forms");
        println!("{order:5} | {cm:9.2} ({cmin:.2}) | {gm:9.2} ({gmin:.2}) | {t1}");
    }
}
