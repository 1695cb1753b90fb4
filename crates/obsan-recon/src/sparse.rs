//! Sparse interpolation of a vector of polynomials sharing one black box
//! (Ben-Or & Tiwari 1988, with early termination: Kaltofen & Lee 2003).
//!
//! Modulo the first prime `p0` the points are `theta_k = (r_1 a_1^k, ...,
//! r_n a_n^k)`, `r_i` random non-zero (so the sequence does not start at the
//! special point `(1, ..., 1)`). For a polynomial `f = sum_j c_j x^{e_j}`
//! the values `v_k = f(theta_k) = sum_j (c_j r^{e_j}) (a^{e_j})^k` form a
//! linearly recurrent sequence whose minimal polynomial (Berlekamp–Massey)
//! has the roots `m_j = a^{e_j} mod p0`; one transposed Vandermonde system
//! gives the weights `c_j r^{e_j}`. The exponents are read in one of two
//! ways:
//! - when every monomial allowed by the degree bounds has `q^e < p0` for
//!   small distinct primes `q_i`, the ratios are `a_i = q_i`: the integer
//!   value of a root is `q^e` itself, and trial division gives `e`;
//! - otherwise the `a_i` are random and, per variable `i`, one more
//!   sequence with `r_i` scaled by a random `c` has the same roots and
//!   weights multiplied by `c^{e_ij}` (shifted sequences, `n T` more
//!   points, [`shifted_exponents`]).
//!
//! Later primes know the supports: `T` shared points each (random geometric
//! progressions), one transposed Vandermonde system per component, then
//! Chinese remaindering and rational reconstruction as [`crate::reconstruct_vec`]
//! does, and the same check at fresh points modulo a prime never used.
//!
//! Anything that does not fit a polynomial within the bounds (a linear
//! complexity above the terms' bound, a minimal polynomial that does not
//! split into distinct linear factors over F_p0, a root that is not a
//! monomial within the bounds, a failed verification) gives
//! `Ok(None)`: the caller falls back to the rational reconstruction.

use crate::field::{add, inv, mul, pow, sub, Rem128, Shoup, MAX_RECON_PRIMES};
use crate::multi::{call, Budget, Image, Terms};
use crate::rng::Rng;
use crate::{verify, Acc, Limit, Options, ReconError, Reconstruction};

/// Early termination of Berlekamp–Massey: a component's sequence is taken as
/// complete once `N >= 2 L + EARLY_TERMINATION` terms were read with linear
/// complexity `L` (the last `EARLY_TERMINATION` discrepancies were zero,
/// since any non-zero one past `2 L` raises `L`). A false stop needs that
/// many zero discrepancies by accident (probability about `T deg / p` each,
/// Kaltofen & Lee 2003) and is caught by the verification anyway.
pub const EARLY_TERMINATION: usize = 3;

/// Fresh random starts `r` after a bad point (a black-box hole breaks the
/// geometric sequence), or after coinciding nodes modulo a later prime.
const RESTARTS: usize = 3;

/// Degree bounds of the polynomials to interpolate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DegreeBounds {
    /// Per variable, the largest exponent of any component.
    pub per_var: Vec<u32>,
    /// The largest total degree, when known (tightens the check that every
    /// allowed monomial value `q^e` stays below the first prime).
    pub total: Option<u32>,
}

impl DegreeBounds {
    /// How many monomials these bounds allow (saturating): an upper bound
    /// on a polynomial's terms, and so on the points its interpolation takes.
    pub fn monomials(&self) -> usize {
        monomials_within(self)
    }
}

/// The first `n` primes 2, 3, 5, ...
fn small_primes(n: usize) -> Vec<u64> {
    let mut out: Vec<u64> = Vec::with_capacity(n);
    let mut c = 2u64;
    while out.len() < n {
        if out
            .iter()
            .take_while(|&&q| q * q <= c)
            .all(|&q| !c.is_multiple_of(q))
        {
            out.push(c);
        }
        c += 1;
    }
    out
}

/// Per variable its prime `q_i`: the smallest primes go to the variables of
/// largest degree bound (this minimises the largest monomial value, by the
/// rearrangement inequality, when only per-variable bounds are known).
fn assign_primes(bounds: &[u32]) -> Vec<u64> {
    let primes = small_primes(bounds.len());
    let mut order: Vec<usize> = (0..bounds.len()).collect();
    order.sort_by(|&a, &b| bounds[b].cmp(&bounds[a]).then(a.cmp(&b)));
    let mut q = vec![0u64; bounds.len()];
    for (rank, &v) in order.iter().enumerate() {
        q[v] = primes[rank];
    }
    q
}

/// The largest `q^e` over the exponents allowed by the bounds, if below
/// `limit` (`None` otherwise): the greedy choice (largest primes first,
/// each up to its bound, within the total) is the maximum, every unit of
/// degree adding `log q_i`.
fn largest_monomial_value(q: &[u64], b: &DegreeBounds, limit: u64) -> Option<u64> {
    let mut order: Vec<usize> = (0..q.len()).collect();
    order.sort_by(|&a, &c| q[c].cmp(&q[a]));
    let mut left = b
        .total
        .unwrap_or(u32::MAX)
        .min(b.per_var.iter().fold(0u32, |s, &d| s.saturating_add(d)));
    let mut v: u128 = 1;
    for &i in &order {
        let e = b.per_var[i].min(left);
        left -= e;
        for _ in 0..e {
            v = v.checked_mul(u128::from(q[i]))?;
            if v >= u128::from(limit) {
                return None;
            }
        }
    }
    Some(v as u64)
}

/// How many monomials the bounds allow (saturating).
fn monomials_within(b: &DegreeBounds) -> usize {
    let total = b
        .total
        .unwrap_or(u32::MAX)
        .min(b.per_var.iter().fold(0u32, |s, &d| s.saturating_add(d))) as usize;
    // counts[s]: exponent vectors so far of total degree s.
    let mut counts = vec![0usize; total + 1];
    counts[0] = 1;
    for &d in &b.per_var {
        let mut next = vec![0usize; total + 1];
        for (s, &c) in counts.iter().enumerate() {
            if c == 0 {
                continue;
            }
            for e in 0..=(d as usize).min(total - s) {
                next[s + e] = next[s + e].saturating_add(c);
            }
        }
        counts = next;
    }
    counts.iter().fold(0usize, |s, &c| s.saturating_add(c))
}

/// Berlekamp–Massey over F_p, one term at a time (Massey 1969).
struct Bm {
    p: u64,
    /// Connection polynomial `C(z) = 1 + c_1 z + ... + c_L z^L`.
    c: Vec<u64>,
    b: Vec<u64>,
    l: usize,
    shift: usize,
    bd: u64,
    seq: Vec<u64>,
}

impl Bm {
    fn new(p: u64) -> Bm {
        Bm {
            p,
            c: vec![1],
            b: vec![1],
            l: 0,
            shift: 1,
            bd: 1,
            seq: Vec::new(),
        }
    }

    /// True once early termination holds.
    fn done(&self) -> bool {
        self.seq.len() >= 2 * self.l + EARLY_TERMINATION
    }

    fn push(&mut self, v: u64) {
        let p = self.p;
        self.seq.push(v);
        let n = self.seq.len() - 1;
        let mut d = v;
        for i in 1..=self.l.min(self.c.len() - 1) {
            d = add(d, mul(self.c[i], self.seq[n - i], p), p);
        }
        if d == 0 {
            self.shift += 1;
            return;
        }
        let Some(ib) = inv(self.bd, p) else {
            return;
        };
        let coef = Shoup::new(mul(d, ib, p), p);
        let old = self.c.clone();
        if self.c.len() < self.b.len() + self.shift {
            self.c.resize(self.b.len() + self.shift, 0);
        }
        for (i, &bi) in self.b.iter().enumerate() {
            let k = i + self.shift;
            self.c[k] = sub(self.c[k], coef.times(bi), p);
        }
        if 2 * self.l <= n {
            self.l = n + 1 - self.l;
            self.b = old;
            self.bd = d;
            self.shift = 1;
        } else {
            self.shift += 1;
        }
    }

    /// The monic characteristic polynomial `z^L C(1/z)`, lowest degree
    /// first.
    fn characteristic(&self) -> Vec<u64> {
        let mut c = self.c.clone();
        c.resize(self.l + 1, 0);
        c.reverse();
        c
    }
}

// Univariate polynomials over F_p, lowest degree first, no trailing zeros
// (the zero polynomial is empty).

fn trim(a: &mut Vec<u64>) {
    while a.last() == Some(&0) {
        a.pop();
    }
}

/// Products of residues summed in `u128`, reduced every `chunk` terms.
fn chunk_for(p: u64) -> usize {
    if p < 1 << 62 {
        15
    } else {
        3
    }
}

fn poly_mul(a: &[u64], b: &[u64], p: u64, rem: Rem128) -> Vec<u64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let chunk = chunk_for(p);
    let mut out = vec![0u64; a.len() + b.len() - 1];
    for (k, o) in out.iter_mut().enumerate() {
        let lo = k.saturating_sub(b.len() - 1);
        let hi = k.min(a.len() - 1);
        let (mut acc, mut cnt, mut res) = (0u128, 0usize, 0u64);
        for i in lo..=hi {
            acc += u128::from(a[i]) * u128::from(b[k - i]);
            cnt += 1;
            if cnt == chunk {
                res = add(res, rem.reduce(acc), p);
                acc = 0;
                cnt = 0;
            }
        }
        *o = add(res, rem.reduce(acc), p);
    }
    trim(&mut out);
    out
}

/// `a mod f`, `f` monic of degree >= 1.
fn poly_rem_monic(mut a: Vec<u64>, f: &[u64], p: u64) -> Vec<u64> {
    let d = f.len() - 1;
    while a.len() > d {
        let Some(&c) = a.last() else { break };
        let top = a.len() - 1;
        if c != 0 {
            let s = Shoup::new(c, p);
            for (j, &fj) in f[..d].iter().enumerate() {
                let k = top - d + j;
                a[k] = sub(a[k], s.times(fj), p);
            }
        }
        a.pop();
    }
    trim(&mut a);
    a
}

/// Monic `a` (non-zero).
fn monic(a: &mut [u64], p: u64) {
    if let Some(&lc) = a.last() {
        if let Some(il) = inv(lc, p) {
            let s = Shoup::new(il, p);
            for x in a.iter_mut() {
                *x = s.times(*x);
            }
        }
    }
}

/// `a mod b` for any non-zero `b`.
fn poly_rem(a: Vec<u64>, b: &[u64], p: u64) -> Vec<u64> {
    let mut bm = b.to_vec();
    monic(&mut bm, p);
    poly_rem_monic(a, &bm, p)
}

/// The monic gcd.
fn poly_gcd(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let (mut x, mut y) = (a.to_vec(), b.to_vec());
    trim(&mut x);
    trim(&mut y);
    while !y.is_empty() {
        let r = poly_rem(x, &y, p);
        x = y;
        y = r;
    }
    monic(&mut x, p);
    x
}

/// Exact quotient `a / b`, `b` monic dividing `a`.
fn poly_div_monic(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let d = b.len() - 1;
    if a.len() < b.len() {
        return Vec::new();
    }
    let mut r = a.to_vec();
    let mut q = vec![0u64; a.len() - d];
    for i in (0..q.len()).rev() {
        let c = r[i + d];
        q[i] = c;
        if c != 0 {
            let s = Shoup::new(c, p);
            for (j, &bj) in b.iter().enumerate() {
                r[i + j] = sub(r[i + j], s.times(bj), p);
            }
        }
    }
    trim(&mut q);
    q
}

/// `base^e mod f`, `f` monic.
fn poly_pow_mod(base: &[u64], mut e: u64, f: &[u64], p: u64, rem: Rem128) -> Vec<u64> {
    let mut result = vec![1u64];
    let mut b = poly_rem_monic(base.to_vec(), f, p);
    while e > 0 {
        if e & 1 == 1 {
            result = poly_rem_monic(poly_mul(&result, &b, p, rem), f, p);
        }
        e >>= 1;
        if e > 0 {
            b = poly_rem_monic(poly_mul(&b, &b, p, rem), f, p);
        }
    }
    result
}

fn eval(a: &[u64], x: u64, p: u64) -> u64 {
    let s = Shoup::new(x % p, p);
    a.iter().rev().fold(0u64, |acc, &c| add(s.times(acc), c, p))
}

/// Divides `a` by `z - x` (synthetic division); the remainder is `a(x)`.
fn deflate(a: &[u64], x: u64, p: u64) -> (Vec<u64>, u64) {
    if a.is_empty() {
        return (Vec::new(), 0);
    }
    let s = Shoup::new(x, p);
    let mut q = vec![0u64; a.len() - 1];
    let mut carry = 0u64;
    for i in (0..a.len()).rev() {
        let v = add(a[i], s.times(carry), p);
        if i == 0 {
            return (q, v);
        }
        q[i - 1] = v;
        carry = v;
    }
    (q, carry)
}

/// The roots of the monic `f` when it is a product of distinct linear
/// factors over F_p (`None` otherwise). Roots in `known` are tried first
/// (the components share most of their monomials), the rest by
/// `gcd(z^p - z, f)` and equal-degree splitting (Cantor–Zassenhaus).
fn split_roots(f: &[u64], p: u64, known: &[u64], rng: &mut Rng) -> Option<Vec<u64>> {
    let rem = Rem128::new(p);
    let mut g = f.to_vec();
    let mut roots = Vec::with_capacity(f.len().saturating_sub(1));
    for &x in known {
        if g.len() <= 1 {
            break;
        }
        let (q, r) = deflate(&g, x, p);
        if r == 0 {
            // A repeated root is not a sparse polynomial's.
            if eval(&q, x, p) == 0 {
                return None;
            }
            roots.push(x);
            g = q;
        }
    }
    if g.len() <= 1 {
        return Some(roots);
    }
    // z^p - z mod g: all of g's roots must be in F_p and distinct.
    let zp = poly_pow_mod(&[0, 1], p, &g, p, rem);
    let mut zpz = zp;
    if zpz.len() < 2 {
        zpz.resize(2, 0);
    }
    zpz[1] = sub(zpz[1], 1, p);
    trim(&mut zpz);
    let h = poly_gcd(&g, &zpz, p);
    if h.len() != g.len() {
        return None;
    }
    let mut stack = vec![g];
    let mut tries = 0;
    while let Some(h) = stack.pop() {
        match h.len() {
            0 | 1 => continue,
            2 => {
                roots.push(sub(0, h[0], p));
                continue;
            }
            _ => {}
        }
        loop {
            tries += 1;
            if tries > 64 * f.len() + 64 {
                return None;
            }
            let a = rng.nonzero(p);
            let mut w = poly_pow_mod(&[a, 1], (p - 1) / 2, &h, p, rem);
            if w.is_empty() {
                w.push(0);
            }
            w[0] = sub(w[0], 1, p);
            trim(&mut w);
            let d = poly_gcd(&h, &w, p);
            if d.len() > 1 && d.len() < h.len() {
                let other = poly_div_monic(&h, &d, p);
                stack.push(d);
                stack.push(other);
                break;
            }
        }
    }
    Some(roots)
}

/// Solves `sum_j w_j b_j^k = v_k`, `k < T`, for distinct nodes `b_j`
/// (`P(z) = prod (z - b_j)`: `sum_k [z^k] (P / (z - b_j)) v_k = w_j (P /
/// (z - b_j))(b_j)`); `None` when two nodes coincide.
fn transposed_vandermonde(nodes: &[u64], vals: &[u64], p: u64) -> Option<Vec<u64>> {
    let rem = Rem128::new(p);
    let mut pz = vec![1u64];
    for &b in nodes {
        pz = poly_mul(&pz, &[sub(0, b, p), 1], p, rem);
    }
    let mut out = Vec::with_capacity(nodes.len());
    for &b in nodes {
        let (q, r) = deflate(&pz, b, p);
        debug_assert_eq!(r, 0);
        let num = q
            .iter()
            .zip(vals)
            .fold(0u64, |s, (&a, &v)| add(s, mul(a, v, p), p));
        let den = inv(eval(&q, b, p), p)?;
        out.push(mul(num, den, p));
    }
    Some(out)
}

/// `r^e mod p`.
fn monomial_value(r: &[u64], e: &[u32], p: u64) -> u64 {
    r.iter()
        .zip(e)
        .fold(1u64, |acc, (&x, &k)| mul(acc, pow(x, u64::from(k), p), p))
}

/// The first prime's sequences at `r_i a_i^k` (`a_i` the ratios: the small
/// primes `q_i`, or random past the prime), one Berlekamp–Massey per
/// component until all terminate: the random scales `r` and the
/// recurrences, or `None` past `tcap` terms or after [`RESTARTS`] holes.
#[allow(clippy::type_complexity)]
fn first_sequences<F, E>(
    blackbox: &mut F,
    budget: &mut Budget,
    rng: &mut Rng,
    m: usize,
    a: &[u64],
    tcap: usize,
) -> Result<Option<(Vec<u64>, Vec<Bm>)>, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let p0 = budget.list[0];
    for _ in 0..RESTARTS {
        let r: Vec<u64> = (0..a.len()).map(|_| rng.nonzero(p0)).collect();
        let mut bms: Vec<Bm> = (0..m).map(|_| Bm::new(p0)).collect();
        let mut pt = r.clone();
        let mut hole = false;
        while bms.iter().any(|b| !b.done()) {
            if bms.iter().any(|b| b.l > tcap) || bms[0].seq.len() > 2 * tcap + EARLY_TERMINATION {
                return Ok(None);
            }
            let Some(vals) = call(blackbox, budget, m, &pt, p0)? else {
                hole = true;
                break;
            };
            // Every component reads the whole sequence so that all stay
            // aligned; a finished one keeps checking its recurrence.
            for (b, &v) in bms.iter_mut().zip(&vals) {
                b.push(v);
            }
            for (x, &ai) in pt.iter_mut().zip(a) {
                *x = mul(*x, ai, p0);
            }
        }
        if !hole {
            return Ok(Some((r, bms)));
        }
    }
    Ok(None)
}

/// The black box's values at the points `start * ratio^k` (componentwise),
/// `k < t`, per component; `None` at a hole.
fn geometric_values<F, E>(
    blackbox: &mut F,
    budget: &mut Budget,
    m: usize,
    start: &[u64],
    ratio: &[u64],
    t: usize,
    p: u64,
) -> Result<Option<Vec<Vec<u64>>>, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let mut vals: Vec<Vec<u64>> = vec![Vec::with_capacity(t); m];
    let mut pt = start.to_vec();
    for _ in 0..t {
        let Some(v) = call(blackbox, budget, m, &pt, p)? else {
            return Ok(None);
        };
        for (col, x) in vals.iter_mut().zip(v) {
            col.push(x);
        }
        for (x, &si) in pt.iter_mut().zip(ratio) {
            *x = mul(*x, si, p);
        }
    }
    Ok(Some(vals))
}

/// Per component, its monomials' exponent vectors.
type Supports = Vec<Vec<Vec<u32>>>;

/// Per component, the roots `m_j` and the weights `w_j`.
type RootsWeights = Vec<(Vec<u64>, Vec<u64>)>;

/// The first prime's sequence, read: the start `r`, the ratios `a`, and
/// per component the roots `m_j = a^(e_j)` of its minimal polynomial with
/// the weights `w_j = c_j r^(e_j)` (transposed Vandermonde).
struct FirstPrime {
    r: Vec<u64>,
    a: Vec<u64>,
    comps: RootsWeights,
}

/// Roots and weights of every component's sequence (`None`: a minimal
/// polynomial with a zero root, or not a product of distinct linear
/// factors over F_p0).
fn roots_and_weights<E>(
    bms: &[Bm],
    budget: &Budget,
    rng: &mut Rng,
) -> Result<Option<RootsWeights>, ReconError<E>> {
    let p0 = budget.list[0];
    let mut known: Vec<u64> = Vec::new();
    let mut known_set = std::collections::HashSet::new();
    let mut comps = Vec::with_capacity(bms.len());
    for b in bms {
        if let Some(d) = budget.deadline {
            if std::time::Instant::now() >= d {
                return Err(budget.limit(Limit::Deadline));
            }
        }
        let lam = b.characteristic();
        if lam.first() == Some(&0) && b.l > 0 {
            return Ok(None);
        }
        let Some(roots) = split_roots(&lam, p0, &known, rng) else {
            return Ok(None);
        };
        for &rho in &roots {
            if known_set.insert(rho) {
                known.push(rho);
            }
        }
        let Some(w) = transposed_vandermonde(&roots, &b.seq, p0) else {
            return Ok(None);
        };
        comps.push((roots, w));
    }
    Ok(Some(comps))
}

/// `c^0, .., c^bound` mod `p` as a table power -> exponent, `None` when
/// two coincide (`c` of order at most `bound`).
fn power_table(c: u64, bound: u32, p: u64) -> Option<std::collections::HashMap<u64, u32>> {
    let mut table = std::collections::HashMap::with_capacity(bound as usize + 1);
    let mut x = 1u64;
    for e in 0..=bound {
        if table.insert(x, e).is_some() {
            return None;
        }
        x = mul(x, c, p);
    }
    Some(table)
}

/// Exponents past the prime (shifted sequences): for each variable `i`,
/// the values at `(r_1 a_1^k, .., c r_i a_i^k, .., r_n a_n^k)`, `k < T`
/// (`T` the largest number of roots of a component; the points are shared
/// by all components), have the same roots `m_j` and the weights
/// `w_j c^(e_ij)`: a transposed Vandermonde system on the known roots gives
/// them, and `e_ij` is the `e <= bound_i` with `c^e = w'_j / w_j` (a table
/// of `c^0..c^bound_i`, all distinct, else a new `c`). No match, a zero
/// weight, exponents past the per-variable or total bounds, or a root
/// `m_j` that is not `a^(e_j)`: `None`, never a guess.
///
/// A wrong support needs two monomials of one component with equal values
/// `a^e = a^e'` (for random `a`, probability at most `C(T, 2) D / (p0 - 1)`
/// by Schwartz–Zippel on `x^e - x^e'`, `D` the total degree bound), or a
/// ratio matching another power `c^e` by accident (at most `T (bound + 1)
/// / p0` per variable); either is then almost surely caught by the check
/// `m_j = a^(e_j)`, by the later primes' stop rule, and in the end by the
/// verification at fresh points modulo a prime never used (Schwartz–Zippel),
/// which is what certifies the answer: a wrong support gives `Ok(None)`.
fn shifted_exponents<F, E>(
    blackbox: &mut F,
    budget: &mut Budget,
    rng: &mut Rng,
    first: &FirstPrime,
    per_var: &[u32],
    max_total: u32,
) -> Result<Option<Supports>, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let p0 = budget.list[0];
    let (m, n) = (first.comps.len(), first.a.len());
    let t = first.comps.iter().map(|(roots, _)| roots.len()).max();
    let mut exps: Supports = first
        .comps
        .iter()
        .map(|(roots, _)| vec![vec![0u32; n]; roots.len()])
        .collect();
    let t = match t {
        Some(t) if t > 0 => t,
        _ => return Ok(Some(exps)),
    };
    for (i, &bound) in per_var.iter().enumerate() {
        let mut shifted = None;
        for _ in 0..RESTARTS {
            let c = rng.nonzero(p0);
            let Some(table) = power_table(c, bound.min(max_total), p0) else {
                continue;
            };
            let mut start = first.r.clone();
            start[i] = mul(start[i], c, p0);
            if let Some(vals) = geometric_values(blackbox, budget, m, &start, &first.a, t, p0)? {
                shifted = Some((table, vals));
                break;
            }
        }
        let Some((table, vals)) = shifted else {
            return Ok(None);
        };
        for (((roots, w), v), es) in first.comps.iter().zip(&vals).zip(&mut exps) {
            let Some(ws) = transposed_vandermonde(roots, v, p0) else {
                return Ok(None);
            };
            for ((&wj, wsj), e) in w.iter().zip(ws).zip(es.iter_mut()) {
                let Some(iw) = inv(wj, p0) else {
                    return Ok(None);
                };
                let Some(&k) = table.get(&mul(wsj, iw, p0)) else {
                    return Ok(None);
                };
                e[i] = k;
            }
        }
    }
    for ((roots, _), es) in first.comps.iter().zip(&exps) {
        for (&rho, e) in roots.iter().zip(es) {
            if e.iter().sum::<u32>() > max_total || monomial_value(&first.a, e, p0) != rho {
                return Ok(None);
            }
        }
    }
    Ok(Some(exps))
}

/// The first prime's supports and image. When every monomial value `q^e`
/// allowed by the bounds is below `p0` the ratios are the small primes and
/// each root's exponents come by trial division (`2T + delta` points);
/// past the prime the ratios are random and the exponents come from one
/// shifted sequence per variable ([`shifted_exponents`], `n T` more).
fn first_image<F, E>(
    blackbox: &mut F,
    budget: &mut Budget,
    rng: &mut Rng,
    m: usize,
    bounds: &DegreeBounds,
    max_total: u32,
) -> Result<Option<(Supports, Image)>, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    let p0 = budget.list[0];
    let nvars = bounds.per_var.len();
    let q = assign_primes(&bounds.per_var);
    let small = largest_monomial_value(&q, bounds, p0).is_some();
    let a = if small {
        q.clone()
    } else {
        (0..nvars).map(|_| rng.nonzero(p0)).collect()
    };
    let tcap = budget.max_terms.min(monomials_within(bounds));
    budget.stage = "sparse: Berlekamp-Massey (first prime)";
    let Some((r, bms)) = first_sequences(blackbox, budget, rng, m, &a, tcap)? else {
        return Ok(None);
    };
    budget.stage = "sparse: roots (first prime)";
    let Some(comps) = roots_and_weights(&bms, budget, rng)? else {
        return Ok(None);
    };
    let first = FirstPrime { r, a, comps };
    let exps = if small {
        first
            .comps
            .iter()
            .map(|(roots, _)| {
                roots
                    .iter()
                    .map(|&rho| exponents(rho, &q, &bounds.per_var, max_total))
                    .collect::<Option<Vec<_>>>()
            })
            .collect::<Option<Vec<_>>>()
    } else {
        budget.stage = "sparse: shifted sequences (first prime)";
        shifted_exponents(blackbox, budget, rng, &first, &bounds.per_var, max_total)?
    };
    let Some(exps) = exps else {
        return Ok(None);
    };
    let mut supports: Supports = Vec::with_capacity(m);
    let mut image: Image = Vec::with_capacity(m);
    for ((_, w), es) in first.comps.iter().zip(exps) {
        let mut terms: Terms = Vec::with_capacity(es.len());
        for (e, &wj) in es.into_iter().zip(w) {
            let Some(ir) = inv(monomial_value(&first.r, &e, p0), p0) else {
                return Ok(None);
            };
            let c = mul(wj, ir, p0);
            if c == 0 {
                return Ok(None);
            }
            terms.push((e, c));
        }
        terms.sort();
        supports.push(terms.iter().map(|(e, _)| e.clone()).collect());
        image.push((terms, vec![(vec![0u32; nvars], 1)]));
    }
    Ok(Some((supports, image)))
}

/// Sparse interpolation of `m` polynomials in `nvars` variables with
/// rational coefficients, from a black box returning all `m` values at a
/// point modulo a prime (`Ok(None)`: a bad point). `Ok(None)` when the
/// functions are not recognised as polynomials within `bounds` (the caller
/// falls back to [`crate::reconstruct_vec`]); an answer is verified at
/// fresh points modulo a prime never used, as `reconstruct_vec`'s. Budgets
/// of `opts` (points, deadline) end the run with an error; `max_terms`
/// bounds the terms of one component and `max_degree` its total degree
/// (beyond either: `Ok(None)`). Custom primes (`opts.primes`) are not
/// supported (`Ok(None)`).
pub fn interpolate_polys_vec<F, E>(
    nvars: usize,
    m: usize,
    blackbox: &mut F,
    opts: &Options,
    bounds: &DegreeBounds,
) -> Result<Option<Reconstruction>, ReconError<E>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, E>,
{
    if m == 0 {
        return Err(ReconError::InvalidOptions("no function to reconstruct"));
    }
    if opts.max_primes < 2 || opts.max_primes > MAX_RECON_PRIMES {
        return Err(ReconError::InvalidOptions("max_primes must be in 2..=20"));
    }
    if nvars == 0 || bounds.per_var.len() != nvars || opts.primes.is_some() {
        return Ok(None);
    }
    let mut rng = Rng::new(opts.seed ^ 0x5ba7_5e00);
    let mut budget = Budget::from_options(opts, "sparse: checking the degree bounds");
    let p0 = budget.list[0];
    let max_total = bounds.total.unwrap_or(u32::MAX).min(budget.max_degree);

    // First prime: supports and coefficients.
    let Some((supports, image)) =
        first_image(blackbox, &mut budget, &mut rng, m, bounds, max_total)?
    else {
        return Ok(None);
    };
    budget.degrees = supports
        .iter()
        .map(|s| (s.iter().map(|e| e.iter().sum()).max().unwrap_or(0), 0))
        .collect();
    budget.primes = 1;
    let mut acc = Acc::new(&image);
    if !acc.push(&image, p0) {
        return Ok(None);
    }
    let mut prev = acc.lift();
    let mut result = None;

    // Later primes: coefficients on the known supports.
    let tmax = supports.iter().map(Vec::len).max().unwrap_or(0);
    for &p in &budget.list[1..opts.max_primes] {
        budget.stage = "sparse: coefficients on the known monomials";
        let mut img: Option<Image> = None;
        'restart: for _ in 0..RESTARTS {
            let r: Vec<u64> = (0..nvars).map(|_| rng.nonzero(p)).collect();
            let s: Vec<u64> = (0..nvars).map(|_| rng.nonzero(p)).collect();
            let nodes: Vec<Vec<u64>> = supports
                .iter()
                .map(|sup| sup.iter().map(|e| monomial_value(&s, e, p)).collect())
                .collect();
            for nd in &nodes {
                let mut sorted = nd.clone();
                sorted.sort_unstable();
                if sorted.windows(2).any(|w| w[0] == w[1]) {
                    continue 'restart;
                }
            }
            let Some(vals) = geometric_values(blackbox, &mut budget, m, &r, &s, tmax, p)? else {
                continue 'restart;
            };
            let mut out: Image = Vec::with_capacity(m);
            for ((sup, nd), v) in supports.iter().zip(&nodes).zip(&vals) {
                let Some(w) = transposed_vandermonde(nd, v, p) else {
                    continue 'restart;
                };
                let mut terms: Terms = Vec::with_capacity(sup.len());
                for (e, wj) in sup.iter().zip(w) {
                    let Some(ir) = inv(monomial_value(&r, e, p), p) else {
                        continue 'restart;
                    };
                    terms.push((e.clone(), mul(wj, ir, p)));
                }
                out.push((terms, vec![(vec![0u32; nvars], 1)]));
            }
            img = Some(out);
            break;
        }
        let Some(img) = img else {
            return Ok(None);
        };
        budget.primes += 1;
        budget.stage = "lifting to Q";
        if !acc.push(&img, p) {
            continue;
        }
        let cand = acc.lift();
        if let (Some(c), Some(pv)) = (&cand, &prev) {
            if c == pv {
                result = cand;
                break;
            }
        }
        prev = cand;
    }
    let Some(functions) = result else {
        return Err(budget.limit(Limit::Primes(opts.max_primes)));
    };
    match verify(nvars, m, blackbox, &functions, opts, &mut rng, &mut budget) {
        Ok(certificate) => {
            budget.stage = "done";
            Ok(Some(Reconstruction {
                functions,
                certificate,
                stats: budget.progress(),
            }))
        }
        Err(ReconError::VerificationFailed { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// The exponents `e` with `q^e = rho` (as integers), within the bounds.
fn exponents(mut rho: u64, q: &[u64], per_var: &[u32], max_total: u32) -> Option<Vec<u32>> {
    let mut e = vec![0u32; q.len()];
    for (i, &qi) in q.iter().enumerate() {
        while rho.is_multiple_of(qi) {
            rho /= qi;
            e[i] += 1;
            if e[i] > per_var[i] {
                return None;
            }
        }
    }
    (rho == 1 && e.iter().sum::<u32>() <= max_total).then_some(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;

    const P: u64 = PRIMES[0];

    #[test]
    fn small_primes_and_assignment() {
        assert_eq!(small_primes(6), vec![2, 3, 5, 7, 11, 13]);
        // The largest bound gets 2, the next 3, ...
        assert_eq!(assign_primes(&[1, 5, 3]), vec![5, 2, 3]);
    }

    #[test]
    fn largest_value_within_bounds() {
        let b = DegreeBounds {
            per_var: vec![2, 1],
            total: None,
        };
        // 2^2 * 3 = 12.
        assert_eq!(largest_monomial_value(&[2, 3], &b, P), Some(12));
        let b = DegreeBounds {
            per_var: vec![2, 2],
            total: Some(2),
        };
        assert_eq!(largest_monomial_value(&[2, 3], &b, P), Some(9));
        let b = DegreeBounds {
            per_var: vec![70],
            total: None,
        };
        assert_eq!(largest_monomial_value(&[2], &b, P), None);
        // C(2 + 2, 2) = 6 monomials of degree <= 2 in 2 variables.
        let b = DegreeBounds {
            per_var: vec![2, 2],
            total: Some(2),
        };
        assert_eq!(monomials_within(&b), 6);
    }

    #[test]
    fn berlekamp_massey_finds_a_planted_recurrence() {
        // v_k = 3 * 5^k + 7 * 11^k: characteristic (z - 5)(z - 11).
        let mut bm = Bm::new(P);
        let mut k = 0u64;
        while !bm.done() {
            bm.push(add(mul(3, pow(5, k, P), P), mul(7, pow(11, k, P), P), P));
            k += 1;
        }
        assert_eq!(bm.l, 2);
        assert_eq!(bm.characteristic(), vec![55, P - 16, 1]);
        let mut rng = Rng::new(1);
        let mut roots = split_roots(&bm.characteristic(), P, &[], &mut rng).unwrap();
        roots.sort_unstable();
        assert_eq!(roots, vec![5, 11]);
        let w = transposed_vandermonde(&roots, &bm.seq, P).unwrap();
        assert_eq!(w, vec![3, 7]);
    }

    #[test]
    fn roots_of_a_product_of_linear_factors() {
        let rem = Rem128::new(P);
        let planted = [2u64, 3, 12, 1 << 40, P - 7, 99_991];
        let mut f = vec![1u64];
        for &x in &planted {
            f = poly_mul(&f, &[sub(0, x, P), 1], P, rem);
        }
        let mut rng = Rng::new(7);
        let mut r = split_roots(&f, P, &[3, 5], &mut rng).unwrap();
        r.sort_unstable();
        let mut want = planted.to_vec();
        want.sort_unstable();
        assert_eq!(r, want);
        // A repeated root, and an irreducible quadratic (z^2 - g, g a
        // non-residue: -1 when P = 3 mod 4), are refused.
        let sq = poly_mul(&f, &[sub(0, 12, P), 1], P, rem);
        assert!(split_roots(&sq, P, &[], &mut rng).is_none());
        assert!(split_roots(&sq, P, &[12], &mut rng).is_none());
        if P % 4 == 3 {
            assert!(split_roots(&[1, 0, 1], P, &[], &mut rng).is_none());
        }
    }
}
