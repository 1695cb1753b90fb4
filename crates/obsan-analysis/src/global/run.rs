//! The prolonged system (SIAN): the derivation ring of the parameters and
//! the states' and inputs' derivatives modulo one prime, at one random point.

use super::model::ZModel;
use super::sian::Cleared;
use super::types::{err, gb_err, too_large};
use crate::rank::AnalysisError;
use obsan_expr::{Int, Poly as ZPoly, SplitMix, Var};
use obsan_groebner::{Field, Mono, Order, Poly, Ring};
use std::collections::HashMap;

pub(super) fn int_mod(f: &Field, c: &Int) -> u64 {
    let p = Int::from(f.modulus());
    let r = c % &p;
    match i64::try_from(&r) {
        Ok(x) => f.from_i64(x),
        Err(_) => 0, // |r| < p < 2^63 always fits
    }
}

/// The random points' generator: the engine's SplitMix64 (one implementation
/// in the workspace's obsan crates), drawing field elements above 1.
pub(super) struct Rng(SplitMix);

impl Rng {
    pub(super) fn new(seed: u64) -> Rng {
        Rng(SplitMix(seed))
    }
    pub(super) fn next(&mut self) -> u64 {
        self.0.next_u64()
    }
    pub(super) fn elem(&mut self, f: &Field) -> u64 {
        loop {
            let x = f.reduce(self.next());
            if x > 1 {
                return x;
            }
        }
    }
}

/// The prolonged system modulo one prime at one random point.
pub(super) struct Run {
    pub(super) field: Field,
    /// Derivation ring: params, then per dynamic state (model states and the
    /// `z` of each denominator) orders `0..=kmax`, then per input orders `0..=kmax`.
    pub(super) ring: Ring,
    pub(super) np: usize,
    pub(super) ns: usize,
    /// Number of model states (the first `nx` of the `ns`).
    pub(super) nx: usize,
    pub(super) nu: usize,
    pub(super) kmax: usize,
    /// `D^j` of each state's right-hand side and each output, computed lazily.
    pub(super) rhs_d: Vec<Vec<Poly>>,
    pub(super) out_d: Vec<Vec<Poly>>,
    /// Polynomials that vanish on the point at order 0 (`z * den - 1`).
    pub(super) inits: Vec<Poly>,
    /// SIAN's system with the denominators cleared (sian.rs): what the
    /// Gröbner basis is computed on.
    pub(super) cleared: Cleared,
    /// The point: values of every derivation-ring variable (filled by order).
    pub(super) point: Vec<u64>,
    pub(super) point_order: usize,
    /// Random coefficient of the separating linear form, and its seed
    /// ([`Run::rewind`]).
    pub(super) rng: Rng,
    rng_seed: u64,
    /// Bytes the derivatives and the system may hold (the memory budget).
    pub(super) max_bytes: usize,
}

impl Run {
    pub(super) fn sv(&self, s: usize, k: usize) -> usize {
        self.np + s * (self.kmax + 1) + k
    }
    pub(super) fn uv(&self, i: usize, k: usize) -> usize {
        self.np + self.ns * (self.kmax + 1) + i * (self.kmax + 1) + k
    }

    /// The system of `m` modulo `p`, at a random point drawn from `seed`,
    /// prepared for Taylor orders below `kmax`.
    pub(super) fn new(m: &ZModel, p: u64, seed: u64, kmax: usize) -> Result<Run, AnalysisError> {
        let field = Field::new(p).ok_or_else(|| err("global: bad prime"))?;
        let mut rng = Rng::new(seed);
        let dens = Denominators::of(m);
        let (np, nx, nu) = (m.param_vars.len(), m.dyn_vars.len(), m.input_vars.len());
        let ns = nx + dens.distinct.len();
        let n = np + (ns + nu) * (kmax + 1);
        let mut run = Run {
            field,
            ring: Ring::new(field, n, Order::Grevlex),
            np,
            ns,
            nx,
            nu,
            kmax,
            rhs_d: Vec::new(),
            out_d: Vec::new(),
            inits: Vec::new(),
            cleared: Cleared::default(),
            point: vec![0; n],
            point_order: 0,
            rng: Rng::new(0),
            rng_seed: 0,
            max_bytes: usize::MAX,
        };
        // Known constants: random values (they are known, hence fixed).
        let consts: Vec<(Var, u64)> = m
            .const_vars
            .iter()
            .map(|&v| (v, rng.elem(&field)))
            .collect();
        let conv = Conv::new(&run, m, &consts);
        let den_p = run.model_polys(m, &conv, &dens)?;
        for _ in 0..16 {
            if run.sample_point(&mut rng, &den_p)? {
                run.rng_seed = rng.next();
                run.rng = Rng::new(run.rng_seed);
                return Ok(run);
            }
        }
        Err(AnalysisError::NoPoint)
    }

    /// The right-hand sides (with `z' = -z^2 sum_s d(den)/dx_s x_s'` for each
    /// denominator's `z`) and the outputs as polynomials, `num * z` (or
    /// `num / constant`). Returns each denominator with its `z`.
    fn model_polys(
        &mut self,
        m: &ZModel,
        conv: &Conv,
        dens: &Denominators,
    ) -> Result<Vec<(Poly, Poly)>, AnalysisError> {
        let nx = self.nx;
        let mut rhs: Vec<Poly> = Vec::with_capacity(self.ns);
        for (s, (num, den)) in m.rhs.iter().enumerate() {
            rhs.push(self.with_den(conv, num, den, dens.rhs[s])?);
        }
        let mut den_p = Vec::new();
        for (i, d) in dens.distinct.iter().enumerate() {
            let dp = conv.poly(self, d)?;
            let mut dd = Poly::zero();
            for (s, f) in rhs.iter().take(nx).enumerate() {
                let g = self.ring.derivative(&dp, self.sv(s, 0));
                if !g.is_zero() {
                    dd = self.ring.add(&dd, &self.ring.mul(&g, f).map_err(gb_err)?);
                }
            }
            let z = self.ring.var(self.sv(nx + i, 0));
            let z2 = self.ring.mul(&z, &z).map_err(gb_err)?;
            let zr = self.ring.mul(&z2, &dd).map_err(gb_err)?;
            den_p.push((dp, z));
            rhs.push(self.ring.scale(&zr, self.field.neg(1)));
        }
        let mut outs = Vec::new();
        for (k, (num, den)) in m.outputs.iter().enumerate() {
            outs.push(self.with_den(conv, num, den, dens.outputs[k])?);
        }
        let mut state_parts = Vec::with_capacity(nx);
        for (num, den) in &m.rhs {
            state_parts.push((conv.poly(self, num)?, conv.poly(self, den)?));
        }
        let mut out_parts = Vec::with_capacity(m.outputs.len());
        for (num, den) in &m.outputs {
            out_parts.push((conv.poly(self, num)?, conv.poly(self, den)?));
        }
        let dens0: Vec<&Poly> = den_p.iter().map(|(d, _)| d).collect();
        self.cleared = Cleared::new(self, &state_parts, &out_parts, &dens0)?;
        self.rhs_d = rhs.into_iter().map(|f| vec![f]).collect();
        self.out_d = outs.into_iter().map(|f| vec![f]).collect();
        Ok(den_p)
    }

    /// `num/den` as a polynomial: `num * z` for a denominator with its `z`,
    /// else `num` divided by the number (known constants at their values).
    fn with_den(
        &self,
        conv: &Conv,
        num: &ZPoly,
        den: &ZPoly,
        di: Option<usize>,
    ) -> Result<Poly, AnalysisError> {
        let nump = conv.poly(self, num)?;
        match di {
            Some(i) => self
                .ring
                .mul(&nump, &self.ring.var(self.sv(self.nx + i, 0)))
                .map_err(gb_err),
            None => {
                let dp = conv.poly(self, den)?;
                let c = self.ring.eval(&dp, &self.point);
                let ci = self
                    .field
                    .inv(c)
                    .ok_or_else(|| err("global: a denominator vanishes modulo the prime"))?;
                Ok(self.ring.scale(&nump, ci))
            }
        }
    }

    /// The point at order 0: params, states, inputs' coefficients random;
    /// `z = 1/den`. False when a denominator vanishes there (draw again).
    fn sample_point(
        &mut self,
        rng: &mut Rng,
        den_p: &[(Poly, Poly)],
    ) -> Result<bool, AnalysisError> {
        let field = self.field;
        for i in 0..self.np {
            self.point[i] = rng.elem(&field);
        }
        for s in 0..self.nx {
            let v = self.sv(s, 0);
            self.point[v] = rng.elem(&field);
        }
        for i in 0..self.nu {
            for k in 0..=self.kmax {
                let v = self.uv(i, k);
                self.point[v] = rng.elem(&field);
            }
        }
        self.inits.clear();
        for (i, (dp, z)) in den_p.iter().enumerate() {
            let dv = self.ring.eval(dp, &self.point);
            let Some(inv) = field.inv(dv) else {
                return Ok(false);
            };
            let zi = self.sv(self.nx + i, 0);
            self.point[zi] = inv;
            let e = self.ring.mul(dp, z).map_err(gb_err)?;
            self.inits.push(self.ring.sub(&e, &self.ring.constant(1)));
        }
        Ok(true)
    }

    /// The total derivative: `x_s^(k) -> x_s^(k+1)`, `u^(k) -> u^(k+1)`.
    pub(super) fn derive(&self, p: &Poly) -> Result<Poly, AnalysisError> {
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

    /// Back to the state of a fresh run for another count: what counts draw
    /// (the separating form's coefficients) from the start again; the
    /// derivatives computed so far, functions of the run's point alone, are
    /// kept (`--route auto`'s Taylor attempts share them: mod.rs
    /// `Prolonged`).
    pub(super) fn rewind(&mut self) {
        self.rng = Rng::new(self.rng_seed);
    }

    /// Bytes held by the derivatives computed so far (as `prepare` and
    /// sian.rs count them).
    pub(super) fn held_bytes(&self) -> usize {
        let n = self.ring.n;
        self.rhs_d
            .iter()
            .chain(&self.out_d)
            .flatten()
            .map(|p| p.stored_bytes(n))
            .sum::<usize>()
            + self.cleared.held_bytes(n)
    }

    /// `D^j` of every right-hand side (j < order) and output (j <= order),
    /// and the point's state derivatives up to `order`.
    pub(super) fn prepare(&mut self, order: usize) -> Result<(), AnalysisError> {
        if order >= self.kmax {
            return Err(err("global: Taylor order past the prepared maximum"));
        }
        // Each derivative is counted as it joins the others (in the
        // derivation ring's `n` variables: every monomial holds all of them).
        let n = self.ring.n;
        let mut held: usize = self
            .rhs_d
            .iter()
            .chain(&self.out_d)
            .flatten()
            .map(|p| p.stored_bytes(n))
            .sum();
        for s in 0..self.ns {
            while self.rhs_d[s].len() < order {
                let last = self.rhs_d[s].last().cloned().unwrap_or_default();
                let d = self.derive(&last)?;
                held = self.count_derivative(held, &d, order)?;
                self.rhs_d[s].push(d);
            }
        }
        for y in 0..self.out_d.len() {
            while self.out_d[y].len() <= order {
                let last = self.out_d[y].last().cloned().unwrap_or_default();
                let d = self.derive(&last)?;
                held = self.count_derivative(held, &d, order)?;
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

    /// `held` plus the bytes of a new derivative, or the memory error.
    fn count_derivative(
        &self,
        held: usize,
        d: &Poly,
        order: usize,
    ) -> Result<usize, AnalysisError> {
        let held = held + d.stored_bytes(self.ring.n);
        if held > self.max_bytes {
            return Err(too_large(
                held as u128,
                self.max_bytes as u128,
                &format!(
                    "the Taylor system (derivatives of the right-hand sides and outputs to order {order}, in {} variables)",
                    self.ring.n
                ),
            ));
        }
        Ok(held)
    }

    /// The equations in the ring of the unknowns (inputs substituted), with
    /// `extra` further variables appended at the end.
    pub(super) fn to_unknown_ring(
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
    pub(super) fn grad_at(&self, p: &Poly) -> Vec<(usize, u64)> {
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

/// The distinct non-constant denominators (each gets a `z` state), and which
/// one each right-hand side and output has (`None`: a constant).
struct Denominators {
    distinct: Vec<ZPoly>,
    rhs: Vec<Option<usize>>,
    outputs: Vec<Option<usize>>,
}

impl Denominators {
    fn of(m: &ZModel) -> Denominators {
        let mut distinct: Vec<ZPoly> = Vec::new();
        let mut index = |d: &ZPoly| -> Option<usize> {
            if d.vars().iter().all(|v| m.const_vars.contains(v)) {
                return None;
            }
            match distinct.iter().position(|e| e == d) {
                Some(i) => Some(i),
                None => {
                    distinct.push(d.clone());
                    Some(distinct.len() - 1)
                }
            }
        };
        let rhs: Vec<Option<usize>> = m.rhs.iter().map(|(_, d)| index(d)).collect();
        let outputs: Vec<Option<usize>> = m.outputs.iter().map(|(_, d)| index(d)).collect();
        Denominators {
            distinct,
            rhs,
            outputs,
        }
    }
}

/// Model polynomials over Z to the derivation ring modulo p: each symbol to
/// its ring variable, or (a known constant) to its random value.
struct Conv {
    vmap: HashMap<Var, Result<usize, u64>>,
}

impl Conv {
    fn new(run: &Run, m: &ZModel, consts: &[(Var, u64)]) -> Conv {
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
        for &(v, x) in consts {
            vmap.insert(v, Err(x));
        }
        Conv { vmap }
    }

    fn poly(&self, run: &Run, z: &ZPoly) -> Result<Poly, AnalysisError> {
        let n = run.ring.n;
        let mut terms = Vec::with_capacity(z.len());
        for (mono, c) in z.terms() {
            let mut c = int_mod(&run.field, c);
            let mut e = vec![0u32; n];
            for (v, k) in mono.iter() {
                match self.vmap.get(&v) {
                    Some(Ok(i)) => e[*i] += k,
                    Some(Err(x)) => c = run.field.mul(c, run.field.pow(*x, k as u64)),
                    None => return Err(err("global: unknown symbol")),
                }
            }
            terms.push((Mono::from_exponents(e).map_err(gb_err)?, c));
        }
        Ok(run.ring.from_terms(terms))
    }
}
