//! Solution counts of classical systems, with the counts from the literature.

use obsan_groebner::{
    distinct_roots, eliminate_to, groebner, Field, GbBudget, Mono, Order, Poly, Ring,
};

const P: u64 = (1 << 61) - 1;

/// Parses "c*x0^a*x1^b + ..." with integer c (tests only).
fn poly(r: &Ring, s: &str) -> Poly {
    let mut terms = Vec::new();
    let s = s.replace(' ', "").replace('-', "+-");
    for t in s.split('+').filter(|t| !t.is_empty()) {
        let mut c: i64 = 1;
        let mut e = vec![0u32; r.n];
        for f in t.split('*') {
            if let Some(rest) = f.strip_prefix('x') {
                let (v, k) = match rest.split_once('^') {
                    Some((v, k)) => (v.parse::<usize>().unwrap(), k.parse::<u32>().unwrap()),
                    None => (rest.parse::<usize>().unwrap(), 1),
                };
                e[v] += k;
            } else if f == "-" {
                c = -c;
            } else if let Some(rest) = f.strip_prefix("-x") {
                c = -c;
                let (v, k) = match rest.split_once('^') {
                    Some((v, k)) => (v.parse::<usize>().unwrap(), k.parse::<u32>().unwrap()),
                    None => (rest.parse::<usize>().unwrap(), 1),
                };
                e[v] += k;
            } else {
                c *= f.parse::<i64>().unwrap();
            }
        }
        terms.push((Mono::from_exponents(e).unwrap(), r.field.from_i64(c)));
    }
    r.from_terms(terms)
}

fn ring(n: usize) -> Ring {
    Ring::new(Field::new(P).unwrap(), n, Order::Grevlex)
}

#[test]
fn katsura_3_has_8_solutions() {
    // Katsura-n has 2^n solutions (Katsura 1990; the PoSSo test suite).
    let r = ring(4);
    let g = [
        poly(&r, "x0 + 2*x1 + 2*x2 + 2*x3 - 1"),
        poly(&r, "x0^2 + 2*x1^2 + 2*x2^2 + 2*x3^2 - x0"),
        poly(&r, "2*x0*x1 + 2*x1*x2 + 2*x2*x3 - x1"),
        poly(&r, "x1^2 + 2*x0*x2 + 2*x1*x3 - x2"),
    ];
    let b = groebner(&r, &g, GbBudget::default()).unwrap();
    assert!(b.is_zero_dimensional());
    assert_eq!(b.standard_monomials(1000).unwrap().len(), 8);
    for p in &g {
        assert!(b.contains(p).unwrap());
    }
    // The last variable separates the 8 solutions.
    let m = b.minimal_polynomial(&r.var(3), 1000).unwrap();
    assert_eq!(m.len() - 1, 8);
    assert_eq!(distinct_roots(r.field, &m), 8);
}

#[test]
fn cyclic_5_has_70_solutions() {
    // Cyclic-5: 70 solutions (Björck and Fröberg 1991).
    let r = ring(5);
    let g = [
        poly(&r, "x0 + x1 + x2 + x3 + x4"),
        poly(&r, "x0*x1 + x1*x2 + x2*x3 + x3*x4 + x4*x0"),
        poly(&r, "x0*x1*x2 + x1*x2*x3 + x2*x3*x4 + x3*x4*x0 + x4*x0*x1"),
        poly(
            &r,
            "x0*x1*x2*x3 + x1*x2*x3*x4 + x2*x3*x4*x0 + x3*x4*x0*x1 + x4*x0*x1*x2",
        ),
        poly(&r, "x0*x1*x2*x3*x4 - 1"),
    ];
    let b = groebner(&r, &g, GbBudget::default()).unwrap();
    assert_eq!(b.standard_monomials(1000).unwrap().len(), 70);
}

#[test]
fn multiple_roots_and_elimination() {
    // (x - 1)^2 (x + 2) = 0, y = x^2: x has 2 distinct values, y too (1 and 4);
    // the quotient has dimension 3 (a double root).
    let r = ring(2);
    let g = [poly(&r, "x0^3 - 3*x0 + 2"), poly(&r, "x1 - x0^2")];
    let b = groebner(&r, &g, GbBudget::default()).unwrap();
    assert_eq!(b.standard_monomials(100).unwrap().len(), 3);
    let m = b.minimal_polynomial(&r.var(0), 100).unwrap();
    assert_eq!(distinct_roots(r.field, &m), 2);
    let e = eliminate_to(r.field, 2, &g, 1, GbBudget::default())
        .unwrap()
        .unwrap();
    assert_eq!(distinct_roots(r.field, &e), 2);
    // y ∈ {1, 4}: the radical of the elimination ideal is (y - 1)(y - 4).
    assert_eq!(r.eval(&poly(&r, "x1 - 1"), &[0, 1]), 0);
}

#[test]
fn positive_dimension_and_unit_ideal() {
    // x*y = 1 alone: a curve, x takes infinitely many values.
    let r = ring(2);
    let g = [poly(&r, "x0*x1 - 1")];
    let b = groebner(&r, &g, GbBudget::default()).unwrap();
    assert!(!b.is_zero_dimensional());
    assert_eq!(
        eliminate_to(r.field, 2, &g, 0, GbBudget::default()).unwrap(),
        None
    );
    // x = 1 and x = 2: no common zero.
    let u = groebner(
        &r,
        &[poly(&r, "x0 - 1"), poly(&r, "x0 - 2")],
        GbBudget::default(),
    )
    .unwrap();
    assert!(u.is_unit());
}

#[test]
fn budget_is_an_error() {
    let r = ring(5);
    let g = [
        poly(&r, "x0 + x1 + x2 + x3 + x4"),
        poly(&r, "x0*x1 + x1*x2 + x2*x3 + x3*x4 + x4*x0"),
        poly(&r, "x0*x1*x2 + x1*x2*x3 + x2*x3*x4 + x3*x4*x0 + x4*x0*x1"),
        poly(
            &r,
            "x0*x1*x2*x3 + x1*x2*x3*x4 + x2*x3*x4*x0 + x3*x4*x0*x1 + x4*x0*x1*x2",
        ),
        poly(&r, "x0*x1*x2*x3*x4 - 1"),
    ];
    let tight = GbBudget {
        max_pairs: 5,
        ..GbBudget::default()
    };
    assert!(groebner(&r, &g, tight).is_err());
}

/// Buchberger's criterion checked from outside: every S-polynomial of the
/// basis reduces to zero and every generator lies in the ideal, under each order.
#[test]
fn bases_of_random_systems_satisfy_buchbergers_criterion() {
    let mut seed: u64 = 0x1234_5678;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    for order in [Order::Grevlex, Order::Lex, Order::Block(2)] {
        for _ in 0..6 {
            let r = Ring::new(Field::new(P).unwrap(), 3, order);
            // Three random dense quadrics in 3 variables.
            let gens: Vec<Poly> = (0..3)
                .map(|_| {
                    let mut terms = Vec::new();
                    for a in 0..3u32 {
                        for b in 0..(3 - a) {
                            for c in 0..(3 - a - b) {
                                terms.push((
                                    Mono::from_exponents(vec![a, b, c]).unwrap(),
                                    next() % 7,
                                ));
                            }
                        }
                    }
                    r.from_terms(terms)
                })
                .collect();
            let b = groebner(&r, &gens, GbBudget::default()).unwrap();
            for g in &gens {
                assert!(b.contains(g).unwrap());
            }
            for i in 0..b.polys.len() {
                for j in i + 1..b.polys.len() {
                    let (mi, mj) = (&b.polys[i].terms()[0].0, &b.polys[j].terms()[0].0);
                    let l = mi.lcm(mj);
                    let s = r
                        .axpy(&Poly::zero(), 1, &mi.quotient(&l), &b.polys[i])
                        .unwrap();
                    let s = r
                        .axpy(&s, r.field.neg(1), &mj.quotient(&l), &b.polys[j])
                        .unwrap();
                    assert!(b.reduce(&s).unwrap().is_zero(), "{order:?}");
                }
            }
            // Three generic quadrics in 3 variables: 2^3 = 8 solutions (Bézout).
            assert_eq!(b.standard_monomials(100).unwrap().len(), 8, "{order:?}");
        }
    }
}
