//! Input-output equations modulo p (issue 36's second route, measured here
//! first): for each output `y_i`, the minimal polynomial relation among the
//! outputs' jets at one numeric parameter point, found as the kernel of an
//! ansatz of monomials evaluated at jets from random initial states.
//!
//! The ranking is orderly (order first, then output: SIAN's interleaving,
//! which balances the orders; the elimination ranking `y_1 < y_2 < ...`
//! put all of MAPK's order 12 on `y_1`): `k_i` is the first order at which
//! `y_i^(k_i)` is algebraically dependent (Jacobian in the initial state,
//! rank over F_p) on the jets kept before it, `T_i = {y_l^(j) : j < k_l,
//! and j < k_i or (j = k_i and l < i)}`; the relation of `y_i` is the
//! minimal polynomial of `y_i^(k_i)` over `T_i` (inputs' jets `u^(j)`,
//! `j <= max k`, join every relation's variables as free). For a generic parameter point the variety of jets
//! `(T_i, y_i^(k_i))` is an irreducible hypersurface, so at the first total
//! degree with a non-zero kernel the kernel is one line: the relation up to
//! scale (Dong, Goodbrake, Harrington, Pogudin 2023: such relations form a
//! characteristic presentation of the input-output ideal).
//!
//! Jets are truncated power series over F_p carrying, beside each value,
//! its gradient in the initial state (forward mode), so no symbolic
//! derivative is ever formed: the cost is polynomial in the order whatever
//! the expression swell of the Taylor route.

use super::io_series::{Arith, IPoly, Relaxed, Ser};
use super::model::ZModel;
use super::run::Rng;
use super::types::err;
use crate::rank::AnalysisError;
use obsan_expr::{Fp, FpField};
use obsan_expr::{Int, Poly as ZPoly, Var};
use obsan_recon::fp::{Echelon, PrimeField, RowEchelon, Shoup, Zp, BLOCK};

/// Arithmetic modulo `p`, with the rank test's shift-and-add products when
/// `p = 2^61 - 1`, and otherwise (the reconstruction's primes) products
/// reduced by obsan-recon's `Rem128`, its constants kept per thread for the
/// last prime seen: `u128 %` was a fifth of the black box's time.
pub(super) mod fp {
    use obsan_recon::fp::Rem128;
    pub(in crate::global) use obsan_recon::fp::{add, sub};
    use std::cell::Cell;

    thread_local! {
        static REM: Cell<(u64, Option<Rem128>)> = const { Cell::new((0, None)) };
    }

    #[inline]
    pub(in crate::global) fn mul(a: u64, b: u64, p: u64) -> u64 {
        if p == obsan_expr::P {
            return (super::Fp(a) * super::Fp(b)).0;
        }
        let m = REM.with(|c| match c.get() {
            (q, Some(m)) if q == p => m,
            _ => {
                let m = Rem128::new(p);
                c.set((p, Some(m)));
                m
            }
        });
        m.reduce(a as u128 * b as u128)
    }
    pub(in crate::global) fn pow(a: u64, mut e: u64, p: u64) -> u64 {
        if p == obsan_expr::P {
            return super::Fp(a).pow(e).0;
        }
        let (mut r, mut a) = (1 % p, a);
        while e > 0 {
            if e & 1 == 1 {
                r = mul(r, a, p);
            }
            a = mul(a, a, p);
            e >>= 1;
        }
        r
    }
    pub(in crate::global) fn inv(a: u64, p: u64) -> Option<u64> {
        obsan_recon::fp::inv(a, p)
    }
}

/// A polynomial over F_p in the series variables (states then inputs), each
/// coefficient a polynomial in the parameters kept apart so the parameter
/// point can change: terms `(coef, param exponents, series exponents)`.
#[derive(Clone, Debug, Default)]
struct SPoly(Vec<(u64, Vec<u32>, Vec<u32>)>);

/// Threads for a kernel's blocks and rows: at most two, read once per
/// process (`available_parallelism` reads the cgroup's quota from files on
/// Linux: a tenth of St's time when asked at every black-box point).
pub(super) fn threads() -> usize {
    static THREADS: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *THREADS.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get().min(2)))
}

/// The model as series arithmetic sees it, modulo one prime.
pub(super) struct IoModel {
    p: u64,
    #[cfg_attr(not(test), allow(dead_code))]
    np: usize,
    nx: usize,
    nu: usize,
    rhs: Vec<(SPoly, SPoly)>,
    outputs: Vec<(SPoly, SPoly)>,
    /// Checked at every sampled row of a kernel.
    pub(super) deadline: Option<std::time::Instant>,
    /// Bytes a kernel's dense rows may hold (the memory budget).
    pub(super) max_bytes: usize,
    /// Multiply-adds this model's kernels may take (`GlobalOptions::
    /// max_io_work`: bounded in `--route auto`'s cheap attempt only, so that
    /// it stops early and deterministically, io_choice.rs). A kernel of `n`
    /// monomials is charged `n^3 / 2` before it runs (about `n` rows, each
    /// reduced against up to `n` rows of `n` entries).
    pub(super) max_work: u64,
    work: std::sync::atomic::AtomicU64,
}

pub(super) fn int_mod(c: &Int, p: u64) -> u64 {
    let pp = Int::from(p);
    let r = ((c % &pp) + &pp) % &pp;
    u64::try_from(&r).unwrap_or(0)
}

impl IoModel {
    /// `m` modulo `p`.
    pub(super) fn new(m: &ZModel, p: u64) -> Result<IoModel, AnalysisError> {
        let (np, nx, nu) = (m.param_vars.len(), m.dyn_vars.len(), m.input_vars.len());
        // Known constants: one random integer each, the same modulo every
        // prime (the coefficients are reconstructed over Q across primes).
        let consts: Vec<(Var, u64)> = m
            .const_vars
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let mut st = 0x10c0_57a7 + k as u64;
                (v, (obsan_recon::splitmix64(&mut st) >> 34) + 2)
            })
            .collect();
        let conv = |q: &ZPoly| -> Result<SPoly, AnalysisError> {
            let mut out = Vec::new();
            for (mono, c) in q.terms() {
                let mut coef = int_mod(c, p);
                let mut pe = vec![0u32; np];
                let mut se = vec![0u32; nx + nu];
                for (v, e) in mono.iter() {
                    if let Some(i) = m.param_vars.iter().position(|&x| x == v) {
                        pe[i] = e;
                    } else if let Some(i) = m.dyn_vars.iter().position(|&x| x == v) {
                        se[i] = e;
                    } else if let Some(i) = m.input_vars.iter().position(|&x| x == v) {
                        se[nx + i] = e;
                    } else if let Some((_, val)) = consts.iter().find(|(x, _)| *x == v) {
                        coef = fp::mul(coef, fp::pow(*val, e as u64, p), p);
                    } else {
                        return Err(err("global (io): a symbol outside the model"));
                    }
                }
                out.push((coef, pe, se));
            }
            Ok(SPoly(out))
        };
        let pair = |(n, d): &(ZPoly, ZPoly)| -> Result<(SPoly, SPoly), AnalysisError> {
            Ok((conv(n)?, conv(d)?))
        };
        Ok(IoModel {
            p,
            np,
            nx,
            nu,
            rhs: m.rhs.iter().map(pair).collect::<Result<_, _>>()?,
            outputs: m.outputs.iter().map(pair).collect::<Result<_, _>>()?,
            deadline: None,
            max_bytes: usize::MAX,
            max_work: u64::MAX,
            work: std::sync::atomic::AtomicU64::new(0),
        })
    }

    /// Multiply-adds charged to this model's kernels so far (`max_work`).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) fn work_spent(&self) -> u64 {
        self.work.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The numbers of states and of inputs.
    pub(super) fn dims(&self) -> (usize, usize) {
        (self.nx, self.nu)
    }

    pub(super) fn prime(&self) -> u64 {
        self.p
    }

    #[cfg(test)]
    pub(super) fn n_params(&self) -> usize {
        self.np
    }
}

/// A random element of F_p outside {0, 1}.
pub(super) fn elem(rng: &mut Rng, p: u64) -> u64 {
    loop {
        let x = rng.next() % p;
        if x > 1 {
            return x;
        }
    }
}

/// One sample: per output, the derivatives `y^(j)(0)`, `j < len`, each as a
/// dual vector (the kernels read the series directly: `fit`).
struct Jets {
    y: Vec<Vec<Vec<u64>>>,
}

/// The model's polynomials with the parameters evaluated at one point
/// (shared by every sample of a kernel).
pub(super) struct Inst {
    rhs: Vec<(IPoly, IPoly)>,
    outputs: Vec<(IPoly, IPoly)>,
}

impl Inst {
    /// Per state: the numerator and denominator of its right-hand side.
    pub(super) fn rhs(&self) -> &[(IPoly, IPoly)] {
        &self.rhs
    }

    /// Per output: its numerator and denominator.
    pub(super) fn outputs(&self) -> &[(IPoly, IPoly)] {
        &self.outputs
    }
}

impl IoModel {
    /// The model at parameters `theta`.
    pub(super) fn at(&self, theta: &[u64]) -> Inst {
        let p = self.p;
        let one = |q: &SPoly| -> IPoly {
            q.0.iter()
                .filter_map(|(c, pe, se)| {
                    let k = theta
                        .iter()
                        .zip(pe)
                        .filter(|(_, &e)| e > 0)
                        .fold(*c, |k, (t, &e)| fp::mul(k, fp::pow(*t, u64::from(e), p), p));
                    let vars = se
                        .iter()
                        .enumerate()
                        .filter(|(_, &e)| e > 0)
                        .map(|(v, &e)| (v, e))
                        .collect();
                    (k != 0).then_some((k, vars))
                })
                .collect()
        };
        let pair = |(n, d): &(SPoly, SPoly)| (one(n), one(d));
        Inst {
            rhs: self.rhs.iter().map(pair).collect(),
            outputs: self.outputs.iter().map(pair).collect(),
        }
    }

    /// Jets of the outputs to order `len - 1` at the parameters of `inst`,
    /// initial state and inputs' Taylor coefficients from `rng`; with
    /// `grad`, each carries its gradient in the initial state. `None` at a
    /// pole. The outputs' and inputs' Taylor coefficients (`[t^j]`,
    /// `j < len`), flat series of dual vectors (io_series.rs).
    fn taylor(
        &self,
        inst: &Inst,
        len: usize,
        grad: bool,
        rng: &mut Rng,
    ) -> Option<(Arith, Vec<Ser>, Vec<Ser>)> {
        if grad {
            self.taylor_by_orders(inst, len, true, rng)
        } else {
            self.taylor_relaxed(inst, len, rng)
        }
    }

    /// [`IoModel::taylor`] without the gradient, the same series (the same
    /// draws from `rng`), by relaxed evaluation (io_series.rs `Relaxed`):
    /// order `k` of each right-hand side and of its quotient costs `O(k)`
    /// per product given the states' first `k + 1` coefficients.
    fn taylor_relaxed(
        &self,
        inst: &Inst,
        len: usize,
        rng: &mut Rng,
    ) -> Option<(Arith, Vec<Ser>, Vec<Ser>)> {
        let p = self.p;
        let a = Arith { p, g: 1, len };
        let mut vars: Vec<Ser> = Vec::with_capacity(self.nx + self.nu);
        for _ in 0..self.nx {
            let mut x = a.zero();
            x[0] = elem(rng, p);
            vars.push(x);
        }
        for _ in 0..self.nu {
            vars.push((0..len).map(|_| elem(rng, p)).collect());
        }
        let dot = super::io_series::Dot::new(p);
        let mut rhs: Vec<(Relaxed, Relaxed)> = inst
            .rhs
            .iter()
            .map(|(n, d)| (Relaxed::new(n, len, p), Relaxed::new(d, len, p)))
            .collect();
        // Per state, its right-hand side's denominator and quotient series.
        let mut dens = vec![a.zero(); self.nx];
        let mut quos = vec![a.zero(); self.nx];
        let mut ivs = vec![0u64; self.nx];
        for k in 0..len.saturating_sub(1) {
            let inv = fp::inv((k as u64 + 1) % p, p)?;
            for (s, (n, d)) in rhs.iter_mut().enumerate() {
                let nk = n.coeff(k, &vars, &dot);
                dens[s][k] = d.coeff(k, &vars, &dot);
                if k == 0 {
                    ivs[s] = fp::inv(dens[s][0], p)?;
                }
                // q_k = (n_k - sum_{i=1..k} d_i q_{k-i}) / d_0.
                let carried = dot.rev(&dens[s][1..=k], &quos[s][..k]);
                quos[s][k] = fp::mul(fp::sub(nk, carried, p), ivs[s], p);
                // Order k reads coefficients up to k: setting k + 1 now
                // changes no other state's order k.
                vars[s][k + 1] = fp::mul(quos[s][k], inv, p);
            }
        }
        self.outputs(inst, a, vars)
    }

    /// The outputs' series from the states' and inputs' (`vars`, states
    /// first), with the inputs split off: [`IoModel::taylor`]'s answer.
    fn outputs(
        &self,
        inst: &Inst,
        a: Arith,
        mut vars: Vec<Ser>,
    ) -> Option<(Arith, Vec<Ser>, Vec<Ser>)> {
        let (mut t1, mut t2) = (a.zero(), a.zero());
        let mut y = Vec::with_capacity(inst.outputs.len());
        for (n, d) in &inst.outputs {
            y.push(a.div(
                &a.eval(n, &vars, &mut t1, &mut t2),
                &a.eval(d, &vars, &mut t1, &mut t2),
            )?);
        }
        let u = vars.split_off(self.nx);
        Some((a, y, u))
    }

    /// The Taylor series by re-evaluating the truncated right-hand sides
    /// at each order, with the gradient in the initial state when `grad`.
    fn taylor_by_orders(
        &self,
        inst: &Inst,
        len: usize,
        grad: bool,
        rng: &mut Rng,
    ) -> Option<(Arith, Vec<Ser>, Vec<Ser>)> {
        let p = self.p;
        let g = if grad { 1 + self.nx } else { 1 };
        let a = Arith { p, g, len };
        let mut vars: Vec<Ser> = Vec::with_capacity(self.nx + self.nu);
        for s in 0..self.nx {
            let mut x = a.zero();
            x[0] = elem(rng, p);
            if grad {
                x[1 + s] = 1;
            }
            vars.push(x);
        }
        for _ in 0..self.nu {
            let mut u = a.zero();
            for k in 0..len {
                u[k * g] = elem(rng, p);
            }
            vars.push(u);
        }
        let (mut t1, mut t2) = (a.zero(), a.zero());
        // x_{k+1} = [t^k] f(x) / (k + 1), the series of f recomputed on
        // the coefficients known so far (those above k do not reach t^k).
        // 1 / D(x(0)) per state: the value at 0 of its denominator's series.
        let mut ivs: Vec<u64> = Vec::with_capacity(self.nx);
        for k in 0..len.saturating_sub(1) {
            let inv = fp::inv((k as u64 + 1) % p, p)?;
            // Order k reads the series truncated after t^k (products of
            // `k + 1` coefficients, not `len`: about a third of the work).
            let ak = Arith { p, g, len: k + 1 };
            for s in 0..self.nx {
                let (n, d) = &inst.rhs[s];
                let den = ak.eval(d, &vars, &mut t1, &mut t2);
                if k == 0 {
                    ivs.push(fp::inv(den[0], p)?);
                }
                let q = ak.div_with(&ak.eval(n, &vars, &mut t1, &mut t2), &den, ivs[s])?;
                for (x, &v) in a.at_mut(&mut vars[s], k + 1).iter_mut().zip(a.at(&q, k)) {
                    *x = fp::mul(v, inv, p);
                }
            }
        }
        self.outputs(inst, a, vars)
    }

    fn jets(&self, inst: &Inst, len: usize, grad: bool, rng: &mut Rng) -> Option<Jets> {
        let p = self.p;
        let (a, ys, _) = self.taylor(inst, len, grad, rng)?;
        // Taylor coefficients to derivatives: y^(j) = j! [t^j] y.
        let mut fact = vec![1u64; len];
        for j in 1..len {
            fact[j] = fp::mul(fact[j - 1], j as u64 % p, p);
        }
        let y = ys
            .iter()
            .map(|q| {
                fact.iter()
                    .enumerate()
                    .map(|(k, &f)| a.at(q, k).iter().map(|&v| fp::mul(v, f, p)).collect())
                    .collect()
            })
            .collect();
        Some(Jets { y })
    }

    /// Whether the relation is the only linear dependence over the
    /// constants among its monomials `support`, as functions of time along
    /// one output of the model at `theta` from a random initial state: their
    /// first `support.len() + 2` Taylor coefficients have rank
    /// `support.len() - 1` (any `N - 1` of them then have a Wronskian not
    /// identically zero). Then the relation's coefficients, up to scale,
    /// are the only ones that output satisfies: a single experiment fixes
    /// them. `false` proves nothing.
    pub(super) fn independent_along(
        &self,
        theta: &[u64],
        orders: &[usize],
        i: usize,
        support: &[Vec<u32>],
        rng: &mut Rng,
    ) -> bool {
        let p = self.p;
        let vars = self.relation_vars(orders, i);
        let kmax = orders.iter().copied().max().unwrap_or(0);
        let l = support.len() + 2;
        let inst = self.at(theta);
        let Some((_, ys, us)) = self.taylor(&inst, l + kmax + 1, false, rng) else {
            return false;
        };
        let a = Arith { p, g: 1, len: l };
        // The series of D^j of a series c: [t^m] = c[m + j] (m+1)...(m+j).
        let deriv = |c: &Ser, j: usize| -> Ser {
            (0..l)
                .map(|m| {
                    let mut v = c[m + j];
                    for r in 1..=j {
                        v = fp::mul(v, (m + r) as u64 % p, p);
                    }
                    v
                })
                .collect()
        };
        let series: Vec<Ser> = vars
            .iter()
            .map(|v| match *v {
                IoVar::Y(o, j) => deriv(&ys[o], j),
                IoVar::U(u, j) => deriv(&us[u], j),
            })
            .collect();
        // The monomials as factor lists (variable indices, repeated, in
        // order) sorted, so that consecutive ones share their prefix's
        // product: a stack of partial products, one series product per
        // factor past the shared prefix (SIWR_orig's 771 monomials of
        // degree up to 10: a third of the products, each O(l^2)). The
        // count of dependent rows does not depend on their order.
        let mut lists: Vec<Vec<usize>> = support
            .iter()
            .map(|m| {
                m.iter()
                    .enumerate()
                    .flat_map(|(v, &e)| std::iter::repeat_n(v, e as usize))
                    .collect()
            })
            .collect();
        lists.sort_unstable();
        // Rows inserted a block at a time: the echelon alone holds `N`
        // rows (the memory the kernel's budget check allowed). Modulo the
        // model's own prime, as the series are (this was the engine's
        // `FpField` whatever `p`, right only while the search ran modulo
        // its prime).
        let threads = threads();
        let mut ech = RowEchelon::new(Zp(p));
        let mut dependent = 0;
        let mut rows: Vec<Vec<u64>> = Vec::with_capacity(BLOCK);
        let mut stack: Vec<(usize, Ser)> = Vec::new();
        for (i, f) in lists.iter().enumerate() {
            let shared = stack
                .iter()
                .zip(f)
                .take_while(|((v, _), w)| v == *w)
                .count();
            stack.truncate(shared);
            for &v in &f[shared..] {
                let next = match stack.last() {
                    None => series[v].clone(),
                    Some((_, t)) => a.mul(t, &series[v]),
                };
                stack.push((v, next));
            }
            rows.push(match stack.last() {
                None => (0..l).map(|k| u64::from(k == 0)).collect(),
                Some((_, t)) => t.clone(),
            });
            if rows.len() == BLOCK || i + 1 == lists.len() {
                let block = std::mem::take(&mut rows);
                dependent += ech
                    .insert_all(block, threads)
                    .iter()
                    .filter(|&&n| !n)
                    .count();
            }
        }
        dependent == 1
    }
}

impl IoModel {
    /// The orders `k_i` of the orderly ranking (module doc), from the
    /// Jacobian of the outputs' jets in the initial state at `theta`.
    pub(super) fn orders(&self, theta: &[u64], rng: &mut Rng) -> Result<Vec<usize>, AnalysisError> {
        let len = self.nx + 2;
        let j = self
            .jets(&self.at(theta), len, true, rng)
            .ok_or_else(|| err("global (io): a pole at the random point"))?;
        let mut ech = Echelon::new(Zp(self.p));
        let m = j.y.len();
        let mut orders = vec![0; m];
        let mut open = vec![true; m];
        for k in 0..len {
            for i in 0..m {
                if open[i] && !ech.insert(j.y[i][k][1..].to_vec()) {
                    open[i] = false;
                    orders[i] = k;
                }
            }
        }
        if open.iter().any(|&o| o) {
            return Err(err(
                "global (io): an output's jets stay independent past the state dimension",
            ));
        }
        Ok(orders)
    }
}

/// The relation of one output: its variables (`(output, order)` or
/// `(input, order)`), the monomials of its support and their coefficients
/// (normalised: the last monomial's coefficient is 1).
#[derive(Clone, Debug)]
pub(super) struct IoRelation {
    pub(super) vars: Vec<IoVar>,
    pub(super) degree: u32,
    /// Monomials tried in the ansatz at `degree`.
    pub(super) ansatz: usize,
    pub(super) support: Vec<Vec<u32>>,
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) coeffs: Vec<u64>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum IoVar {
    Y(usize, usize),
    U(usize, usize),
}

/// The time a block of rows must take (measured on the rows drawn before
/// it, on one thread) to be sampled on two: a thread's start takes tens of
/// microseconds.
const PARALLEL_ROWS: std::time::Duration = std::time::Duration::from_micros(500);

/// The right kernel of the rows `sample` draws (a block at a time), drawn until the rank stops
/// growing for 4 rows in a row (a dependent row of a random point on the
/// variety: probability at most `deg / p` each) or reaches `stop`.
/// The monomials of a kernel's rows, each from a parent: the monomial
/// with one exponent lowered, among `monos` or added to them (their
/// closure under that step along one path per monomial), parents first.
/// A row's values are then one Shoup product each (the jet's, prepared
/// once per row), and those of one degree do not wait on each other; a
/// product per factor of every monomial, each waiting on the last, was
/// 14% of SIWR_orig's black box.
struct Chain {
    /// Per monomial of the closure after the first (the constant 1): its
    /// parent's index and the variable raised.
    steps: Vec<(usize, usize)>,
    /// Per monomial of `monos`, its index in the closure.
    at: Vec<usize>,
}

impl Chain {
    fn new(monos: &[Vec<u32>]) -> Chain {
        let n = monos.first().map_or(0, Vec::len);
        let mut index: std::collections::HashMap<Vec<u32>, usize> =
            std::collections::HashMap::new();
        index.insert(vec![0; n], 0);
        let mut steps = Vec::new();
        let mut at = Vec::with_capacity(monos.len());
        for m in monos {
            // The path down to a monomial already present, then back up
            // (each step's parent created before it).
            let mut path: Vec<(Vec<u32>, usize)> = Vec::new();
            let mut cur = m.clone();
            let mut found = index.get(&cur).copied();
            while found.is_none() {
                // Lower an exponent whose parent is present, else the first.
                let lowered = |k: usize| {
                    let mut q = cur.clone();
                    q[k] -= 1;
                    q
                };
                let ks: Vec<usize> = (0..n).filter(|&k| cur[k] > 0).collect();
                let k = ks
                    .iter()
                    .copied()
                    .find(|&k| index.contains_key(&lowered(k)))
                    .unwrap_or(ks[0]);
                let parent = lowered(k);
                path.push((cur, k));
                found = index.get(&parent).copied();
                cur = parent;
            }
            let mut idx = found.unwrap_or(0);
            for (mono, k) in path.into_iter().rev() {
                steps.push((idx, k));
                idx = steps.len();
                index.insert(mono, idx);
            }
            at.push(idx);
        }
        Chain { steps, at }
    }

    /// The monomials' values at the jets' values `vals` modulo `p`.
    fn values(&self, vals: &[u64], p: u64) -> Vec<u64> {
        let sh: Vec<Shoup> = vals.iter().map(|&v| Shoup::new(v, p)).collect();
        let mut all = Vec::with_capacity(self.steps.len() + 1);
        all.push(1 % p);
        for &(parent, k) in &self.steps {
            all.push(sh[k].times(all[parent]));
        }
        self.at.iter().map(|&i| all[i]).collect()
    }
}

fn kernel<F: PrimeField>(
    field: F,
    to: impl Fn(u64) -> F::Elem,
    back: impl Fn(F::Elem) -> u64,
    sample: &mut dyn FnMut(usize) -> Result<Vec<Vec<u64>>, AnalysisError>,
    ncols: usize,
    stop: usize,
) -> Result<Vec<Vec<u64>>, AnalysisError> {
    let mut ech = RowEchelon::new(field);
    let mut stale = 0;
    // Rows by blocks, each block reduced on two threads when the machine
    // has them and the kernel is large (`RowEchelon::insert_all`): a
    // stalled search draws at most a block past its last independent row.
    let threads = threads();
    // Blocks of about a sixteenth of the columns: a search that stalls
    // draws past its rank at most that many rows.
    let block = (ncols / 16).clamp(1, BLOCK);
    while stale < 4 && ech.rank() < stop {
        let want = (stop - ech.rank()).clamp(1, block);
        let rows: Vec<Vec<F::Elem>> = sample(want)?
            .into_iter()
            .map(|r| r.into_iter().map(&to).collect())
            .collect();
        for new in ech.insert_all(rows, threads) {
            if new {
                stale = 0;
            } else {
                stale += 1;
            }
        }
    }
    Ok(ech
        .null_space(ncols)
        .into_iter()
        .map(|v| v.into_iter().map(&back).collect())
        .collect())
}

/// Per-variable caps: `c` on the penultimate jet, `l` on the leader.
fn caps(n: usize, lead: usize, pen: Option<usize>, c: u32, l: u32) -> Vec<u32> {
    let mut caps = vec![u32::MAX; n];
    caps[lead] = l;
    if let Some(q) = pen {
        caps[q] = c;
    }
    caps
}

/// All exponent vectors in `n` variables of total degree at most `d` and
/// degree at most `caps[v]` in variable `v`.
fn monomials_capped(n: usize, d: u32, caps: &[u32]) -> Vec<Vec<u32>> {
    let mut out = vec![vec![0u32; n]];
    for v in 0..n {
        let mut next = Vec::new();
        for m in &out {
            let used: u32 = m.iter().sum();
            for e in 0..=(d - used).min(caps[v]) {
                let mut m2 = m.clone();
                m2[v] = e;
                next.push(m2);
            }
        }
        out = next;
    }
    out
}

/// `monomials_capped(n, d, caps).len()`, without listing them: the number
/// of vectors of the first `v` variables of each total degree, variable by
/// variable.
fn count_capped(n: usize, d: u32, caps: &[u32]) -> usize {
    let d = d as usize;
    let mut ways = vec![0usize; d + 1];
    ways[0] = 1;
    for &cap in caps.iter().take(n) {
        let cap = (cap as usize).min(d);
        let mut next = vec![0usize; d + 1];
        for (s, &w) in ways.iter().enumerate() {
            if w == 0 {
                continue;
            }
            for e in 0..=cap.min(d - s) {
                next[s + e] = next[s + e].saturating_add(w);
            }
        }
        ways = next;
    }
    ways.iter().fold(0usize, |a, &w| a.saturating_add(w))
}

impl IoModel {
    /// The variables of output `i`'s relation (module doc).
    pub(super) fn relation_vars(&self, orders: &[usize], i: usize) -> Vec<IoVar> {
        let kmax = orders.iter().copied().max().unwrap_or(0);
        let mut vars = Vec::new();
        for j in 0..=orders[i] {
            for (l, &k) in orders.iter().enumerate() {
                if j < k && (j < orders[i] || l < i) {
                    vars.push(IoVar::Y(l, j));
                }
            }
        }
        vars.push(IoVar::Y(i, orders[i]));
        for u in 0..self.nu {
            vars.extend((0..=kmax).map(|j| IoVar::U(u, j)));
        }
        vars
    }

    /// The kernel of the monomials `monos` in `vars` evaluated at jets of
    /// random initial states (and inputs) at `theta`, sampled until the rank
    /// reaches `stop` or stalls ([`kernel`]).
    fn fit(
        &self,
        theta: &[u64],
        vars: &[IoVar],
        len: usize,
        monos: &[Vec<u32>],
        stop: usize,
        rng: &mut Rng,
    ) -> Result<Vec<Vec<u64>>, AnalysisError> {
        let p = self.p;
        // The echelon holds up to `n` rows of `n` field elements.
        let bytes = (monos.len() as u128).pow(2) * 8;
        if bytes > self.max_bytes as u128 {
            return Err(super::types::too_large(
                bytes,
                self.max_bytes as u128,
                &format!(
                    "the input-output relation's kernel ({} monomials)",
                    monos.len()
                ),
            ));
        }
        let n = monos.len() as u64;
        let work = self
            .work
            .load(std::sync::atomic::Ordering::Relaxed)
            .saturating_add(n.saturating_pow(3) / 2);
        if work > self.max_work {
            return Err(err(format!(
                "global (io): work budget exhausted: the relations' kernels would pass {:.1e} multiply-adds",
                self.max_work as f64
            )));
        }
        self.work.store(work, std::sync::atomic::Ordering::Relaxed);
        let tries = std::sync::atomic::AtomicUsize::new(0);
        let inst = self.at(theta);
        let mut fact = vec![1u64; len];
        for j in 1..len {
            fact[j] = fp::mul(fact[j - 1], j as u64 % p, p);
        }
        let chain = Chain::new(monos);
        // One row from its own generator (seeded from `rng` in order, so
        // the rows, and the answer, do not depend on the threads).
        let row = |seed: u64| -> Result<Vec<u64>, AnalysisError> {
            let mut rng = Rng::new(seed);
            loop {
                if self.deadline.is_some_and(|d| std::time::Instant::now() > d) {
                    return Err(AnalysisError::Timeout(
                        "the input-output relations (global, --route io)".into(),
                    ));
                }
                let t = tries.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                if t > 2 * monos.len() + 64 {
                    return Err(err("global (io): too many poles sampling the jets"));
                }
                // Values only (g = 1): read `k! [t^k]` straight from the
                // series, without `jets`' nested vectors (one allocation
                // per order: a fifth of the black box's time was malloc).
                let Some((_, ys, us)) = self.taylor(&inst, len, false, &mut rng) else {
                    continue;
                };
                let vals: Vec<u64> = vars
                    .iter()
                    .map(|v| match *v {
                        IoVar::Y(l, k) => fp::mul(ys[l][k], fact[k], p),
                        IoVar::U(u, k) => fp::mul(us[u][k], fact[k], p),
                    })
                    .collect();
                return Ok(chain.values(&vals, p));
            }
        };
        let threads = threads();
        // A block of rows, split between the threads when the block costs
        // far more than starting them (the series' products: a third of
        // SIWR_orig's time on one thread), by the rows drawn so far.
        let (mut drawn, mut spent) = (0u32, std::time::Duration::ZERO);
        let mut sample = |want: usize| -> Result<Vec<Vec<u64>>, AnalysisError> {
            let seeds: Vec<u64> = (0..want).map(|_| rng.next()).collect();
            let per_row = spent.checked_div(drawn).unwrap_or_default();
            if threads < 2 || want < 2 || per_row * want as u32 <= PARALLEL_ROWS {
                let t0 = std::time::Instant::now();
                let rows = seeds.into_iter().map(&row).collect();
                drawn += want as u32;
                spent += t0.elapsed();
                return rows;
            }
            let per = want.div_ceil(threads);
            std::thread::scope(|s| {
                let handles: Vec<_> = seeds
                    .chunks(per)
                    .map(|part| {
                        let row = &row;
                        s.spawn(move || part.iter().map(|&k| row(k)).collect::<Vec<_>>())
                    })
                    .collect();
                handles
                    .into_iter()
                    .flat_map(|h| {
                        h.join().unwrap_or_else(|_| {
                            vec![Err(err("global (io): a sampling thread failed"))]
                        })
                    })
                    .collect()
            })
        };
        if p == obsan_expr::P {
            kernel(FpField, Fp, |x| x.0, &mut sample, monos.len(), stop)
        } else {
            kernel(Zp(p), |x| x, |x| x, &mut sample, monos.len(), stop)
        }
    }

    /// The relation of output `i` at `theta`, given the orders; `None` when
    /// no relation of total degree at most `max_degree` fits in
    /// `max_monomials` ansatz monomials.
    ///
    /// The ansatz is searched over the sets `S(d, c, l)`: total degree
    /// `<= d`, degree `<= c` in the penultimate jet `y_i^(k_i - 1)` and
    /// `<= l` in the leader `y_i^(k_i)`, of three kinds, all tried by
    /// increasing size: `S(d, 1, 1)`, `S(d, d, 1)` and the full `S(d, d, d)` (the
    /// relation is linear in the leader when the states are rational
    /// functions of the outputs' lower jets, and low in the jet below:
    /// Goodwin's per-jet degrees are 6, 7, 3, 1, 1). Exact whatever the
    /// phase: every polynomial vanishing on the jets is `P R` (`P` the
    /// irreducible relation) and each degree of `P R` bounds that of `P`, so
    /// if `R` were not constant `P` would lie in `S(d - deg R, ..)` of the
    /// same kind, a strict subset, smaller, tried before with a zero kernel:
    /// the first non-zero kernel is `P`'s line alone.
    pub(super) fn relation(
        &self,
        theta: &[u64],
        orders: &[usize],
        i: usize,
        max_degree: u32,
        max_monomials: usize,
        rng: &mut Rng,
    ) -> Result<Option<IoRelation>, AnalysisError> {
        let vars = self.relation_vars(orders, i);
        let len = orders.iter().copied().max().unwrap_or(0) + 1;
        let lead = vars.len() - 1 - self.nu * len;
        let pen = (orders[i] > 0)
            .then(|| vars.iter().position(|&v| v == IoVar::Y(i, orders[i] - 1)))
            .flatten();
        let mut sets: Vec<(usize, u32, u32, u32)> = Vec::new();
        // Without a penultimate jet, phase 0 is phase 1.
        for phase in u32::from(pen.is_none())..3 {
            for d in 1..=max_degree {
                let (c, l) = match phase {
                    0 => (1, 1),
                    1 => (d, 1),
                    _ => (d, d),
                };
                let n = count_capped(vars.len(), d, &caps(vars.len(), lead, pen, c, l));
                if n > max_monomials {
                    break;
                }
                sets.push((n, d, c.min(d), l.min(d)));
            }
        }
        // All phases by size: a phase whose guess is wrong then costs at
        // most as much as the sets of the right one below the relation.
        sets.sort_unstable();
        sets.dedup();
        for (_, d, c, l) in sets {
            let monos = monomials_capped(vars.len(), d, &caps(vars.len(), lead, pen, c, l));
            let ker = self.fit(theta, &vars, len, &monos, monos.len(), rng)?;
            if ker.is_empty() {
                continue;
            }
            if ker.len() > 1 {
                return Err(err(format!(
                    "global (io): the kernel at degree {d} has dimension {} (a non-generic point)",
                    ker.len()
                )));
            }
            let v = &ker[0];
            let support: Vec<Vec<u32>> = monos
                .iter()
                .zip(v)
                .filter(|(_, &c)| c != 0)
                .map(|(m, _)| m.clone())
                .collect();
            let degree = support.iter().map(|m| m.iter().sum()).max().unwrap_or(0);
            let coeffs = self.normalise(v.iter().copied().filter(|&c| c != 0).collect());
            return Ok(Some(IoRelation {
                vars,
                degree,
                ansatz: monos.len(),
                support,
                coeffs,
            }));
        }
        Ok(None)
    }

    /// The coefficients of the relation at `theta` on a known support (that
    /// of a generic point): a kernel of `support.len()` columns only.
    /// `None` when the kernel is not one line (a non-generic `theta`).
    pub(super) fn on_support(
        &self,
        theta: &[u64],
        orders: &[usize],
        i: usize,
        support: &[Vec<u32>],
        rng: &mut Rng,
    ) -> Result<Option<Vec<u64>>, AnalysisError> {
        let vars = self.relation_vars(orders, i);
        let len = orders.iter().copied().max().unwrap_or(0) + 1;
        // The relation's vector c(theta) vanishes on every sample, so rank
        // `N - 1` leaves exactly its line: no stale rows to wait for.
        let ker = self.fit(theta, &vars, len, support, support.len() - 1, rng)?;
        if ker.len() != 1 || ker[0].contains(&0) {
            return Ok(None);
        }
        Ok(Some(self.normalise(ker[0].clone())))
    }

    /// Scaled so that the last coefficient is 1.
    pub(super) fn normalise(&self, mut v: Vec<u64>) -> Vec<u64> {
        let p = self.p;
        if let Some(inv) = v.last().and_then(|&c| fp::inv(c, p)) {
            for c in v.iter_mut() {
                *c = fp::mul(*c, inv, p);
            }
        }
        v
    }
}

#[cfg(test)]
#[path = "io_tests.rs"]
mod tests;
