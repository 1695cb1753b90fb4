//! Floating-point evaluation of a syntax tree, before canonicalisation.
//!
//! The engine works in a field of rational functions where `sqrt(u)^2 = u`,
//! so `sqrt(x^2)` canonicalises to `x` (engine.md: sqrt is a formal root).
//! A data derivation wants the real function, `sqrt(x^2) = |x|`: this
//! evaluator computes each node of the parse tree with the f64 function of
//! its name, so square roots are the principal (non-negative) ones and
//! every branch is the real one (`atan2`, `log`, `powf`).

use crate::parse::{Ast, AstKind, BinOp};

/// A syntax tree ready for floating-point evaluation, its identifiers
/// resolved once to value slots (in order of first appearance).
#[derive(Clone, Debug, PartialEq)]
pub struct FloatExpr {
    ast: Ast,
    names: Vec<String>,
}

impl FloatExpr {
    /// Resolve `ast`'s identifiers.
    pub fn new(ast: Ast) -> FloatExpr {
        let mut names: Vec<String> = Vec::new();
        for (n, _) in ast.idents() {
            if !names.iter().any(|x| x == n) {
                names.push(n.to_string());
            }
        }
        FloatExpr { ast, names }
    }

    /// The identifiers, in the order [`FloatExpr::eval`] takes their values.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The value with `values[i]` for `names()[i]`; an identifier without a
    /// value (a short slice) is NaN, as are a function outside the language
    /// and a real function outside its domain (`log(-1)`, `sqrt(-1)`).
    /// Recursion is bounded by the parser's [`crate::limits::MAX_DEPTH`].
    pub fn eval(&self, values: &[f64]) -> f64 {
        self.node(&self.ast, values)
    }

    fn node(&self, a: &Ast, x: &[f64]) -> f64 {
        match &a.kind {
            AstKind::Num(q) => q.to_f64(),
            AstKind::Pi => std::f64::consts::PI,
            AstKind::Ident(n) => self
                .names
                .iter()
                .position(|m| m == n)
                .and_then(|i| x.get(i).copied())
                .unwrap_or(f64::NAN),
            AstKind::Neg(b) => -self.node(b, x),
            AstKind::Bin(op, l, r) => {
                let (l, r) = (self.node(l, x), self.node(r, x));
                match op {
                    BinOp::Add => l + r,
                    BinOp::Sub => l - r,
                    BinOp::Mul => l * r,
                    BinOp::Div => l / r,
                    BinOp::Pow => l.powf(r),
                }
            }
            AstKind::Call(f, args) => {
                let v: Vec<f64> = args.iter().map(|b| self.node(b, x)).collect();
                match (f.as_str(), v.as_slice()) {
                    ("sin", [a]) => a.sin(),
                    ("cos", [a]) => a.cos(),
                    ("tan", [a]) => a.tan(),
                    ("atan", [a]) => a.atan(),
                    ("atan2", [y, x]) => y.atan2(*x),
                    ("exp", [a]) => a.exp(),
                    ("log", [a]) => a.ln(),
                    ("sqrt", [a]) => a.sqrt(),
                    _ => f64::NAN,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::FloatExpr;
    use crate::{parse_ast, Ctx, Tape};
    use proptest::prelude::*;

    /// Random expression text in x and y without sqrt or atan2 (no branch:
    /// atan2's cut is the negative x axis, where a y that is zero only up to
    /// rounding, `-(x - x)` or `sin(2 pi)`, picks -pi or pi by its sign).
    fn expr() -> impl Strategy<Value = String> {
        let leaf = prop_oneof![
            Just("x".to_string()),
            Just("y".to_string()),
            Just("pi".to_string()),
            (1i32..9).prop_map(|n| n.to_string()),
            (1i32..9, 2i32..7).prop_map(|(p, q)| format!("({p}/{q})")),
        ];
        leaf.prop_recursive(4, 24, 2, |inner| {
            prop_oneof![
                (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} + {b})")),
                (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} - {b})")),
                (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} * {b})")),
                (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a} / {b})")),
                (inner.clone(), 0u32..4).prop_map(|(a, k)| format!("({a})^{k}")),
                inner.clone().prop_map(|a| format!("-({a})")),
                inner.clone().prop_map(|a| format!("sin({a})")),
                inner.clone().prop_map(|a| format!("cos({a})")),
                inner.prop_map(|a| format!("atan({a})")),
            ]
        })
    }

    /// The engine's value: the canonical form, rebuilt as a graph and
    /// compiled to its f64 tape.
    fn engine(text: &str, x: f64, y: f64) -> Result<f64, String> {
        let mut ctx = Ctx::new();
        let (sx, sy) = (ctx.symbol("x"), ctx.symbol("y"));
        let e = ctx.parse(text).map_err(|e| e.message)?;
        let c = ctx.canon(e);
        let e = ctx.from_canonical(&c);
        let tape = Tape::compile(&ctx, &[e], &[sx.var, sy.var]).map_err(|e| e.to_string())?;
        Ok(tape.eval(&[x, y])[0])
    }

    fn float(text: &str, x: f64, y: f64) -> f64 {
        let f = FloatExpr::new(parse_ast(text).unwrap());
        let v: Vec<f64> = f
            .names()
            .iter()
            .map(|n| if n == "x" { x } else { y })
            .collect();
        f.eval(&v)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Without a square root no branch is involved: the tree's value is
        /// the engine's (rewritten exactly, so equal up to rounding).
        #[test]
        fn agrees_with_the_engine_without_branches(
            text in expr(), x in -3.0f64..3.0, y in -3.0f64..3.0,
        ) {
            let a = float(&text, x, y);
            // Skip poles and cancellations where rounding dominates.
            prop_assume!(a.is_finite() && a.abs() < 1e6);
            // The engine refuses a division by an exact zero: not a value.
            let b = engine(&text, x, y);
            prop_assume!(b.is_ok());
            let b = b.unwrap();
            prop_assume!(b.is_finite());
            let tol = 1e-6 * (1.0 + a.abs());
            // The comparison needs the exact form's f64 value to be good to
            // `tol`. An exact form can be ill-conditioned in f64: sin(42 x/5)
            // is a polynomial in sin(x/5), cos(x/5) with coefficients up to
            // 2^41, and its rounding noise (up to 20 on cos((7/3 - x)^3))
            // shows as a jump under a move of the point far too small to
            // move the function itself (1e-12 relative).
            let (xn, yn) = (x * (1.0 + 1e-12), y * (1.0 + 1e-12));
            let moved = engine(&text, xn, yn).unwrap_or(f64::NAN);
            prop_assume!((moved - b).abs() <= tol / 10.0);
            prop_assert!((a - b).abs() <= tol, "{text}: {a} vs {b}");
        }

        /// sqrt(u^2) is |u| here, where the engine's canonical form is u.
        #[test]
        fn sqrt_of_a_square_is_the_absolute_value(
            text in expr(), x in -3.0f64..3.0, y in -3.0f64..3.0,
        ) {
            let u = float(&text, x, y);
            prop_assume!(u.is_finite() && u.abs() < 1e6);
            let r = float(&format!("sqrt(({text})^2)"), x, y);
            prop_assert!((r - u.abs()).abs() <= 1e-12 * (1.0 + u.abs()), "{text}: {r} vs |{u}|");
        }
    }

    #[test]
    fn the_engine_refuses_the_branch_this_evaluator_takes() {
        assert_eq!(float("sqrt(x^2)", -2.0, 0.0), 2.0);
        assert_eq!(float("sqrt(x^2*y^2) - x*y", -2.0, 3.0), 12.0);
        let e = engine("sqrt(x^2)", -2.0, 0.0).unwrap_err();
        assert!(e.contains("|.|"), "{e}");
        assert!(float("log(x)", -1.0, 0.0).is_nan());
        assert!(FloatExpr::new(parse_ast("x + y").unwrap())
            .eval(&[1.0])
            .is_nan());
    }
}
