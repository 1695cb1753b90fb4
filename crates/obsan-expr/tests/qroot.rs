//! Rational exponents `u^(p/q)` as exact q-th-root atoms (issue 32,
//! docs/engine.md "Roots"): `b^(p/q) = b^floor(p/q) root_q(b)^(p mod q)` with
//! the relation `r^q = u`. Every expected value is derived by hand beside the
//! test (exponent arithmetic on the principal branch, u > 0).

use obsan_expr::{Ctx, Tape};

fn is_zero(src: &str) -> bool {
    let mut ctx = Ctx::new();
    let id = ctx.parse(src).unwrap();
    ctx.is_identically_zero(id)
}

fn text(src: &str) -> String {
    let mut ctx = Ctx::new();
    let id = ctx.parse(src).unwrap();
    let r = ctx.canon(id);
    ctx.ratfun_text(&r)
}

#[test]
fn exponent_arithmetic() {
    // 1.7 + 0.3 = 2: r^10 = x, x^1.7 = x r^7, x^0.3 = r^3, product x r^10 = x^2.
    assert!(is_zero("x^1.7 * x^0.3 - x^2"));
    // (x^(1/3))^3 = r^3 = x.
    assert!(is_zero("(x^(1/3))^3 - x"));
    // x^(1/3)^2 written out: r^2 - r^2.
    assert!(is_zero("(x^(1/3))^2 - x^(2/3)"));
    // x^(2/3) x^(4/3) = x^2; x^(-1/3) x^(1/3) = 1; x^(5/3) / x^(2/3) = x.
    assert!(is_zero("x^(2/3) * x^(4/3) - x^2"));
    assert!(is_zero("x^(-1/3) * x^(1/3) - 1"));
    assert!(is_zero("x^(5/3) / x^(2/3) - x"));
    // A rational exponent in lowest terms: 6/4 = 3/2 is the square root.
    assert!(is_zero("x^(6/4) - x*sqrt(x)"));
    assert!(is_zero("x^1.5 - x*sqrt(x)"));
    // Non-zero differences stay non-zero.
    assert!(!is_zero("x^(1/3) - x^(2/3)"));
    assert!(!is_zero("x^1.7 - x^2"));
}

#[test]
fn derivative() {
    // d/dx x^(5/3) = 5/3 x^(2/3)
    let mut ctx = Ctx::new();
    let e = ctx.parse("x^(5/3)").unwrap();
    let x = ctx.symbol("x").var;
    let d = ctx.diff(e, x);
    let want = ctx.parse("5/3 * x^(2/3)").unwrap();
    let diff = ctx.sub(d, want);
    assert!(ctx.is_identically_zero(diff));
    // d/dx x^1.7 = 1.7 x^0.7, and d/dx (x + y^2)^(1/4) = (x + y^2)^(-3/4)/4.
    let e = ctx.parse("x^1.7").unwrap();
    let d = ctx.diff(e, x);
    let want = ctx.parse("17/10 * x^0.7").unwrap();
    let diff = ctx.sub(d, want);
    assert!(ctx.is_identically_zero(diff));
    let e = ctx.parse("(x + y^2)^(1/4)").unwrap();
    let d = ctx.diff(e, x);
    let want = ctx.parse("(x + y^2)^(-3/4)/4").unwrap();
    let diff = ctx.sub(d, want);
    assert!(ctx.is_identically_zero(diff));
}

#[test]
fn printing_reads_back_and_evaluates() {
    // The printed form parses back to the same form.
    for src in ["x^1.7", "x^(-2/3) + y", "(x + 1)^(1/3) * x^(2/3)", "2^(1/3)"] {
        let t = text(src);
        assert!(is_zero(&format!("({src}) - ({t})")), "{src} printed {t}");
    }
    // f64: 8^(2/3) = 4, 2^(1/3)^3 = 2.
    let mut ctx = Ctx::new();
    let e = ctx.parse("x^(2/3)").unwrap();
    let x = ctx.symbol("x").var;
    let tape = Tape::compile(&ctx, &[e], &[x]).unwrap();
    assert!((tape.eval(&[8.0])[0] - 4.0).abs() < 1e-12);
}

#[test]
fn constant_roots() {
    // 4^(1/3) = 2^(2/3) (per-prime atoms), 16^(1/3) = 2 * 2^(1/3), 8^(1/3) = 2.
    assert!(is_zero("4^(1/3) - 2^(2/3)"));
    assert!(is_zero("16^(1/3) - 2*2^(1/3)"));
    assert!(is_zero("8^(1/3) - 2"));
    // (1/2)^(1/3) = 4^(1/3)/2 = 2^(2/3)/2.
    assert!(is_zero("(1/2)^(1/3) - 2^(2/3)/2"));
    // 6^(1/3) = 2^(1/3) 3^(1/3).
    assert!(is_zero("6^(1/3) - 2^(1/3)*3^(1/3)"));
}

#[test]
fn refused() {
    let mut ctx = Ctx::new();
    // (x^2)^(1/4) = sqrt(|x|): a perfect-power radicand is refused as sqrt(x^2) is.
    assert!(ctx.parse("(x^2)^(1/4)").is_err());
    // (x^(2/3))^(3/2) = |x| on the reals: sqrt of a perfect square, refused.
    assert!(ctx.parse("(x^(2/3))^(3/2)").is_err());
    // Exponent range: the numerator is a power-node exponent.
    assert!(ctx.parse("x^(10000000000/3)").is_err());
}
