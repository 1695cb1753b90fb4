//! Times the slow property-test cases (docs/performance.md, "Engine: slow
//! property-test cases"): `cargo run --release -p obsan-expr --example slow_cases`.
//!
//! Seed 29 of `canonical_derivative_agrees_with_graph_derivative` draws the
//! atan2 below. Its d/dy divides by `X^2 + Y^2`, a 2855/595-term form with the
//! sine leaves of x, y and z; the canonical inverse is the quotient by its norm
//! over those quadratic extensions and has about 280,000 terms (gcd 1), so the
//! default budget of 100,000 terms is the honest answer.

use obsan_expr::Ctx;
use std::time::Instant;

const SEED29: &str =
    "atan2((sin(2*x - y))/(2 + (sin(2*z - y))^2 + y^2), 3 + ((2)/(2 + (x)^2 + y^2))^2)";

fn main() {
    // Under the default budget: a Limit, not a run-on.
    let mut ctx = Ctx::new();
    let y = ctx.symbol("y").var;
    let id = ctx.parse(SEED29).unwrap();
    let t = Instant::now();
    let r = ctx.within_budget(|c| {
        let d = c.diff(id, y);
        c.canon(d).term_count()
    });
    println!(
        "{:>8.3} s  seed 29, d/dy under the default budget: {r:?}",
        t.elapsed().as_secs_f64()
    );

    // Without a budget: the inverse of the divisor alone (the rationalisation).
    let mut ctx = Ctx::new();
    let id = ctx
        .parse("(sin(2*x - y)/(2 + sin(2*z - y)^2 + y^2))^2 + (3 + (2/(2 + x^2 + y^2))^2)^2")
        .unwrap();
    let c = ctx.canon(id);
    let t = Instant::now();
    let inv = ctx.rf_inv(&c).unwrap();
    println!(
        "{:>8.3} s  seed 29, inverse of the {}/{}-term divisor: {}/{} terms",
        t.elapsed().as_secs_f64(),
        c.numerator().len(),
        c.denominator().len(),
        inv.numerator().len(),
        inv.denominator().len()
    );
}
