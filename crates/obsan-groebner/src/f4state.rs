//! F4's state (`f4.rs`): the basis so far as monomial ids of one
//! [`Table`] and coefficients, its critical pairs, and their Gebauer–Möller
//! update.

use crate::gb::{elem_slot_bytes, GbBudget, Work};
use crate::mem::{block, over, poly_bytes};
use crate::poly::{Poly, Ring};
use crate::table::{Exp, Table};
use crate::GbError;
use std::mem::size_of;
use std::time::Instant;

/// A critical pair: elements `i < j` and their lcm's id in the basis table.
#[derive(Clone, Copy)]
pub(crate) struct Pair {
    pub(crate) i: u32,
    pub(crate) j: u32,
    pub(crate) lcm: u32,
    pub(crate) sugar: u32,
}

/// An element: monomial ids of the basis table (leading first), coefficients.
pub(crate) struct Elem {
    pub(crate) ids: Vec<u32>,
    pub(crate) cfs: Vec<u64>,
}

/// F4's state: the basis so far (in the basis table), its pairs, the limits.
pub(crate) struct St<'a> {
    pub(crate) ring: &'a Ring,
    pub(crate) budget: GbBudget,
    pub(crate) t: Table,
    pub(crate) el: Vec<Elem>,
    pub(crate) sugar: Vec<u32>,
    pub(crate) active: Vec<bool>,
    pub(crate) pairs: Vec<Pair>,
    /// Bytes of the elements and their slots; the pairs and the table are
    /// counted by [`St::held`].
    elem_bytes: usize,
    /// Multiply-adds of the eliminations so far (`GbBudget::max_work`).
    pub(crate) work: std::cell::Cell<u64>,
}

/// Bytes of an element of `len` terms and its slots (the `Elem`, its sugar
/// and active flag): 12 bytes a term, against a `Poly`'s 32 + 4 n.
pub(crate) fn elem_bytes(len: usize) -> usize {
    size_of::<Elem>() + block(4 * len) + block(8 * len) + 4 + 1
}

impl<'a> St<'a> {
    /// Bytes held by the basis, its pairs and its table.
    pub(crate) fn held(&self) -> usize {
        self.elem_bytes + self.pairs.len() * size_of::<Pair>() + self.t.bytes()
    }

    /// Refuses `extra` more bytes past the budget (`what` names the stage).
    pub(crate) fn room(&self, extra: usize, what: impl FnOnce() -> String) -> Result<(), GbError> {
        let need = self.held() + extra;
        if need > self.budget.max_bytes {
            return Err(over(need, self.budget.max_bytes, what));
        }
        Ok(())
    }

    pub(crate) fn check(&self, len: usize) -> Result<(), GbError> {
        if len > self.budget.max_terms {
            return Err(GbError::Budget("terms of a polynomial"));
        }
        if let Some(d) = self.budget.deadline {
            if Instant::now() > d {
                return Err(GbError::Budget("deadline"));
            }
        }
        Ok(())
    }

    /// The work of `gb.rs`'s [`start`] in the table's terms.
    pub(crate) fn from_work(w: Work<'a>) -> Result<St<'a>, GbError> {
        let ring = w.ring;
        let mut s = St {
            ring,
            budget: w.budget,
            t: Table::new(ring.n, crate::table::weights(ring.n)),
            el: Vec::new(),
            sugar: w.sugar.clone(),
            active: w.active.clone(),
            pairs: Vec::new(),
            elem_bytes: 0,
            work: std::cell::Cell::new(0),
        };
        let base = w.held();
        let what = || "the Groebner basis (its generators in the F4 table)".to_string();
        for p in &w.polys {
            s.room(base + elem_bytes(p.len()), what)?;
            let mut ids = Vec::with_capacity(p.len());
            for (m, _) in p.terms() {
                let extra = base + s.held();
                let max = s.budget.max_bytes;
                ids.push(s.t.insert_mono(m, |g| {
                    if extra + g > max {
                        return Err(over(extra + g, max, what));
                    }
                    Ok(())
                })?);
            }
            s.elem_bytes += elem_bytes(p.len());
            s.el.push(Elem {
                ids,
                cfs: p.terms().iter().map(|t| t.1).collect(),
            });
        }
        for p in &w.pairs {
            let extra = base + s.held() + size_of::<Pair>();
            let max = s.budget.max_bytes;
            let lcm = s.t.insert_mono(&p.lcm, |g| {
                if extra + g > max {
                    return Err(over(extra + g, max, what));
                }
                Ok(())
            })?;
            s.pairs.push(Pair {
                i: p.i as u32,
                j: p.j as u32,
                lcm,
                sugar: p.sugar,
            });
        }
        s.elem_bytes += s.el.len() * (size_of::<u32>() + 1);
        Ok(s)
    }

    fn lm(&self, k: usize) -> u32 {
        self.el[k].ids[0]
    }

    /// Adds a monic element with its sugar: Gebauer–Möller UPDATE (Becker
    /// and Weispfenning), as `gb.rs`'s `Work::update`, on table ids.
    pub(crate) fn update(&mut self, h: Elem, sugar: u32) -> Result<(), GbError> {
        let hi = self.el.len();
        if hi >= self.budget.max_basis {
            return Err(GbError::Budget("basis size"));
        }
        let n = self.ring.n;
        let lh = h.ids[0];
        // The new element, at most one new pair per active element beside
        // the old ones until criterion B has run, and the candidates' lcms
        // (exponents, degree, mask) before the kept ones enter the table.
        let grow = elem_bytes(h.ids.len());
        let cand = 2 * n + 4 + 8;
        let extra = grow + hi * (2 * size_of::<Pair>() + cand);
        self.room(extra, || {
            format!(
                "the Groebner basis ({} elements, {} critical pairs, {} variables)",
                hi + 1,
                self.pairs.len() + hi,
                n
            )
        })?;
        let t = &self.t;
        let eh = t.exps(lh).to_vec();
        // New pairs (h, g) for active g: lcm exponents in `le`.
        let mut le: Vec<Exp> = Vec::with_capacity(hi * n);
        let mut c: Vec<(u32, u32, u64, u32)> = Vec::with_capacity(hi); // g, degree, mask, sugar
        for g in 0..hi {
            if !self.active[g] {
                continue;
            }
            let lg = self.lm(g);
            let k = c.len();
            le.extend(eh.iter().zip(t.exps(lg)).map(|(a, b)| *a.max(b)));
            let e = &le[k * n..];
            let d: u32 = e.iter().map(|&x| x as u32).sum();
            let mut m = 0u64;
            for (v, &x) in e.iter().enumerate() {
                if x > 0 {
                    m |= 1 << (v % 64);
                }
            }
            let s = (sugar + d - t.deg(lh)).max(self.sugar[g] + d - t.deg(lg));
            c.push((g as u32, d, m, s));
        }
        let lce = |k: usize| &le[k * n..(k + 1) * n];
        let coprime = |a: &[Exp], b: &[Exp]| a.iter().zip(b).all(|(x, y)| *x == 0 || *y == 0);
        let divides = |a: &[Exp], b: &[Exp]| a.iter().zip(b).all(|(x, y)| x <= y);
        // Criterion M/F (see gb.rs): by ascending lcm degree, a candidate is
        // compared with the ones kept before it.
        let mut order: Vec<usize> = (0..c.len()).collect();
        order.sort_by_key(|&k| c[k].1);
        let mut d: Vec<usize> = Vec::new();
        for k in order {
            let cop = coprime(&eh, t.exps(self.lm(c[k].0 as usize)));
            let dominated = d
                .iter()
                .any(|&q| c[q].2 & !c[k].2 == 0 && divides(lce(q), lce(k)));
            if cop || !dominated {
                d.push(k);
            }
        }
        // Criterion B on old pairs.
        let hm = t.mask(lh);
        let lcm_is = |a: &[Exp], b: &[Exp], l: &[Exp]| {
            a.iter().zip(b).zip(l).all(|((x, y), z)| *x.max(y) == *z)
        };
        let old = std::mem::take(&mut self.pairs);
        for p in old {
            let l = t.exps(p.lcm);
            let dropped = hm & !t.mask(p.lcm) == 0
                && divides(&eh, l)
                && !lcm_is(&eh, t.exps(self.lm(p.i as usize)), l)
                && !lcm_is(&eh, t.exps(self.lm(p.j as usize)), l);
            if !dropped {
                self.pairs.push(p);
            }
        }
        // Product criterion: coprime leading monomials reduce to zero.
        for k in d {
            let (g, deg, _, s) = c[k];
            if coprime(&eh, self.t.exps(self.lm(g as usize))) {
                continue;
            }
            let e = lce(k);
            let hash = self.t.hash_of(e);
            let base = self.held() + extra;
            let max = self.budget.max_bytes;
            let lcm = self.t.insert(e, deg, hash, |g| {
                if base + g > max {
                    return Err(over(base + g, max, || {
                        format!("the Groebner basis (a table of {hi} elements' pairs)")
                    }));
                }
                Ok(())
            })?;
            self.pairs.push(Pair {
                i: g,
                j: hi as u32,
                lcm,
                sugar: s,
            });
        }
        for g in 0..hi {
            if self.active[g] && self.t.divides(lh, &self.t, self.lm(g)) {
                self.active[g] = false;
            }
        }
        self.el.push(h);
        self.sugar.push(sugar);
        self.active.push(true);
        self.elem_bytes += grow;
        Ok(())
    }

    /// The active elements as `Poly`s with their sugars (the table's bytes
    /// are released by the caller; the polynomials are counted first).
    pub(crate) fn into_polys(self) -> Result<(Vec<Poly>, Vec<u32>), GbError> {
        let n = self.ring.n;
        let keep: Vec<usize> = (0..self.el.len()).filter(|&k| self.active[k]).collect();
        let need: usize = self.held()
            + keep
                .iter()
                .map(|&k| poly_bytes(self.el[k].ids.len(), n) + elem_slot_bytes(n))
                .sum::<usize>();
        if need > self.budget.max_bytes {
            return Err(over(need, self.budget.max_bytes, || {
                format!(
                    "the Groebner basis (its {} elements as polynomials)",
                    keep.len()
                )
            }));
        }
        let mut polys = Vec::with_capacity(keep.len());
        for &k in &keep {
            let e = &self.el[k];
            let mut terms = Vec::with_capacity(e.ids.len());
            for (&id, &c) in e.ids.iter().zip(&e.cfs) {
                terms.push((self.t.mono(id)?, c));
            }
            polys.push(Poly { terms });
        }
        let sugar = keep.iter().map(|&k| self.sugar[k]).collect();
        Ok((polys, sugar))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layout the byte counts assume: a pair is four u32s; a term of an
    /// element a u32 id and a u64 coefficient in two exact-length buffers
    /// (4 + 8 bytes, plus at most one 16-byte chunk rounding each).
    #[test]
    fn pairs_and_terms_are_packed() {
        assert_eq!(size_of::<Pair>(), 16);
        let per = elem_bytes(1000) - elem_bytes(0);
        assert!((12_000..=12_032).contains(&per), "{per}");
    }
}
