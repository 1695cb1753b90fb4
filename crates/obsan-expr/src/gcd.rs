//! Multivariate gcd over Z: the one hard kernel of the canonical form.
//!
//! Strategy, cheapest first (each step is exact):
//! 1. trivial cases, monomial and integer content;
//! 2. a variable in only one argument: gcd with that argument's content in it;
//! 3. a modular coprimality proof: for each variable x, substitute random
//!    F_p values for the others; if lc_x does not vanish, the degree in x of
//!    the true gcd is at most that of the image gcd. All images of degree 0
//!    prove the primitive parts coprime (no probability involved);
//! 4. the heuristic gcd of Char, Geddes and Gonnet
//!    (evaluate the main variable at a large integer, recurse, rebuild by
//!    xi-adic expansion, verify by exact division) for coefficients of at most
//!    128 bits while its integer images stay below 2^20 bits: on such inputs
//!    it is as fast as the modular gcd or faster;
//! 5. Brown's modular gcd (`gcd_modular.rs`): images modulo 62-bit primes and
//!    at random points, rebuilt by interpolation and CRT, proven by exact
//!    division; unlucky primes and points are detected and skipped;
//! 6. the primitive polynomial remainder sequence, which always succeeds
//!    (reached only if the modular gcd gives up: a tripped budget).
//!
//! Before the modular gcd the heuristic gcd ran with images up to 2^26 bits
//! and then the PRS; that chain stays as [`HeuristicGcd`] for comparison.

use crate::budget::{self, invariant};
use crate::num::{int, int_gcd, int_symmetric_mod, Fp, Int, SplitMix};
use crate::poly::{Mono, Poly, Var};
use dashu_int::ops::{BitTest, SquareRoot};
use dashu_int::UBig;
use std::ops::{Mul, Sub};

/// The gcd interface of the canonical form, so that another implementation
/// (a crate, or a faster algorithm) can be put behind it and tested against ours.
pub trait PolyGcd {
    /// Greatest common divisor with positive leading coefficient (zero iff both are zero).
    fn gcd(&self, a: &Poly, b: &Poly) -> Poly;
}

/// The engine's gcd, [`gcd`] (see the module documentation).
#[derive(Default, Clone, Copy, Debug)]
pub struct EngineGcd;

impl PolyGcd for EngineGcd {
    fn gcd(&self, a: &Poly, b: &Poly) -> Poly {
        gcd(a, b)
    }
}

/// The shortcuts, then the modular gcd alone (no heuristic gcd): what the
/// engine's gcd uses past small integer images, exposed for tests and benches.
#[derive(Default, Clone, Copy, Debug)]
pub struct ModularGcd;

impl PolyGcd for ModularGcd {
    fn gcd(&self, a: &Poly, b: &Poly) -> Poly {
        gcd_with(a, b, Method::Modular)
    }
}

/// The same shortcuts with the heuristic gcd in place of the modular one (the
/// engine's gcd before the modular one), for comparison and benchmarks.
#[derive(Default, Clone, Copy, Debug)]
pub struct HeuristicGcd;

impl PolyGcd for HeuristicGcd {
    fn gcd(&self, a: &Poly, b: &Poly) -> Poly {
        gcd_with(a, b, Method::Heuristic)
    }
}

/// The always-correct but slow reference gcd (primitive PRS), for tests.
#[derive(Default, Clone, Copy, Debug)]
pub struct PrsGcd;

impl PolyGcd for PrsGcd {
    fn gcd(&self, a: &Poly, b: &Poly) -> Poly {
        gcd_with(a, b, Method::Prs)
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Method {
    Fast,
    Modular,
    Heuristic,
    Prs,
}

/// Greatest common divisor, normalised to a positive leading coefficient.
pub fn gcd(a: &Poly, b: &Poly) -> Poly {
    gcd_with(a, b, Method::Fast)
}

fn gcd_with(a: &Poly, b: &Poly, method: Method) -> Poly {
    if a.is_zero() {
        return b.clone().normalize_sign();
    }
    if b.is_zero() {
        return a.clone().normalize_sign();
    }
    if a == b {
        return a.clone().normalize_sign();
    }
    // Monomial content.
    let (ma, mb) = (a.mono_content(), b.mono_content());
    let mg = ma.gcd(&mb);
    // Integer content.
    let (ca, cb) = (a.content(), b.content());
    let cg = int_gcd(&ca, &cb);
    let pa = strip(a, &ma, &ca);
    let pb = strip(b, &mb, &cb);
    let g = if pa.is_constant() || pb.is_constant() {
        Poly::one()
    } else {
        primitive_gcd(&pa, &pb, method)
    };
    g.mul_term(&mg, &cg).normalize_sign()
}

fn strip(p: &Poly, m: &Mono, c: &Int) -> Poly {
    let q = if m.is_one() { p.clone() } else { p.div_mono(m) };
    if c.is_one() {
        q
    } else {
        invariant(q.div_exact(&Poly::constant(c.clone())), "content divides")
    }
}

/// Gcd of two non-constant polynomials with trivial integer and monomial content.
fn primitive_gcd(a: &Poly, b: &Poly, method: Method) -> Poly {
    let (va, vb) = (a.vars(), b.vars());
    // A variable present in only one argument: the gcd lies in its content.
    if let Some(&x) = va.iter().find(|v| !vb.contains(v)) {
        return gcd_with_content(b, a, x, method);
    }
    if let Some(&x) = vb.iter().find(|v| !va.contains(v)) {
        return gcd_with_content(a, b, x, method);
    }
    if method != Method::Prs && images_prove_coprime(a, b, &va) {
        return Poly::one();
    }
    let fast = match method {
        // Small integer images: the heuristic gcd is the cheapest exact
        // answer; past them the modular gcd takes over.
        Method::Fast => {
            let bits = a.max_abs_coeff().bit_len().min(b.max_abs_coeff().bit_len());
            (bits <= FAST_HEURISTIC_MAX_COEFF_BITS)
                .then(|| heuristic(a, b, &va, FAST_HEURISTIC_MAX_BITS, method))
                .flatten()
                .or_else(|| crate::gcd_modular::modular_gcd(a, b))
        }
        Method::Modular => crate::gcd_modular::modular_gcd(a, b),
        Method::Heuristic => heuristic(a, b, &va, HEURISTIC_MAX_BITS, method),
        Method::Prs => None,
    };
    if let Some(g) = fast {
        return g;
    }
    prs(a, b, va[0], method)
}

/// gcd(other, content_x(p)), where x does not occur in `other`.
fn gcd_with_content(other: &Poly, p: &Poly, x: Var, method: Method) -> Poly {
    let mut g = other.clone();
    for (_, c) in p.coeffs_in(x) {
        g = gcd_with(&g, &c, method);
        if g.is_constant() {
            break;
        }
    }
    g
}

/// Largest degree for which the dense image test is tried.
const IMAGE_MAX_DEGREE: u32 = 1 << 16;

/// Largest `degree * bits(xi)` for which the heuristic gcd is tried (its
/// integer images have about that many bits).
const HEURISTIC_MAX_BITS: u64 = 1 << 26;

/// The same bound when the modular gcd is there to take over. On the small
/// inputs of canonical forms the heuristic gcd is as fast or faster (the
/// engine and gcd benches); at a megabit its integer gcds take about a
/// second, and the modular gcd's cost does not grow with the coefficients.
const FAST_HEURISTIC_MAX_BITS: u64 = 1 << 20;

/// Coefficients of more bits than this go to the modular gcd at once: the
/// heuristic's evaluation point exceeds them, so its images grow with them
/// (benches/gcd.rs: 3200-bit coefficients, 3.4 s heuristic, 0.15 s modular).
const FAST_HEURISTIC_MAX_COEFF_BITS: usize = 128;

/// Exact proof of coprimality by univariate images modulo p (see module docs).
fn images_prove_coprime(a: &Poly, b: &Poly, vars: &[Var]) -> bool {
    let mut rng = SplitMix(0x5eed_0b5a_u64 ^ (a.len() as u64) << 20 ^ b.len() as u64);
    let vals: Vec<(Var, Fp)> = vars.iter().map(|&v| (v, rng.fp())).collect();
    let val = |v: Var| {
        vals.iter()
            .find(|(x, _)| *x == v)
            .map(|(_, f)| *f)
            .unwrap_or(Fp::ZERO)
    };
    for &x in vars {
        // Dense images: beyond this degree leave the proof to the PRS.
        if a.degree(x).max(b.degree(x)) > IMAGE_MAX_DEGREE {
            return false;
        }
        let ia = a.univariate_image(x, &val);
        let ib = b.univariate_image(x, &val);
        // Degrees must survive the substitution for the bound to hold.
        if ia.last().is_none_or(|c| c.is_zero()) || ib.last().is_none_or(|c| c.is_zero()) {
            return false;
        }
        if uni_gcd_degree(ia, ib) > 0 {
            return false;
        }
    }
    true
}

fn trim(p: &mut Vec<Fp>) {
    while p.last().is_some_and(|c| c.is_zero()) {
        p.pop();
    }
}

/// Degree of the gcd of two dense polynomials over F_p.
fn uni_gcd_degree(mut a: Vec<Fp>, mut b: Vec<Fp>) -> usize {
    trim(&mut a);
    trim(&mut b);
    // `b` is trimmed, so its last coefficient is nonzero and invertible.
    while let Some(inv) = b.last().and_then(|l| l.inv()) {
        if !budget::poll() {
            return 1;
        }
        // a mod b
        while a.len() >= b.len() {
            let Some(&top) = a.last() else { break };
            let c = top.mul(inv);
            let shift = a.len() - b.len();
            for (i, bi) in b.iter().enumerate() {
                a[shift + i] = a[shift + i].sub(c.mul(*bi));
            }
            trim(&mut a);
            if a.is_empty() {
                break;
            }
        }
        std::mem::swap(&mut a, &mut b);
    }
    a.len().saturating_sub(1)
}

/// Heuristic gcd; `None` after six failed evaluation points or past
/// `max_bits`. The gcds of the integer images use `method`.
fn heuristic(a: &Poly, b: &Poly, vars: &[Var], max_bits: u64, method: Method) -> Option<Poly> {
    let x = vars[0];
    let na = a.max_abs_coeff();
    let nb = b.max_abs_coeff();
    let m = if na < nb { na } else { nb };
    let mut xi: Int = m * int(2) + int(29);
    let deg = a.degree(x).max(b.degree(x)) as u64;
    for _ in 0..6 {
        if deg.saturating_mul(xi.bit_len() as u64) > max_bits || !budget::poll() {
            return None;
        }
        let ea = a.eval_var(x, &xi);
        let eb = b.eval_var(x, &xi);
        if !ea.is_zero() && !eb.is_zero() {
            let h = gcd_with(&ea, &eb, method);
            let cand = primitive_part(&interpolate(&h, &xi, x));
            if !cand.is_constant() || cand.is_one() {
                if let (Some(_), Some(_)) = (a.div_exact(&cand), b.div_exact(&cand)) {
                    return Some(cand.normalize_sign());
                }
            }
            // Cofactor variants.
            for (p, q, e) in [(a, b, &ea), (b, a, &eb)] {
                if let Some(cof) = e.div_exact(&h) {
                    let cf = interpolate(&cof, &xi, x);
                    if cf.is_zero() {
                        continue;
                    }
                    if let Some(g) = p.div_exact(&cf) {
                        let g = primitive_part(&g);
                        if !g.is_zero() && q.div_exact(&g).is_some() {
                            return Some(g.normalize_sign());
                        }
                    }
                }
            }
        }
        // xi <- xi * 73794 * sqrt(sqrt(xi)) / 27011, as in the literature.
        let u: UBig = UBig::try_from(xi.clone()).ok()?;
        let r = u.sqrt().sqrt();
        xi = (&xi * int(73794) * Int::from(r)) / int(27011);
    }
    None
}

fn primitive_part(p: &Poly) -> Poly {
    let c = p.content();
    if c.is_zero() || c.is_one() {
        p.clone()
    } else {
        invariant(p.div_exact(&Poly::constant(c)), "content divides")
    }
}

/// xi-adic reconstruction: the polynomial in `x` whose value at xi is `h`,
/// with coefficients in the symmetric range.
fn interpolate(h: &Poly, xi: &Int, x: Var) -> Poly {
    let mut rest = h.clone();
    let mut terms = Vec::new();
    let mut e = 0u32;
    while !rest.is_zero() {
        let digit = Poly::from_terms(
            rest.terms()
                .iter()
                .map(|(m, c)| (m.clone(), int_symmetric_mod(c, xi))),
        );
        for (m, c) in digit.terms() {
            terms.push((m.mul(&Mono::var(x, e)), c.clone()));
        }
        rest = invariant(
            rest.sub(&digit).div_exact(&Poly::constant(xi.clone())),
            "digit removed",
        );
        e += 1;
        if e > 0xFFFF {
            return Poly::zero();
        }
    }
    Poly::from_terms(terms)
}

/// Primitive polynomial remainder sequence in the main variable `x`.
fn prs(a: &Poly, b: &Poly, x: Var, method: Method) -> Poly {
    let content = |p: &Poly| {
        let mut g = Poly::zero();
        for (_, c) in p.coeffs_in(x) {
            g = gcd_with(&g, &c, method);
            if g.is_one() {
                break;
            }
        }
        g
    };
    let (ca, cb) = (content(a), content(b));
    let c = gcd_with(&ca, &cb, method);
    let mut f = invariant(a.div_exact(&ca), "content divides");
    let mut g = invariant(b.div_exact(&cb), "content divides");
    if f.degree(x) < g.degree(x) {
        std::mem::swap(&mut f, &mut g);
    }
    while !g.is_zero() && budget::poll() {
        if g.degree(x) == 0 {
            // Primitive in x and of degree 0: a unit.
            f = Poly::one();
            break;
        }
        let r = pseudo_rem(&f, &g, x);
        f = g;
        g = if r.is_zero() {
            r
        } else {
            invariant(r.div_exact(&content(&r)), "content divides")
        };
    }
    let pp = invariant(f.div_exact(&content(&f)), "content divides");
    c.mul(&pp).normalize_sign()
}

/// Pseudo-remainder of f by g in variable x.
fn pseudo_rem(f: &Poly, g: &Poly, x: Var) -> Poly {
    let dg = g.degree(x);
    let Some(lg) = g.coeffs_in(x).first().map(|c| c.1.clone()) else {
        return Poly::zero();
    };
    let mut r = f.clone();
    while !r.is_zero() && r.degree(x) >= dg && budget::poll() {
        let dr = r.degree(x);
        let Some(lr) = r.coeffs_in(x).first().map(|c| c.1.clone()) else {
            break;
        };
        let shift = Poly::monomial(Mono::var(x, dr - dg), int(1));
        r = r.mul(&lg).sub(&lr.mul(&shift).mul(g));
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::num::SplitMix;

    fn rand_poly(rng: &mut SplitMix, nvars: u32, nterms: usize, maxdeg: u32) -> Poly {
        Poly::from_terms((0..nterms).map(|_| {
            let mut m = Mono::one();
            for v in 0..nvars {
                let e = (rng.next_u64() % (maxdeg as u64 + 1)) as u32;
                m = m.mul(&Mono::var(v, e));
            }
            let c = (rng.next_u64() % 19) as i64 - 9;
            (m, int(if c == 0 { 1 } else { c }))
        }))
    }

    #[test]
    fn gcd_recovers_planted_factor() {
        let mut rng = SplitMix(42);
        for round in 0..60 {
            let nv = 1 + (round % 4) as u32;
            let g = rand_poly(&mut rng, nv, 3, 2);
            let a = rand_poly(&mut rng, nv, 3, 2);
            let b = rand_poly(&mut rng, nv, 3, 2);
            if g.is_zero() || a.is_zero() || b.is_zero() {
                continue;
            }
            let (ga, gb) = (g.mul(&a), g.mul(&b));
            let h = gcd(&ga, &gb);
            let h2 = PrsGcd.gcd(&ga, &gb);
            assert_eq!(h, h2, "fast and PRS gcd disagree");
            // g divides the gcd, and the gcd divides both.
            assert!(
                h.div_exact(&g.clone().normalize_sign()).is_some()
                    || h.div_exact(&g.neg()).is_some()
            );
            let ca = ga.div_exact(&h).expect("gcd divides a");
            let cb = gb.div_exact(&h).expect("gcd divides b");
            // Cofactors are coprime.
            assert!(gcd(&ca, &cb).is_constant());
        }
    }

    #[test]
    fn coprime_and_trivial_cases() {
        let x = Poly::var(0);
        let y = Poly::var(1);
        let one = Poly::one();
        assert_eq!(gcd(&x, &y), one);
        assert_eq!(gcd(&x.mul(&y), &x.pow(2)), x);
        let six = Poly::constant(int(6));
        assert_eq!(
            gcd(&six.mul(&x), &Poly::constant(int(-4)).mul(&x)),
            Poly::constant(int(2)).mul(&x)
        );
        let p = x.add(&y);
        let q = x.sub(&y);
        assert_eq!(gcd(&p.mul(&q), &p.pow(2).neg()), p);
        assert_eq!(gcd(&Poly::zero(), &q.neg()), q.clone().normalize_sign());
    }
}
