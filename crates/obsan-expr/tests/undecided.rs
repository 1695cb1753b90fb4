//! A nonzero canonical form is a proof of "nonzero" only when its atoms are
//! algebraically independent (docs/engine.md, "Decided and not decided").
//! Every identity here is identically zero on its stated real domain, so the
//! engine must answer zero or "not decided", never "nonzero".

use obsan_expr::Ctx;
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// (form is zero, undecided atoms as text)
fn answer(text: &str) -> (bool, Vec<String>) {
    let mut ctx = Ctx::new();
    let e = ctx.parse(text).unwrap();
    let r = ctx.canon(e);
    let atoms = ctx.undecided_atom_texts(&r);
    (r.is_zero(), atoms)
}

/// Identities outside the decided fragment: each holds on the domain named
/// beside it, so "decided, nonzero" would be a false exact claim.
#[test]
fn identities_outside_the_fragment_are_not_decided_nonzero() {
    for (text, domain) in [
        ("log(x*y) - log(x) - log(y)", "x, y > 0"),
        ("log(x^2) - 2*log(x)", "x > 0"),
        ("sqrt(x*y) - sqrt(x)*sqrt(y)", "x, y >= 0"),
        ("sqrt(2*x^2) - sqrt(2)*x", "x >= 0"),
        ("atan(1/x) + atan(x) - pi/2", "x > 0"),
        ("exp(x*y + 1) - exp(x*y)*exp(1)", "all reals"),
        ("sin(2*x*y) - 2*sin(x*y)*cos(x*y)", "all reals"),
        ("exp(2) - exp(1)^2", "a number"),
        ("sin(3) - 3*sin(1) + 4*sin(1)^3", "a number"),
        ("atan(sqrt(3)) - pi/3", "a number"),
        ("sin(pi/5)^2 - (5 - sqrt(5))/8", "a number: sin^2(36 deg)"),
    ] {
        let (zero, atoms) = answer(text);
        assert!(
            zero || !atoms.is_empty(),
            "{text} (zero for {domain}) was answered decided and nonzero"
        );
    }
}

/// The atoms named are the related ones, as text.
#[test]
fn the_related_atoms_are_named() {
    let (zero, atoms) = answer("log(x*y) - log(x) - log(y)");
    assert!(!zero);
    assert_eq!(atoms, ["log(x)", "log(x*y)", "log(y)"]);
    let (_, atoms) = answer("atan(1/x) + atan(x) - pi/2");
    assert_eq!(atoms.len(), 2, "{atoms:?}");
}

/// Nonzero forms whose atoms are provably independent are decided. The
/// reasons, by hand: symbols with their per-symbol sin/cos/exp (Ax's
/// theorem); one generic exponential or angle or logarithm or arctangent of
/// the symbols (Ax); square roots whose radicands' primitive parts are
/// coprime non-squares (x^2 + y^2 and x); sqrt of primes (a quadratic tower);
/// one transcendental constant (Lindemann); a linear form in pi and the
/// arctangents of Gaussian primes (Baker).
#[test]
fn independent_atoms_are_decided() {
    for text in [
        "x + sin(x) + exp(y)",
        "sqrt(x^2 + y^2) - x + sqrt(x)",
        "exp(x*y) - 1",
        "log(x) - x",
        "atan2(y, x) - atan(z)*0 + x",
        "sin(x*y) + exp(x*y)",
        "sqrt(2) + sqrt(3) - 3",
        "pi^2 - 10",
        "exp(1) - 2718/1000",
        "sin(1)^2 + cos(1) - 1",
        "atan(1/2) + pi/7 - 1",
        "x*pi - atan(1/3)*y",
    ] {
        let (zero, atoms) = answer(text);
        assert!(!zero, "{text}");
        assert!(atoms.is_empty(), "{text}: {atoms:?}");
    }
}

/// Products of transcendental constants are outside what is known
/// (pi*e, pi + e are not known to be irrational): not decided.
#[test]
fn nonlinear_constant_relations_are_not_decided() {
    for text in ["pi*atan(1/2) - 1", "exp(1) + pi - 6", "log(2) - atan(1/2)"] {
        let (zero, atoms) = answer(text);
        assert!(!zero);
        assert!(!atoms.is_empty(), "{text}");
    }
}

/// A rational constant term leaves a generic exponent (exp(a + b) = exp(a)
/// exp(b) for all reals), so this identity is decided exactly.
#[test]
fn constant_terms_leave_exponentials() {
    assert!(answer("exp(x*y + 1) - exp(x*y)*exp(1)").0);
}

/// A zero form stays a proof of zero whatever its atoms.
#[test]
fn zero_is_always_decided() {
    let (zero, _) = answer("log(x*y) - log(x*y)");
    assert!(zero);
}

fn arg() -> impl Strategy<Value = String> {
    // Positive on x, y, z > 0: the identities' domains are not empty.
    (1u32..5, 0u32..3, 0u32..3, 1u32..4).prop_map(|(a, i, j, c)| format!("({a}*x^{i}*z^{j} + {c})"))
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    /// The fuzz oracle's identities, over random positive arguments.
    #[test]
    fn identities_are_zero_or_undecided(a in arg(), b in arg(), k in 0usize..5) {
        let text = match k {
            0 => format!("log({a}*{b}) - log({a}) - log({b})"),
            1 => format!("sqrt({a}*{b}) - sqrt({a})*sqrt({b})"),
            2 => format!("atan(1/{a}) + atan({a}) - pi/2"),
            3 => format!("exp({a}*{b} + 1) - exp({a}*{b})*exp(1)"),
            _ => format!("sin(2*{a}*{b}) - 2*sin({a}*{b})*cos({a}*{b})"),
        };
        let mut ctx = Ctx::new();
        let e = ctx.parse(&text);
        prop_assume!(e.is_ok());
        let r = ctx.canon(e.unwrap());
        let atoms = ctx.undecided_atoms(&r);
        prop_assert!(r.is_zero() || !atoms.is_empty(), "{} decided nonzero", text);
    }
}
