//! The modular gcd against independent computations: the heuristic gcd it
//! replaced, the primitive PRS, the Zippel gcd of the `zippel-gcd` crate (an
//! independent implementation on `polycore`), and the identity
//! gcd(a g, b g) = g gcd(a, b) up to sign.

use obsan_expr::{
    gcds::gcd, gcds::HeuristicGcd, gcds::ModularGcd, gcds::PolyGcd, gcds::PrsGcd,
    within_thread_budget, Budget, Int, Limit, Mono, Poly, SplitMix, Var,
};
use polycore::{Order, Ring};
use proptest::prelude::*;
use std::time::Instant;

/// A random polynomial: `nterms` terms in `nvars` variables, exponents up to
/// `maxdeg`, coefficients of up to `bits` bits with random signs (never zero).
fn rand_poly(rng: &mut SplitMix, nvars: u32, nterms: usize, maxdeg: u32, bits: usize) -> Poly {
    Poly::from_terms((0..nterms).map(|_| {
        let m = Mono::from_pairs(
            (0..nvars).map(|v| (v as Var, (rng.next_u64() % (maxdeg as u64 + 1)) as u32)),
        );
        let mut c = Int::from(1 + rng.next_u64() % 9);
        for _ in 0..bits / 64 {
            c = (c << 64) + Int::from(rng.next_u64());
        }
        if rng.next_u64().is_multiple_of(2) {
            c = -c;
        }
        (m, c)
    }))
}

/// Non-constant random polynomial (retries a few seeds).
fn rand_nonconst(rng: &mut SplitMix, nvars: u32, nterms: usize, maxdeg: u32, bits: usize) -> Poly {
    loop {
        let p = rand_poly(rng, nvars, nterms, maxdeg, bits);
        if !p.is_constant() {
            return p;
        }
    }
}

fn primitive(p: &Poly) -> Poly {
    let c = p.content();
    p.div_exact(&Poly::constant(c)).unwrap().normalize_sign()
}

fn same_up_to_sign(a: &Poly, b: &Poly) -> bool {
    a == b || *a == b.neg()
}

/// `p` as text for polycore's parser over variables x0, x1, ...
fn text(p: &Poly) -> String {
    if p.is_zero() {
        return "0".into();
    }
    let mut s = String::new();
    for (i, (m, c)) in p.terms().iter().enumerate() {
        if i > 0 {
            s.push_str(" + ");
        }
        s.push_str(&format!("({c})"));
        for (v, e) in m.iter() {
            s.push_str(&format!("*x{v}^{e}"));
        }
    }
    s
}

/// The oracle: `zippel_gcd::zippel` (called explicitly, per crates.md), then
/// compared with the primitive part of ours up to sign.
fn agrees_with_zippel(a: &Poly, b: &Poly, g: &Poly, nvars: u32) -> bool {
    let ring = Ring::new((0..nvars).map(|i| format!("x{i}")), Order::Lex);
    let (za, zb) = (ring.parse(&text(a)).unwrap(), ring.parse(&text(b)).unwrap());
    let z = zippel_gcd::zippel(&za, &zb);
    let ours = ring.parse(&text(&primitive(g))).unwrap();
    z == ours || z == -&ours
}

/// Every property a gcd must have, checked without trusting the gcd itself
/// except for the cofactor test, which is done by the heuristic gcd; the
/// engine's gcd and the modular gcd alone must agree.
fn check_gcd(a: &Poly, b: &Poly, planted: &Poly) -> Poly {
    let g = gcd(a, b);
    assert_eq!(g, ModularGcd.gcd(a, b), "engine and modular gcd differ");
    assert!(!g.is_zero());
    assert!(!g.lc_is_negative(), "normalised sign");
    let (ca, cb) = (
        a.div_exact(&g).expect("g | a"),
        b.div_exact(&g).expect("g | b"),
    );
    assert!(
        g.div_exact(planted).is_some(),
        "planted factor divides the gcd"
    );
    assert!(HeuristicGcd.gcd(&ca, &cb).is_one(), "cofactors coprime");
    g
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// The modular gcd gives exactly the heuristic gcd's answer (same
    /// normalisation), and the planted factor divides it.
    #[test]
    fn modular_agrees_with_heuristic(seed in any::<u64>(), nvars in 1u32..5, deg in 1u32..4) {
        let mut rng = SplitMix(seed);
        let g = rand_nonconst(&mut rng, nvars, 3, deg, 1);
        let a = rand_poly(&mut rng, nvars, 4, deg, 1);
        let b = rand_poly(&mut rng, nvars, 4, deg, 1);
        prop_assume!(!a.is_zero() && !b.is_zero());
        let (ga, gb) = (g.mul(&a), g.mul(&b));
        let m = ModularGcd.gcd(&ga, &gb);
        prop_assert_eq!(&m, &HeuristicGcd.gcd(&ga, &gb));
        check_gcd(&ga, &gb, &g);
    }

    /// gcd(a g, b g) = g gcd(a, b) up to sign (Gauss's lemma: contents included).
    #[test]
    fn gcd_is_multiplicative(seed in any::<u64>(), nvars in 2u32..5) {
        let mut rng = SplitMix(seed);
        let g = rand_nonconst(&mut rng, nvars, 3, 2, 20);
        let a = rand_nonconst(&mut rng, nvars, 3, 2, 1).scale(&Int::from(6));
        let b = rand_nonconst(&mut rng, nvars, 3, 2, 1).scale(&Int::from(-4));
        let lhs = gcd(&a.mul(&g), &b.mul(&g));
        let rhs = g.mul(&gcd(&a, &b));
        prop_assert!(same_up_to_sign(&lhs, &rhs), "{:?} vs {:?}", lhs, rhs);
    }

    /// Against the independent Zippel implementation of zippel-gcd.
    #[test]
    fn modular_agrees_with_zippel_oracle(seed in any::<u64>(), nvars in 2u32..6) {
        let mut rng = SplitMix(seed);
        let g = rand_nonconst(&mut rng, nvars, 3, 2, 8);
        let a = rand_nonconst(&mut rng, nvars, 3, 2, 8);
        let b = rand_nonconst(&mut rng, nvars, 3, 2, 8);
        let (ga, gb) = (g.mul(&a), g.mul(&b));
        let m = check_gcd(&ga, &gb, &g);
        prop_assert!(agrees_with_zippel(&ga, &gb, &m, nvars));
    }
}

#[test]
fn agrees_with_prs_and_zippel_on_small_structured_cases() {
    let x = |v: Var| Poly::var(v);
    let c = |n: i64| Poly::constant(Int::from(n));
    // (x0 + x1)^2 (x0 - 2 x2) and (x0 + x1)(x0^2 + x2)(x0 - 2 x2)^2.
    let s = x(0).add(&x(1));
    let t = x(0).sub(&x(2).scale(&Int::from(2)));
    let a = s.pow(2).mul(&t);
    let b = s.mul(&x(0).pow(2).add(&x(2))).mul(&t.pow(2));
    let g = gcd(&a, &b);
    assert_eq!(g, s.mul(&t).normalize_sign());
    assert_eq!(g, PrsGcd.gcd(&a, &b));
    assert!(agrees_with_zippel(&a, &b, &g, 3));
    // Integer contents multiply in: gcd(6 (x0 x1 - 1)^3, -4 (x0 x1 - 1)(x2 - 1)).
    let u = x(0).mul(&x(1)).sub(&c(1));
    let a = u.pow(3).scale(&Int::from(6));
    let b = u.mul(&x(2).sub(&c(1))).scale(&Int::from(-4));
    assert_eq!(gcd(&a, &b), u.scale(&Int::from(2)).normalize_sign());
    // Non-monic leading coefficients in every variable (needs the lc correction).
    let g = x(0)
        .mul(&x(1))
        .scale(&Int::from(3))
        .add(&x(2).pow(2).scale(&Int::from(5)))
        .add(&c(7));
    let a = g.mul(&x(0).scale(&Int::from(2)).mul(&x(2)).add(&c(1)));
    let b = g.mul(&x(1).pow(2).scale(&Int::from(4)).sub(&x(0)));
    assert_eq!(gcd(&a, &b), g.clone().normalize_sign());
    assert_eq!(gcd(&a, &b), PrsGcd.gcd(&a, &b));
}

/// Coefficients of about 600 bits: many primes, CRT, and a proof by division.
#[test]
fn big_coefficients() {
    let mut rng = SplitMix(7);
    for nvars in [1u32, 2, 3] {
        for _ in 0..4 {
            let g = rand_nonconst(&mut rng, nvars, 4, 3, 600);
            let a = rand_nonconst(&mut rng, nvars, 4, 3, 300);
            let b = rand_nonconst(&mut rng, nvars, 4, 3, 300);
            let (ga, gb) = (g.mul(&a), g.mul(&b));
            let m = check_gcd(&ga, &gb, &g);
            assert_eq!(m, HeuristicGcd.gcd(&ga, &gb));
            assert!(agrees_with_zippel(&ga, &gb, &m, nvars));
            // gcd(a g, b g) = g gcd(a, b).
            assert!(same_up_to_sign(&m, &g.mul(&gcd(&a, &b))));
        }
    }
}

/// Eight variables, sparse, with the modular gcd interpolating densely in all
/// but one (so low degrees: its cost is about the product of the degrees).
#[test]
fn many_variables() {
    let mut rng = SplitMix(99);
    for nvars in [6u32, 8] {
        for _ in 0..3 {
            let g = rand_nonconst(&mut rng, nvars, 4, 1, 4);
            let a = rand_nonconst(&mut rng, nvars, 4, 1, 4);
            let b = rand_nonconst(&mut rng, nvars, 4, 1, 4);
            let (ga, gb) = (g.mul(&a), g.mul(&b));
            let m = check_gcd(&ga, &gb, &g);
            assert!(agrees_with_zippel(&ga, &gb, &m, nvars));
        }
    }
}

/// A passed deadline is a `Limit::Timeout`, never an answer.
#[test]
fn deadline_is_an_error() {
    let mut rng = SplitMix(3);
    let g = rand_nonconst(&mut rng, 3, 12, 5, 200);
    let a = rand_nonconst(&mut rng, 3, 12, 5, 200);
    let b = rand_nonconst(&mut rng, 3, 12, 5, 200);
    let (ga, gb) = (g.mul(&a), g.mul(&b));
    let budget = Budget {
        deadline: Some(Instant::now()),
        ..Budget::default()
    };
    let r = within_thread_budget(&budget, || gcd(&ga, &gb));
    assert_eq!(r, Err(Limit::Timeout));
    let r = within_thread_budget(&budget, || ModularGcd.gcd(&ga, &gb));
    assert_eq!(r, Err(Limit::Timeout));
    // And without the deadline the same call is exact.
    check_gcd(&ga, &gb, &g);
}
