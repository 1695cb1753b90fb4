//! Property tests: random sparse rational functions, reconstructed exactly.

mod common;

use common::{eval, is_canonical, same_function, Terms};
use dashu_int::IBig;
use obsan_recon::{fp, reconstruct, reconstruct_vec, Options, Thiele, Univariate, PRIMES};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// A sparse polynomial in `n` variables: up to `terms` terms of total degree
/// at most `deg`, coefficients small or up to ~2^120.
fn poly(n: usize, terms: usize, deg: u32) -> impl Strategy<Value = Terms> {
    let term = (
        prop::collection::vec(0..=deg, n),
        prop_oneof![
            3 => (-50i64..=50).prop_map(IBig::from),
            1 => (any::<i64>(), any::<u64>()).prop_map(|(a, b)| (IBig::from(a) << 64) + IBig::from(b)),
        ],
    )
        .prop_map(move |(mut e, c)| {
            // Scale the exponents down to total degree <= deg.
            while e.iter().sum::<u32>() > deg {
                if let Some(x) = e.iter_mut().find(|x| **x > 0) {
                    *x -= 1;
                }
            }
            (e, c)
        });
    prop::collection::vec(term, 1..=terms)
}

/// A denominator that is not the zero polynomial. Like terms are merged before the zero
/// test: the generator may draw the same monomial twice (`-50 x^2 + 50 x^2`), and a list
/// whose terms cancel is the zero function, which no black box can evaluate (PROPTEST_RNG_SEED=39
/// drew exactly that and `reconstruct_vec` found no good point, as it should).
fn nonzero(d: Terms, n: usize) -> Terms {
    let mut merged: std::collections::BTreeMap<Vec<u32>, IBig> = std::collections::BTreeMap::new();
    for (e, c) in d {
        *merged.entry(e).or_insert(IBig::ZERO) += c;
    }
    let mut d: Terms = merged
        .into_iter()
        .filter(|(_, c)| *c != IBig::ZERO)
        .collect();
    if d.is_empty() {
        d.push((vec![0; n], IBig::ONE));
    }
    d
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn random_sparse_functions_reconstruct_exactly(
        (n, num, den) in (1usize..=6).prop_flat_map(|n| (Just(n), poly(n, 6, 10), poly(n, 4, 8))),
        seed in any::<u64>(),
    ) {
        let den = nonzero(den, n);
        let mut bb = |x: &[u64], p: u64| -> Result<Option<u64>, ()> { Ok(eval(&num, &den, x, p)) };
        let opts = Options { seed, ..Options::default() };
        let r = reconstruct(n, &mut bb, &opts).unwrap();
        let f = &r.functions[0];
        prop_assert!(same_function(f, &num, &den), "{}", f);
        prop_assert!(is_canonical(f));
        // The reduced form is never of higher degree than the input.
        let deg = |t: &Terms| t.iter().filter(|(_, c)| *c != IBig::ZERO).map(|(e, _)| e.iter().sum::<u32>()).max().unwrap_or(0);
        prop_assert!(f.den().degree() <= deg(&den));
        prop_assert!(f.num().degree() <= deg(&num));
        prop_assert!(r.certificate.error_bound < 1e-60);
    }

    #[test]
    fn vectors_agree_with_their_components(
        (n, fs) in (1usize..=4).prop_flat_map(|n| (Just(n), prop::collection::vec((poly(n, 3, 4), poly(n, 3, 3)), 1..=3))),
    ) {
        let fs: Vec<(Terms, Terms)> = fs.into_iter().map(|(a, b)| (a, nonzero(b, n))).collect();
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            Ok(fs.iter().map(|(a, b)| eval(a, b, x, p)).collect())
        };
        let r = reconstruct_vec(n, fs.len(), &mut bb, &Options::default()).unwrap();
        for (f, (a, b)) in r.functions.iter().zip(&fs) {
            prop_assert!(same_function(f, a, b), "{}", f);
            prop_assert!(is_canonical(f));
        }
    }

    /// The Euclidean interpolation and Thiele's continued fraction are two
    /// independent ways to the same reduced fraction; the first takes at
    /// most `a + b + 2` points before its checks (`a`, `b` the degrees,
    /// `a + 1` for a polynomial), never more than Thiele.
    #[test]
    fn univariate_interpolation_agrees_with_thiele_from_fewer_points(
        num in prop::collection::vec(any::<u64>(), 0..=12),
        den in prop::collection::vec(any::<u64>(), 1..=8),
        low in 0usize..=3,
        seed in any::<u64>(),
    ) {
        let p = PRIMES[2];
        let num: Vec<u64> = num.iter().map(|c| c % p).collect();
        // A denominator with a factor t^low (the io route's axis fractions).
        let den: Vec<u64> = if den.iter().all(|c| c % p == 0) {
            vec![1]
        } else {
            std::iter::repeat_n(0, low).chain(den.iter().map(|c| c % p)).collect()
        };
        let ev = |c: &[u64], t: u64| c.iter().rev().fold(0, |a, &x| fp::add(fp::mul(a, t, p), x, p));
        let (mut u, mut th) = (Univariate::new(p, 2), Thiele::new(p, 2));
        let mut t = seed % (p - 200) + 1;
        let mut thiele_points = 0;
        while !u.done() || !th.done() {
            t += 1;
            let Some(id) = fp::inv(ev(&den, t), p) else { continue };
            let y = fp::mul(ev(&num, t), id, p);
            if !u.done() { u.add(t, y); }
            if !th.done() { th.add(t, y); thiele_points += 1; }
        }
        prop_assert_eq!(u.rational(), th.rational());
        let (n, d) = u.rational();
        let (a, b) = (n.len().saturating_sub(1), d.len().saturating_sub(1));
        let most = if b == 0 { a + 3 } else { a + b + 4 };
        prop_assert!(u.len() <= most, "{} points, at most {}", u.len(), most);
        prop_assert!(u.len() <= thiele_points + 1);
    }
}
