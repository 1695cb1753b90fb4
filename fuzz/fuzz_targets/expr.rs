//! Fuzz the expression parser and canonicaliser.
//!
//! Input bytes are an expression (invalid UTF-8 is skipped). It is parsed
//! and canonicalised under a small budget; an error is fine, a panic or a
//! hang is a bug. When both succeed, the oracles are:
//! - the canonical form and the parsed expression agree at random points of
//!   F_p (p = 2^61 - 1) wherever both are defined;
//! - a zero canonical form evaluates to zero at every such point;
//! - the printed canonical form parses back to the same canonical form;
//! - an expression built from the input to be identically zero by an identity
//!   outside the decided fragment (`log(a y) = log a + log y`, ...) is never
//!   answered "decided, nonzero": its form is zero or it has undecided atoms.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_expr::{Budget, Ctx, Limit, SplitMix};
use std::time::{Duration, Instant};

fuzz_target!(|data: &[u8]| {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let budget = || Budget {
        max_terms: 2_000,
        max_nodes: 200_000,
        max_degree: 300,
        deadline: Some(Instant::now() + Duration::from_secs(2)),
    };
    let mut ctx = Ctx::new();
    ctx.set_budget(budget());
    let Ok(id) = ctx.parse(src) else {
        return;
    };
    let Ok(r) = ctx.try_canon(id) else {
        return;
    };
    let Ok(back) = ctx.within_budget(|c| c.from_canonical(&r)) else {
        return;
    };
    // The printed form re-reads to the same canonical form. It is expanded,
    // so it can be far larger than the input: it gets a budget of its own,
    // and reaching that budget is not a bug; a syntax error is.
    let Ok(text) = ctx.try_ratfun_text(&r, 1 << 20) else {
        return;
    };
    ctx.set_budget(budget());
    let reread = match ctx.parse(&text) {
        Ok(t) => ctx.try_canon(t),
        Err(e) if e.limit.as_ref().is_some_and(|l| !matches!(l, Limit::Internal(_))) => return,
        Err(e) => panic!("printed form {text:?} of {src:?} does not parse: {e}"),
    };
    if let Ok(r2) = reread {
        assert_eq!(r, r2, "{src:?} prints as {text:?}, which reads back differently");
    }
    let seed = data
        .iter()
        .fold(0x9e37_79b9_7f4a_7c15_u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    let mut rng = SplitMix(seed);
    for _ in 0..4 {
        let Ok(pt) = ctx.random_fp_point(&mut rng, &|_| None) else {
            continue;
        };
        let Ok(v) = ctx.eval_fp(&[id, back], &pt) else {
            continue;
        };
        assert_eq!(v[0], v[1], "{src:?}: canonical form {text:?} differs in value");
        if r.is_zero() {
            assert!(v[0].is_zero(), "{src:?} is canonically zero but not at a point");
        }
    }
    identities_are_never_decided_nonzero(src, budget(), &r);
});

/// Identities on the real domain where both sides are defined (`A > 0`,
/// `y > 0` for the logarithm and the roots; `A != 0` with `A > 0` for the
/// arctangent), with `A` the fuzzed expression.
const IDENTITIES: [&str; 5] = [
    "log((A)*y) - log(A) - log(y)",
    "sqrt((A)*y) - sqrt(A)*sqrt(y)",
    "atan(1/(A)) + atan(A) - pi/2",
    "exp((A)*y + 1) - exp((A)*y)*exp(1)",
    "sin(2*(A)*y) - 2*sin((A)*y)*cos((A)*y)",
];

fn identities_are_never_decided_nonzero(src: &str, budget: Budget, a: &obsan_expr::RatFun) {
    // The domains need A > 0: a rational A <= 0 leaves them empty (and
    // atan(-1/2) + atan(-2) - pi/2 = -pi is rightly decided nonzero).
    if src.len() > 200 || a.as_q().is_some_and(|q| q.is_negative() || q.is_zero()) {
        return;
    }
    for t in IDENTITIES {
        let text = t.replace('A', src);
        let mut ctx = Ctx::new();
        ctx.set_budget(budget.clone());
        let Ok(id) = ctx.parse(&text) else {
            continue;
        };
        let Ok(r) = ctx.try_canon(id) else {
            continue;
        };
        let Ok(undecided) = ctx.within_budget(|c| c.undecided_atoms(&r)) else {
            continue;
        };
        assert!(
            r.is_zero() || !undecided.is_empty(),
            "{text:?} is identically zero but is answered decided and nonzero"
        );
    }
}
