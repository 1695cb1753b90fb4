//! Engine benchmark: the Lie derivatives of systems/calib.sys up to order K
//! along both input fields (all 2^k words of each order k), then every
//! gradient entry in canonical form. Prints time and sizes.
//!
//! Run: `cargo bench --bench lie` (optionally `-- K REPS`).

use obsan_expr::{Id, RatFun};
use obsan_model::System;
use std::time::{Duration, Instant};

struct Figures {
    build: Duration,
    grad: Duration,
    canon: Duration,
    nodes_lie: usize,
    nodes_grad: usize,
    n_lie: usize,
    terms: usize,
    max_terms: usize,
}

fn once(sys: &System, order: usize) -> Figures {
    let mut nf = sys.normal_form(None, &[]).expect("calib.sys loads");
    let states = nf.state_vars.clone();
    let fields = nf.fields.clone();
    let t0 = Instant::now();
    let mut level: Vec<Id> = vec![nf.outputs[0].1];
    let mut all = level.clone();
    for _ in 0..order {
        let mut next = Vec::new();
        for &g in &level {
            for f in &fields {
                next.push(nf.ctx.lie_derivative(g, &states, f));
            }
        }
        all.extend(&next);
        level = next;
    }
    let build = t0.elapsed();
    let nodes_lie = nf.ctx.count_nodes(&all);
    let t1 = Instant::now();
    let mut grads = Vec::new();
    for &l in &all {
        for &x in &states {
            grads.push(nf.ctx.diff(l, x));
        }
    }
    let grad = t1.elapsed();
    let nodes_grad = nf.ctx.count_nodes(&grads);
    let t2 = Instant::now();
    let mut terms = 0;
    let mut max_terms = 0;
    for &g in &grads {
        let c = nf.ctx.canon(g);
        terms += c.term_count();
        max_terms = max_terms.max(c.term_count());
    }
    let canon = t2.elapsed();
    Figures {
        build,
        grad,
        canon,
        nodes_lie,
        nodes_grad,
        n_lie: all.len(),
        terms,
        max_terms,
    }
}

/// The canonical route: Lie derivatives and gradients computed on canonical forms.
fn once_canonical(sys: &System, order: usize) -> (Duration, usize, usize) {
    let mut nf = sys.normal_form(None, &[]).expect("calib.sys loads");
    let states = nf.state_vars.clone();
    let t0 = Instant::now();
    let fields: Vec<Vec<RatFun>> = nf
        .fields
        .clone()
        .iter()
        .map(|f| f.iter().map(|&c| nf.ctx.canon(c)).collect())
        .collect();
    let h = nf.ctx.canon(nf.outputs[0].1);
    let mut level = vec![h];
    let mut all = level.clone();
    for _ in 0..order {
        let mut next = Vec::new();
        for g in &level {
            for f in &fields {
                next.push(nf.ctx.rf_lie_derivative(g, &states, f));
            }
        }
        all.extend(next.iter().cloned());
        level = next;
    }
    let mut terms = 0;
    let mut max_terms = 0;
    for l in &all {
        for &x in &states {
            let g = nf.ctx.rf_diff(l, x);
            terms += g.term_count();
            max_terms = max_terms.max(g.term_count());
        }
    }
    (t0.elapsed(), terms, max_terms)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let max_order: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(4);
    let reps: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/systems/calib.sys");
    let src = std::fs::read_to_string(path).expect("systems/calib.sys");
    let sys = System::parse(&src, "systems/calib.sys").expect("parses");
    println!(
        "calib.sys (eq. 16), outputs beta, fields f_wR and f_wL; {reps} repetitions, median (min)"
    );
    println!("order | Lie derivs | DAG nodes (Lie) | build ms | grad nodes | grad ms | entries | canon ms | terms total (max)");
    for order in 1..=max_order {
        let mut runs: Vec<Figures> = (0..reps).map(|_| once(&sys, order)).collect();
        runs.sort_by_key(|r| r.build + r.grad + r.canon);
        let med = &runs[runs.len() / 2];
        let min = &runs[0];
        println!(
            "{order:5} | {:10} | {:15} | {:8.3} ({:.3}) | {:10} | {:7.3} ({:.3}) | {:7} | {:8.2} ({:.2}) | {} ({})",
            med.n_lie,
            med.nodes_lie,
            ms(med.build),
            ms(min.build),
            med.nodes_grad,
            ms(med.grad),
            ms(min.grad),
            med.n_lie * 7,
            ms(med.canon),
            ms(min.canon),
            med.terms,
            med.max_terms
        );
    }
    println!();
    println!("canonical route (Lie derivatives and gradients differentiated as canonical forms):");
    println!("order | Lie derivs | entries | total ms median (min) | terms total (max)");
    for order in 1..=max_order {
        let mut runs: Vec<(Duration, usize, usize)> =
            (0..reps).map(|_| once_canonical(&sys, order)).collect();
        runs.sort_by_key(|r| r.0);
        let med = &runs[runs.len() / 2];
        let n_lie = (1usize << (order + 1)) - 1;
        println!(
            "{order:5} | {n_lie:10} | {:7} | {:8.2} ({:.2}) | {} ({})",
            n_lie * 7,
            ms(med.0),
            ms(runs[0].0),
            med.1,
            med.2
        );
    }
}
