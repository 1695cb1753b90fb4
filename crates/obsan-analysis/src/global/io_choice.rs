//! `--route auto`'s choice before the Taylor route's Gröbner basis: the
//! size of SIAN's system (its cheap stages only: Taylor orders, equations,
//! linear presolve) decides whether F4 is attempted at all (issue 36).
//! A skipped attempt still falls back on the Taylor route when the
//! input-output route does not answer, so a wrong guess costs time or the
//! initial states' verdicts, never a parameter's (mod.rs).

use super::model::ZModel;
use super::run::Run;
use super::types::{err, gb_err, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::{presolve_linear, Poly};
use obsan_recon::fp::{Echelon, Zp};

/// SIAN's system after the linear presolve, at one prime and point.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct TaylorSize {
    pub(super) unknowns: usize,
    pub(super) equations: usize,
    /// Sum of log2 of the equations' total degrees (a Bézout exponent).
    pub(super) log2_bezout: f64,
    /// Terms of all equations.
    pub(super) terms: usize,
}

/// The Taylor orders by the rank test of count.rs (`count_once`, the lead's
/// file: the same greedy test on the total gradients, repeated here because
/// that function runs F4 right after), then the system's size.
pub(super) fn taylor_size(m: &ZModel, opts: &GlobalOptions) -> Result<TaylorSize, AnalysisError> {
    let p = obsan_recon::PRIMES[0];
    let mut run = Run::new(m, p, opts.seed, opts.max_order + 2)?;
    run.max_bytes = opts.max_bytes;
    let orders = taylor_orders(&mut run, opts)?;
    let (eqs, unk) = run.sian_equations(&orders)?;
    let q = run.cleared.q.clone();
    let with_z = q.degree() > 0;
    let mut eqs = eqs;
    if with_z {
        eqs.push(q);
    }
    let (ring, mut gens) = run.to_unknown_ring(&eqs, &unk, usize::from(with_z))?;
    if with_z {
        let zq = gens.pop().unwrap_or_default();
        gens.push(ring.sub(
            &ring.mul(&zq, &ring.var(ring.n - 1)).map_err(gb_err)?,
            &ring.constant(1),
        ));
    }
    let gens = presolve_linear(&ring, &gens, opts.max_bytes).map_err(gb_err)?;
    Ok(size_of(&gens, ring.n))
}

/// The size of a presolved system in `n` variables: only the variables some
/// equation still uses count as unknowns.
pub(super) fn size_of(gens: &[Poly], n: usize) -> TaylorSize {
    let mut used = vec![false; n];
    let mut log2_bezout = 0.0;
    let mut terms = 0;
    for g in gens {
        terms += g.len();
        log2_bezout += (g.degree().max(1) as f64).log2();
        for (mono, _) in g.terms() {
            for (v, &e) in mono.exponents().iter().enumerate() {
                used[v] |= e > 0;
            }
        }
    }
    TaylorSize {
        unknowns: used.iter().filter(|&&u| u).count(),
        equations: gens.len(),
        log2_bezout,
        terms,
    }
}

/// Per output, the first Taylor order whose gradient (in the params and the
/// initial state) depends on those kept before, orders interleaved.
fn taylor_orders(run: &mut Run, opts: &GlobalOptions) -> Result<Vec<usize>, AnalysisError> {
    let f = run.field;
    let targets: Vec<usize> = (0..run.np)
        .chain((0..run.nx).map(|s| run.sv(s, 0)))
        .collect();
    let nt = targets.len();
    let mut grads: Vec<Option<Vec<u64>>> = vec![None; run.ring.n];
    for (t, &v) in targets.iter().enumerate() {
        let mut e = vec![0u64; nt];
        e[t] = 1;
        grads[v] = Some(e);
    }
    let combine = |g: &[(usize, u64)], grads: &[Option<Vec<u64>>]| -> Vec<u64> {
        let mut out = vec![0u64; nt];
        for &(v, c) in g {
            if let Some(gv) = &grads[v] {
                for (a, b) in out.iter_mut().zip(gv) {
                    *a = f.add(*a, f.mul(c, *b));
                }
            }
        }
        out
    };
    for (i, q) in run.inits.clone().iter().enumerate() {
        let zv = run.sv(run.nx + i, 0);
        let g = run.grad_at(q);
        let qz = g.iter().find(|(v, _)| *v == zv).map_or(0, |x| x.1);
        let rest: Vec<(usize, u64)> = g.into_iter().filter(|(v, _)| *v != zv).collect();
        let num = combine(&rest, &grads);
        let inv = f
            .inv(qz)
            .ok_or_else(|| err("global: a denominator's auxiliary state is degenerate"))?;
        let k = f.neg(inv);
        grads[zv] = Some(num.iter().map(|&x| f.mul(x, k)).collect());
    }
    let m = run.out_d.len();
    let mut open = vec![true; m];
    let mut orders = vec![0usize; m];
    let mut ech = Echelon::new(Zp(f.modulus()));
    let mut j = 0;
    while open.iter().any(|&o| o) {
        if j >= opts.max_order {
            return Err(err("global: the outputs' Jacobian still gains rank"));
        }
        run.prepare(j)?;
        if j >= 1 {
            for s in 0..run.ns {
                let g = run.grad_at(&run.rhs_d[s][j - 1]);
                let v = run.sv(s, j);
                grads[v] = Some(combine(&g, &grads));
            }
        }
        for i in 0..m {
            if open[i] {
                let g = run.grad_at(&run.out_d[i][j]);
                if !ech.insert(combine(&g, &grads)) {
                    open[i] = false;
                    orders[i] = j;
                }
            }
        }
        if opts.deadline.is_some_and(|d| std::time::Instant::now() > d) {
            return Err(AnalysisError::Timeout("choosing the Taylor orders".into()));
        }
        j += 1;
    }
    Ok(orders)
}
