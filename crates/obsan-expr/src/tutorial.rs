//! A guided tour of the engine; every example here runs as a doc test.
//!
//! # Building and canonical forms
//!
//! Parse text into a context; equal functions get equal canonical forms.
//!
//! ```
//! use obsan_expr::Ctx;
//! let mut ctx = Ctx::new();
//! let a = ctx.parse("sin(x)^2 + cos(x)^2").unwrap();
//! assert_eq!(ctx.to_text(a), "1");
//! let b = ctx.parse("cos(2*a) - (1 - 2*sin(a)^2)").unwrap();
//! assert!(ctx.is_identically_zero(b));
//! let c = ctx.parse("(x^2 - y^2)/(x - y)").unwrap();
//! assert_eq!(ctx.to_text(c), "x + y");
//! ```
//!
//! # Hash-consing
//!
//! One node per distinct subexpression: building the same thing twice gives
//! the same id, and sums and products are sorted, so `a + b` is `b + a`.
//!
//! ```
//! use obsan_expr::Ctx;
//! let mut ctx = Ctx::new();
//! let p = ctx.parse("a*b + c").unwrap();
//! let q = ctx.parse("c + b*a").unwrap();
//! assert_eq!(p, q);
//! ```
//!
//! # Derivatives and Lie derivatives
//!
//! ```
//! use obsan_expr::Ctx;
//! let mut ctx = Ctx::new();
//! let (d, th) = (ctx.symbol("D"), ctx.symbol("theta"));
//! // Section II of the paper, eq. (5): D' = v cos(theta), theta' = w - v sin(theta)/D.
//! let f_v = vec![ctx.parse("cos(theta)").unwrap(), ctx.parse("-sin(theta)/D").unwrap()];
//! let h = d.id;
//! let l1 = ctx.lie_derivative(h, &[d.var, th.var], &f_v);
//! assert_eq!(ctx.to_text(l1), "cos(theta)");
//! let l2 = ctx.lie_derivative(l1, &[d.var, th.var], &f_v);
//! assert_eq!(ctx.to_text(l2), "(-cos(theta)^2 + 1)/D");
//! ```
//!
//! # Evaluation
//!
//! Compile once, evaluate many times in f64; or evaluate exactly in F_p at a
//! random point, which is what the rank test does.
//!
//! ```
//! use obsan_expr::{Ctx, Tape, SplitMix};
//! let mut ctx = Ctx::new();
//! let x = ctx.symbol("x");
//! let e = ctx.parse("atan2(sin(x), cos(x))").unwrap();
//! let tape = Tape::compile(&ctx, &[e], &[x.var]).unwrap();
//! assert!((tape.eval(&[0.5])[0] - 0.5).abs() < 1e-15);
//! let mut rng = SplitMix(1);
//! let pt = ctx.random_fp_point(&mut rng, &|_| None).unwrap();
//! let s2c2 = ctx.parse("sin(x)^2 + cos(x)^2").unwrap();
//! assert_eq!(ctx.eval_fp(&[s2c2], &pt).unwrap()[0], obsan_expr::Fp::ONE);
//! ```
