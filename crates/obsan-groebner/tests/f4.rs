//! F4 against Buchberger's algorithm (the oracle): the reduced Gröbner basis
//! of an ideal is unique for a given order, so both must return the same
//! polynomials, term for term, on random ideals, Katsura-n and Cyclic-n.

use obsan_groebner::{buchberger, f4, groebner, Field, GbBudget, Mono, Order, Poly, Ring};
use proptest::prelude::*;

const P: u64 = 0x3fff_ffff_ffff_ffc7; // obsan-recon's PRIMES[0], the prime `obsan global` uses

fn same_basis(r: &Ring, gens: &[Poly]) {
    let a = f4(r, gens, GbBudget::default()).unwrap();
    let b = buchberger(r, gens, GbBudget::default()).unwrap();
    assert_eq!(a.polys, b.polys, "{:?}", r.order);
}

fn lin(r: &Ring, terms: &[(Vec<u32>, i64)]) -> Poly {
    r.from_terms(terms.iter().map(|(e, c)| {
        (
            Mono::from_exponents(e.clone()).unwrap(),
            r.field.from_i64(*c),
        )
    }))
}

/// Katsura-n in n + 1 variables u_0..u_n (the PoSSo suite): sum_{l=-n..n}
/// u_l u_{m-l} = u_m for m < n with u_{-l} = u_l, and u_0 + 2 sum u_l = 1.
fn katsura(r: &Ring, n: usize) -> Vec<Poly> {
    let idx = |l: i64| l.unsigned_abs() as usize;
    let mut out = Vec::new();
    for m in 0..n as i64 {
        let mut t: Vec<(Vec<u32>, i64)> = Vec::new();
        for l in -(n as i64)..=(n as i64) {
            let k = m - l;
            if k.unsigned_abs() as usize > n {
                continue;
            }
            let mut e = vec![0u32; n + 1];
            e[idx(l)] += 1;
            e[idx(k)] += 1;
            t.push((e, 1));
        }
        let mut e = vec![0u32; n + 1];
        e[idx(m)] = 1;
        t.push((e, -1));
        out.push(lin(r, &t));
    }
    let mut t: Vec<(Vec<u32>, i64)> = vec![(vec![0; n + 1], -1)];
    for l in 0..=n {
        let mut e = vec![0u32; n + 1];
        e[l] = 1;
        t.push((e, if l == 0 { 1 } else { 2 }));
    }
    out.push(lin(r, &t));
    out
}

/// Cyclic-n: the elementary cyclic sums of x_0..x_{n-1}, the last one minus 1.
fn cyclic(r: &Ring, n: usize) -> Vec<Poly> {
    (1..=n)
        .map(|d| {
            let mut t: Vec<(Vec<u32>, i64)> = (0..n)
                .map(|s| {
                    let mut e = vec![0u32; n];
                    for k in 0..d {
                        e[(s + k) % n] = 1;
                    }
                    (e, 1)
                })
                .collect();
            if d == n {
                t.truncate(1);
                t.push((vec![0; n], -1));
            }
            lin(r, &t)
        })
        .collect()
}

#[test]
fn katsura_and_cyclic_agree_with_buchberger() {
    let f = Field::new(P).unwrap();
    for order in [Order::Grevlex, Order::Lex, Order::Block(2)] {
        for n in 2..=4 {
            if order != Order::Grevlex && n == 4 {
                continue; // F4 under lex blows up the degrees (see f4.rs)
            }
            let r = Ring::new(f, n + 1, order);
            same_basis(&r, &katsura(&r, n));
        }
        for n in 3..=5 {
            if order != Order::Grevlex && n == 5 {
                continue; // as Katsura-4
            }
            let r = Ring::new(f, n, order);
            same_basis(&r, &cyclic(&r, n));
        }
    }
    // Katsura-n has 2^n solutions (Katsura 1990), Cyclic-5 has 70 (Björck and
    // Fröberg 1991): counts from the literature, not from either algorithm.
    let r = Ring::new(f, 5, Order::Grevlex);
    let b = groebner(&r, &katsura(&r, 4), GbBudget::default()).unwrap();
    assert_eq!(b.standard_monomials(1000).unwrap().len(), 16);
    let b = groebner(&r, &cyclic(&r, 5), GbBudget::default()).unwrap();
    assert_eq!(b.standard_monomials(1000).unwrap().len(), 70);
}

/// A random polynomial in `n` variables: up to `t` terms, each exponent up to
/// `d` (kept small: a lex basis of a random ideal grows with its Bézout
/// number, and the oracle must finish).
fn arb_poly(n: usize, t: usize, d: u32) -> impl Strategy<Value = Vec<(Vec<u32>, i64)>> {
    prop::collection::vec((prop::collection::vec(0..=d, n), -5i64..=5), 1..=t)
}

fn arb_order() -> impl Strategy<Value = Order> {
    prop_oneof![
        Just(Order::Grevlex),
        Just(Order::Lex),
        Just(Order::Block(1))
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
    /// The product by halves (`Ring::mul`, past 8 terms) against the sum of
    /// one-term products (`Ring::axpy`, one merge each) and against
    /// evaluation at a point, under every order; commutative.
    #[test]
    fn products_by_halves_are_products(
        a in arb_poly(3, 40, 3),
        b in arb_poly(3, 40, 3),
        x in prop::collection::vec(0u64..1 << 40, 3),
        order in arb_order(),
    ) {
        let f = Field::new((1 << 61) - 1).unwrap();
        let r = Ring::new(f, 3, order);
        let (pa, pb) = (lin(&r, &a), lin(&r, &b));
        let ab = r.mul(&pa, &pb).unwrap();
        let mut by_term = Poly::zero();
        for (m, c) in pa.terms() {
            by_term = r.axpy(&by_term, *c, m, &pb).unwrap();
        }
        prop_assert_eq!(&ab, &by_term);
        prop_assert_eq!(&ab, &r.mul(&pb, &pa).unwrap());
        prop_assert_eq!(r.eval(&ab, &x), f.mul(r.eval(&pa, &x), r.eval(&pb, &x)));
    }

    /// Grevlex (the order `obsan global` uses): exponents up to 2.
    #[test]
    fn random_ideals_agree_with_buchberger(
        gens in prop::collection::vec(arb_poly(3, 4, 2), 1..=4),
    ) {
        let r = Ring::new(Field::new(P).unwrap(), 3, Order::Grevlex);
        let gens: Vec<Poly> = gens.iter().map(|t| lin(&r, t)).collect();
        let a = f4(&r, &gens, GbBudget::default()).unwrap();
        let b = buchberger(&r, &gens, GbBudget::default()).unwrap();
        prop_assert_eq!(&a.polys, &b.polys);
    }

    /// Every order, multilinear generators (F4 under lex blows up the degrees
    /// of larger ones, see f4.rs; `groebner` uses Buchberger there).
    #[test]
    fn random_multilinear_ideals_agree_under_every_order(
        order in arb_order(),
        gens in prop::collection::vec(arb_poly(3, 4, 1), 1..=4),
    ) {
        let r = Ring::new(Field::new(P).unwrap(), 3, order);
        let gens: Vec<Poly> = gens.iter().map(|t| lin(&r, t)).collect();
        let a = f4(&r, &gens, GbBudget::default()).unwrap();
        let b = buchberger(&r, &gens, GbBudget::default()).unwrap();
        prop_assert_eq!(&a.polys, &b.polys);
        let c = groebner(&r, &gens, GbBudget::default()).unwrap();
        prop_assert_eq!(&c.polys, &b.polys);
    }
}

/// Cyclic-6 has 156 solutions (Björck and Fröberg 1991): F4's basis must
/// leave exactly that many standard monomials (a few ms; its speed is
/// measured in docs/performance.md, not here).
#[test]
fn cyclic_6_has_156_solutions() {
    let r = Ring::new(Field::new(P).unwrap(), 6, Order::Grevlex);
    let b = f4(&r, &cyclic(&r, 6), GbBudget::default()).unwrap();
    assert_eq!(b.standard_monomials(1000).unwrap().len(), 156);
}

/// F4 stores exponents packed in 16 bits: one that would not fit is
/// `GbError::Degree`, never a wrapped exponent (Buchberger, with 32-bit
/// exponents, is not bound by that width).
/// Derivation: for f1 = y^2 - x and f2 = x^a y - 1 (leading monomials y^2
/// and x^a y under grevlex, a >= 2), the only pair has lcm x^a y^2 and its
/// row x^a * f1 holds x^(a+1); the S-polynomial x^(a+1) - y then joins the
/// basis, whose monomials stay within exponent a + 1 (its remaining pair is
/// coprime or reduces to zero). So the run needs exponent a + 1 exactly:
/// Degree for a + 1 > 65535, Buchberger's basis otherwise; a generator
/// exponent past 65535 (a >= 65536) is refused on entry.
mod packed_width {
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]
        #[test]
        fn exponents_past_16_bits_are_a_degree_error(a in 65_520u32..=65_560) {
            let r = Ring::new(Field::new(P).unwrap(), 2, Order::Grevlex);
            let f1 = lin(&r, &[(vec![0, 2], 1), (vec![1, 0], -1)]);
            let f2 = lin(&r, &[(vec![a, 1], 1), (vec![0, 0], -1)]);
            let gens = [f1, f2];
            let got = f4(&r, &gens, GbBudget::default());
            if a + 1 > u16::MAX as u32 {
                prop_assert_eq!(got.err(), Some(obsan_groebner::GbError::Degree));
            } else {
                let b = buchberger(&r, &gens, GbBudget::default()).unwrap();
                prop_assert_eq!(&got.unwrap().polys, &b.polys);
            }
        }
    }
}

#[test]
fn the_work_bound_stops_f4_and_never_changes_a_basis() {
    // Cyclic-5 needs elimination work; a bound below it is an error naming
    // the work, never a partial basis; a bound above it gives the unbounded
    // basis term for term.
    let f = Field::new(P).unwrap();
    let r = Ring::new(f, 5, Order::Grevlex);
    let gens = cyclic(&r, 5);
    let full = f4(&r, &gens, GbBudget::default()).unwrap();
    let tight = GbBudget {
        max_work: 10,
        ..GbBudget::default()
    };
    match f4(&r, &gens, tight) {
        Err(obsan_groebner::GbError::Budget(w)) => assert!(w.starts_with("work"), "{w}"),
        other => panic!("expected the work bound, got {other:?}"),
    }
    let loose = GbBudget {
        max_work: 1 << 40,
        ..GbBudget::default()
    };
    assert_eq!(f4(&r, &gens, loose).unwrap().polys, full.polys);
}
