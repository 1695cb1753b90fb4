//! The normal form of constant `atan` leaves (gauss.rs, docs/engine.md
//! "Constant arctangents"): identities the engine must now detect, checked
//! against independent values (known formulas and f64 evaluation).

use obsan_expr::{Ctx, SplitMix, Tape};

fn is_zero(src: &str) -> bool {
    let mut ctx = Ctx::new();
    let id = ctx.parse(src).unwrap();
    ctx.is_identically_zero(id)
}

/// The f64 value of a constant expression.
fn value(ctx: &Ctx, id: obsan_expr::Id) -> f64 {
    Tape::compile(ctx, &[id], &[]).unwrap().eval(&[])[0]
}

/// Regression (PROPTEST_RNG_SEED=6..8, PROPTEST_CASES=128,
/// `zero_test_agrees_with_evaluation`): `cos(atan(2))` and `sin(atan(1/2))`
/// were independent atoms, so their difference (0: both are 1/sqrt(5)) was
/// reported nonzero.
#[test]
fn seed_six_case_is_zero() {
    assert!(is_zero("cos(atan(2)) - sin(atan(1/2))"));
    assert!(is_zero("cos(atan(2)) - 1/sqrt(5)"));
    assert!(is_zero("sin(atan(1/2)) - sqrt(5)/5"));
}

#[test]
fn reflection_and_sums_of_arctangents() {
    // atan(r) + atan(1/r) = pi/2 for r > 0.
    assert!(is_zero("atan(1/2) + atan(2) - pi/2"));
    assert!(is_zero("atan(7/3) + atan(3/7) - pi/2"));
    assert!(is_zero("atan(-2) + atan(2)"));
    // Sums that need the factorisation: 1/2 + 1/3 (Euler), Machin, Hutton.
    assert!(is_zero("atan(1/2) + atan(1/3) - pi/4"));
    assert!(is_zero("4*atan(1/5) - atan(1/239) - pi/4"));
    assert!(is_zero("2*atan(1/3) + atan(1/7) - pi/4"));
    // Double angle: tan(2 atan(1/2)) = 4/3.
    assert!(is_zero("2*atan(1/2) - atan(4/3)"));
    assert!(is_zero("atan(3/4) - pi/2 + 2*atan(1/2)"));
    assert!(is_zero("atan(1) - pi/4"));
    // Independent atoms stay independent.
    assert!(!is_zero("atan(1/2) - atan(1/3)"));
    assert!(!is_zero("atan(1/2) + atan(1/3)"));
    assert!(!is_zero("2*atan(1/2) - atan(1/3)"));
}

#[test]
fn atan2_of_constants() {
    assert!(is_zero("atan2(2, 4) - atan(1/2)"));
    assert!(is_zero("atan2(1, -1) - 3*pi/4"));
    assert!(is_zero("atan2(-1, -1) + 3*pi/4"));
    // Third quadrant: atan2(-3, -4) = atan(3/4) - pi.
    assert!(is_zero("atan2(-3, -4) - atan(3/4) + pi"));
    assert!(is_zero("atan2(3/2, -1/3) - atan(-9/2) - pi"));
    assert!(is_zero("atan2(-2, 0) + pi/2"));
}

#[test]
fn trigonometric_functions_of_arctangents() {
    // sin(atan r) = r/sqrt(1 + r^2), cos(atan r) = 1/sqrt(1 + r^2), tan(atan r) = r.
    assert!(is_zero("sin(atan(3)) - 3/sqrt(10)"));
    assert!(is_zero("cos(atan(-2/3)) - 3/sqrt(13)"));
    assert!(is_zero("sin(atan(-2/3)) + 2/sqrt(13)"));
    assert!(is_zero("tan(atan(5/7)) - 5/7"));
    assert!(is_zero("tan(atan(11)) - 11"));
    // Multiples by the addition formulas: sin(2 atan(1/2)) = 2 (1/2) / (1 + 1/4) = 4/5.
    assert!(is_zero("sin(2*atan(1/2)) - 4/5"));
    assert!(is_zero("cos(2*atan(1/2)) - 3/5"));
    // Mixed with symbols: the atom's part expands, the rest stays.
    assert!(is_zero("sin(x + atan(2)) - (sin(x) + 2*cos(x))/sqrt(5)"));
    // A constant that is not rational: sin(atan(sqrt(3))) = sin(pi/3).
    assert!(is_zero("sin(atan(sqrt(3))) - sqrt(3)/2"));
    assert!(is_zero("cos(atan(pi)) - 1/sqrt(1 + pi^2)"));
}

/// Random rationals p/q: the normal form keeps the value of atan, atan2,
/// and of sin/cos of integer combinations of them (f64 reference).
#[test]
fn normal_form_keeps_values_at_random_rationals() {
    let mut rng = SplitMix(20261202);
    let mut small = |lo: i64, hi: i64| lo + (rng.next_u64() % (hi - lo + 1) as u64) as i64;
    for _ in 0..300 {
        let (p, q) = (small(-60, 60), small(1, 60));
        let (y, x) = (small(-60, 60), small(-60, 60));
        let (n, m) = (small(-3, 3), small(-3, 3));
        if x == 0 && y == 0 {
            continue;
        }
        let mut ctx = Ctx::new();
        for text in [
            format!("atan({p}/{q})"),
            format!("atan2({y}, {x})"),
            format!("sin({n}*atan({p}/{q}) + {m}*atan2({y}, {x}))"),
            format!("cos({n}*atan({p}/{q}) - {m}*atan({x}/{q}))"),
            format!("tan(atan({p}/{q}))"),
        ] {
            let id = ctx.parse(&text).unwrap();
            let c = ctx.canon(id);
            let back = ctx.from_canonical(&c);
            let want = {
                let (pf, qf, yf, xf) = (p as f64, q as f64, y as f64, x as f64);
                let (a, b) = ((pf / qf).atan(), yf.atan2(xf));
                let (nf, mf) = (n as f64, m as f64);
                match text.split('(').next().unwrap() {
                    "atan" => a,
                    "atan2" => b,
                    "sin" => (nf * a + mf * b).sin(),
                    "cos" => (nf * a - mf * (xf / qf).atan()).cos(),
                    _ => pf / qf,
                }
            };
            let got = value(&ctx, back);
            assert!((got - want).abs() < 1e-9, "{text}: {got} vs {want}");
        }
    }
}

/// The zero test of `atan(a) + atan(b) - atan(c)` agrees with its value for
/// small rationals (a nonzero value of such a combination is far from 0).
#[test]
fn zero_test_of_arctangent_sums_agrees_with_evaluation() {
    let mut rng = SplitMix(7);
    let mut small = |lo: i64, hi: i64| lo + (rng.next_u64() % (hi - lo + 1) as u64) as i64;
    let mut zeros = 0;
    for i in 0..3000 {
        let mut r: Vec<(i64, i64)> = (0..3).map(|_| (small(-12, 12), small(1, 12))).collect();
        // Every other case, c = (a + b)/(1 - ab): then the sum is 0 or +-pi.
        let (a, b) = (r[0], r[1]);
        let (num, den) = (a.0 * b.1 + b.0 * a.1, a.1 * b.1 - a.0 * b.0);
        if i % 2 == 0 && den != 0 {
            r[2] = if den < 0 { (-num, -den) } else { (num, den) };
        }
        let k = 4 * small(-1, 1);
        let text = format!(
            "atan({}/{}) + atan({}/{}) - atan({}/{}) - {k}*pi/4",
            r[0].0, r[0].1, r[1].0, r[1].1, r[2].0, r[2].1
        );
        let mut ctx = Ctx::new();
        let id = ctx.parse(&text).unwrap();
        let v = value(&ctx, id);
        let zero = ctx.is_identically_zero(id);
        assert_eq!(zero, v.abs() < 1e-9, "{text}: value {v}");
        zeros += zero as usize;
    }
    // The sample must contain true identities, or it proves little.
    assert!(zeros > 300, "only {zeros} identities drawn");
}

/// A norm with a prime factor beyond the trial division bound: the cofactor
/// is one atom, and the value is kept.
#[test]
fn large_prime_cofactors_keep_their_value() {
    // 1000003 is prime, 1000003^2 + 1 has factors above 2^16.
    for text in ["atan(1/1000003)", "atan(1000003)", "atan2(-1000003, -2)"] {
        let mut ctx = Ctx::new();
        let id = ctx.parse(text).unwrap();
        let c = ctx.canon(id);
        let back = ctx.from_canonical(&c);
        let want = match text {
            "atan(1/1000003)" => (1.0f64 / 1000003.0).atan(),
            "atan(1000003)" => 1000003.0f64.atan(),
            _ => (-1000003.0f64).atan2(-2.0),
        };
        assert!((value(&ctx, back) - want).abs() < 1e-12, "{text}");
    }
    assert!(is_zero("atan(1000003) + atan(1/1000003) - pi/2"));
}

/// sin/cos of arctangents produce square roots of integers, whose products
/// must have one form: one atom per prime (square roots of distinct primes
/// are independent over Q), square factors found up to 2^16.
#[test]
fn constant_square_roots_split_into_primes() {
    assert!(is_zero("sqrt(10) - sqrt(2)*sqrt(5)"));
    assert!(is_zero("1/sqrt(6) - sqrt(2)*sqrt(3)/6"));
    assert!(is_zero("sqrt(3/2) - sqrt(6)/2"));
    assert!(is_zero("sqrt(1009^2*2) - 1009*sqrt(2)"));
    assert!(is_zero("sqrt(65521^2*3*x) - 65521*sqrt(3*x)"));
    assert!(is_zero("sqrt(30)^2 - 30"));
    assert!(!is_zero("sqrt(2)*sqrt(3) - sqrt(5)"));
    assert!(!is_zero("sqrt(6) - sqrt(2)"));
    // 2^31 - 1 and 2^61 - 1 are primes above the trial bound: each is one atom, cofactor of the rest.
    assert!(is_zero("sqrt(2147483647)^2 - 2147483647"));
    assert!(is_zero(
        "sqrt(2*2305843009213693951) - sqrt(2)*sqrt(2305843009213693951)"
    ));
}

/// Regression (found by float_eval's `agrees_with_the_engine_without_branches`):
/// an angle with a constant atan and a number besides, `sin(1 - atan(pi))`,
/// was read as `sin(1)`: the number's angle atom replaced the atan's factor
/// instead of multiplying it. The reference is f64 evaluation of the text.
#[test]
fn a_number_beside_a_constant_arctangent_keeps_both() {
    let cases: [(&str, f64); 6] = [
        (
            "sin(1 - atan(pi))",
            (1.0 - std::f64::consts::PI.atan()).sin(),
        ),
        (
            "cos(1 + atan(pi))",
            (1.0 + std::f64::consts::PI.atan()).cos(),
        ),
        ("sin(1 + atan(1/2))", (1.0 + 0.5f64.atan()).sin()),
        ("sin(1 - atan(2))", (1.0 - 2f64.atan()).sin()),
        (
            "cos(3/2 + 2*atan(1/3))",
            (1.5 + 2.0 * (1.0f64 / 3.0).atan()).cos(),
        ),
        ("tan(1 + atan(5))", (1.0 + 5f64.atan()).tan()),
    ];
    for (text, want) in cases {
        let mut ctx = Ctx::new();
        let id = ctx.parse(text).unwrap();
        let c = ctx.canon(id);
        let back = ctx.from_canonical(&c);
        let got = value(&ctx, back);
        assert!((got - want).abs() < 1e-12, "{text}: {got} vs {want}");
    }
    assert!(!is_zero("sin(1 - atan(pi)) - sin(1)"));
    assert!(is_zero("sin(1 + atan(2)) - (sin(1) + 2*cos(1))/sqrt(5)"));
}
