//! The tangent half-angle view: `sin x = 2t/(1+t^2)`, `cos x = (1-t^2)/(1+t^2)`
//! with `t = tan(x/2)`, for every angle pair. In this view every form is a
//! plain rational function (no relation), so polynomial gcds remove every
//! common factor: Q[t, ...] is a unique-factorisation domain, while modulo
//! s^2 + c^2 = 1 common factors can hide (s^2 = (1 - c)(1 + c)). Linear
//! algebra that must keep its results small (null spaces) runs here; results
//! are mapped back with `t = s/(1 + c)`.

use crate::graph::LeafKind;
use crate::memo::Ctx;
use crate::num::int;
use crate::num::Int;
use crate::poly::{Mono, Poly, Var};
use crate::ratfun::RatFun;
use std::collections::BTreeMap;

/// The angle pairs of a context and their half-angle symbols.
#[derive(Clone, Debug)]
pub struct TanHalf {
    /// (sin leaf, cos leaf, t symbol)
    pairs: Vec<(Var, Var, Var)>,
}

impl TanHalf {
    /// No sin/cos pair: the view is the identity.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Whether the view covers every relation of the context (no root leaf).
    pub fn complete(&self, ctx: &Ctx) -> bool {
        !ctx.leaves
            .iter()
            .any(|l| matches!(l.kind, LeafKind::Root(..)))
    }
}

impl Ctx {
    /// Half-angle symbols for every sin/cos pair of the context.
    pub fn tan_half(&mut self) -> TanHalf {
        TanHalf {
            pairs: self.half_angles.clone(),
        }
    }

    fn poly_to_tan_half(&self, th: &TanHalf, p: &Poly) -> (Poly, Vec<u32>) {
        // Per angle, the highest total degree in (s, c) over the terms.
        let degs: Vec<u32> = th
            .pairs
            .iter()
            .map(|&(s, c, _)| {
                p.terms()
                    .iter()
                    .map(|(m, _)| m.degree(s) + m.degree(c))
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        // One pair at a time, terms grouped by their (s, c) exponents: the
        // t-image of s^a c^b depends on (a, b) only, so each group costs one
        // product. Expanding term by term and summing into one accumulator was
        // quadratic (cos(64 (x - y)): 2114 terms, 33 s).
        let mut acc = p.clone();
        for (i, &(s, c, t)) in th.pairs.iter().enumerate() {
            if degs[i] == 0 {
                continue;
            }
            let mut groups: BTreeMap<(u32, u32), Vec<(Mono, Int)>> = BTreeMap::new();
            for (m, k) in acc.terms() {
                let (a, r1) = m.split(s);
                let (b, rest) = r1.split(c);
                groups.entry((a, b)).or_default().push((rest, k.clone()));
            }
            let tt = Poly::var(t);
            let one_plus = Poly::one().add(&tt.mul(&tt));
            let one_minus = Poly::one().sub(&tt.mul(&tt));
            let two_t = tt.scale(&int(2));
            let mut parts = Vec::with_capacity(groups.len());
            for ((a, b), rest) in groups {
                let image = two_t
                    .pow(a)
                    .mul(&one_minus.pow(b))
                    .mul(&one_plus.pow(degs[i] - a - b));
                parts.push(Poly::from_terms(rest).mul(&image));
            }
            acc = sum_balanced(parts);
        }
        (acc, degs)
    }

    /// A form in the half-angle view (no sin/cos leaf; canonical by plain gcd).
    pub fn to_tan_half(&self, th: &TanHalf, r: &RatFun) -> RatFun {
        let (n, dn) = self.poly_to_tan_half(th, &r.num);
        let (d, dd) = self.poly_to_tan_half(th, &r.den);
        // num/den = (n/(1+t^2)^dn) / (d/(1+t^2)^dd)
        let mut num = n;
        let mut den = d;
        for (i, &(_, _, t)) in th.pairs.iter().enumerate() {
            let tt = Poly::var(t);
            let one_plus = Poly::one().add(&tt.mul(&tt));
            if dd[i] > dn[i] {
                num = num.mul(&one_plus.pow(dd[i] - dn[i]));
            } else if dn[i] > dd[i] {
                den = den.mul(&one_plus.pow(dn[i] - dd[i]));
            }
        }
        self.normalize(num, den)
    }

    /// Back from the half-angle view: `t = s/(1 + c)`; the result is canonical.
    pub fn from_tan_half(&self, th: &TanHalf, r: &RatFun) -> RatFun {
        let (mut nn, nd) = self.poly_from_tan_half(th, &r.num);
        let (mut dn, dd) = self.poly_from_tan_half(th, &r.den);
        // Reduce first (s^2 -> 1 - c^2): the images then carry the map's
        // spurious powers of (1 + c) as plain factors, since 1 + t^2 = 2/(1 + c).
        let (n, m) = self.reduce_poly(nn);
        nn = n;
        dn = dn.mul(&m);
        let (d, m) = self.reduce_poly(dn);
        dn = d;
        nn = nn.mul(&m);
        // Cancel those powers now: left in, they multiply the size of every
        // conjugate product of the rationalisation in `normalize` (a 15-term
        // denominator came back with 1472 terms and its norm never finished).
        let mut num_pow = Poly::one();
        let mut den_pow = Poly::one();
        for (i, &(_, c, _)) in th.pairs.iter().enumerate() {
            let one_plus_c = Poly::one().add(&Poly::var(c));
            let en = strip_factor(&mut nn, &one_plus_c) + dd[i];
            let ed = strip_factor(&mut dn, &one_plus_c) + nd[i];
            if en > ed {
                num_pow = num_pow.mul(&one_plus_c.pow(en - ed));
            } else if ed > en {
                den_pow = den_pow.mul(&one_plus_c.pow(ed - en));
            }
        }
        self.normalize(nn.mul(&num_pow), dn.mul(&den_pow))
    }

    /// `p(t)` with `t = s/(1+c)` for each pair: `(numerator, k)` with the
    /// value `numerator / prod (1+c)^k`.
    fn poly_from_tan_half(&self, th: &TanHalf, p: &Poly) -> (Poly, Vec<u32>) {
        let mut num = p.clone();
        let mut pows = Vec::with_capacity(th.pairs.len());
        for &(s, c, t) in &th.pairs {
            let deg = num.degree(t);
            if deg == 0 {
                pows.push(0);
                continue;
            }
            // s^e (1+c)^(deg-e) reduced at once with s^2 = (1-c)(1+c):
            // s^(e%2) (1-c)^(e/2) (1+c)^(deg-ceil(e/2)), and (1+c)^(deg/2)
            // divides every term. Expanding s^e first and reducing afterwards
            // swelled cos(64 (x - y)) to gigabytes.
            let low = deg / 2;
            pows.push(deg - low);
            let one_plus_c = Poly::one().add(&Poly::var(c));
            let one_minus_c = Poly::one().sub(&Poly::var(c));
            let parts = num
                .coeffs_in(t)
                .into_iter()
                .map(|(e, k)| {
                    k.mul_term(&Mono::var(s, e % 2), &int(1))
                        .mul(&one_minus_c.pow(e / 2))
                        .mul(&one_plus_c.pow(deg - e.div_ceil(2) - low))
                })
                .collect();
            num = sum_balanced(parts);
        }
        (num, pows)
    }

    /// Inverse through the half-angle view: cancel there (a UFD), then map
    /// back, so that only what truly remains in the denominator is rationalised.
    pub(crate) fn inv_via_tan_half(&self, a: &RatFun) -> RatFun {
        let th = TanHalf {
            pairs: self.half_angles.clone(),
        };
        let at = self.to_tan_half(&th, a);
        let inv = RatFun {
            num: at.den.clone(),
            den: at.num.clone(),
        };
        let inv = if inv.den.lc_is_negative() {
            RatFun {
                num: inv.num.neg(),
                den: inv.den.neg(),
            }
        } else {
            inv
        };
        self.from_tan_half(&th, &inv)
    }
}

/// Divide `p` by `f` as often as it goes; returns how often.
fn strip_factor(p: &mut Poly, f: &Poly) -> u32 {
    let mut k = 0;
    while !p.is_zero() && crate::budget::poll() {
        match p.div_exact(f) {
            Some(q) => {
                *p = q;
                k += 1;
            }
            None => break,
        }
    }
    k
}

/// Sum of many polynomials, pairwise (each term is merged O(log n) times).
fn sum_balanced(mut parts: Vec<Poly>) -> Poly {
    while parts.len() > 1 {
        let mut next = Vec::with_capacity(parts.len().div_ceil(2));
        let mut it = parts.into_iter();
        while let Some(a) = it.next() {
            next.push(match it.next() {
                Some(b) => a.add(&b),
                None => a,
            });
        }
        parts = next;
    }
    parts.pop().unwrap_or_default()
}
