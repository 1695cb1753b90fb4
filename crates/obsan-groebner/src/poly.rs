//! Sparse polynomials over F_p in a fixed number of variables, terms sorted
//! by a monomial order (largest first).

use crate::field::Field;
use crate::GbError;
use std::cmp::Ordering;

/// Largest total degree of a monomial: past it an operation is an error,
/// never a wrapped exponent.
pub const MAX_DEGREE: u32 = 1 << 24;

/// A monomial: one exponent per variable.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub struct Mono {
    deg: u32,
    e: Box<[u32]>,
}

impl Mono {
    pub fn one(n: usize) -> Mono {
        Mono {
            deg: 0,
            e: vec![0; n].into_boxed_slice(),
        }
    }

    /// `x_v^k` in `n` variables.
    pub fn var(n: usize, v: usize, k: u32) -> Mono {
        let mut e = vec![0; n];
        e[v] = k;
        Mono {
            deg: k,
            e: e.into_boxed_slice(),
        }
    }

    pub fn from_exponents(e: Vec<u32>) -> Result<Mono, GbError> {
        let mut deg: u32 = 0;
        for &x in &e {
            deg = deg.checked_add(x).ok_or(GbError::Degree)?;
        }
        if deg > MAX_DEGREE {
            return Err(GbError::Degree);
        }
        Ok(Mono {
            deg,
            e: e.into_boxed_slice(),
        })
    }

    pub fn exponents(&self) -> &[u32] {
        &self.e
    }

    pub fn degree(&self) -> u32 {
        self.deg
    }

    pub fn is_one(&self) -> bool {
        self.deg == 0
    }

    pub fn mul(&self, o: &Mono) -> Result<Mono, GbError> {
        let deg = self.deg + o.deg; // both <= 2^24
        if deg > MAX_DEGREE {
            return Err(GbError::Degree);
        }
        let e: Box<[u32]> = self.e.iter().zip(o.e.iter()).map(|(a, b)| a + b).collect();
        Ok(Mono { deg, e })
    }

    pub fn divides(&self, o: &Mono) -> bool {
        self.deg <= o.deg && self.e.iter().zip(o.e.iter()).all(|(a, b)| a <= b)
    }

    /// `o / self`, assuming `self | o`.
    pub fn quotient(&self, o: &Mono) -> Mono {
        Mono {
            deg: o.deg - self.deg,
            e: o.e.iter().zip(self.e.iter()).map(|(a, b)| a - b).collect(),
        }
    }

    pub fn lcm(&self, o: &Mono) -> Mono {
        let e: Box<[u32]> = self
            .e
            .iter()
            .zip(o.e.iter())
            .map(|(a, b)| *a.max(b))
            .collect();
        Mono {
            deg: e.iter().sum(),
            e,
        }
    }

    /// Whether `lcm(self, o) == l`, without building the lcm (the
    /// Gebauer–Möller update asks this for every old pair).
    pub(crate) fn lcm_is(&self, o: &Mono, l: &Mono) -> bool {
        self.e
            .iter()
            .zip(o.e.iter())
            .zip(l.e.iter())
            .all(|((a, b), c)| *a.max(b) == *c)
    }

    /// A 64-bit summary of the variables present (variable `v` sets bit
    /// `v mod 64`): `a | b` needs `mask(a) & !mask(b) == 0`, a cheap
    /// rejection before [`Mono::divides`].
    pub fn mask(&self) -> u64 {
        let mut m = 0u64;
        for (v, &x) in self.e.iter().enumerate() {
            if x > 0 {
                m |= 1 << (v % 64);
            }
        }
        m
    }

    pub fn coprime(&self, o: &Mono) -> bool {
        self.e
            .iter()
            .zip(o.e.iter())
            .all(|(a, b)| *a == 0 || *b == 0)
    }

    /// The only variable with a non-zero exponent, if exactly one has.
    pub fn pure_power(&self) -> Option<usize> {
        let mut it = self.e.iter().enumerate().filter(|(_, &x)| x > 0);
        match (it.next(), it.next()) {
            (Some((v, _)), None) => Some(v),
            _ => None,
        }
    }
}

/// A monomial order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Graded reverse lexicographic, `x_0 > x_1 > ...`.
    Grevlex,
    /// Elimination order: the first `k` variables by grevlex, then, on ties,
    /// the rest by grevlex. A basis then meets `F_p[x_k, ...]` in a basis of
    /// the elimination ideal.
    Block(usize),
    /// Pure lexicographic, `x_0 > x_1 > ...`.
    Lex,
}

fn grevlex(a: &[u32], b: &[u32]) -> Ordering {
    let da: u64 = a.iter().map(|&x| x as u64).sum();
    let db: u64 = b.iter().map(|&x| x as u64).sum();
    match da.cmp(&db) {
        Ordering::Equal => {}
        o => return o,
    }
    for (x, y) in a.iter().zip(b.iter()).rev() {
        if x != y {
            // The smaller exponent in the last differing variable wins.
            return y.cmp(x);
        }
    }
    Ordering::Equal
}

impl Order {
    pub fn cmp(&self, a: &Mono, b: &Mono) -> Ordering {
        match *self {
            Order::Grevlex => match a.deg.cmp(&b.deg) {
                Ordering::Equal => {
                    for (x, y) in a.e.iter().zip(b.e.iter()).rev() {
                        if x != y {
                            return y.cmp(x);
                        }
                    }
                    Ordering::Equal
                }
                o => o,
            },
            Order::Block(k) => match grevlex(&a.e[..k], &b.e[..k]) {
                Ordering::Equal => grevlex(&a.e[k..], &b.e[k..]),
                o => o,
            },
            Order::Lex => a.e.cmp(&b.e),
        }
    }
}

/// A polynomial: terms with non-zero coefficients, largest monomial first.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Poly {
    pub(crate) terms: Vec<(Mono, u64)>,
}

impl Poly {
    pub fn zero() -> Poly {
        Poly { terms: Vec::new() }
    }

    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    pub fn terms(&self) -> &[(Mono, u64)] {
        &self.terms
    }

    pub fn len(&self) -> usize {
        self.terms.len()
    }

    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    pub fn leading(&self) -> Option<&(Mono, u64)> {
        self.terms.first()
    }

    /// Total degree (0 for the zero polynomial).
    pub fn degree(&self) -> u32 {
        self.terms.iter().map(|(m, _)| m.deg).max().unwrap_or(0)
    }
}

/// The ring F_p[x_0, ..., x_{n-1}] with a monomial order: every polynomial
/// operation goes through it.
#[derive(Clone, Debug)]
pub struct Ring {
    pub field: Field,
    pub n: usize,
    pub order: Order,
}

impl Ring {
    pub fn new(field: Field, n: usize, order: Order) -> Ring {
        Ring { field, n, order }
    }

    /// The same polynomials under another order (terms re-sorted).
    pub fn with_order(&self, order: Order) -> Ring {
        Ring {
            field: self.field,
            n: self.n,
            order,
        }
    }

    /// Builds a polynomial from any terms (reduces coefficients, merges
    /// equal monomials, drops zeros, sorts).
    pub fn from_terms(&self, terms: impl IntoIterator<Item = (Mono, u64)>) -> Poly {
        let mut t: Vec<(Mono, u64)> = terms
            .into_iter()
            .map(|(m, c)| (m, self.field.reduce(c)))
            .collect();
        t.sort_by(|a, b| self.order.cmp(&b.0, &a.0));
        let mut out: Vec<(Mono, u64)> = Vec::with_capacity(t.len());
        for (m, c) in t {
            match out.last_mut() {
                Some((lm, lc)) if *lm == m => *lc = self.field.add(*lc, c),
                _ => out.push((m, c)),
            }
        }
        out.retain(|(_, c)| *c != 0);
        Poly { terms: out }
    }

    pub fn constant(&self, c: u64) -> Poly {
        self.from_terms([(Mono::one(self.n), c)])
    }

    pub fn var(&self, v: usize) -> Poly {
        self.from_terms([(Mono::var(self.n, v, 1), 1)])
    }

    /// Re-sorts a polynomial built under another order.
    pub fn resort(&self, p: &Poly) -> Poly {
        let mut t = p.terms.clone();
        t.sort_by(|a, b| self.order.cmp(&b.0, &a.0));
        Poly { terms: t }
    }

    pub fn add(&self, a: &Poly, b: &Poly) -> Poly {
        self.axpy(a, 1, &Mono::one(self.n), b)
            .unwrap_or_else(|_| unreachable_degree())
    }

    pub fn sub(&self, a: &Poly, b: &Poly) -> Poly {
        self.axpy(a, self.field.neg(1), &Mono::one(self.n), b)
            .unwrap_or_else(|_| unreachable_degree())
    }

    pub fn scale(&self, a: &Poly, c: u64) -> Poly {
        let c = self.field.reduce(c);
        if c == 0 {
            return Poly::zero();
        }
        Poly {
            terms: a
                .terms
                .iter()
                .map(|(m, x)| (m.clone(), self.field.mul(*x, c)))
                .collect(),
        }
    }

    /// `a + c * m * b` by one merge (a monomial order is compatible with
    /// multiplication, so `m * b` stays sorted).
    pub fn axpy(&self, a: &Poly, c: u64, m: &Mono, b: &Poly) -> Result<Poly, GbError> {
        Ok(Poly {
            terms: self.axpy_terms(&a.terms, c, m, &b.terms)?,
        })
    }

    /// [`Ring::axpy`] on sorted term slices.
    pub(crate) fn axpy_terms(
        &self,
        a: &[(Mono, u64)],
        c: u64,
        m: &Mono,
        b: &[(Mono, u64)],
    ) -> Result<Vec<(Mono, u64)>, GbError> {
        let f = &self.field;
        let mut out = Vec::with_capacity(a.len() + b.len());
        let mut i = 0;
        let mut j = 0;
        let mut bj: Option<(Mono, u64)> = None;
        loop {
            if bj.is_none() && j < b.len() {
                let (bm, bc) = &b[j];
                bj = Some((m.mul(bm)?, f.mul(c, *bc)));
                j += 1;
            }
            match (a.get(i), bj.take()) {
                (None, None) => break,
                (Some(t), None) => {
                    out.push(t.clone());
                    i += 1;
                }
                (None, Some(t)) => {
                    if t.1 != 0 {
                        out.push(t);
                    }
                }
                (Some(ta), Some(tb)) => match self.order.cmp(&ta.0, &tb.0) {
                    Ordering::Greater => {
                        out.push(ta.clone());
                        i += 1;
                        bj = Some(tb);
                    }
                    Ordering::Less => {
                        if tb.1 != 0 {
                            out.push(tb);
                        }
                    }
                    Ordering::Equal => {
                        let s = f.add(ta.1, tb.1);
                        if s != 0 {
                            out.push((tb.0, s));
                        }
                        i += 1;
                    }
                },
            }
        }
        Ok(out)
    }

    /// The product, by halves of the shorter factor: one term of `a` times
    /// `b` is one merge into the running sum, so a term-by-term loop over
    /// the longer factor costs `|a|` merges of a growing sum (quadratic in
    /// `|a|` even for `b` a single variable, as a total derivative's
    /// `dp/dv * v'`: 98 % of the Taylor route's time on calib.sys). Halving
    /// instead costs `O(|a| |b| log |a|)` term moves.
    pub fn mul(&self, a: &Poly, b: &Poly) -> Result<Poly, GbError> {
        let (a, b) = if a.terms.len() <= b.terms.len() {
            (a, b)
        } else {
            (b, a)
        };
        self.mul_terms(&a.terms, b)
    }

    /// `sum(a) * b`, `a` a run of sorted terms.
    fn mul_terms(&self, a: &[(Mono, u64)], b: &Poly) -> Result<Poly, GbError> {
        /// Below this many terms, one merge per term of `a`.
        const BY_TERM: usize = 8;
        if a.len() <= BY_TERM {
            let mut acc = Poly::zero();
            for (m, c) in a {
                acc = self.axpy(&acc, *c, m, b)?;
            }
            return Ok(acc);
        }
        let (lo, hi) = a.split_at(a.len() / 2);
        let lo = self.mul_terms(lo, b)?;
        let hi = self.mul_terms(hi, b)?;
        Ok(self.add(&lo, &hi))
    }

    pub fn pow(&self, a: &Poly, mut e: u32) -> Result<Poly, GbError> {
        let mut r = self.constant(1);
        let mut b = a.clone();
        while e > 0 {
            if e & 1 == 1 {
                r = self.mul(&r, &b)?;
            }
            e >>= 1;
            if e > 0 {
                b = self.mul(&b, &b)?;
            }
        }
        Ok(r)
    }

    /// The polynomial made monic (zero stays zero).
    pub fn monic(&self, a: &Poly) -> Poly {
        match a.terms.first() {
            None => Poly::zero(),
            Some((_, c)) => match self.field.inv(*c) {
                Some(ci) => self.scale(a, ci),
                None => Poly::zero(),
            },
        }
    }

    /// The value at a point (one value per variable).
    pub fn eval(&self, a: &Poly, x: &[u64]) -> u64 {
        let f = &self.field;
        let mut s = 0;
        for (m, c) in &a.terms {
            let mut t = *c;
            for (v, &e) in m.e.iter().enumerate() {
                if e > 0 {
                    t = f.mul(t, f.pow(x[v], e as u64));
                }
            }
            s = f.add(s, t);
        }
        s
    }

    /// `d a / d x_v`.
    pub fn derivative(&self, a: &Poly, v: usize) -> Poly {
        let f = &self.field;
        let terms = a.terms.iter().filter(|(m, _)| m.e[v] > 0).map(|(m, c)| {
            let k = m.e[v];
            let mut e = m.e.clone();
            e[v] -= 1;
            (Mono { deg: m.deg - 1, e }, f.mul(*c, f.reduce(k as u64)))
        });
        self.from_terms(terms.collect::<Vec<_>>())
    }

    /// Substitutes values for some variables (`None` keeps the variable).
    pub fn substitute(&self, a: &Poly, vals: &[Option<u64>]) -> Poly {
        let f = &self.field;
        let terms: Vec<(Mono, u64)> = a
            .terms
            .iter()
            .map(|(m, c)| {
                let mut c = *c;
                let mut e = m.e.clone();
                for (v, val) in vals.iter().enumerate() {
                    if let Some(x) = val {
                        if e[v] > 0 {
                            c = f.mul(c, f.pow(*x, e[v] as u64));
                            e[v] = 0;
                        }
                    }
                }
                let deg = e.iter().sum();
                (Mono { deg, e }, c)
            })
            .collect();
        self.from_terms(terms)
    }

    /// Whether only variables in `vars` occur.
    pub fn only_in(&self, a: &Poly, vars: &[usize]) -> bool {
        a.terms.iter().all(|(m, _)| {
            m.e.iter()
                .enumerate()
                .all(|(v, &e)| e == 0 || vars.contains(&v))
        })
    }
}

#[cold]
fn unreachable_degree() -> Poly {
    // add/sub multiply by the monomial 1, which never raises a degree.
    Poly::zero()
}

#[cfg(test)]
mod tests {
    use super::Mono;

    fn m(e: &[u32]) -> Mono {
        Mono::from_exponents(e.to_vec()).unwrap()
    }

    /// By hand: lcm(x^2 y, y^3 z) = x^2 y^3 z; neither x^2 y^2 z nor
    /// x^2 y^3 z^2 is that lcm, though the second is a common multiple.
    #[test]
    fn lcm_is_matches_the_exponentwise_maximum() {
        let (a, b) = (m(&[2, 1, 0]), m(&[0, 3, 1]));
        assert!(a.lcm_is(&b, &m(&[2, 3, 1])));
        assert!(!a.lcm_is(&b, &m(&[2, 2, 1])));
        assert!(!a.lcm_is(&b, &m(&[2, 3, 2])));
        assert_eq!(a.lcm(&b), m(&[2, 3, 1]));
    }
}
