//! The unknown-input rank test over roots no point of F_p satisfies
//! together (docs/engine.md, "Roots in an extension field"): both routes run
//! at points where the roots take free values, and every decision whose
//! truth such a point cannot carry over is checked again at a point of an
//! extension field where every root is a root of its radicand.
//!
//! Why this suffices. A free point is a point of the family where each root
//! is replaced by a free constant multiple of itself (rank.rs, `rank_point`),
//! whose generic values specialise to the true system's. A function zero at a
//! random free point is zero on the whole family (with the stated
//! Schwartz–Zippel bound), so zero on the true system too: every "zero",
//! "dependent" and "not moved" decision carries over. A "non-zero" or
//! "independent" one need not; each is recorded as a [`Claim`] (a non-zero
//! function, or a matrix of functions whose rank at the free point was
//! `expected`, an upper bound on the true one) and proven at a point of
//! `F_(p^k)` on the roots' relations: a non-zero value there is non-zero on
//! the true system. When every claim holds there, every decision of the run
//! is the one the true system's generic point gives, so are its verdicts.

use crate::rank::AnalysisError;
use obsan_expr::evaluate::ExtField;
use obsan_expr::{Ctx, Id, SplitMix};
use obsan_recon::fp::Echelon;

/// Extension points tried before the claims are given up.
const EXT_POINTS: usize = 3;

/// A decision made at a free point that a true point must confirm.
#[derive(Clone, Debug)]
pub(crate) enum Claim {
    /// The function is not identically zero.
    NonZero(Id),
    /// The matrix of functions has rank `expected` (its rank at the free
    /// point, an upper bound on the true one).
    Rank { rows: Vec<Vec<Id>>, expected: usize },
}

/// The claims of one run, recorded only when its points have free roots.
#[derive(Default, Clone, Debug)]
pub(crate) struct Claims {
    pub(crate) active: bool,
    pub(crate) list: Vec<Claim>,
}

impl Claims {
    pub(crate) fn nonzero(&mut self, f: Id) {
        if self.active {
            self.list.push(Claim::NonZero(f));
        }
    }
    pub(crate) fn rank(&mut self, rows: Vec<Vec<Id>>, expected: usize) {
        if self.active {
            self.list.push(Claim::Rank { rows, expected });
        }
    }
    /// Gradient rows of `funcs` over `cols`, claimed of rank `expected`.
    pub(crate) fn gradients(
        &mut self,
        ctx: &mut Ctx,
        funcs: &[Id],
        cols: &[obsan_expr::Var],
        expected: usize,
    ) {
        if self.active {
            let rows = funcs
                .iter()
                .map(|&f| cols.iter().map(|&v| ctx.diff(f, v)).collect())
                .collect();
            self.list.push(Claim::Rank { rows, expected });
        }
    }
}

/// Proves every claim at one point of an extension field in which every
/// root of `ctx` has a value: the field's degree, or an error saying why the
/// free-root run stays unproven.
pub(crate) fn prove(ctx: &mut Ctx, claims: &Claims, seed: u64) -> Result<u32, AnalysisError> {
    let unproven = |why: &str| {
        AnalysisError::Invalid(format!(
            "no point mod p = 2^61-1 satisfies the roots' relations (their radicands multiply to a constant that is no power there), and the unknown-input rank test's decisions at free root values could not be proven in an extension field: {why}"
        ))
    };
    let field = ctx
        .root_indices()
        .and_then(ExtField::for_indices)
        .ok_or_else(|| {
            unproven("the roots' indices need a field of degree above 30 or not dividing p - 1")
        })?;
    let mut rng = SplitMix(seed ^ 0x0e47_5eed_0b5a_0033);
    let mut last = String::from("no point of the extension avoided the poles");
    'points: for _ in 0..EXT_POINTS {
        let Ok(point) = ctx.random_ext_point(&mut rng, &field, &|_| None) else {
            continue;
        };
        for c in &claims.list {
            match c {
                Claim::NonZero(f) => {
                    let Ok(v) = ctx.eval_ext(&[*f], &field, &point) else {
                        continue 'points;
                    };
                    if field.is_zero(&v[0]) {
                        last = "a function non-zero at the free point is zero there".into();
                        continue 'points;
                    }
                }
                Claim::Rank { rows, expected } => {
                    let flat: Vec<Id> = rows.iter().flatten().copied().collect();
                    let Ok(vals) = ctx.eval_ext(&flat, &field, &point) else {
                        continue 'points;
                    };
                    let w = rows.first().map_or(0, |r| r.len()).max(1);
                    let r = Echelon::of_rows(field, vals.chunks(w).map(|c| c.to_vec())).rank();
                    if r != *expected {
                        last = format!("a rank {expected} at the free point is {r} there");
                        continue 'points;
                    }
                }
            }
        }
        return Ok(field.degree());
    }
    Err(unproven(&last))
}
