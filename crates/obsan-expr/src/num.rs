//! Numbers: exact integers and rationals (over dashu's `IBig`) and the prime
//! field F_p with p = 2^61 - 1 used by the probabilistic rank test.

use dashu_int::ops::{Abs, BitTest, DivRem, Gcd, SquareRoot};
use dashu_int::{IBig, Sign, UBig};
use obsan_recon::fp;
use std::fmt;
use std::ops::{Mul, Neg};

/// Arbitrary-precision integer. Small values are stored inline by dashu.
pub type Int = IBig;

pub(crate) fn int(n: i64) -> Int {
    IBig::from(n)
}

pub(crate) fn int_gcd(a: &Int, b: &Int) -> Int {
    IBig::from(a.gcd(b))
}

/// Exact division (the caller knows `b` divides `a`).
pub(crate) fn int_div_exact(a: &Int, b: &Int) -> Int {
    debug_assert!((a % b).is_zero(), "inexact integer division");
    a / b
}

/// Remainder in the symmetric range (-m/2, m/2].
pub(crate) fn int_symmetric_mod(a: &Int, m: &Int) -> Int {
    let (_, mut r) = a.clone().div_rem(m.clone());
    if r.sign() == Sign::Negative {
        r += m;
    }
    // now 0 <= r < m
    let twice: Int = &r * int(2);
    if &twice > m {
        r -= m;
    }
    r
}

pub(crate) fn int_to_f64(a: &Int) -> f64 {
    a.to_f64().value()
}

/// Integer square root if `a` is a perfect square (a >= 0).
pub(crate) fn int_exact_sqrt(a: &Int) -> Option<Int> {
    if a.sign() == Sign::Negative {
        return None;
    }
    let u: UBig = a.clone().abs().try_into().ok()?;
    let r = u.sqrt();
    if &r * &r == u {
        Some(IBig::from(r))
    } else {
        None
    }
}

/// Trial divisors go up to this bound (1000 for numbers above 4096 bits,
/// whose every remainder is costly).
pub(crate) fn trial_bound(n: &Int) -> i64 {
    if n.bit_len() <= 4096 {
        1 << 16
    } else {
        1000
    }
}

/// Trial division of `|n|` (n != 0) by the integers up to [`trial_bound`],
/// while their square is at most what is left: the prime powers found, and
/// the cofactor, which has no prime factor up to the bound (so it is 1 or a
/// prime when it is below the bound squared).
pub(crate) fn trial_factor(n: &Int) -> (Vec<(Int, u32)>, Int) {
    let bound = trial_bound(n);
    let mut t = n.clone().abs();
    let mut out = Vec::new();
    let mut d = 2i64;
    while d <= bound && int(d) * int(d) <= t {
        let di = int(d);
        if (&t % &di).is_zero() {
            let mut e = 0;
            while (&t % &di).is_zero() {
                t = &t / &di;
                e += 1;
            }
            out.push((di, e));
        }
        d += if d == 2 { 1 } else { 2 };
    }
    (out, t)
}

/// Exact rational number with positive denominator and gcd(num, den) = 1.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub struct Q {
    num: Int,
    den: Int,
}

impl Q {
    pub fn new(num: Int, den: Int) -> Q {
        assert!(!den.is_zero(), "rational with zero denominator");
        let g = int_gcd(&num, &den);
        let (mut n, mut d) = (int_div_exact(&num, &g), int_div_exact(&den, &g));
        if d.sign() == Sign::Negative {
            n = -n;
            d = -d;
        }
        Q { num: n, den: d }
    }
    pub fn from_int(n: Int) -> Q {
        Q {
            num: n,
            den: int(1),
        }
    }
    pub fn from_i64(n: i64) -> Q {
        Q::from_int(int(n))
    }
    pub fn zero() -> Q {
        Q::from_i64(0)
    }
    pub fn one() -> Q {
        Q::from_i64(1)
    }
    pub fn num(&self) -> &Int {
        &self.num
    }
    pub fn den(&self) -> &Int {
        &self.den
    }
    pub fn is_zero(&self) -> bool {
        self.num.is_zero()
    }
    pub fn is_one(&self) -> bool {
        self.num.is_one() && self.den.is_one()
    }
    pub fn is_integer(&self) -> bool {
        self.den.is_one()
    }
    pub fn is_negative(&self) -> bool {
        self.num.sign() == Sign::Negative
    }
    pub fn add(&self, o: &Q) -> Q {
        Q::new(&self.num * &o.den + &o.num * &self.den, &self.den * &o.den)
    }
    pub fn sub(&self, o: &Q) -> Q {
        self.add(&o.neg())
    }
    pub fn mul(&self, o: &Q) -> Q {
        Q::new(&self.num * &o.num, &self.den * &o.den)
    }
    pub fn neg(&self) -> Q {
        Q {
            num: -self.num.clone(),
            den: self.den.clone(),
        }
    }
    /// Inverse; `None` for zero.
    pub fn inv(&self) -> Option<Q> {
        if self.is_zero() {
            None
        } else {
            Some(Q::new(self.den.clone(), self.num.clone()))
        }
    }
    pub fn div(&self, o: &Q) -> Option<Q> {
        Some(self.mul(&o.inv()?))
    }
    /// Integer power (negative powers of zero give `None`).
    pub fn powi(&self, e: i64) -> Option<Q> {
        let base = if e < 0 { self.inv()? } else { self.clone() };
        let k = e.unsigned_abs() as usize;
        Some(Q {
            num: base.num.pow(k),
            den: base.den.pow(k),
        })
    }
    pub fn to_f64(&self) -> f64 {
        // Scale to keep precision for huge numerators/denominators.
        let (n, d) = (int_to_f64(&self.num), int_to_f64(&self.den));
        if n.is_finite() && d.is_finite() {
            return n / d;
        }
        let shift = (self.num.clone().abs().bit_len() as i64 - 60)
            .max(self.den.bit_len() as i64 - 60)
            .max(0) as usize;
        let n2 = int_to_f64(&(&self.num >> shift));
        let d2 = int_to_f64(&(&self.den >> shift));
        n2 / d2
    }
    /// Exact value of a finite f64.
    pub fn from_f64(x: f64) -> Option<Q> {
        if !x.is_finite() {
            return None;
        }
        let bits = x.to_bits();
        let sign = if bits >> 63 == 1 { -1i64 } else { 1 };
        let exp = ((bits >> 52) & 0x7ff) as i64;
        let frac = bits & ((1u64 << 52) - 1);
        let (mant, e) = if exp == 0 {
            (frac, -1074)
        } else {
            (frac | (1u64 << 52), exp - 1075)
        };
        let m = int(sign) * IBig::from(mant);
        Some(if e >= 0 {
            Q::from_int(m << e as usize)
        } else {
            Q::new(m, int(1) << (-e) as usize)
        })
    }
    /// Value modulo p, `None` when p divides the denominator.
    pub fn to_fp(&self) -> Option<Fp> {
        let n = Fp::from_int(&self.num);
        let d = Fp::from_int(&self.den);
        Some(n.mul(d.inv()?))
    }
}

impl fmt::Display for Q {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.den.is_one() {
            write!(f, "{}", self.num)
        } else {
            write!(f, "{}/{}", self.num, self.den)
        }
    }
}

/// `x mod q` in `0..q` for any modulus `q` (the residue of an exact integer
/// in a prime field).
pub(crate) fn int_mod(x: &Int, q: u64) -> u64 {
    if let Ok(v) = i64::try_from(x) {
        return (v as i128).rem_euclid(q as i128) as u64;
    }
    let (_, mut r) = x.clone().div_rem(IBig::from(q));
    if r.sign() == Sign::Negative {
        r += IBig::from(q);
    }
    // 0 <= r < q < 2^64.
    u64::try_from(&r).unwrap_or(0)
}

/// The Mersenne prime 2^61 - 1: reduction is a shift and an add.
pub const P: u64 = (1u64 << 61) - 1;

/// Element of F_p, p = 2^61 - 1, always reduced to [0, p).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
pub struct Fp(pub u64);

impl Fp {
    pub const ZERO: Fp = Fp(0);
    pub const ONE: Fp = Fp(1);
    pub fn new(x: u64) -> Fp {
        Fp(x % P)
    }
    pub fn from_i64(x: i64) -> Fp {
        if x >= 0 {
            Fp::new(x as u64)
        } else {
            Fp::new(x.unsigned_abs()).neg()
        }
    }
    pub fn from_int(x: &Int) -> Fp {
        Fp(int_mod(x, P))
    }
    pub fn pow(self, mut e: u64) -> Fp {
        let (mut b, mut r) = (self, Fp::ONE);
        while e > 0 {
            if e & 1 == 1 {
                r = r.mul(b);
            }
            b = b.mul(b);
            e >>= 1;
        }
        r
    }
    /// Inverse by Fermat; `None` for zero.
    pub fn inv(self) -> Option<Fp> {
        if self.0 == 0 {
            None
        } else {
            Some(self.pow(P - 2))
        }
    }
    pub fn is_zero(self) -> bool {
        self.0 == 0
    }
    /// The rank of a matrix over F_p given by its rows ([`FpEchelon`]).
    pub fn matrix_rank(rows: Vec<Vec<Fp>>) -> usize {
        fp::rank(FpField, rows)
    }
    /// A basis of the right null space of the rows, vectors of length
    /// `ncols`, in reduced form: 1 at its own free column, 0 at the others.
    pub fn null_space(rows: Vec<Vec<Fp>>, ncols: usize) -> Vec<Vec<Fp>> {
        fp::null_space(FpField, rows, ncols)
    }
    /// A `q`-th root if one exists (`q >= 1`; any root: each satisfies
    /// `r^q = u`, which is all the relation asks). With `n = p - 1 = n1 n2`,
    /// `n1` the part of `n` on the primes of `gcd(q, n)`: `u = u1 u2` in the
    /// subgroups of orders `n1` and `n2`; `q` is invertible mod `n2`, so `u2`
    /// has the one root `u2^(q^-1 mod n2)`; the root of `u1` is found among the
    /// `n1` elements of its subgroup (`n1 <= 2 * 9 * 25 * ...`, small for the
    /// indices obsan accepts). `None` when `u` is no q-th power (then `u^(n/g)
    /// != 1`, `g = gcd(q, n)`: a fraction `1 - 1/g` of the units).
    pub fn root(self, q: u32) -> Option<Fp> {
        if q == 2 {
            return self.sqrt();
        }
        if self.0 == 0 || q == 1 {
            return Some(self);
        }
        let n = P - 1;
        let q64 = q as u64;
        let g = gcd64(q64, n);
        if self.pow(n / g) != Fp::ONE {
            return None;
        }
        let (mut n1, mut n2) = (1u64, n);
        let mut primes = Vec::new();
        let mut h = g;
        let mut d = 2;
        while h > 1 {
            if h.is_multiple_of(d) {
                primes.push(d);
                while h.is_multiple_of(d) {
                    h /= d;
                }
                while n2 % d == 0 {
                    n2 /= d;
                    n1 *= d;
                }
            }
            d += 1;
        }
        // a = 1 mod n1, 0 mod n2: u1 = u^a, u2 = u^(1 - a).
        let a = mulmod(n2, inv_mod(n2 % n1, n1)?, n);
        let u1 = self.pow(a);
        let u2 = self.pow((1 + n - a) % n);
        let r2 = u2.pow(inv_mod(q64 % n2, n2)?);
        let mut r1 = Fp::ONE;
        if n1 > 1 {
            // A generator of the subgroup of order n1: x^n2 of exact order n1.
            let gen = (2..1000u64)
                .map(|x| Fp::new(x).pow(n2))
                .find(|h| primes.iter().all(|&l| h.pow(n1 / l) != Fp::ONE))?;
            let step = gen.pow(q64);
            let (mut cur, mut cand) = (Fp::ONE, Fp::ONE);
            let mut found = false;
            for _ in 0..n1 {
                if cur == u1 {
                    found = true;
                    break;
                }
                cur = cur.mul(step);
                cand = cand.mul(gen);
            }
            if !found {
                return None;
            }
            r1 = cand;
        }
        let r = r1.mul(r2);
        (r.pow(q64) == self).then_some(r)
    }
    /// A square root if one exists (Tonelli–Shanks; p - 1 = 2 * odd * ...).
    pub fn sqrt(self) -> Option<Fp> {
        if self.0 == 0 {
            return Some(self);
        }
        if self.pow((P - 1) / 2) != Fp::ONE {
            return None;
        }
        // p - 1 = 2^s * q
        let (mut q, mut s) = (P - 1, 0u32);
        while q % 2 == 0 {
            q /= 2;
            s += 1;
        }
        let mut z = Fp(2);
        while z.pow((P - 1) / 2) == Fp::ONE {
            z = Fp(z.0 + 1);
        }
        let (mut m, mut c, mut t, mut r) = (s, z.pow(q), self.pow(q), self.pow(q.div_ceil(2)));
        while t != Fp::ONE {
            let mut i = 0;
            let mut t2 = t;
            while t2 != Fp::ONE {
                t2 = t2.mul(t2);
                i += 1;
            }
            let b = c.pow(1u64 << (m - i - 1));
            m = i;
            c = b.mul(b);
            t = t.mul(c);
            r = r.mul(b);
        }
        Some(r)
    }
}

impl std::ops::Add for Fp {
    type Output = Fp;
    #[inline]
    fn add(self, o: Fp) -> Fp {
        let s = self.0 + o.0;
        Fp(if s >= P { s - P } else { s })
    }
}

impl std::ops::Sub for Fp {
    type Output = Fp;
    #[inline]
    fn sub(self, o: Fp) -> Fp {
        Fp(if self.0 >= o.0 {
            self.0 - o.0
        } else {
            self.0 + P - o.0
        })
    }
}

impl std::ops::Neg for Fp {
    type Output = Fp;
    #[inline]
    fn neg(self) -> Fp {
        Fp(if self.0 == 0 { 0 } else { P - self.0 })
    }
}

impl std::ops::Mul for Fp {
    type Output = Fp;
    /// Reduction modulo 2^61 - 1: split at bit 61 and add.
    #[inline]
    fn mul(self, o: Fp) -> Fp {
        let w = self.0 as u128 * o.0 as u128;
        let lo = (w as u64) & P;
        let hi = (w >> 61) as u64;
        let s = lo + hi;
        Fp(if s >= P { s - P } else { s })
    }
}

/// F_p with p = 2^61 - 1 as a field for obsan-recon's one dense elimination
/// ([`FpEchelon`]), with the shift-and-add products above.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FpField;

impl fp::PrimeField for FpField {
    type Elem = Fp;
    #[inline]
    fn zero(self) -> Fp {
        Fp::ZERO
    }
    #[inline]
    fn one(self) -> Fp {
        Fp::ONE
    }
    #[inline]
    fn sub(self, a: Fp, b: Fp) -> Fp {
        a - b
    }
    #[inline]
    fn mul(self, a: Fp, b: Fp) -> Fp {
        a * b
    }
    fn inv(self, a: Fp) -> Option<Fp> {
        a.inv()
    }
    /// Delayed reduction (`fp::reduce_delayed`): products below `2^122`
    /// summed in u128, folded by `2^61 = 1` once every [`MERSENNE_ADDS`]
    /// rows; the per-row shift-and-add products were most of the io route's
    /// Wronskian checks (io.rs `independent_along`, 771 columns on
    /// SIWR_orig).
    fn reduce_sorted(self, v: &mut [Fp], rows: &[(usize, Vec<Fp>)]) {
        fp::reduce_delayed(&mut [v], rows, P, MERSENNE_ADDS, fold61, reduce61);
    }
    fn reduce_block(self, vs: &mut [Vec<Fp>], rows: &[(usize, Vec<Fp>)]) {
        fp::reduce_delayed(vs, rows, P, MERSENNE_ADDS, fold61, reduce61);
    }
}

impl fp::Residue for Fp {
    #[inline]
    fn residue(self) -> u64 {
        self.0
    }
    #[inline]
    fn of_residue(x: u64) -> Fp {
        Fp(x)
    }
}

/// `x` with the same residue modulo `P = 2^61 - 1`, below `2^68`: its low 61
/// bits plus the rest (`2^61 = 1`).
#[inline]
fn fold61(x: u128) -> u128 {
    (x & u128::from(P)) + (x >> 61)
}

/// `x mod P` for any u128.
#[inline]
fn reduce61(x: u128) -> u64 {
    // Below 2^68, then below 2^61 + 2^7, then below P.
    let y = fold61(fold61(x)) as u64;
    if y >= P {
        y - P
    } else {
        y
    }
}

/// Products (each below `(P - 1)^2 < 2^122`) [`FpField`]'s delayed reduction
/// adds between folds: the folded entries are below `2^68`, and `2^68 + 63
/// (P - 1)^2 < 2^128`.
const MERSENNE_ADDS: usize = 63;

/// Rows over [`Fp`] in reduced row echelon form: ranks, null spaces,
/// membership and solves (`obsan_recon::fp::Echelon`).
pub type FpEchelon = fp::Echelon<FpField>;

/// Small deterministic PRNG (SplitMix64, stepped by obsan-recon's
/// `splitmix64`) for random evaluation points: the engine must not depend on
/// a particular `rand` version for reproducibility.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next SplitMix64 output (obsan-recon's `splitmix64`, the one step).
    pub fn next_u64(&mut self) -> u64 {
        obsan_recon::splitmix64(&mut self.0)
    }
    /// Uniform element of F_p.
    pub fn fp(&mut self) -> Fp {
        loop {
            let x = self.next_u64() >> 3;
            if x < P {
                return Fp(x);
            }
        }
    }
    /// Uniform f64 in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

fn gcd64(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

fn mulmod(a: u64, b: u64, m: u64) -> u64 {
    ((a as u128 * b as u128) % m as u128) as u64
}

/// `a^-1 mod m` (`m >= 1`; `Some(0)` for `m = 1`), `None` when not coprime.
fn inv_mod(a: u64, m: u64) -> Option<u64> {
    if m == 1 {
        return Some(0);
    }
    let (mut r0, mut r1) = (m as i128, a as i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    while r1 != 0 {
        let k = r0 / r1;
        (r0, r1) = (r1, r0 - k * r1);
        (t0, t1) = (t1, t0 - k * t1);
    }
    (r0 == 1).then(|| t0.rem_euclid(m as i128) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fp_field_identities() {
        let mut r = SplitMix(7);
        for _ in 0..200 {
            let (a, b) = (r.fp(), r.fp());
            assert_eq!(a.mul(b), b.mul(a));
            if !a.is_zero() {
                assert_eq!(a.mul(a.inv().unwrap()), Fp::ONE);
            }
            assert_eq!(a - b + b, a);
            let sq = a.mul(a);
            let s = sq.sqrt().unwrap();
            assert_eq!(s.mul(s), sq);
        }
    }

    #[test]
    fn delayed_reduction_is_row_by_row_reduction() {
        // FpField's delayed reduction against the trait's default loops
        // (one shift-and-add product per entry), past one fold's 63 rows.
        #[derive(Clone, Copy)]
        struct Plain;
        impl fp::PrimeField for Plain {
            type Elem = Fp;
            fn zero(self) -> Fp {
                Fp::ZERO
            }
            fn one(self) -> Fp {
                Fp::ONE
            }
            fn sub(self, a: Fp, b: Fp) -> Fp {
                a - b
            }
            fn mul(self, a: Fp, b: Fp) -> Fp {
                a * b
            }
            fn inv(self, a: Fp) -> Option<Fp> {
                a.inv()
            }
        }
        let mut r = SplitMix(11);
        for n in [1usize, 7, 70, 140] {
            let (mut fast, mut slow) = (fp::RowEchelon::new(FpField), fp::RowEchelon::new(Plain));
            let rows: Vec<Vec<Fp>> = (0..n + 3)
                .map(|i| {
                    // Entries near P too, and a repeated row (a dependent one).
                    (0..n)
                        .map(|k| {
                            if (i + k) % 5 == 0 {
                                Fp(P - 1 - (k as u64 % 3))
                            } else {
                                r.fp()
                            }
                        })
                        .collect()
                })
                .collect();
            let mut rows = rows;
            if n > 2 {
                rows[2] = rows[1].clone();
            }
            for row in &rows {
                assert_eq!(fast.insert(row.clone()), slow.insert(row.clone()));
            }
            assert_eq!(fast.null_space(n), slow.null_space(n));
            let (mut a, mut b) = (fp::RowEchelon::new(FpField), fp::RowEchelon::new(Plain));
            assert_eq!(a.insert_all(rows.clone(), 2), b.insert_all(rows, 1));
            assert_eq!(a.null_space(n), b.null_space(n));
        }
        for x in [
            0u128,
            u128::MAX,
            u128::from(P),
            u128::from(P) * u128::from(P - 1),
        ] {
            assert_eq!(u128::from(reduce61(x)), x % u128::from(P));
            assert!(fold61(x) < 1 << 68 && fold61(x) % u128::from(P) == x % u128::from(P));
        }
    }

    #[test]
    fn rational_arithmetic_and_conversions() {
        let a = Q::new(int(6), int(-4));
        assert_eq!(a, Q::new(int(-3), int(2)));
        assert_eq!(a.add(&Q::new(int(3), int(2))), Q::zero());
        assert_eq!(Q::from_f64(0.375).unwrap(), Q::new(int(3), int(8)));
        assert_eq!(Q::new(int(1), int(3)).to_f64(), 1.0 / 3.0);
        let x = Q::new(int(5), int(7)).to_fp().unwrap();
        assert_eq!(x.mul(Fp::from_i64(7)), Fp::from_i64(5));
        assert_eq!(int_symmetric_mod(&int(7), &int(5)), int(2));
        assert_eq!(int_symmetric_mod(&int(9), &int(5)), int(-1));
        assert_eq!(int_symmetric_mod(&int(-7), &int(5)), int(-2));
    }
}
