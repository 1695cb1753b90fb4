//! SIAN's polynomial system (Hong, Ovchinnikov, Pogudin, Yap 2020,
//! Algorithm 1, step 1), on which the Gröbner basis is computed: each state
//! equation with its denominator cleared, `E_s = den_s x_s' - num_s = 0`, and
//! its total derivatives `D^k E_s`; each output `den_y y - num_y = 0` with its
//! Taylor coefficients `y^(j)` the numbers of the point, and its derivatives
//! (Leibniz: `D^j(den y) = sum_l C(j, l) D^l(den) y^(j-l)`); and one
//! `z Q - 1 = 0`, `Q` the product of the distinct denominators at order 0.
//!
//! Its zeros are those of the explicit system of run.rs (where each
//! denominator is a state `z = 1/den`): `z Q = 1` keeps every denominator
//! non-zero at order 0, and `D^k E_s = den_s x_s^(k+1) + (orders <= k)` then
//! fixes `x_s^(k+1)` as the explicit system does, so the jets, hence the
//! counts, are the same. But its degrees are lower (`x3 x4' = ...` is one
//! degree below `x4' = ... z` with `z' = -z^2 x3'`) and it has no `z^(k)`
//! unknowns, which is what makes the bases of rational models small.

use super::run::Run;
use super::types::{err, gb_err, too_large};
use crate::rank::AnalysisError;
use obsan_groebner::Poly;

/// The cleared system's derivatives, computed lazily by order.
#[derive(Default)]
pub(super) struct Cleared {
    /// Per model state: `D^k E_s`, `k = 0, 1, ...`.
    state: Vec<Vec<Poly>>,
    /// Per output: `D^j num_y` and `D^j den_y`.
    num: Vec<Vec<Poly>>,
    den: Vec<Vec<Poly>>,
    /// The product of the distinct non-constant denominators (order 0).
    pub(super) q: Poly,
}

impl Cleared {
    /// Bytes of the derivatives held (`q` aside, as the budget counts them).
    pub(super) fn held_bytes(&self, n: usize) -> usize {
        self.state
            .iter()
            .chain(&self.num)
            .chain(&self.den)
            .flatten()
            .map(|p| p.stored_bytes(n))
            .sum()
    }

    /// From the states' and outputs' `(num, den)` in the derivation ring and
    /// the distinct non-constant denominators.
    pub(super) fn new(
        run: &Run,
        states: &[(Poly, Poly)],
        outputs: &[(Poly, Poly)],
        dens: &[&Poly],
    ) -> Result<Cleared, AnalysisError> {
        let r = &run.ring;
        let mut state = Vec::with_capacity(states.len());
        for (s, (num, den)) in states.iter().enumerate() {
            let dx = r.mul(den, &r.var(run.sv(s, 1))).map_err(gb_err)?;
            state.push(vec![r.sub(&dx, num)]);
        }
        let mut q = r.constant(1);
        for d in dens {
            q = r.mul(&q, d).map_err(gb_err)?;
        }
        Ok(Cleared {
            state,
            num: outputs.iter().map(|(n, _)| vec![n.clone()]).collect(),
            den: outputs.iter().map(|(_, d)| vec![d.clone()]).collect(),
            q,
        })
    }
}

/// `C(j, l)` modulo the field's prime (j is a Taylor order, far below p).
fn binomial(run: &Run, j: usize, l: usize) -> u64 {
    let f = &run.field;
    let mut c = 1u64;
    for i in 0..l {
        c = f.mul(c, f.reduce((j - i) as u64));
        let inv = f.inv(f.reduce((i + 1) as u64)).unwrap_or(0);
        c = f.mul(c, inv);
    }
    c
}

impl Run {
    /// `list` extended by total derivatives to length `len`, each counted
    /// against the memory budget.
    fn extend_derivatives(
        &self,
        list: &mut Vec<Poly>,
        len: usize,
        held: &mut usize,
    ) -> Result<(), AnalysisError> {
        while list.len() < len {
            let last = list.last().cloned().unwrap_or_default();
            let d = self.derive(&last)?;
            *held += d.stored_bytes(self.ring.n);
            if *held > self.max_bytes {
                return Err(too_large(
                    *held as u128,
                    self.max_bytes as u128,
                    &format!(
                        "the Taylor system (derivatives of the cleared equations to order {len}, in {} variables)",
                        self.ring.n
                    ),
                ));
            }
            list.push(d);
        }
        Ok(())
    }

    /// The cleared system of the proven truncation: output `y` up to order
    /// `orders[y]` (inclusive) and `D^(k-1) E_s` for exactly the `x_s^(k)`
    /// those equations use (a closure, from the highest order down: `D^(k-1)
    /// E_s` uses `x_s^(k)` and orders below `k` only). Returns the equations
    /// in the derivation ring (without `z Q - 1`, which the caller adds in
    /// the unknowns' ring) and the unknowns, highest derivatives first,
    /// params last.
    pub(super) fn sian_equations(
        &mut self,
        orders: &[usize],
    ) -> Result<(Vec<Poly>, Vec<usize>), AnalysisError> {
        let top = orders.iter().copied().max().unwrap_or(0);
        // The point's output coefficients come from the explicit system.
        self.prepare(top)?;
        let mut c = std::mem::take(&mut self.cleared);
        let built = self.cleared_equations(&mut c, orders, top);
        self.cleared = c;
        built
    }

    fn cleared_equations(
        &self,
        c: &mut Cleared,
        orders: &[usize],
        top: usize,
    ) -> Result<(Vec<Poly>, Vec<usize>), AnalysisError> {
        let r = &self.ring;
        let f = &self.field;
        // Held beside the explicit system's derivatives (prepare counts
        // those) and the cleared ones of earlier orders.
        let n = r.n;
        let mut held: usize = self
            .rhs_d
            .iter()
            .chain(&self.out_d)
            .chain(&c.state)
            .chain(&c.num)
            .chain(&c.den)
            .flatten()
            .map(|p| p.stored_bytes(n))
            .sum();
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
        let mut eqs = Vec::new();
        for (y, &d) in orders.iter().enumerate() {
            self.extend_derivatives(&mut c.num[y], d + 1, &mut held)?;
            self.extend_derivatives(&mut c.den[y], d + 1, &mut held)?;
            let vals: Vec<u64> = (0..=d)
                .map(|j| r.eval(&self.out_d[y][j], &self.point))
                .collect();
            for j in 0..=d {
                let mut e = r.scale(&c.num[y][j], f.neg(1));
                for l in 0..=j {
                    let k = f.mul(binomial(self, j, l), vals[j - l]);
                    e = r.add(&e, &r.scale(&c.den[y][l], k));
                }
                mark(&e, &mut used);
                eqs.push(e);
            }
        }
        mark(&c.q, &mut used);
        for k in (1..=top).rev() {
            for s in 0..self.nx {
                if used[self.sv(s, k)] {
                    self.extend_derivatives(&mut c.state[s], k, &mut held)?;
                    let e = c.state[s][k - 1].clone();
                    mark(&e, &mut used);
                    eqs.push(e);
                }
            }
        }
        if (1..=top).any(|k| (0..self.nx).any(|s| used[self.sv(s, k)] && c.state[s].len() < k)) {
            return Err(err("global: the cleared system is not closed"));
        }
        let bytes: usize = eqs.iter().map(|p| p.stored_bytes(r.n)).sum();
        if bytes > self.max_bytes {
            return Err(too_large(
                bytes as u128,
                self.max_bytes as u128,
                &format!(
                    "the Taylor system ({} equations to order {top}, in {} variables)",
                    eqs.len(),
                    r.n
                ),
            ));
        }
        let mut unknowns = Vec::new();
        for k in (1..=top).rev() {
            for s in 0..self.nx {
                if used[self.sv(s, k)] {
                    unknowns.push(self.sv(s, k));
                }
            }
        }
        for s in 0..self.nx {
            unknowns.push(self.sv(s, 0));
        }
        unknowns.extend(0..self.np);
        Ok((eqs, unknowns))
    }
}
