//! The field `F_(p^k) = F_p[t]/(t^k - g)`, `p = 2^61 - 1`, `g` a primitive
//! root mod p, for root leaves no point of F_p satisfies together
//! (docs/engine.md, "Roots in an extension field").
//!
//! Why it is a field: `t^k - g` is irreducible over F_p when every prime of
//! `k` divides `ord(g) = p - 1` and `4 ∤ k` (Lidl–Niederreiter, Thm 3.75; `p =
//! 3 mod 4`, so `4 ∤ p - 1`): here `k | p - 1`. Why every root a point needs
//! is there: every `c = g^e` of F_p has the `q`-th root `t^(e k / q)` for `q |
//! k`, whatever `c` is (the BIG models' `sqrt(42/(5x)) sqrt(5x/6) = sqrt(7)`,
//! 7 no square mod p, has a point here).
//!
//! Why any root will do: the canonical form is over the tower of the root
//! leaves, each irreducible over the field below it (root.rs), so every
//! choice of `r` with `r^q = u` is an embedding of that field; a value that is
//! not zero at such a point proves the element is not zero, as in F_p.

use crate::eval::BadPoint;
use crate::graph::{Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::{Fp, SplitMix, P};
use crate::poly::{Poly, Var};
use obsan_recon::fp::PrimeField;
use std::ops::{Add, Mul, Sub};

/// The largest extension degree offered (elements are arrays of this size).
pub const EXT_MAX: usize = 30;

/// `p - 1 = 2 * 3^2 * 5^2 * 7 * 11 * 13 * 31 * 41 * 61 * 151 * 331 * 1321`.
const P_MINUS_1: [(u64, u32); 12] = [
    (2, 1),
    (3, 2),
    (5, 2),
    (7, 1),
    (11, 1),
    (13, 1),
    (31, 1),
    (41, 1),
    (61, 1),
    (151, 1),
    (331, 1),
    (1321, 1),
];

/// An element of [`ExtField`]: the coefficients of `1, t, .., t^(k-1)`, the
/// others zero.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Ext(pub [Fp; EXT_MAX]);

/// `F_p[t]/(t^k - g)` for a `k | p - 1`, `k <= EXT_MAX`.
#[derive(Clone, Copy, Debug)]
pub struct ExtField {
    k: usize,
    /// The primitive root `g = t^k`.
    g: Fp,
    /// `zeta = g^((p - 1)/k)`, so that Frobenius is `t -> zeta t`.
    zeta: Fp,
}

fn primitive_root() -> Fp {
    // Every candidate is checked, so the loop ends at the least primitive root (37).
    (2u64..)
        .map(Fp::new)
        .find(|g| {
            P_MINUS_1
                .iter()
                .all(|&(l, _)| g.pow((P - 1) / l) != Fp::ONE)
        })
        .unwrap_or(Fp(37))
}

/// The discrete logarithm of `c != 0` to the base `g`, by Pohlig–Hellman
/// (the prime powers of `p - 1` are at most 1321).
fn dlog(g: Fp, c: Fp) -> Option<u64> {
    let n = P - 1;
    let (mut x, mut m) = (0u128, 1u128);
    for &(l, a) in &P_MINUS_1 {
        let la = l.pow(a);
        let h = c.pow(n / la);
        let gamma = g.pow(n / la);
        let mut cur = Fp::ONE;
        let e = (0..la).find(|_| {
            let hit = cur == h;
            cur = cur.mul(gamma);
            hit
        })? as u128;
        // CRT: x = e mod la, keeping x mod m.
        let la = la as u128;
        let mut y = x;
        while y % la != e {
            y += m;
        }
        x = y;
        m *= la;
    }
    (g.pow(x as u64) == c).then_some(x as u64)
}

impl ExtField {
    /// The field of degree `k`, if `k | p - 1` and `k <= EXT_MAX`.
    pub fn new(k: u32) -> Option<ExtField> {
        let k = k as usize;
        if k == 0 || k > EXT_MAX || !(P - 1).is_multiple_of(k as u64) {
            return None;
        }
        let g = primitive_root();
        Some(ExtField {
            k,
            g,
            zeta: g.pow((P - 1) / k as u64),
        })
    }

    /// The smallest field with every root of index in `qs` (their lcm),
    /// `None` when that is not a divisor of `p - 1` within [`EXT_MAX`].
    pub fn for_indices(qs: impl IntoIterator<Item = u32>) -> Option<ExtField> {
        let mut k = 1u64;
        for q in qs {
            let q = q as u64;
            k = k / gcd(k, q) * q;
            if k > EXT_MAX as u64 {
                return None;
            }
        }
        ExtField::new(k as u32)
    }

    pub fn degree(&self) -> u32 {
        self.k as u32
    }

    pub fn embed(&self, c: Fp) -> Ext {
        let mut a = [Fp::ZERO; EXT_MAX];
        a[0] = c;
        Ext(a)
    }

    /// The element as one of F_p, if it is one.
    pub fn in_base(&self, a: &Ext) -> Option<Fp> {
        a.0[1..self.k].iter().all(|c| c.is_zero()).then_some(a.0[0])
    }

    pub fn is_zero(&self, a: &Ext) -> bool {
        a.0[..self.k].iter().all(|c| c.is_zero())
    }

    pub fn add(&self, a: &Ext, b: &Ext) -> Ext {
        let mut c = *a;
        for i in 0..self.k {
            c.0[i] = c.0[i].add(b.0[i]);
        }
        c
    }

    fn sub_(&self, a: &Ext, b: &Ext) -> Ext {
        let mut c = *a;
        for i in 0..self.k {
            c.0[i] = c.0[i].sub(b.0[i]);
        }
        c
    }

    fn mul_(&self, a: &Ext, b: &Ext) -> Ext {
        let k = self.k;
        let mut lo = [Fp::ZERO; EXT_MAX];
        let mut hi = [Fp::ZERO; EXT_MAX];
        for i in 0..k {
            if a.0[i].is_zero() {
                continue;
            }
            for j in 0..k {
                let t = a.0[i].mul(b.0[j]);
                if i + j < k {
                    lo[i + j] = lo[i + j].add(t);
                } else {
                    hi[i + j - k] = hi[i + j - k].add(t);
                }
            }
        }
        // t^(k + i) = g t^i.
        for i in 0..k {
            lo[i] = lo[i].add(hi[i].mul(self.g));
        }
        Ext(lo)
    }

    /// `a^(p^j)`: the coefficient of `t^i` times `zeta^(i j)`.
    fn frobenius(&self, a: &Ext, j: u64) -> Ext {
        let z = self.zeta.pow(j % self.k as u64);
        let mut c = *a;
        let mut zi = Fp::ONE;
        for i in 0..self.k {
            c.0[i] = c.0[i].mul(zi);
            zi = zi.mul(z);
        }
        c
    }

    /// The inverse through the norm: `a^-1 = prod_(j=1..k-1) a^(p^j) / N(a)`,
    /// `N(a) = prod_(j=0..k-1) a^(p^j)` in F_p, zero only for `a = 0`.
    fn inv_(&self, a: &Ext) -> Option<Ext> {
        if self.is_zero(a) {
            return None;
        }
        let mut conj = self.embed(Fp::ONE);
        for j in 1..self.k as u64 {
            conj = self.mul_(&conj, &self.frobenius(a, j));
        }
        let norm = self.mul_(a, &conj).0[0];
        let ni = self.embed(norm.inv()?);
        Some(self.mul_(&conj, &ni))
    }

    /// `a^e` for any integer `e` (`None`: `a = 0`, `e < 0`).
    pub fn pow(&self, a: &Ext, e: i64) -> Option<Ext> {
        let mut b = if e < 0 { self.inv_(a)? } else { *a };
        let mut e = e.unsigned_abs();
        let mut r = self.embed(Fp::ONE);
        while e > 0 {
            if e & 1 == 1 {
                r = self.mul_(&r, &b);
            }
            b = self.mul_(&b, &b);
            e >>= 1;
        }
        Some(r)
    }

    /// A `q`-th root of `c` in F_p (`q | k`): `t^(e k / q)` for `c = g^e`.
    pub fn root_of_base(&self, c: Fp, q: u32) -> Option<Ext> {
        let q = q as u64;
        let k = self.k as u64;
        if q == 0 || !k.is_multiple_of(q) {
            return None;
        }
        if c.is_zero() {
            return Some(self.embed(Fp::ZERO));
        }
        let e = dlog(self.g, c)? as u128;
        let m = e * (k / q) as u128;
        let (a, b) = ((m / k as u128) as u64, (m % k as u128) as usize);
        let mut r = self.embed(Fp::ZERO);
        r.0[b] = self.g.pow(a);
        Some(r)
    }
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

impl PrimeField for ExtField {
    type Elem = Ext;
    fn zero(self) -> Ext {
        self.embed(Fp::ZERO)
    }
    fn one(self) -> Ext {
        self.embed(Fp::ONE)
    }
    fn sub(self, a: Ext, b: Ext) -> Ext {
        self.sub_(&a, &b)
    }
    fn mul(self, a: Ext, b: Ext) -> Ext {
        self.mul_(&a, &b)
    }
    fn inv(self, a: Ext) -> Option<Ext> {
        self.inv_(&a)
    }
}

/// A point of [`ExtField`]: symbols in F_p, every root leaf a root of its
/// radicand's value.
#[derive(Clone, Debug)]
pub struct ExtPoint {
    values: Vec<Ext>,
}

impl ExtPoint {
    pub fn value(&self, v: Var) -> Ext {
        self.values[v as usize]
    }
}

fn poly_ext(p: &Poly, field: &ExtField, val: &[Ext]) -> Option<Ext> {
    let mut acc = field.embed(Fp::ZERO);
    for (m, c) in p.terms() {
        let mut t = field.embed(Fp::from_int(c));
        for (v, e) in m.iter() {
            t = field.mul_(&t, &field.pow(&val[v as usize], e as i64)?);
        }
        acc = field.add(&acc, &t);
    }
    Some(acc)
}

impl Ctx {
    /// The indices of the root leaves, `None` when there are none.
    pub fn root_indices(&self) -> Option<Vec<u32>> {
        let qs: Vec<u32> = self
            .leaves
            .iter()
            .filter_map(|l| match l.kind {
                LeafKind::Root(_, q) => Some(q),
                _ => None,
            })
            .collect();
        (!qs.is_empty()).then_some(qs)
    }

    /// A random point of `field`: symbols and angles (tangent half-angles) in
    /// F_p, `fixed` where it gives a value, other atoms free, and every root leaf
    /// a root of its radicand's value. A radicand whose value is not in F_p (a
    /// root of a root whose value is not) is a `BadPoint`.
    pub fn random_ext_point(
        &mut self,
        rng: &mut SplitMix,
        field: &ExtField,
        fixed: &dyn Fn(Var) -> Option<Fp>,
    ) -> Result<ExtPoint, BadPoint> {
        let base = self.random_point(rng, fixed, false)?;
        let mut values: Vec<Ext> = (0..self.leaves.len())
            .map(|v| field.embed(base.value(v as Var)))
            .collect();
        for v in 0..self.leaves.len() {
            let LeafKind::Root(_, q) = self.leaves[v].kind else {
                continue;
            };
            let r = self.radicand(v as Var).ok_or(BadPoint)?;
            let n = poly_ext(&r.num, field, &values).ok_or(BadPoint)?;
            let d = poly_ext(&r.den, field, &values).ok_or(BadPoint)?;
            let u = field.mul_(&n, &field.inv_(&d).ok_or(BadPoint)?);
            let u = field.in_base(&u).ok_or(BadPoint)?;
            values[v] = field.root_of_base(u, q).ok_or(BadPoint)?;
        }
        Ok(ExtPoint { values })
    }

    /// Values of `roots` at a point of `field`.
    pub fn eval_ext(
        &self,
        roots: &[Id],
        field: &ExtField,
        point: &ExtPoint,
    ) -> Result<Vec<Ext>, BadPoint> {
        let order = self.reachable(roots);
        let mut val = vec![field.embed(Fp::ZERO); self.len()];
        for id in order {
            let x = match self.node(id) {
                Node::Num(q) => field.embed(q.to_fp().ok_or(BadPoint)?),
                Node::Leaf(v) => point.value(*v),
                Node::Add(cs) => cs
                    .iter()
                    .fold(field.embed(Fp::ZERO), |a, c| field.add(&a, &val[c.index()])),
                Node::Mul(cs) => cs
                    .iter()
                    .fold(field.embed(Fp::ONE), |a, c| field.mul_(&a, &val[c.index()])),
                Node::Pow(b, e) => field.pow(&val[b.index()], *e as i64).ok_or(BadPoint)?,
            };
            val[id.index()] = x;
        }
        Ok(roots.iter().map(|r| val[r.index()]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(k: u32) -> ExtField {
        ExtField::new(k).unwrap()
    }

    fn rand_ext(f: &ExtField, rng: &mut SplitMix) -> Ext {
        let mut a = f.embed(Fp::ZERO);
        for i in 0..f.k {
            a.0[i] = rng.fp();
        }
        a
    }

    #[test]
    fn degrees_are_the_divisors_of_p_minus_1() {
        assert!(ExtField::new(10).is_some());
        assert!(ExtField::new(4).is_none(), "4 does not divide p - 1");
        assert!(ExtField::new(27).is_none());
        assert_eq!(ExtField::for_indices([2, 5]).unwrap().degree(), 10);
        assert!(ExtField::for_indices([2, 17]).is_none());
    }

    /// Field identities: a a^-1 = 1, distributivity, Frobenius a^p.
    #[test]
    fn field_identities() {
        let mut rng = SplitMix(7);
        for k in [1, 2, 3, 5, 6, 10, 30] {
            let f = field(k);
            for _ in 0..20 {
                let (a, b, c) = (
                    rand_ext(&f, &mut rng),
                    rand_ext(&f, &mut rng),
                    rand_ext(&f, &mut rng),
                );
                let one = f.embed(Fp::ONE);
                assert_eq!(f.mul_(&a, &f.inv_(&a).unwrap()), one, "k = {k}");
                assert_eq!(
                    f.mul_(&a, &f.add(&b, &c)),
                    f.add(&f.mul_(&a, &b), &f.mul_(&a, &c))
                );
                // a^p by square-and-multiply against the Frobenius map.
                let mut ap = one;
                let mut base = a;
                let mut e = P;
                while e > 0 {
                    if e & 1 == 1 {
                        ap = f.mul_(&ap, &base);
                    }
                    base = f.mul_(&base, &base);
                    e >>= 1;
                }
                assert_eq!(ap, f.frobenius(&a, 1), "k = {k}");
            }
        }
    }

    /// Roots of non-residues: 3 and 7 have no square root in F_p.
    #[test]
    fn roots_of_every_constant() {
        let f = field(10);
        assert!(Fp(3).sqrt().is_none() && Fp(7).sqrt().is_none());
        for c in [2u64, 3, 7, 42, 26250, P - 1] {
            for q in [1u32, 2, 5, 10] {
                let r = f.root_of_base(Fp(c), q).unwrap();
                assert_eq!(f.pow(&r, q as i64).unwrap(), f.embed(Fp(c)), "c {c} q {q}");
            }
        }
        assert!(f.root_of_base(Fp(3), 3).is_none());
    }

    #[test]
    fn dlog_inverts_pow() {
        let g = primitive_root();
        let mut rng = SplitMix(3);
        for _ in 0..50 {
            let e = rng.next_u64() % (P - 1);
            assert_eq!(dlog(g, g.pow(e)), Some(e));
        }
    }
}
