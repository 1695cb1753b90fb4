//! Truncated power series over F_p for the input-output route's jets
//! (io.rs), stored flat: coefficient `k` of a series is the slice
//! `[k g, (k + 1) g)`, a dual vector (value, then the gradient in the
//! initial state when `g > 1`). One allocation per series, not one per
//! coefficient, and products by one scalar use Shoup's precomputed quotient
//! instead of a 128-bit remainder: the per-point cost of the
//! reconstruction's black box (docs/performance.md, session 31).

use super::io::fp;
use obsan_recon::fp::{ifma, mul_truncated52, Fold, Rem128, Shoup, IFMA_BOUND};

/// A polynomial in the series variables with its parameters already
/// evaluated: terms `(coefficient, [(variable, exponent)])`.
pub(super) type IPoly = Vec<(u64, Vec<(usize, u32)>)>;

/// A series: `len` dual vectors of `g` residues, flat.
pub(super) type Ser = Vec<u64>;

/// Sums of products modulo `p` with one 128-bit remainder per
/// [`Dot::max_adds`] products, not one per product.
#[derive(Clone, Copy)]
pub(super) struct Dot {
    m: obsan_recon::fp::Rem128,
    max_adds: usize,
}

impl Dot {
    pub(super) fn new(p: u64) -> Dot {
        let pm = u128::from(p.saturating_sub(1)).max(1);
        // The sum stays below p + max_adds (p - 1)^2 <= u128::MAX.
        let max_adds = ((u128::MAX / (pm * pm)).min(1 << 20) as usize)
            .saturating_sub(2)
            .max(1);
        Dot {
            m: obsan_recon::fp::Rem128::new(p),
            max_adds,
        }
    }

    /// `sum_i a[i] b[n - 1 - i]`, `n = a.len() = b.len()` (one coefficient
    /// of a product of series).
    pub(super) fn rev(&self, a: &[u64], b: &[u64]) -> u64 {
        let mut acc = 0u128;
        for (ca, cb) in a.chunks(self.max_adds).zip(b.rchunks(self.max_adds)) {
            for (&x, &y) in ca.iter().zip(cb.iter().rev()) {
                acc += x as u128 * y as u128;
            }
            acc = u128::from(self.m.reduce(acc));
        }
        acc as u64
    }
}

/// A polynomial's series one coefficient at a time (values only, `g = 1`;
/// "relaxed" evaluation): each term's partial products are kept, so
/// coefficient `k` costs `O(k)` per factor given the variables' first
/// `k + 1`. A Taylor recursion of length `len` then costs `O(len^2)`, not
/// the `O(len^3)` of re-evaluating the truncated polynomial at each order
/// (io.rs `taylor`; SIWR_orig's 773-term check along one output).
pub(super) struct Relaxed {
    p: u64,
    /// Per term, its coefficient and its factors (variables, repeated).
    terms: Vec<(u64, Vec<usize>)>,
    /// Per term, the series of the products of its first 2, 3, .. factors.
    partial: Vec<Vec<Ser>>,
}

impl Relaxed {
    pub(super) fn new(poly: &IPoly, len: usize, p: u64) -> Relaxed {
        let terms: Vec<(u64, Vec<usize>)> = poly
            .iter()
            .map(|(c, se)| {
                let f = se
                    .iter()
                    .flat_map(|&(v, e)| std::iter::repeat_n(v, e as usize))
                    .collect();
                (*c, f)
            })
            .collect();
        let partial = terms
            .iter()
            .map(|(_, f)| (1..f.len()).map(|_| vec![0u64; len]).collect())
            .collect();
        Relaxed { p, terms, partial }
    }

    /// Coefficient `k` at `vars`, whose coefficients `0..=k` are set; called
    /// for `k = 0, 1, ..` in order (the partial products' earlier
    /// coefficients are kept from the calls before).
    pub(super) fn coeff(&mut self, k: usize, vars: &[Ser], dot: &Dot) -> u64 {
        let p = self.p;
        let mut acc = 0u64;
        for ((c, f), part) in self.terms.iter().zip(self.partial.iter_mut()) {
            let v = match f.len() {
                0 => u64::from(k == 0),
                1 => vars[f[0]][k],
                n => {
                    for j in 1..n {
                        let (done, rest) = part.split_at_mut(j - 1);
                        let left: &[u64] = if j == 1 { &vars[f[0]] } else { &done[j - 2] };
                        rest[0][k] = dot.rev(&left[..=k], &vars[f[j]][..=k]);
                    }
                    part[n - 2][k]
                }
            };
            acc = fp::add(acc, fp::mul(*c, v, p), p);
        }
        acc
    }
}

/// `out = a b` truncated to `out.len()`, the products summed in `u128` and
/// folded (`Fold`) once every `max_adds` rows instead of reduced one by
/// one: SIWR_orig's monomial series, as many products per point as its
/// kernel's elimination has multiply-adds.
fn mul_folded(a: &[u64], b: &[u64], out: &mut [u64], p: u64, f: Fold) {
    let pm = u128::from(p - 1).max(1);
    // Entries stay below Fold::BOUND + max_adds (p - 1)^2 <= u128::MAX.
    let max_adds = ((u128::MAX - Fold::BOUND) / (pm * pm)).min(1 << 20) as usize;
    let mut acc = vec![0u128; out.len()];
    let mut adds = 0;
    for (i, &ai) in a.iter().enumerate().take(out.len()) {
        if ai == 0 {
            continue;
        }
        if adds >= max_adds {
            acc[i..].iter_mut().for_each(|x| *x = f.fold(*x));
            adds = 0;
        }
        for (o, &bj) in acc[i..].iter_mut().zip(b) {
            *o += u128::from(ai) * u128::from(bj);
        }
        adds += 1;
    }
    let m = Rem128::new(p);
    for (o, &x) in out.iter_mut().zip(&acc) {
        *o = m.reduce(x);
    }
}

pub(super) struct Arith {
    pub(super) p: u64,
    pub(super) g: usize,
    pub(super) len: usize,
}

impl Arith {
    pub(super) fn zero(&self) -> Ser {
        vec![0; self.g * self.len]
    }

    /// Coefficient `k` of `s`.
    pub(super) fn at<'s>(&self, s: &'s [u64], k: usize) -> &'s [u64] {
        &s[k * self.g..(k + 1) * self.g]
    }

    pub(super) fn at_mut<'s>(&self, s: &'s mut [u64], k: usize) -> &'s mut [u64] {
        &mut s[k * self.g..(k + 1) * self.g]
    }

    /// `out += a b` for dual vectors (first-order: `(a0 b0, a0 b_i + a_i b0)`).
    fn dmul(&self, a: &[u64], b: &[u64], out: &mut [u64]) {
        let p = self.p;
        out[0] = fp::add(out[0], fp::mul(a[0], b[0], p), p);
        for i in 1..self.g {
            let t = fp::add(fp::mul(a[0], b[i], p), fp::mul(a[i], b[0], p), p);
            out[i] = fp::add(out[i], t, p);
        }
    }

    /// `out = a b`, the Cauchy product truncated to `len`.
    pub(super) fn mul_into(&self, a: &[u64], b: &[u64], out: &mut [u64]) {
        let (p, g, len) = (self.p, self.g, self.len);
        out.fill(0);
        if g == 1 {
            // The io route's 52-bit primes: the product on IFMA.
            if p < IFMA_BOUND && ifma() {
                return mul_truncated52(a, b, out, p);
            }
            if let Some(f) = Fold::new(p) {
                return mul_folded(a, b, out, p, f);
            }
            for (i, &ai) in a.iter().enumerate() {
                if ai == 0 {
                    continue;
                }
                let s = Shoup::new(ai, p);
                for (o, &bj) in out[i..].iter_mut().zip(b) {
                    *o = fp::add(*o, s.times(bj), p);
                }
            }
            return;
        }
        for i in 0..len {
            let ai = &a[i * g..(i + 1) * g];
            if ai.iter().all(|&x| x == 0) {
                continue;
            }
            for j in 0..len - i {
                let (bj, o) = (&b[j * g..(j + 1) * g], i + j);
                self.dmul(ai, bj, &mut out[o * g..(o + 1) * g]);
            }
        }
    }

    pub(super) fn mul(&self, a: &[u64], b: &[u64]) -> Ser {
        let mut out = self.zero();
        self.mul_into(a, b, &mut out);
        out
    }

    /// `acc += c a`.
    fn add_scaled(&self, acc: &mut [u64], a: &[u64], c: u64) {
        let p = self.p;
        let s = Shoup::new(c, p);
        for (x, &y) in acc.iter_mut().zip(a) {
            *x = fp::add(*x, s.times(y), p);
        }
    }

    /// `a / b`; `None` when `b(0)` vanishes.
    pub(super) fn div(&self, a: &[u64], b: &[u64]) -> Option<Ser> {
        self.div_with(a, b, fp::inv(b[0], self.p)?)
    }

    /// `a / b` given `iv = 1 / b(0)` (a Taylor recursion divides by series
    /// sharing their value at 0: one inversion, not one per order).
    pub(super) fn div_with(&self, a: &[u64], b: &[u64], iv: u64) -> Option<Ser> {
        let (p, g) = (self.p, self.g);
        let b0 = self.at(b, 0);
        if b[g..].iter().all(|&x| x == 0) && b0[1..].iter().all(|&x| x == 0) {
            // A constant denominator (every polynomial model's).
            let mut q = a.to_vec();
            let s = Shoup::new(iv, p);
            q.iter_mut().for_each(|x| *x = s.times(*x));
            return Some(q);
        }
        // Dual inverse of b0: (1/v, -g/v^2).
        let mut inv0 = vec![0u64; g];
        inv0[0] = iv;
        let iv2 = fp::mul(iv, iv, p);
        for i in 1..g {
            inv0[i] = fp::sub(0, fp::mul(b0[i], iv2, p), p);
        }
        let mut q = self.zero();
        let (mut r, mut t) = (vec![0u64; g], vec![0u64; g]);
        for k in 0..self.len {
            r.copy_from_slice(self.at(a, k));
            for i in 1..=k {
                t.fill(0);
                self.dmul(self.at(b, i), self.at(&q, k - i), &mut t);
                for (x, y) in r.iter_mut().zip(&t) {
                    *x = fp::sub(*x, *y, p);
                }
            }
            let qk = self.at_mut(&mut q, k);
            qk.fill(0);
            self.dmul(&r, &inv0, qk);
        }
        Some(q)
    }

    /// `poly` at the series `vars`; `t1`, `t2` are scratch series. The
    /// series may be longer than `len`: their first `len` coefficients are
    /// read (a Taylor recursion's order `k` needs `k + 1` of them).
    pub(super) fn eval(&self, poly: &IPoly, vars: &[Ser], t1: &mut Ser, t2: &mut Ser) -> Ser {
        let p = self.p;
        let n = self.g * self.len;
        let (mut t1, mut t2) = (&mut t1[..n], &mut t2[..n]);
        let mut acc = self.zero();
        for (k, se) in poly {
            // The product so far: none, one variable, or in t1.
            let mut first: Option<usize> = None;
            let mut in_t1 = false;
            for &(v, e) in se {
                for _ in 0..e {
                    match first {
                        None => first = Some(v),
                        Some(f) => {
                            if in_t1 {
                                self.mul_into(t1, &vars[v][..n], t2);
                                std::mem::swap(&mut t1, &mut t2);
                            } else {
                                self.mul_into(&vars[f][..n], &vars[v][..n], t1);
                                in_t1 = true;
                            }
                        }
                    }
                }
            }
            match first {
                None => acc[0] = fp::add(acc[0], *k, p),
                Some(_) if in_t1 => self.add_scaled(&mut acc, t1, *k),
                Some(f) => self.add_scaled(&mut acc, &vars[f][..n], *k),
            }
        }
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: u64 = obsan_recon::PRIMES[2];

    /// The naive truncated product of series of dual vectors, nested.
    fn naive_mul(a: &[Vec<u64>], b: &[Vec<u64>], p: u64) -> Vec<Vec<u64>> {
        let (len, g) = (a.len(), a[0].len());
        let m = |x: u64, y: u64| ((x as u128 * y as u128) % p as u128) as u64;
        let mut out = vec![vec![0u64; g]; len];
        for i in 0..len {
            for j in 0..len - i {
                let o = &mut out[i + j];
                o[0] = (o[0] + m(a[i][0], b[j][0])) % p;
                for d in 1..g {
                    o[d] = (o[d] + m(a[i][0], b[j][d]) + m(a[i][d], b[j][0])) % p;
                }
            }
        }
        out
    }

    #[test]
    fn cached_remainders_agree_with_u128_ones_across_primes() {
        // io.rs's fp::mul keeps the last prime's constants: alternate primes
        // (the Mersenne one takes its own path) and compare with `%`.
        let mut st = 5u64;
        let primes = [P, obsan_recon::PRIMES[7], obsan_expr::P, P, 65_537];
        for i in 0..2000 {
            let p = primes[i % primes.len()];
            let (a, b) = (
                obsan_recon::splitmix64(&mut st) % p,
                obsan_recon::splitmix64(&mut st) % p,
            );
            assert_eq!(
                fp::mul(a, b, p),
                ((a as u128 * b as u128) % p as u128) as u64
            );
            let e = i as u64 % 40;
            assert_eq!(fp::pow(a, e, p), obsan_recon::fp::pow(a, e, p));
        }
    }

    #[test]
    fn flat_products_and_quotients_agree_with_the_nested_naive_ones() {
        // A 62-bit prime (folded u128 sums) and a 52-bit one (IFMA's
        // halves where the CPU has it).
        for p in [P, obsan_recon::PRIMES52[0]] {
            let mut st = 17u64;
            let mut next = || obsan_recon::splitmix64(&mut st) % p;
            for (g, len) in [(1, 1), (1, 6), (3, 5), (5, 2), (1, 9), (1, 40), (1, 100)] {
                let a = Arith { p, g, len };
                let nested = |next: &mut dyn FnMut() -> u64| -> Vec<Vec<u64>> {
                    (0..len).map(|_| (0..g).map(|_| next()).collect()).collect()
                };
                let x = nested(&mut next);
                let mut y = nested(&mut next);
                // Some zero coefficients, to take the skips.
                y[len / 2].iter_mut().for_each(|c| *c = 0);
                let flat = |s: &[Vec<u64>]| -> Ser { s.concat() };
                let prod = a.mul(&flat(&x), &flat(&y));
                assert_eq!(prod, flat(&naive_mul(&x, &y, p)));
                // (x y) / y = x wherever y(0) != 0.
                if y[0][0] != 0 {
                    assert_eq!(a.div(&prod, &flat(&y)).unwrap(), flat(&x));
                    let iv = fp::inv(y[0][0], p).unwrap();
                    assert_eq!(a.div_with(&prod, &flat(&y), iv).unwrap(), flat(&x));
                }
                // Division by a constant series.
                let mut c = vec![vec![0u64; g]; len];
                c[0][0] = 7;
                let q = a.div(&flat(&x), &flat(&c)).unwrap();
                assert_eq!(a.mul(&q, &flat(&c)), flat(&x));
                // 3 x^2 y + 5 + 2 y against the products.
                let poly: IPoly = vec![(3, vec![(0, 2), (1, 1)]), (5, vec![]), (2, vec![(1, 1)])];
                let vars = vec![flat(&x), flat(&y)];
                let (mut t1, mut t2) = (a.zero(), a.zero());
                let got = a.eval(&poly, &vars, &mut t1, &mut t2);
                let x2y = naive_mul(&naive_mul(&x, &x, p), &y, p);
                let mut want = a.zero();
                for k in 0..len {
                    for d in 0..g {
                        let v = &mut want[k * g + d];
                        *v = ((3 * x2y[k][d] as u128 + 2 * y[k][d] as u128) % p as u128) as u64;
                    }
                }
                want[0] = (want[0] + 5) % p;
                assert_eq!(got, want);
            }
        }
    }
}
