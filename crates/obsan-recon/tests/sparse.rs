//! Sparse interpolation of polynomial vectors (`interpolate_polys_vec`):
//! planted polynomials with rational coefficients recovered exactly, the
//! same canonical form as `reconstruct_vec`'s; rational functions, holes in
//! the black box and bounds too large never give a wrong answer; bounds
//! whose largest monomial value `q^e` is past the first prime go by shifted
//! sequences, with the same answers.

mod common;

use common::{eval, eval_terms, is_canonical, same_function, Terms};
use dashu_int::IBig;
use obsan_recon::{interpolate_polys_vec, reconstruct_vec, DegreeBounds, Options};
use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, TestCaseError};

/// A sparse polynomial in `n` variables: up to `terms` terms, each exponent
/// at most `deg`, coefficients small or up to ~2^100.
fn poly(n: usize, terms: usize, deg: u32) -> impl Strategy<Value = Terms> {
    let term = (
        prop::collection::vec(0..=deg, n),
        prop_oneof![
            3 => (-50i64..=50).prop_map(IBig::from),
            1 => (any::<i64>(), any::<u32>()).prop_map(|(a, b)| (IBig::from(a) << 40) + IBig::from(b)),
        ],
    );
    prop::collection::vec(term, 0..=terms)
}

/// Like [`poly`], with every term's total degree at most `total` (the
/// largest exponents lowered one at a time until it fits) and coefficients
/// up to ~2^100.
fn poly_total(n: usize, terms: usize, deg: u32, total: u32) -> impl Strategy<Value = Terms> {
    let term = (
        prop::collection::vec(0..=deg, n),
        prop_oneof![
            1 => (-50i64..=50).prop_map(IBig::from),
            2 => (any::<i64>(), any::<u64>(), any::<u32>())
                .prop_map(|(a, b, c)| (IBig::from(a) << 96) + (IBig::from(b) << 32) + IBig::from(c)),
        ],
    )
        .prop_map(move |(mut e, c)| {
            while e.iter().sum::<u32>() > total {
                let i = (0..e.len()).max_by_key(|&i| (e[i], i)).unwrap_or(0);
                e[i] -= 1;
            }
            (e, c)
        });
    prop::collection::vec(term, 1..=terms)
}

/// Bounds of 8 variables, 12 each and total degree 30: the largest
/// monomial value over the small primes, `19^12 17^12 13^6`, is far past
/// the first prime (~2^62), so the exponents come from shifted sequences.
fn past_prime_bounds() -> DegreeBounds {
    DegreeBounds {
        per_var: vec![12; 8],
        total: Some(30),
    }
}

/// Per variable the largest exponent of the terms with a non-zero
/// coefficient once like terms are merged (0 for the zero polynomial).
fn per_var(ps: &[Terms], n: usize) -> Vec<u32> {
    let mut out = vec![0u32; n];
    for p in ps {
        let mut merged: std::collections::BTreeMap<Vec<u32>, IBig> =
            std::collections::BTreeMap::new();
        for (e, c) in p {
            *merged.entry(e.clone()).or_insert(IBig::ZERO) += c;
        }
        for (e, c) in merged {
            if c != IBig::ZERO {
                for (o, x) in out.iter_mut().zip(e) {
                    *o = (*o).max(x);
                }
            }
        }
    }
    out
}

/// The black box of `nums` (integer coefficients) with a bad point at the
/// calls numbered in `holes`: the right answer, or `None` only when every
/// restart of some stage met a hole (at least three distinct ones).
fn holes_give_the_answer_or_none(
    n: usize,
    nums: &[Terms],
    holes: &[u64],
    seed: u64,
    bounds: &DegreeBounds,
) -> Result<(), TestCaseError> {
    let one: Terms = vec![(vec![0; n], IBig::ONE)];
    let mut calls = 0u64;
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
        calls += 1;
        if holes.contains(&calls) {
            return Ok(None);
        }
        Ok(nums.iter().map(|a| eval(a, &one, x, p)).collect())
    };
    let opts = Options {
        seed,
        ..Options::default()
    };
    match interpolate_polys_vec(n, nums.len(), &mut bb, &opts, bounds).unwrap() {
        Some(r) => {
            for (f, a) in r.functions.iter().zip(nums) {
                prop_assert!(same_function(f, a, &one), "{}", f);
            }
        }
        None => {
            prop_assert!(
                holes
                    .iter()
                    .collect::<std::collections::BTreeSet<_>>()
                    .len()
                    >= 3
            )
        }
    }
    Ok(())
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 48,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    /// `num_c / den_c` with integer constants `den_c`: polynomials with
    /// rational coefficients, recovered exactly, as `reconstruct_vec` writes
    /// them. (Five variables of degree <= 5: `(2 3 5 7 11)^5 < 2^62`, so
    /// the bounds always fit the first prime.)
    #[test]
    fn planted_polynomial_vectors_are_recovered(
        (n, nums) in (1usize..=5).prop_flat_map(|n| (Just(n), prop::collection::vec(poly(n, 12, 4), 1..=4))),
        dens in prop::collection::vec(prop_oneof![Just(1i64), 2i64..=1000, -1000i64..=-2], 4),
        slack in 0u32..=1,
        seed in any::<u64>(),
    ) {
        let m = nums.len();
        let den: Vec<Terms> = dens[..m].iter().map(|&d| vec![(vec![0; n], IBig::from(d))]).collect();
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            Ok(nums.iter().zip(&den).map(|(a, b)| eval(a, b, x, p)).collect())
        };
        let bounds = DegreeBounds {
            per_var: per_var(&nums, n).iter().map(|d| d + slack).collect(),
            total: None,
        };
        let opts = Options { seed, ..Options::default() };
        let r = interpolate_polys_vec(n, m, &mut bb, &opts, &bounds).unwrap();
        let r = r.expect("polynomials within the bounds are recognised");
        for ((f, a), b) in r.functions.iter().zip(&nums).zip(&den) {
            prop_assert!(same_function(f, a, b), "{}", f);
            prop_assert!(is_canonical(f));
        }
        prop_assert!(r.certificate.error_bound < 1e-60);
        prop_assert_eq!(r.stats.points, r.stats.points.min(opts.max_points));
        let dense = reconstruct_vec(n, m, &mut bb, &opts).unwrap();
        prop_assert_eq!(&r.functions, &dense.functions);
    }

    /// A rational function among the components: `None`, or the right answer.
    #[test]
    fn rational_functions_are_never_answered_wrongly(
        (n, nums, den) in (1usize..=4).prop_flat_map(|n| (Just(n), prop::collection::vec(poly(n, 6, 3), 2), poly(n, 3, 2))),
        seed in any::<u64>(),
    ) {
        let one: Terms = vec![(vec![0; n], IBig::ONE)];
        let mut den = den;
        den.push((vec![0; n], IBig::from(7)));
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            let a = eval(&nums[0], &one, x, p);
            let b = eval(&nums[1], &den, x, p);
            Ok(a.zip(b).map(|(a, b)| vec![a, b]))
        };
        let bounds = DegreeBounds { per_var: vec![6; n], total: None };
        let opts = Options { seed, max_terms: 200, ..Options::default() };
        if let Some(r) = interpolate_polys_vec(n, 2, &mut bb, &opts, &bounds).unwrap() {
            prop_assert!(same_function(&r.functions[0], &nums[0], &one));
            prop_assert!(same_function(&r.functions[1], &nums[1], &den));
        }
    }

    /// Holes (bad points) anywhere, including in the geometric sequences.
    #[test]
    fn holes_restart_the_sequence(
        (n, nums) in (1usize..=4).prop_flat_map(|n| (Just(n), prop::collection::vec(poly(n, 8, 3), 1..=3))),
        holes in prop::collection::vec(0u64..40, 1..4),
        seed in any::<u64>(),
    ) {
        let bounds = DegreeBounds { per_var: per_var(&nums, n), total: None };
        holes_give_the_answer_or_none(n, &nums, &holes, seed, &bounds)?;
    }

    /// Past the prime (8 variables, total degree 30): planted polynomials
    /// with coefficients up to ~2^100 over integers recovered exactly, in
    /// canonical form, with the (slower) `reconstruct_vec`'s answer.
    #[test]
    fn past_the_prime_planted_vectors_are_recovered(
        nums in prop::collection::vec(poly_total(8, 5, 12, 30), 1..=3),
        dens in prop::collection::vec(prop_oneof![Just(1i64), 2i64..=1000, -1000i64..=-2], 3),
        seed in any::<u64>(),
    ) {
        let (n, m) = (8, nums.len());
        let den: Vec<Terms> = dens[..m].iter().map(|&d| vec![(vec![0; n], IBig::from(d))]).collect();
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            Ok(nums.iter().zip(&den).map(|(a, b)| eval(a, b, x, p)).collect())
        };
        let opts = Options { seed, ..Options::default() };
        let r = interpolate_polys_vec(n, m, &mut bb, &opts, &past_prime_bounds()).unwrap();
        let r = r.expect("polynomials within the bounds are recognised");
        for ((f, a), b) in r.functions.iter().zip(&nums).zip(&den) {
            prop_assert!(same_function(f, a, b), "{}", f);
            prop_assert!(is_canonical(f));
        }
        prop_assert!(r.certificate.error_bound < 1e-60);
        let dense = reconstruct_vec(n, m, &mut bb, &opts).unwrap();
        prop_assert_eq!(&r.functions, &dense.functions);
    }

    /// Past the prime, holes anywhere (the first sequence, the shifted
    /// ones, later primes, the checks): the right answer, or `None` when
    /// every restart of some stage met one.
    #[test]
    fn past_the_prime_holes_restart_the_sequence(
        nums in prop::collection::vec(poly_total(8, 4, 12, 30), 1..=2),
        holes in prop::collection::vec(0u64..80, 1..4),
        seed in any::<u64>(),
    ) {
        holes_give_the_answer_or_none(8, &nums, &holes, seed, &past_prime_bounds())?;
    }
}

/// Bounds whose largest monomial value `q^e` (here `2^62`) is not below
/// the first prime: the shifted sequences (one more per variable) find the
/// exponents all the same.
#[test]
fn bounds_past_the_prime() {
    let mut calls = 0u64;
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
        calls += 1;
        Ok(Some(vec![x[0] % p]))
    };
    let bounds = DegreeBounds {
        per_var: vec![62],
        total: None,
    };
    let r = interpolate_polys_vec(1, 1, &mut bb, &Options::default(), &bounds)
        .unwrap()
        .unwrap();
    let x: Terms = vec![(vec![1], IBig::ONE)];
    let one1: Terms = vec![(vec![0], IBig::ONE)];
    assert!(same_function(&r.functions[0], &x, &one1));
    assert_eq!(r.stats.points, calls);
    // With two variables of degree 31 and 19 it fits (2^31 3^19 ~ 2^61.1,
    // the first prime is ~2^62), not with 31 and 20 (~2^62.7): the small
    // primes' path, then the shifted one, the same answer at more points.
    let f: Terms = vec![
        (vec![31, 0], IBig::from(5)),
        (vec![0, 19], IBig::from(-3)),
        (vec![1, 1], IBig::ONE),
    ];
    let mut bb2 = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
        Ok(Some(vec![eval_terms(&f, x, p)]))
    };
    let ok = DegreeBounds {
        per_var: vec![31, 19],
        total: None,
    };
    let r = interpolate_polys_vec(2, 1, &mut bb2, &Options::default(), &ok)
        .unwrap()
        .unwrap();
    let one: Terms = vec![(vec![0, 0], IBig::ONE)];
    assert!(same_function(&r.functions[0], &f, &one));
    let big = DegreeBounds {
        per_var: vec![31, 20],
        total: None,
    };
    let s = interpolate_polys_vec(2, 1, &mut bb2, &Options::default(), &big)
        .unwrap()
        .unwrap();
    assert_eq!(s.functions, r.functions);
    // 2 T + 3 points and the checks on the small primes' path, 2 T more
    // (T = 3 terms, 2 variables) on the shifted one.
    assert_eq!(s.stats.points, r.stats.points + 2 * 3);
}

/// Past the prime, a component with an exponent above its variable's
/// bound, or a total degree above the total bound or `max_degree`: `None`
/// (no power `c^e` within the bound matches, or the sum is checked), never
/// a truncated answer.
#[test]
fn past_the_prime_degrees_above_the_bounds_are_refused() {
    let bounds = past_prime_bounds();
    let within: Terms = vec![
        (vec![12, 12, 6, 0, 0, 0, 0, 0], IBig::from(3)),
        (vec![0, 0, 0, 1, 0, 0, 0, 2], IBig::from(-1)),
    ];
    let per_var_above: Terms = vec![
        (vec![13, 0, 0, 0, 0, 0, 0, 1], IBig::from(5)),
        (vec![0, 1, 0, 0, 0, 0, 0, 0], IBig::ONE),
    ];
    let total_above: Terms = vec![
        (vec![12, 12, 7, 0, 0, 0, 0, 0], IBig::from(5)),
        (vec![0, 1, 0, 0, 0, 0, 0, 0], IBig::ONE),
    ];
    let one: Terms = vec![(vec![0; 8], IBig::ONE)];
    for (bad, why) in [(&per_var_above, "per variable"), (&total_above, "total")] {
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            Ok(Some(vec![eval_terms(&within, x, p), eval_terms(bad, x, p)]))
        };
        let r = interpolate_polys_vec(8, 2, &mut bb, &Options::default(), &bounds).unwrap();
        assert!(r.is_none(), "{why}");
    }
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
        Ok(Some(vec![eval_terms(&within, x, p)]))
    };
    let r = interpolate_polys_vec(8, 1, &mut bb, &Options::default(), &bounds)
        .unwrap()
        .unwrap();
    assert!(same_function(&r.functions[0], &within, &one));
    let low = Options {
        max_degree: 29,
        ..Options::default()
    };
    assert!(interpolate_polys_vec(8, 1, &mut bb, &low, &bounds)
        .unwrap()
        .is_none());
}

/// A polynomial whose degree exceeds the bounds it is given: `None` (a
/// root that is not a monomial within them), never a truncated answer.
#[test]
fn degrees_above_the_bounds_are_refused() {
    let f: Terms = vec![(vec![3, 1], IBig::from(2)), (vec![0, 0], IBig::ONE)];
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
        Ok(Some(vec![eval_terms(&f, x, p)]))
    };
    let bounds = DegreeBounds {
        per_var: vec![2, 1],
        total: None,
    };
    assert!(
        interpolate_polys_vec(2, 1, &mut bb, &Options::default(), &bounds)
            .unwrap()
            .is_none()
    );
}
