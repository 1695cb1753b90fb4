//! Buchberger's algorithm with the sugar strategy (Giovini, Mora, Niesi,
//! Robbiano, Traverso 1991) and the Gebauer–Möller criteria (Gebauer and
//! Möller 1988, in the form of Becker and Weispfenning, "Gröbner Bases",
//! algorithm UPDATE).

use crate::poly::{Mono, Poly, Ring};
use crate::GbError;
use std::cmp::Ordering;
use std::time::Instant;

/// Limits of one computation: past any of them it stops with an error.
#[derive(Clone, Copy, Debug)]
pub struct GbBudget {
    /// Elements added to the basis (before interreduction).
    pub max_basis: usize,
    /// Terms of one polynomial.
    pub max_terms: usize,
    /// S-polynomials reduced.
    pub max_pairs: usize,
    pub deadline: Option<Instant>,
}

impl Default for GbBudget {
    fn default() -> Self {
        GbBudget {
            max_basis: 20_000,
            max_terms: 2_000_000,
            max_pairs: 2_000_000,
            deadline: None,
        }
    }
}

/// A reduced Gröbner basis (monic, sorted by leading monomial, smallest first).
#[derive(Clone, Debug)]
pub struct Basis {
    pub ring: Ring,
    pub polys: Vec<Poly>,
}

struct Pair {
    i: usize,
    j: usize,
    lcm: Mono,
    sugar: u32,
}

struct Work<'a> {
    ring: &'a Ring,
    polys: Vec<Poly>,
    sugar: Vec<u32>,
    /// Leading monomials of `polys`.
    lm: Vec<Mono>,
    /// Members of the current basis (not superseded by a later element).
    active: Vec<bool>,
    pairs: Vec<Pair>,
    budget: GbBudget,
}

impl Work<'_> {
    fn check(&self, p: &Poly) -> Result<(), GbError> {
        if p.len() > self.budget.max_terms {
            return Err(GbError::Budget("terms of a polynomial"));
        }
        if let Some(d) = self.budget.deadline {
            if Instant::now() > d {
                return Err(GbError::Budget("deadline"));
            }
        }
        Ok(())
    }

    fn check_deadline(&self) -> Result<(), GbError> {
        if let Some(d) = self.budget.deadline {
            if Instant::now() > d {
                return Err(GbError::Budget("deadline"));
            }
        }
        Ok(())
    }

    /// Full reduction of `f` by the active elements.
    fn reduce(&self, f: Poly) -> Result<Poly, GbError> {
        let r = self.ring;
        // `rest[start..]` is still to reduce; `done` the irreducible terms.
        let mut rest = f.terms;
        let mut start = 0;
        let mut done: Vec<(Mono, u64)> = Vec::new();
        while start < rest.len() {
            let (m, c) = &rest[start];
            let g = (0..self.polys.len()).find(|&k| self.active[k] && self.lm[k].divides(m));
            match g {
                Some(k) => {
                    let q = self.lm[k].quotient(m);
                    // the active elements are monic
                    let neg = r.field.neg(*c);
                    rest = r.axpy_terms(&rest[start..], neg, &q, &self.polys[k].terms)?;
                    start = 0;
                    if rest.len() > self.budget.max_terms {
                        return Err(GbError::Budget("terms of a polynomial"));
                    }
                    self.check_deadline()?;
                }
                None => {
                    done.push((m.clone(), *c));
                    start += 1;
                }
            }
        }
        Ok(Poly { terms: done })
    }

    fn spoly(&self, p: &Pair) -> Result<Poly, GbError> {
        let r = self.ring;
        let a = &self.polys[p.i];
        let b = &self.polys[p.j];
        let ma = self.lm[p.i].quotient(&p.lcm);
        let mb = self.lm[p.j].quotient(&p.lcm);
        let t = r.axpy(&Poly::zero(), 1, &ma, a)?;
        r.axpy(&t, r.field.neg(1), &mb, b)
    }

    /// Adds a monic `h` with its sugar: Gebauer–Möller UPDATE.
    fn update(&mut self, h: Poly, sugar: u32) -> Result<(), GbError> {
        if self.polys.len() >= self.budget.max_basis {
            return Err(GbError::Budget("basis size"));
        }
        let hi = self.polys.len();
        let lh = match h.leading() {
            Some((m, _)) => m.clone(),
            None => return Ok(()),
        };
        // New pairs (h, g) for active g.
        let mut c: Vec<Pair> = Vec::new();
        for g in 0..hi {
            if !self.active[g] {
                continue;
            }
            let lcm = lh.lcm(&self.lm[g]);
            let s = (sugar + lcm.degree() - lh.degree())
                .max(self.sugar[g] + lcm.degree() - self.lm[g].degree());
            c.push(Pair {
                i: g,
                j: hi,
                lcm,
                sugar: s,
            });
        }
        // Criterion M/F: drop (h, g) if another new pair's lcm divides its lcm
        // (keeping coprime ones for the product criterion below).
        let mut d: Vec<Pair> = Vec::new();
        while let Some(p) = c.pop() {
            let coprime = lh.coprime(&self.lm[p.i]);
            let dominated = c.iter().chain(d.iter()).any(|q| q.lcm.divides(&p.lcm));
            if coprime || !dominated {
                d.push(p);
            }
        }
        // Criterion B on old pairs.
        let old = std::mem::take(&mut self.pairs);
        for p in old {
            let keep = !(lh.divides(&p.lcm)
                && lh.lcm(&self.lm[p.i]) != p.lcm
                && lh.lcm(&self.lm[p.j]) != p.lcm);
            if keep {
                self.pairs.push(p);
            }
        }
        // Product criterion: coprime leading monomials reduce to zero.
        for p in d {
            if !lh.coprime(&self.lm[p.i]) {
                self.pairs.push(p);
            }
        }
        for g in 0..hi {
            if self.active[g] && lh.divides(&self.lm[g]) {
                self.active[g] = false;
            }
        }
        self.polys.push(h);
        self.sugar.push(sugar);
        self.lm.push(lh);
        self.active.push(true);
        Ok(())
    }
}

/// The reduced Gröbner basis of the ideal generated by `gens` in `ring`.
pub fn groebner(ring: &Ring, gens: &[Poly], budget: GbBudget) -> Result<Basis, GbError> {
    let mut w = Work {
        ring,
        polys: Vec::new(),
        sugar: Vec::new(),
        lm: Vec::new(),
        active: Vec::new(),
        pairs: Vec::new(),
        budget,
    };
    // Generators: smallest leading monomial first, each reduced by those before.
    let mut g: Vec<Poly> = gens
        .iter()
        .map(|p| ring.resort(p))
        .filter(|p| !p.is_zero())
        .collect();
    g.sort_by(|a, b| ring.order.cmp(&a.terms[0].0, &b.terms[0].0));
    for p in g {
        let s = p.degree();
        let h = w.reduce(p)?;
        if !h.is_zero() {
            let h = ring.monic(&h);
            if h.terms[0].0.is_one() {
                return Ok(unit(ring));
            }
            w.update(h, s)?;
        }
    }
    let mut reduced = 0usize;
    while !w.pairs.is_empty() {
        // Normal strategy with sugar: smallest sugar, then smallest lcm.
        let mut best = 0;
        for k in 1..w.pairs.len() {
            let (a, b) = (&w.pairs[k], &w.pairs[best]);
            let o = a
                .sugar
                .cmp(&b.sugar)
                .then_with(|| ring.order.cmp(&a.lcm, &b.lcm));
            if o == Ordering::Less {
                best = k;
            }
        }
        let p = w.pairs.swap_remove(best);
        reduced += 1;
        if reduced > budget.max_pairs {
            return Err(GbError::Budget("pairs reduced"));
        }
        let s = w.spoly(&p)?;
        w.check(&s)?;
        let h = w.reduce(s)?;
        if h.is_zero() {
            continue;
        }
        let h = ring.monic(&h);
        if h.terms[0].0.is_one() {
            return Ok(unit(ring));
        }
        w.update(h, p.sugar)?;
    }
    // Reduced basis: the minimal leading monomials, tails reduced.
    let mut keep: Vec<usize> = (0..w.polys.len()).filter(|&k| w.active[k]).collect();
    keep.sort_by(|&a, &b| ring.order.cmp(&w.lm[a], &w.lm[b]));
    let mut out: Vec<Poly> = Vec::with_capacity(keep.len());
    for &k in &keep {
        let (m, c) = w.polys[k].terms[0].clone();
        let tail = Poly {
            terms: w.polys[k].terms[1..].to_vec(),
        };
        let mut t = w.reduce(tail)?;
        t.terms.insert(0, (m, c));
        out.push(t);
    }
    Ok(Basis {
        ring: ring.clone(),
        polys: out,
    })
}

fn unit(ring: &Ring) -> Basis {
    Basis {
        ring: ring.clone(),
        polys: vec![ring.constant(1)],
    }
}

impl Basis {
    /// Whether the ideal is the whole ring (no common zero).
    pub fn is_unit(&self) -> bool {
        self.polys.len() == 1 && self.polys[0].terms[0].0.is_one()
    }

    /// The normal form of `f` (its remainder on division by the basis).
    pub fn reduce(&self, f: &Poly) -> Result<Poly, GbError> {
        let r = &self.ring;
        let mut rest = r.resort(f).terms;
        let mut start = 0;
        let mut done: Vec<(Mono, u64)> = Vec::new();
        while start < rest.len() {
            let (m, c) = &rest[start];
            match self.polys.iter().find(|g| g.terms[0].0.divides(m)) {
                Some(g) => {
                    let q = g.terms[0].0.quotient(m);
                    let neg = r.field.neg(*c);
                    rest = r.axpy_terms(&rest[start..], neg, &q, &g.terms)?;
                    start = 0;
                }
                None => {
                    done.push((m.clone(), *c));
                    start += 1;
                }
            }
        }
        Ok(Poly { terms: done })
    }

    pub fn contains(&self, f: &Poly) -> Result<bool, GbError> {
        Ok(self.reduce(f)?.is_zero())
    }

    pub fn leading_monomials(&self) -> Vec<&Mono> {
        self.polys.iter().map(|p| &p.terms[0].0).collect()
    }
}
