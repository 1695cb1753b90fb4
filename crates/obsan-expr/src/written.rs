//! Written forms: for a node in canonical form (a numerator and a
//! denominator, expanded), the expression it was expanded from, when that
//! is the same function. Evaluation at points (the Taylor jets) may use
//! either; the written one can be far smaller: a sum of rate laws over eight
//! distinct denominators expands into thousands of monomials over their
//! product, while as written it is a few dozen operations.
//!
//! Only relation-free forms are recorded (no `sin`/`cos` pair, no root): a
//! canonical form is reduced by the relations `s^2 + c^2 = 1` and
//! `r^q = u`, so off their variety the two forms are different functions of
//! the leaves, and the extension-field and free-root routes evaluate there.

use crate::graph::{Id, Node};
use crate::memo::Ctx;
use crate::num::SplitMix;

impl Ctx {
    /// Record `written` as an equal, smaller form of `canonical` (a node
    /// built from a canonical form of `written`). Kept only when both are
    /// relation-free and `written` evaluates at a random point to the same
    /// value: a written form whose denominator vanishes identically (an input
    /// set to zero in `u*x/u`) never evaluates, and is not kept. Equality is
    /// the caller's claim (the canonical form was computed from `written`);
    /// the point only guards against a form that cannot be evaluated.
    pub fn note_written_form(&mut self, canonical: Id, written: Id) {
        if canonical == written || self.is_zero(canonical) {
            return;
        }
        let with_relation = self
            .reachable(&[canonical, written])
            .into_iter()
            .any(|n| matches!(self.node(n), Node::Leaf(v) if self.has_relation(*v)));
        if with_relation {
            return;
        }
        let mut rng = SplitMix(0x5eed_0f_0b5a_u64 ^ u64::from(canonical.0));
        let Ok(point) = self.random_fp_point(&mut rng, &|_| None) else {
            return;
        };
        match (
            self.eval_fp(&[canonical], &point),
            self.eval_fp(&[written], &point),
        ) {
            (Ok(a), Ok(b)) if a == b => {
                self.memo.written.insert(canonical, written);
            }
            (Ok(a), Ok(b)) => {
                debug_assert_eq!(a, b, "a written form differs from its canonical form");
            }
            _ => {}
        }
    }

    /// The written form recorded for `id` ([`Ctx::note_written_form`]), else `id`.
    pub fn written_form(&self, id: Id) -> Id {
        self.memo.written.get(&id).copied().unwrap_or(id)
    }
}

#[cfg(test)]
mod tests {
    use crate::Ctx;

    #[test]
    fn a_sum_over_distinct_denominators_keeps_its_written_form() {
        let mut ctx = Ctx::new();
        let w = ctx
            .parse("a*x/(k1 + x) + b*y/(k2 + y) + c*z/(k3 + z*x)")
            .unwrap();
        let c = ctx.canon(w);
        let canonical = ctx.from_canonical(&c);
        ctx.note_written_form(canonical, w);
        assert_eq!(ctx.written_form(canonical), w);
        // Identity: the two are the same function.
        let d = ctx.sub(canonical, w);
        assert!(ctx.is_identically_zero(d));
    }

    #[test]
    fn a_written_form_that_cannot_be_evaluated_is_not_kept() {
        let mut ctx = Ctx::new();
        // (u*x + u^2)/u at u = 0 is 0/0; its canonical form x is fine.
        let w = ctx.parse("(0*x + 0^2)/0").ok();
        let x = ctx.parse("x").unwrap();
        if let Some(w) = w {
            ctx.note_written_form(x, w);
            assert_eq!(ctx.written_form(x), x);
        }
        let u = ctx.symbol("u");
        let e = ctx.parse("(u*x + u^2)/u").unwrap();
        let zero = ctx.int(0);
        let e0 = ctx.substitute(e, &[(u.var, zero)]);
        if let Ok(e0) = e0 {
            ctx.note_written_form(x, e0);
            assert_eq!(ctx.written_form(x), x);
        }
    }

    #[test]
    fn forms_with_a_relation_are_not_kept() {
        let mut ctx = Ctx::new();
        let w = ctx.parse("sin(th)^2 + x/(1 + x)").unwrap();
        let c = ctx.canon(w);
        let canonical = ctx.from_canonical(&c);
        ctx.note_written_form(canonical, w);
        assert_eq!(ctx.written_form(canonical), canonical);
    }
}
