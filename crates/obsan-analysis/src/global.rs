//! Global identifiability: how many values of each parameter and initial
//! state give the output of a generic one, and the discrete symmetries that
//! map one to another (docs/engine.md, "Global identifiability").
//!
//! SIAN's route (Hong, Ovchinnikov, Pogudin, Yap, Bioinformatics 2019): the
//! output's Taylor coefficients `y^(j)(0)` are polynomials in the parameters,
//! the initial state and the higher derivatives `x^(k)(0)` (new unknowns tied
//! by `x^(k+1) = D^k f`), the inputs' coefficients random. At a random point
//! the coefficients are numbers; the zeros of the system over the algebraic
//! closure of F_p are the (params, initial states) with the same output jet,
//! and a Gröbner basis over F_p (obsan-groebner) counts the values each
//! variable takes on them. Denominators are cleared by `z * den = 1`, with
//! `z' = -z^2 den'` so the system stays polynomial.

use crate::rank::AnalysisError;
use obsan_expr::{Int, Poly as ZPoly, Var};
use obsan_groebner::{distinct_roots, groebner, Field, GbBudget, GbError, Mono, Order, Poly, Ring};
use obsan_model::NormalForm;
use std::collections::HashMap;
use std::time::Instant;

mod trig;

/// Options of [`global_identifiability`].
#[derive(Clone, Debug)]
pub struct GlobalOptions {
    /// Seed of the random points (two independent runs use `seed` and `seed + 1`).
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Largest Taylor order tried.
    pub max_order: usize,
    /// Largest Gröbner basis (elements added) before giving up.
    pub max_basis: usize,
    /// Largest quotient dimension counted.
    pub max_solutions: usize,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        GlobalOptions {
            seed: 0x5eed_61b0,
            deadline: None,
            max_order: 24,
            max_basis: 20_000,
            max_solutions: 100_000,
        }
    }
}

/// The verdict on one variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identifiability {
    /// One value: globally identifiable.
    Global,
    /// Finitely many values (`k > 1`) over the complex numbers.
    Local(usize),
    /// Infinitely many values.
    NotIdentifiable,
}

#[derive(Clone, Debug)]
pub struct GlobalVariable {
    pub name: String,
    /// A parameter (else the initial value of a state).
    pub param: bool,
    /// An angle entering only through sin/cos: its values are counted modulo
    /// 2 pi (as its half-angle tangent `tan(theta/2)`).
    pub angle: bool,
    pub verdict: Identifiability,
}

/// A discrete symmetry: each moved variable and its image, `(v, sign, w)`
/// meaning `v -> sign * w`. Checked exactly: the dynamics and outputs are
/// invariant as rational functions over Q.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DiscreteMap {
    pub images: Vec<(String, i8, String)>,
}

impl std::fmt::Display for DiscreteMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let lhs: Vec<&str> = self.images.iter().map(|(v, _, _)| v.as_str()).collect();
        let rhs: Vec<String> = self
            .images
            .iter()
            .map(|(_, s, w)| if *s < 0 { format!("-{w}") } else { w.clone() })
            .collect();
        if lhs.len() == 1 {
            write!(f, "{} -> {}", lhs[0], rhs[0])
        } else {
            write!(f, "({}) -> ({})", lhs.join(", "), rhs.join(", "))
        }
    }
}

/// The answer of [`global_identifiability`].
#[derive(Clone, Debug)]
pub struct GlobalReport {
    /// Parameters, then initial states, in the system's order.
    pub variables: Vec<GlobalVariable>,
    /// How many (params, initial states) give the output of the generic one
    /// (counting only the locally identifiable variables when some are not:
    /// `None` then means that even those take infinitely many joint values).
    pub solutions: Option<usize>,
    /// Whether every variable is at least locally identifiable.
    pub all_local: bool,
    /// Exact discrete symmetries found (signed permutations of the variables).
    pub maps: Vec<DiscreteMap>,
    /// Size of the group the maps generate (an orbit of a generic point).
    pub group_order: usize,
    /// Highest Taylor order used, and the highest order of a row that
    /// raised the Jacobian's rank.
    pub order: usize,
    pub rank_order: usize,
    /// Per output, the Taylor order used (inclusive): the proven truncation
    /// of docs/engine.md, "Taylor orders".
    pub output_orders: Vec<(String, usize)>,
    /// SIAN's degree bounds for one run (Hong, Ovchinnikov, Pogudin, Yap
    /// 2020, Algorithm 1): `delta_local` for the orders and local verdicts,
    /// `log10_delta_global` (log10 of the Bezout bound, which can pass any
    /// float) for the global verdicts.
    pub delta_local: f64,
    pub log10_delta_global: f64,
    /// Probability that a verdict (global / local / not identifiable) is
    /// wrong: both independent runs would have to be wrong,
    /// `min(1, D/p1) * min(1, D/p2)` with `D = delta_local + delta_global`.
    /// 1 means no bound.
    pub error_bound: f64,
    /// Unknowns and equations of the polynomial system at `order`.
    pub unknowns: usize,
    pub equations: usize,
    /// The primes of the two independent runs.
    pub primes: [u64; 2],
}

/// The model over Z: dynamic states (with their derivative `num/den`), params,
/// inputs, known constants (given random values), outputs.
struct ZModel {
    /// Per state then param: an angle counted as `t = tan(theta/2)`.
    angle: Vec<bool>,
    dyn_vars: Vec<Var>,
    param_vars: Vec<Var>,
    input_vars: Vec<Var>,
    const_vars: Vec<Var>,
    rhs: Vec<(ZPoly, ZPoly)>,
    outputs: Vec<(ZPoly, ZPoly)>,
}

fn err(s: impl Into<String>) -> AnalysisError {
    AnalysisError::Invalid(s.into())
}

fn gb_err(e: GbError) -> AnalysisError {
    match e {
        GbError::Budget("deadline") => {
            AnalysisError::Timeout("the Gröbner basis did not finish".into())
        }
        e => err(format!("global: {e}")),
    }
}

fn zmodel(nf: &mut NormalForm) -> Result<ZModel, AnalysisError> {
    if nf.delay.is_some() {
        return Err(err(
            "global: a model with `delay` is analysed only to first order; global counts need the exact dynamics",
        ));
    }
    let nd = nf.n_dynamic;
    let input_vars = nf.input_vars.clone();
    let mut const_vars = Vec::new();
    for (name, _) in &nf.consts {
        if let Some(s) = nf.ctx.lookup(name) {
            const_vars.push(s.var);
        }
    }
    let limit = |l: obsan_expr::Limit| err(format!("global: {l}"));
    let mut rhs = Vec::with_capacity(nd);
    for s in 0..nd {
        let mut parts = vec![nf.f0[s]];
        for (i, field) in nf.fields.iter().enumerate() {
            let u = nf
                .ctx
                .lookup(&nf.inputs[i])
                .ok_or_else(|| err("global: an input without a symbol"))?;
            let t = nf.ctx.mul(&[field[s], u.id]);
            parts.push(t);
        }
        let id = nf.ctx.add(&parts);
        rhs.push(nf.ctx.try_canon(id).map_err(limit)?);
    }
    let mut outputs = Vec::new();
    for k in 0..nf.outputs.len() {
        let id = nf.outputs[k].1;
        outputs.push(nf.ctx.try_canon(id).map_err(limit)?);
    }
    // Angles in sin/cos become their half-angle tangents (trig.rs).
    let mut vars = nf.state_vars.clone();
    let angle = trig::half_angle_view(&mut nf.ctx, &mut vars, &mut rhs, &mut outputs)?;
    let dyn_vars = vars[..nd].to_vec();
    let param_vars = vars[nd..].to_vec();
    let parts = |r: obsan_expr::RatFun| (r.numerator().clone(), r.denominator().clone());
    let rhs: Vec<(ZPoly, ZPoly)> = rhs.into_iter().map(parts).collect();
    let outputs: Vec<(ZPoly, ZPoly)> = outputs.into_iter().map(parts).collect();
    let known: Vec<Var> = dyn_vars
        .iter()
        .chain(&param_vars)
        .chain(&input_vars)
        .chain(&const_vars)
        .copied()
        .collect();
    for (n, d) in rhs.iter().chain(&outputs) {
        for v in n.vars().into_iter().chain(d.vars()) {
            if !known.contains(&v) {
                return Err(err(format!(
                    "global: `{}` is not a plain symbol; only sin/cos of a state or parameter (counted in the half-angle view) and rational functions are counted; atan/exp/log/sqrt and sin/cos of inputs are not",
                    nf.ctx.leaf_text(v)
                )));
            }
        }
    }
    Ok(ZModel {
        angle,
        dyn_vars,
        param_vars,
        input_vars,
        const_vars,
        rhs,
        outputs,
    })
}

fn int_mod(f: &Field, c: &Int) -> u64 {
    let p = Int::from(f.modulus());
    let r = c % &p;
    match i64::try_from(&r) {
        Ok(x) => f.from_i64(x),
        Err(_) => 0, // |r| < p < 2^63 always fits
    }
}

/// Small deterministic generator (SplitMix64) for the random points.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn elem(&mut self, f: &Field) -> u64 {
        loop {
            let x = f.reduce(self.next());
            if x > 1 {
                return x;
            }
        }
    }
}

/// The prolonged system modulo one prime at one random point.
struct Run {
    field: Field,
    /// Derivation ring: params, then per dynamic state (model states and the
    /// `z` of each denominator) orders `0..=kmax`, then per input orders `0..=kmax`.
    ring: Ring,
    np: usize,
    ns: usize,
    /// Number of model states (the first `nx` of the `ns`).
    nx: usize,
    nu: usize,
    kmax: usize,
    /// `D^j` of each state's right-hand side and each output, computed lazily.
    rhs_d: Vec<Vec<Poly>>,
    out_d: Vec<Vec<Poly>>,
    /// Polynomials that vanish on the point at order 0 (`z * den - 1`).
    inits: Vec<Poly>,
    /// The point: values of every derivation-ring variable (filled by order).
    point: Vec<u64>,
    point_order: usize,
    /// Random coefficient of the separating linear form.
    rng: Rng,
}

impl Run {
    fn sv(&self, s: usize, k: usize) -> usize {
        self.np + s * (self.kmax + 1) + k
    }
    fn uv(&self, i: usize, k: usize) -> usize {
        self.np + self.ns * (self.kmax + 1) + i * (self.kmax + 1) + k
    }

    fn new(m: &ZModel, p: u64, seed: u64, kmax: usize) -> Result<Run, AnalysisError> {
        let field = Field::new(p).ok_or_else(|| err("global: bad prime"))?;
        let mut rng = Rng(seed);
        let np = m.param_vars.len();
        let nx = m.dyn_vars.len();
        let nu = m.input_vars.len();
        // Distinct non-constant denominators, each with its z state.
        let mut dens: Vec<ZPoly> = Vec::new();
        let const_only = |d: &ZPoly| d.vars().iter().all(|v| m.const_vars.contains(v));
        let den_index = |dens: &mut Vec<ZPoly>, d: &ZPoly| -> Option<usize> {
            if const_only(d) {
                return None;
            }
            match dens.iter().position(|e| e == d) {
                Some(i) => Some(i),
                None => {
                    dens.push(d.clone());
                    Some(dens.len() - 1)
                }
            }
        };
        let rhs_den: Vec<Option<usize>> =
            m.rhs.iter().map(|(_, d)| den_index(&mut dens, d)).collect();
        let out_den: Vec<Option<usize>> = m
            .outputs
            .iter()
            .map(|(_, d)| den_index(&mut dens, d))
            .collect();
        let ns = nx + dens.len();
        let n = np + (ns + nu) * (kmax + 1);
        let ring = Ring::new(field, n, Order::Grevlex);
        let mut run = Run {
            field,
            ring,
            np,
            ns,
            nx,
            nu,
            kmax,
            rhs_d: Vec::new(),
            out_d: Vec::new(),
            inits: Vec::new(),
            point: vec![0; n],
            point_order: 0,
            rng: Rng(0),
        };
        // Known constants: random values (they are known, hence fixed).
        let consts: Vec<(Var, u64)> = m
            .const_vars
            .iter()
            .map(|&v| (v, rng.elem(&field)))
            .collect();
        let mut vmap: HashMap<Var, Result<usize, u64>> = HashMap::new();
        for (i, &v) in m.param_vars.iter().enumerate() {
            vmap.insert(v, Ok(i));
        }
        for (i, &v) in m.dyn_vars.iter().enumerate() {
            vmap.insert(v, Ok(run.sv(i, 0)));
        }
        for (i, &v) in m.input_vars.iter().enumerate() {
            vmap.insert(v, Ok(run.uv(i, 0)));
        }
        for &(v, x) in &consts {
            vmap.insert(v, Err(x));
        }
        let conv = |run: &Run, z: &ZPoly| -> Result<Poly, AnalysisError> {
            let mut terms = Vec::with_capacity(z.len());
            for (mono, c) in z.terms() {
                let mut c = int_mod(&run.field, c);
                let mut e = vec![0u32; n];
                for (v, k) in mono.iter() {
                    match vmap.get(&v) {
                        Some(Ok(i)) => e[*i] += k,
                        Some(Err(x)) => c = run.field.mul(c, run.field.pow(*x, k as u64)),
                        None => return Err(err("global: unknown symbol")),
                    }
                }
                terms.push((Mono::from_exponents(e).map_err(gb_err)?, c));
            }
            Ok(run.ring.from_terms(terms))
        };
        // The right-hand sides as polynomials: num * z (or num / constant).
        let with_den = |run: &Run, num: &ZPoly, den: &ZPoly, di: Option<usize>| {
            let nump = conv(run, num)?;
            match di {
                Some(i) => run
                    .ring
                    .mul(&nump, &run.ring.var(run.sv(nx + i, 0)))
                    .map_err(gb_err),
                None => {
                    // A number, or known constants at their random values.
                    let dp = conv(run, den)?;
                    let c = run.ring.eval(&dp, &run.point);
                    let ci = run
                        .field
                        .inv(c)
                        .ok_or_else(|| err("global: a denominator vanishes modulo the prime"))?;
                    Ok(run.ring.scale(&nump, ci))
                }
            }
        };
        let mut rhs: Vec<Poly> = Vec::with_capacity(ns);
        for (s, (num, den)) in m.rhs.iter().enumerate() {
            rhs.push(with_den(&run, num, den, rhs_den[s])?);
        }
        // z' = -z^2 * sum_s d(den)/dx_s * x_s'
        let mut den_p = Vec::new();
        for (i, d) in dens.iter().enumerate() {
            let dp = conv(&run, d)?;
            let mut dd = Poly::zero();
            for (s, f) in rhs.iter().take(nx).enumerate() {
                let g = run.ring.derivative(&dp, run.sv(s, 0));
                if !g.is_zero() {
                    dd = run.ring.add(&dd, &run.ring.mul(&g, f).map_err(gb_err)?);
                }
            }
            let z = run.ring.var(run.sv(nx + i, 0));
            let z2 = run.ring.mul(&z, &z).map_err(gb_err)?;
            let zr = run.ring.mul(&z2, &dd).map_err(gb_err)?;
            den_p.push((dp, z));
            rhs.push(run.ring.scale(&zr, field.neg(1)));
        }
        let mut outs = Vec::new();
        for (k, (num, den)) in m.outputs.iter().enumerate() {
            outs.push(with_den(&run, num, den, out_den[k])?);
        }
        run.rhs_d = rhs.into_iter().map(|f| vec![f]).collect();
        run.out_d = outs.into_iter().map(|f| vec![f]).collect();
        // The point at order 0: params, states, inputs' coefficients random;
        // z = 1/den (resampled where a denominator vanishes).
        'sample: for _ in 0..16 {
            for i in 0..np {
                run.point[i] = rng.elem(&field);
            }
            for s in 0..nx {
                let v = run.sv(s, 0);
                run.point[v] = rng.elem(&field);
            }
            for i in 0..nu {
                for k in 0..=kmax {
                    let v = run.uv(i, k);
                    run.point[v] = rng.elem(&field);
                }
            }
            run.inits.clear();
            for (i, (dp, z)) in den_p.iter().enumerate() {
                let dv = run.ring.eval(dp, &run.point);
                let Some(inv) = field.inv(dv) else {
                    continue 'sample;
                };
                let zi = run.sv(nx + i, 0);
                run.point[zi] = inv;
                let e = run.ring.mul(dp, z).map_err(gb_err)?;
                run.inits.push(run.ring.sub(&e, &run.ring.constant(1)));
            }
            run.rng = Rng(rng.next());
            return Ok(run);
        }
        Err(AnalysisError::NoPoint)
    }

    /// The total derivative: `x_s^(k) -> x_s^(k+1)`, `u^(k) -> u^(k+1)`.
    fn derive(&self, p: &Poly) -> Result<Poly, AnalysisError> {
        let r = &self.ring;
        let mut out = Poly::zero();
        for s in 0..self.ns {
            for k in 0..=self.kmax {
                let v = self.sv(s, k);
                let g = r.derivative(p, v);
                if g.is_zero() {
                    continue;
                }
                if k == self.kmax {
                    return Err(err("global: Taylor order past the prepared maximum"));
                }
                out = r.add(&out, &r.mul(&g, &r.var(self.sv(s, k + 1))).map_err(gb_err)?);
            }
        }
        for i in 0..self.nu {
            for k in 0..=self.kmax {
                let v = self.uv(i, k);
                let g = r.derivative(p, v);
                if g.is_zero() {
                    continue;
                }
                if k == self.kmax {
                    return Err(err("global: Taylor order past the prepared maximum"));
                }
                out = r.add(&out, &r.mul(&g, &r.var(self.uv(i, k + 1))).map_err(gb_err)?);
            }
        }
        Ok(out)
    }

    /// `D^j` of every right-hand side (j < order) and output (j <= order),
    /// and the point's state derivatives up to `order`.
    fn prepare(&mut self, order: usize) -> Result<(), AnalysisError> {
        if order >= self.kmax {
            return Err(err("global: Taylor order past the prepared maximum"));
        }
        for s in 0..self.ns {
            while self.rhs_d[s].len() < order {
                let last = self.rhs_d[s].last().cloned().unwrap_or_default();
                let d = self.derive(&last)?;
                self.rhs_d[s].push(d);
            }
        }
        for y in 0..self.out_d.len() {
            while self.out_d[y].len() <= order {
                let last = self.out_d[y].last().cloned().unwrap_or_default();
                let d = self.derive(&last)?;
                self.out_d[y].push(d);
            }
        }
        while self.point_order < order {
            let j = self.point_order;
            let vals: Vec<u64> = (0..self.ns)
                .map(|s| self.ring.eval(&self.rhs_d[s][j], &self.point))
                .collect();
            for (s, x) in vals.into_iter().enumerate() {
                let v = self.sv(s, j + 1);
                self.point[v] = x;
            }
            self.point_order += 1;
        }
        Ok(())
    }

    /// The system of the proven truncation: output `y` up to order
    /// `orders[y]` (inclusive), and the state equations `x^(k) = D^(k-1) f`
    /// for exactly the derivatives those rows use (a closure: each added row
    /// uses only lower orders). Returns `(equations in the derivation ring,
    /// unknowns)`, the unknowns highest derivatives first (grevlex then treats
    /// them as the largest variables), params last.
    fn equations(&mut self, orders: &[usize]) -> Result<(Vec<Poly>, Vec<usize>), AnalysisError> {
        let top = orders.iter().copied().max().unwrap_or(0);
        self.prepare(top)?;
        let r = &self.ring;
        let mut used = vec![false; r.n];
        let mark = |p: &Poly, used: &mut Vec<bool>| {
            for (m, _) in p.terms() {
                for (v, &e) in m.exponents().iter().enumerate() {
                    if e > 0 {
                        used[v] = true;
                    }
                }
            }
        };
        let mut eqs = self.inits.clone();
        for e in &eqs {
            mark(e, &mut used);
        }
        for (y, &d) in orders.iter().enumerate() {
            for j in 0..=d {
                let c = r.eval(&self.out_d[y][j], &self.point);
                let e = r.sub(&self.out_d[y][j], &r.constant(c));
                mark(&e, &mut used);
                eqs.push(e);
            }
        }
        for k in (1..=top).rev() {
            for s in 0..self.ns {
                let v = self.sv(s, k);
                if used[v] {
                    let e = r.sub(&r.var(v), &self.rhs_d[s][k - 1]);
                    mark(&e, &mut used);
                    eqs.push(e);
                }
            }
        }
        let mut unknowns = Vec::new();
        for k in (1..=top).rev() {
            for s in 0..self.ns {
                if used[self.sv(s, k)] {
                    unknowns.push(self.sv(s, k));
                }
            }
        }
        for s in 0..self.ns {
            unknowns.push(self.sv(s, 0));
        }
        unknowns.extend(0..self.np);
        Ok((eqs, unknowns))
    }

    /// The equations in the ring of the unknowns (inputs substituted), with
    /// `extra` further variables appended at the end.
    fn to_unknown_ring(
        &self,
        eqs: &[Poly],
        unknowns: &[usize],
        extra: usize,
    ) -> Result<(Ring, Vec<Poly>), AnalysisError> {
        let n = unknowns.len() + extra;
        let ring = Ring::new(self.field, n, Order::Grevlex);
        let mut pos: HashMap<usize, usize> = HashMap::new();
        for (i, &v) in unknowns.iter().enumerate() {
            pos.insert(v, i);
        }
        let mut out = Vec::with_capacity(eqs.len());
        for p in eqs {
            let mut terms = Vec::with_capacity(p.len());
            for (m, c) in p.terms() {
                let mut c = *c;
                let mut e = vec![0u32; n];
                for (v, &k) in m.exponents().iter().enumerate() {
                    if k == 0 {
                        continue;
                    }
                    match pos.get(&v) {
                        Some(&i) => e[i] = k,
                        None => c = self.field.mul(c, self.field.pow(self.point[v], k as u64)),
                    }
                }
                terms.push((Mono::from_exponents(e).map_err(gb_err)?, c));
            }
            out.push(ring.from_terms(terms));
        }
        Ok((ring, out))
    }

    /// The gradient of `p` at the point: `(variable, d p / d variable)` for
    /// the variables `p` uses.
    fn grad_at(&self, p: &Poly) -> Vec<(usize, u64)> {
        let f = &self.field;
        let mut out: HashMap<usize, u64> = HashMap::new();
        for (m, c) in p.terms() {
            let occ: Vec<(usize, u32)> = m
                .exponents()
                .iter()
                .enumerate()
                .filter(|(_, &e)| e > 0)
                .map(|(v, &e)| (v, e))
                .collect();
            for (i, &(v, e)) in occ.iter().enumerate() {
                // c * e * x_v^(e-1) * prod of the other factors
                let mut t = f.mul(*c, f.reduce(e as u64));
                t = f.mul(t, f.pow(self.point[v], e as u64 - 1));
                for (k, &(w, ew)) in occ.iter().enumerate() {
                    if k != i {
                        t = f.mul(t, f.pow(self.point[w], ew as u64));
                    }
                }
                let acc = out.entry(v).or_insert(0);
                *acc = f.add(*acc, t);
            }
        }
        out.into_iter().filter(|&(_, x)| x != 0).collect()
    }
}

/// Rows in echelon form over F_p (each row reduced by the earlier ones at
/// insertion, so reducing in insertion order is a full reduction).
struct Echelon {
    field: Field,
    rows: Vec<(Vec<u64>, usize)>,
}

impl Echelon {
    fn reduce(&self, mut v: Vec<u64>) -> Vec<u64> {
        let f = &self.field;
        for (row, piv) in &self.rows {
            let c = v[*piv];
            if c != 0 {
                for (a, b) in v.iter_mut().zip(row) {
                    *a = f.sub(*a, f.mul(c, *b));
                }
            }
        }
        v
    }

    /// Adds `v` if it is independent of the rows; whether it was.
    fn insert(&mut self, v: Vec<u64>) -> bool {
        let v = self.reduce(v);
        let Some(piv) = v.iter().position(|&x| x != 0) else {
            return false;
        };
        let inv = self.field.inv(v[piv]).unwrap_or(0);
        let v: Vec<u64> = v.iter().map(|&x| self.field.mul(x, inv)).collect();
        self.rows.push((v, piv));
        true
    }

    fn contains(&self, v: Vec<u64>) -> bool {
        self.reduce(v).iter().all(|&x| x == 0)
    }
}

/// One run's answer: per target (params then model states) the number of
/// values (`None`: infinitely many), and the joint count.
struct Counts {
    per_var: Vec<Option<usize>>,
    joint: Option<usize>,
    /// Per output, the Taylor order used (inclusive): the first order at
    /// which its row of the Jacobian is dependent on the rows kept before.
    orders: Vec<usize>,
    /// Highest order of an independent (kept) row.
    rank_order: usize,
    unknowns: usize,
    equations: usize,
    /// Total degrees of the equations in the unknowns (SIAN's Bezout product).
    degrees: Vec<u32>,
    /// Number of locally identifiable targets (SIAN's |theta_l|).
    n_local: usize,
}

/// One run: the per-output orders by SIAN's greedy rank test on the total
/// gradients of the output coefficients (docs/engine.md, "Taylor orders"),
/// local identifiability from the same Jacobian, then the counts.
fn count_once(run: &mut Run, opts: &GlobalOptions) -> Result<Counts, AnalysisError> {
    let f = run.field;
    let targets: Vec<usize> = (0..run.np)
        .chain((0..run.nx).map(|s| run.sv(s, 0)))
        .collect();
    let nt = targets.len();
    // Total gradients d v / d (params, x(0)) of the derivation variables at
    // the point, built order by order (inputs are known: gradient 0).
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
    // z = 1/den at order 0: from z den - 1 = 0, grad z = -(sum_{v != z}
    // q_v grad v) / q_z.
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
    let mut ech = Echelon {
        field: f,
        rows: Vec::new(),
    };
    let mut rank_order = 0;
    let mut j = 0;
    while open.iter().any(|&o| o) {
        if j >= opts.max_order {
            return Err(err(format!(
                "global: the outputs' Jacobian still gained rank at Taylor order {}",
                opts.max_order
            )));
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
            if !open[i] {
                continue;
            }
            let g = run.grad_at(&run.out_d[i][j]);
            if ech.insert(combine(&g, &grads)) {
                rank_order = j;
            } else {
                open[i] = false;
                orders[i] = j;
            }
        }
        if let Some(d) = opts.deadline {
            if Instant::now() > d {
                return Err(AnalysisError::Timeout("choosing the Taylor orders".into()));
            }
        }
        j += 1;
    }
    let rank = ech.rows.len();
    let fibre_dim = nt - rank;
    // theta_t is locally identifiable iff e_t lies in the row space.
    let local: Vec<bool> = (0..nt)
        .map(|t| {
            let mut e = vec![0u64; nt];
            e[t] = 1;
            ech.contains(e)
        })
        .collect();
    let budget = GbBudget {
        max_basis: opts.max_basis,
        deadline: opts.deadline,
        ..GbBudget::default()
    };
    count_at(
        run, &orders, &targets, &local, fibre_dim, budget, opts, rank_order,
    )
}

/// The counts on the truncated system. A fibre of positive dimension `d` (some
/// variables not locally identifiable) is first cut by `d` random affine
/// hyperplanes through the point in the coordinates of those variables: a
/// generic fibre of the output map is equidimensional (every component has
/// dimension `d`, the fibre-dimension theorem for the dominant map from the
/// irreducible space of (params, initial states)), and the locally
/// identifiable variables are constant on each component, so a generic
/// codimension-`d` slice meets every component and keeps every value they take.
#[allow(clippy::too_many_arguments)]
fn count_at(
    run: &mut Run,
    orders: &[usize],
    targets: &[usize],
    local: &[bool],
    fibre_dim: usize,
    budget: GbBudget,
    opts: &GlobalOptions,
    rank_order: usize,
) -> Result<Counts, AnalysisError> {
    let f = run.field;
    let (mut eqs, unk) = run.equations(orders)?;
    let free: Vec<usize> = targets
        .iter()
        .zip(local)
        .filter(|(_, &l)| !l)
        .map(|(&t, _)| t)
        .collect();
    if fibre_dim > free.len() {
        return Err(err(
            "global: the fibre is larger than the non-identifiable variables span (a non-generic point); try another --seed",
        ));
    }
    for _ in 0..fibre_dim {
        let r = &run.ring;
        let mut h = Poly::zero();
        let mut c0 = 0u64;
        for &v in &free {
            let c = run.rng.elem(&f);
            h = r.add(&h, &r.scale(&r.var(v), c));
            c0 = f.add(c0, f.mul(c, run.point[v]));
        }
        eqs.push(r.sub(&h, &r.constant(c0)));
    }
    let (ring, gens) = run.to_unknown_ring(&eqs, &unk, 0)?;
    let tpos: Vec<usize> = targets
        .iter()
        .map(|v| unk.iter().position(|u| u == v).unwrap_or(0))
        .collect();
    let b = groebner(&ring, &gens, budget).map_err(gb_err)?;
    if b.is_unit() {
        return Err(err(
            "global: the system at the random point has no solution (a degenerate point); try another --seed",
        ));
    }
    if !b.is_zero_dimensional() {
        return Err(err(
            "global: the sliced system still has infinitely many solutions (a non-generic point); try another --seed",
        ));
    }
    let mut per_var = Vec::with_capacity(targets.len());
    for (i, &t) in tpos.iter().enumerate() {
        if !local[i] {
            per_var.push(None);
            continue;
        }
        let m = b
            .minimal_polynomial(&ring.var(t), opts.max_solutions)
            .map_err(gb_err)?;
        per_var.push(Some(distinct_roots(f, &m)));
    }
    // A random linear form in the locally identifiable variables separates
    // their joint values (with probability at least 1 - C(s, 2)/p), so its
    // distinct values count them.
    let mut terms = Vec::new();
    for (i, &t) in tpos.iter().enumerate() {
        if local[i] {
            terms.push((Mono::var(ring.n, t, 1), run.rng.elem(&f)));
        }
    }
    let lf = ring.from_terms(terms);
    let m = b
        .minimal_polynomial(&lf, opts.max_solutions)
        .map_err(gb_err)?;
    let joint = Some(distinct_roots(f, &m));
    Ok(Counts {
        per_var,
        joint,
        orders: orders.to_vec(),
        rank_order,
        unknowns: unk.len(),
        equations: eqs.len(),
        degrees: gens.iter().map(|g| g.degree()).collect(),
        n_local: local.iter().filter(|&&l| l).count(),
    })
}

/// SIAN's bounds (Hong, Ovchinnikov, Pogudin, Yap 2020, Algorithm 1, steps
/// 2(b) and 3(a); docs/engine.md): with `n` states, `l` params, `s = n + l`,
/// `d0` the largest degree of `Q f`, `Q h` and `Q` (`Q` the lcm of the
/// denominators, here bounded by their product), the orders and local
/// verdicts are wrong only on a hypersurface of degree
/// `D1 = (s + 1) 2 d0 s (n + 1)(1 + 2 d0 s)` in the point, the global ones on
/// one of degree `D2 = 6 |theta_l| prod(deg E_t) (1 + 2 d0 max beta)`.
/// Schwartz–Zippel over F_p: one run errs with probability at most
/// `(D1 + D2)/p`; the two runs are independent and must agree.
fn error_bounds(m: &ZModel, runs: &[Counts], primes: &[u64; 2]) -> (f64, f64, f64) {
    let n = m.dyn_vars.len() as f64;
    let s = n + m.param_vars.len() as f64;
    let mut dens: Vec<&ZPoly> = Vec::new();
    for (_, d) in m.rhs.iter().chain(&m.outputs) {
        if d.total_degree() > 0 && !dens.contains(&d) {
            dens.push(d);
        }
    }
    let deg_q: u64 = dens.iter().map(|d| d.total_degree()).sum();
    let mut d0 = deg_q;
    for (num, den) in m.rhs.iter().chain(&m.outputs) {
        d0 = d0.max(num.total_degree() + deg_q - den.total_degree().min(deg_q));
    }
    let d0 = d0.max(1) as f64;
    let d1 = (s + 1.0) * 2.0 * d0 * s * (n + 1.0) * (1.0 + 2.0 * d0 * s);
    let mut worst_log = f64::NEG_INFINITY;
    let mut probs = Vec::new();
    for (c, &p) in runs.iter().zip(primes) {
        let max_beta = c.orders.iter().copied().max().unwrap_or(0) as f64;
        let log_d2 = if c.n_local == 0 {
            f64::NEG_INFINITY
        } else {
            (6.0 * c.n_local as f64 * (1.0 + 2.0 * d0 * max_beta)).log10()
                + c.degrees
                    .iter()
                    .map(|&d| (d.max(1) as f64).log10())
                    .sum::<f64>()
        };
        worst_log = worst_log.max(log_d2);
        let total = d1 + 10f64.powf(log_d2);
        probs.push((total / p as f64).min(1.0));
    }
    (d1, worst_log, probs.iter().product())
}

/// A signed permutation of the model's variables (dynamic states, then params):
/// `perm[i] = (j, sign)` maps variable i to sign * variable j.
type Signed = Vec<(usize, i8)>;

/// Whether `sigma` maps the model to itself exactly (over Z): with
/// `S(g) = g(w_{pi(v)} := e_v v)`, `S(f_{pi(s)}) = e_s f_s` for each state
/// and `S(h) = h` for each output.
fn is_symmetry(m: &ZModel, sigma: &Signed) -> bool {
    let vars: Vec<Var> = m.dyn_vars.iter().chain(&m.param_vars).copied().collect();
    // w = vars[pi(v)] -> e_v * vars[v]
    let mut inv: HashMap<Var, (Var, i8)> = HashMap::new();
    for (v, &(w, e)) in sigma.iter().enumerate() {
        inv.insert(vars[w], (vars[v], e));
    }
    let subst = |p: &ZPoly| -> ZPoly {
        let terms: Vec<(obsan_expr::Mono, Int)> = p
            .terms()
            .iter()
            .map(|(mono, c)| {
                let mut neg = false;
                let pairs: Vec<(Var, u32)> = mono
                    .iter()
                    .map(|(v, k)| match inv.get(&v) {
                        Some(&(u, e)) => {
                            if e < 0 && k % 2 == 1 {
                                neg = !neg;
                            }
                            (u, k)
                        }
                        None => (v, k),
                    })
                    .collect();
                let c = if neg { -c.clone() } else { c.clone() };
                (obsan_expr::Mono::from_pairs(pairs), c)
            })
            .collect();
        ZPoly::from_terms(terms)
    };
    let same = |(n1, d1): (&ZPoly, &ZPoly), (n2, d2): (&ZPoly, &ZPoly), sign: i8| -> bool {
        let lhs = n1.mul(d2);
        let rhs = n2.mul(d1);
        if sign < 0 {
            lhs.add(&rhs).is_zero()
        } else {
            lhs.sub(&rhs).is_zero()
        }
    };
    for (s, &(ps, es)) in sigma.iter().enumerate().take(m.dyn_vars.len()) {
        let (n, d) = &m.rhs[ps];
        let (sn, sd) = (subst(n), subst(d));
        if !same((&sn, &sd), (&m.rhs[s].0, &m.rhs[s].1), es) {
            return false;
        }
    }
    for (n, d) in &m.outputs {
        if !same((&subst(n), &subst(d)), (n, d), 1) {
            return false;
        }
    }
    true
}

/// Signed permutations of the multi-valued variables (states to states,
/// params to params), each checked exactly; at most `cap` candidates.
fn find_maps(m: &ZModel, multi: &[bool], cap: usize) -> Vec<Signed> {
    let nx = m.dyn_vars.len();
    let n = nx + m.param_vars.len();
    let movable: Vec<usize> = (0..n).filter(|&i| multi[i]).collect();
    let mut found = Vec::new();
    let mut tried = 0usize;
    // Depth-first over images: each movable variable to a movable variable
    // of its kind not yet used, with a sign.
    #[allow(clippy::too_many_arguments)]
    fn rec(
        i: usize,
        movable: &[usize],
        nx: usize,
        cur: &mut Signed,
        used: &mut Vec<bool>,
        out: &mut Vec<Signed>,
        m: &ZModel,
        tried: &mut usize,
        cap: usize,
    ) {
        if *tried >= cap {
            return;
        }
        if i == movable.len() {
            let identity = cur.iter().enumerate().all(|(k, &(j, e))| k == j && e > 0);
            if !identity {
                *tried += 1;
                if is_symmetry(m, cur) {
                    out.push(cur.clone());
                }
            }
            return;
        }
        let v = movable[i];
        for &w in movable {
            if used[w] || (v < nx) != (w < nx) {
                continue;
            }
            for e in [1i8, -1] {
                used[w] = true;
                cur[v] = (w, e);
                rec(i + 1, movable, nx, cur, used, out, m, tried, cap);
                used[w] = false;
            }
        }
        cur[v] = (v, 1);
    }
    let mut cur: Signed = (0..n).map(|i| (i, 1)).collect();
    let mut used = vec![false; n];
    rec(
        0, &movable, nx, &mut cur, &mut used, &mut found, m, &mut tried, cap,
    );
    found
}

/// The group generated by signed permutations (closure under composition),
/// capped at `cap` elements.
fn group_order(maps: &[Signed], n: usize, cap: usize) -> usize {
    let id: Signed = (0..n).map(|i| (i, 1)).collect();
    let mut elems = vec![id];
    let mut k = 0;
    while k < elems.len() && elems.len() < cap {
        for g in maps {
            let a = &elems[k];
            // (g . a)(v) = g(a(v))
            let c: Signed = a
                .iter()
                .map(|&(w, e)| {
                    let (w2, e2) = g[w];
                    (w2, e * e2)
                })
                .collect();
            if !elems.contains(&c) {
                elems.push(c);
            }
        }
        k += 1;
    }
    elems.len()
}

/// Global identifiability of every parameter and initial state (SIAN's
/// route; the certificate and the bounds are in docs/engine.md): two
/// independent runs (different primes and random points) must agree.
pub fn global_identifiability(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
) -> Result<GlobalReport, AnalysisError> {
    let m = zmodel(nf)?;
    let primes = [obsan_recon::PRIMES[0], obsan_recon::PRIMES[1]];
    let kmax = opts.max_order + 2;
    let mut results = Vec::new();
    for (r, &p) in primes.iter().enumerate() {
        let mut run = Run::new(&m, p, opts.seed.wrapping_add(r as u64), kmax)?;
        results.push(count_once(&mut run, opts)?);
    }
    let (a, b) = (&results[0], &results[1]);
    if a.per_var != b.per_var || a.joint != b.joint || a.orders != b.orders {
        return Err(err(
            "global: two independent random points disagree on the counts (a non-generic point); try another --seed",
        ));
    }
    let nx = m.dyn_vars.len();
    let np = m.param_vars.len();
    let bounds = error_bounds(&m, &results, &primes);
    // Names: params then states, as the counts are ordered.
    let names: Vec<(String, bool)> = nf.state[nx..]
        .iter()
        .map(|s| (s.clone(), true))
        .chain(nf.state[..nx].iter().map(|s| (s.clone(), false)))
        .collect();
    let variables: Vec<GlobalVariable> = names
        .iter()
        .zip(&a.per_var)
        .enumerate()
        .map(|(i, ((name, param), c))| GlobalVariable {
            name: name.clone(),
            param: *param,
            angle: m.angle[if i < np { nx + i } else { i - np }],
            verdict: match c {
                None => Identifiability::NotIdentifiable,
                Some(1) => Identifiability::Global,
                Some(k) => Identifiability::Local(*k),
            },
        })
        .collect();
    let all_local = a.per_var.iter().all(|c| c.is_some());
    // Multi-valued variables in model order (states then params).
    let mut multi = vec![false; nx + np];
    for (i, c) in a.per_var.iter().enumerate() {
        let idx = if i < np { nx + i } else { i - np };
        multi[idx] = matches!(c, Some(k) if *k > 1);
    }
    let maps = if multi.iter().any(|&x| x) {
        find_maps(&m, &multi, 200_000)
    } else {
        Vec::new()
    };
    let group = group_order(&maps, nx + np, 100_000);
    let all_names: Vec<&str> = nf.state.iter().map(|s| s.as_str()).collect();
    let maps_out = maps
        .iter()
        .map(|s| DiscreteMap {
            images: s
                .iter()
                .enumerate()
                .filter(|(v, &(w, e))| *v != w || e < 0)
                .map(|(v, &(w, e))| (all_names[v].to_string(), e, all_names[w].to_string()))
                .collect(),
        })
        .collect();
    Ok(GlobalReport {
        variables,
        solutions: a.joint,
        all_local,
        maps: maps_out,
        group_order: group,
        order: a.orders.iter().copied().max().unwrap_or(0),
        rank_order: a.rank_order,
        output_orders: nf
            .outputs
            .iter()
            .zip(&a.orders)
            .map(|(o, &k)| (o.0.clone(), k))
            .collect(),
        delta_local: bounds.0,
        log10_delta_global: bounds.1,
        error_bound: bounds.2,
        unknowns: a.unknowns,
        equations: a.equations,
        primes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use obsan_model::System;

    fn report(src: &str) -> GlobalReport {
        let sys = System::parse(&format!("system t\n{src}"), "t.sys").unwrap();
        let mut nf = sys.normal_form(None, &[]).unwrap();
        global_identifiability(&mut nf, &GlobalOptions::default()).unwrap()
    }

    fn verdict(r: &GlobalReport, name: &str) -> Identifiability {
        r.variables.iter().find(|v| v.name == name).unwrap().verdict
    }

    #[test]
    fn single_decay_is_global() {
        // x' = -a x, y = x: y(0) = x0, y'(0) = -a x0, so a = -y'/y: unique.
        let r = report("state x\nparam a\nx' = -a*x\noutput y = x\n");
        assert_eq!(verdict(&r, "a"), Identifiability::Global);
        assert_eq!(verdict(&r, "x"), Identifiability::Global);
        assert_eq!(r.solutions, Some(1));
        assert!(r.maps.is_empty());
    }

    #[test]
    fn squared_rate_has_two_values() {
        // x' = -a^2 x, y = x: y'/y = -a^2 fixes a only up to sign; x0 = y(0).
        let r = report("state x\nparam a\nx' = -a^2*x\noutput y = x\n");
        assert_eq!(verdict(&r, "a"), Identifiability::Local(2));
        assert_eq!(verdict(&r, "x"), Identifiability::Global);
        assert_eq!(r.solutions, Some(2));
        assert_eq!(r.maps.len(), 1);
        assert_eq!(r.maps[0].to_string(), "a -> -a");
        assert_eq!(r.group_order, 2);
    }

    #[test]
    fn two_decays_swap() {
        // y = x1 e^{-a t} + x2 e^{-b t}: the exponents and amplitudes are
        // known as an unordered pair {(a, x1), (b, x2)}: 2 values each, and
        // the swap maps one to the other.
        let r = report("state x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n");
        for v in ["a", "b", "x1", "x2"] {
            assert_eq!(verdict(&r, v), Identifiability::Local(2), "{v}");
        }
        assert_eq!(r.solutions, Some(2));
        assert_eq!(r.maps.len(), 1);
        assert_eq!(r.maps[0].to_string(), "(x1, x2, a, b) -> (x2, x1, b, a)");
        assert_eq!(r.group_order, 2);
    }

    #[test]
    fn unidentifiable_product() {
        // x' = -a b x, y = c x... here y = x, x' = a*b*x: only a*b is seen;
        // a and b take infinitely many values, x0 = y(0) is global.
        let r = report("state x\nparam a, b\nx' = a*b*x\noutput y = x\n");
        assert_eq!(verdict(&r, "a"), Identifiability::NotIdentifiable);
        assert_eq!(verdict(&r, "b"), Identifiability::NotIdentifiable);
        assert_eq!(verdict(&r, "x"), Identifiability::Global);
        assert!(!r.all_local);
        // Jointly only x is locally identifiable: one value.
        assert_eq!(r.solutions, Some(1));
    }

    fn file_report(rel: &str) -> GlobalReport {
        let path = format!("{}/../../systems/{rel}", env!("CARGO_MANIFEST_DIR"));
        let src = std::fs::read_to_string(path).unwrap();
        let sys = System::parse(&src, rel).unwrap();
        let mut nf = sys.normal_form(None, &[]).unwrap();
        global_identifiability(&mut nf, &GlobalOptions::default()).unwrap()
    }

    #[test]
    fn hiv_xia_moog_swaps_delta_and_c() {
        // Derived by hand: T' = s - d T - beta T V gives s, d, beta; with
        // V' = p I - c V and I' = beta T V - delta I,
        // V'' + (delta + c) V' + delta c V = p beta T V: the outputs see p and
        // only delta + c and delta c, so (delta, c) is an unordered pair (2
        // values each) and I = (V' + c V)/p takes 2 values; the rest is global.
        let r = file_report("classic/hiv.sys");
        for v in ["delta", "c", "I"] {
            assert_eq!(verdict(&r, v), Identifiability::Local(2), "{v}");
        }
        for v in ["s", "d", "beta", "p", "T", "V"] {
            assert_eq!(verdict(&r, v), Identifiability::Global, "{v}");
        }
        assert_eq!(r.solutions, Some(2));
        // Not a signed permutation (I moves by an affine map): none is claimed.
        assert!(r.maps.is_empty());
    }

    #[test]
    fn llw1987_published_pair() {
        // Published (SI.jl tutorial "Globally identifiable functions"): the
        // identifiable functions are p1 + p3, p2 p4, p1 p3: p1 and p3 are an
        // unordered pair (2 values each), p2, p4, x1, x2 not identifiable.
        let r = file_report("benchmarks/llw1987.sys");
        assert_eq!(verdict(&r, "p1"), Identifiability::Local(2));
        assert_eq!(verdict(&r, "p3"), Identifiability::Local(2));
        for v in ["p2", "p4", "x1", "x2"] {
            assert_eq!(verdict(&r, v), Identifiability::NotIdentifiable, "{v}");
        }
        assert_eq!(r.solutions, Some(2));
    }

    #[test]
    fn rational_model_clears_denominators() {
        // x' = -x/(a + x)... y = x: y' = -y/(a + y) gives a = -y - y/y'
        // uniquely (Michaelis-Menten-like elimination by hand).
        let r = report("state x\nparam a\nx' = -x/(a + x)\noutput y = x\n");
        assert_eq!(verdict(&r, "a"), Identifiability::Global);
        assert_eq!(verdict(&r, "x"), Identifiability::Global);
    }
}
