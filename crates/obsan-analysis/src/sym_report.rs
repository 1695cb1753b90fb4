//! What a symmetry search returns (the report, its certificate, the options
//! and route that chose it) and how its vectors are written (primitive and
//! readable multiples). Below every symmetry route, so each can use them.

use crate::structure::SymmetryKind;
use crate::sym_recon::RandomCheck;
use obsan_expr::{Ctx, Poly, RatFun};
use std::time::Instant;

/// The symmetries of a system.
#[derive(Clone, Debug)]
pub struct SymmetryReport {
    pub n: usize,
    pub rank: usize,
    /// The symmetries that move reached variables, each a vector field over
    /// the analysed state; with the `d/dx` of `free`, a basis.
    pub vectors: Vec<Vec<RatFun>>,
    /// Variables no output reaches (state indices, increasing): each `d/dx`
    /// is a symmetry, exactly (its column of the codistribution is zero), kept
    /// apart from `vectors` so that n unused params cost n indices, not n^2
    /// canonical forms. [`crate::derive_modes`] wants a
    /// report without them: run it on [`crate::restrict_to_reached`]'s subsystem.
    pub free: Vec<usize>,
    /// The exact closure check passed: the rank and the symmetries are exact.
    pub exact: bool,
    /// Number of exact identities checked (gradient rows times vectors for
    /// the closure check, invariance identities for the cheap structure).
    pub rows_checked: usize,
    /// Which exact certificate proved the vectors.
    pub certificate: Certificate,
    /// Independent blocks solved apart (`sym_blocks.rs`); 1 when the
    /// system was solved whole.
    pub blocks: usize,
    /// Atoms of the system the engine cannot prove independent
    /// ([`crate::certify::undecided_atoms_of`]). Empty: everything above is certified
    /// as `certificate` says. Not empty: each vector still annihilates the
    /// codistribution (zero forms) where its components are defined, but the
    /// rank's minor and the pivots are nonzero forms over these atoms, so
    /// neither the count ("no more symmetries") nor the vectors'
    /// independence is proven: the true rank may be lower.
    pub undecided: Vec<String>,
}

/// How a symmetry basis was proved.
#[derive(Clone, Debug, PartialEq)]
pub enum Certificate {
    /// Each vector annihilates the gradients of the basis Lie derivatives and
    /// of all their one-step Lie derivatives (canonical forms).
    Closure,
    /// Cheap structure (`structure.rs`): each vector leaves every
    /// output invariant and commutes with every field (canonical forms), so
    /// it annihilates every Lie derivative; the kinds, one per vector.
    Invariance(Vec<SymmetryKind>),
    /// Found by reconstruction and proven exactly (canonical forms): each
    /// vector leaves every output invariant and its bracket with every field
    /// lies in the span of the vectors, so the span is invariant and
    /// annihilates every Lie derivative (docs/engine.md, "The span
    /// certificate"). Used where the closure words are too deep to build.
    Span,
    /// Found by reconstruction (`sym_recon.rs`) and certified by the
    /// closure identities evaluated exactly over Q at random integer points;
    /// correct except with the stated probability.
    Random(RandomCheck),
}

/// Options of [`crate::symmetries_with`].
#[derive(Clone, Debug, Default)]
pub struct SymmetryOptions {
    /// Give up (with [`AnalysisError::Timeout`], saying how far it got) after this instant.
    pub deadline: Option<Instant>,
    /// Which route decides.
    pub route: Route,
}

/// The route of [`crate::symmetries_with`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Route {
    /// Cheap structure, then exact when cheap, else reconstruction.
    #[default]
    Auto,
    /// Cheap structure, then exact Gauss–Jordan and the exact closure check.
    Exact,
    /// Reconstruction and the random certificate only (no cheap structure;
    /// the exact route only where reconstruction does not apply: square roots).
    Reconstruct,
}

impl SymmetryReport {
    /// The number of independent symmetries: `vectors` and `free`.
    pub fn count(&self) -> usize {
        self.vectors.len() + self.free.len()
    }

    /// The count and the independence of the symmetries are proven (no
    /// undecided atom); the annihilation of each vector is proven either way.
    pub fn decided(&self) -> bool {
        self.undecided.is_empty()
    }
}

/// A readable multiple of `v`: content and common factors removed; then the
/// scaling (polynomial, or one entry made 1) with the fewest terms.
pub(crate) fn normalize_vector(ctx: &mut Ctx, v: &[RatFun]) -> Vec<RatFun> {
    // Candidates: v divided by each entry (canonical), and that with its
    // denominators cleared and polynomial content removed; keep the smallest.
    let size = |w: &[RatFun]| {
        w.iter()
            .map(|e| {
                e.numerator().len()
                    + if e.denominator().is_one() {
                        0
                    } else {
                        e.denominator().len()
                    }
            })
            .sum::<usize>()
    };
    // Dividing by an entry with a sin leaf would rationalise by conjugates: skip those.
    let mut order: Vec<usize> = (0..v.len())
        .filter(|&i| !v[i].is_zero() && ctx.is_relation_free(&v[i]))
        .collect();
    order.sort_by_key(|&i| v[i].term_count());
    let mut best: Vec<RatFun> = primitive_vector(ctx, v);
    let mut best_size = size(&best);
    for &k in &order {
        #[allow(clippy::expect_used)] // `order` holds non-zero entries only
        let inv = ctx.rf_inv(&v[k]).expect("nonzero");
        let u: Vec<RatFun> = v.iter().map(|e| ctx.rf_mul(e, &inv)).collect();
        let p = primitive_vector(ctx, &u);
        for cand in [u, p] {
            let s = size(&cand);
            if s < best_size {
                best_size = s;
                best = cand;
            }
        }
    }
    // Sign: the first non-zero entry has a positive leading coefficient.
    if let Some(first) = best.iter().find(|e| !e.is_zero()) {
        if first.numerator().lc_is_negative() {
            best = best.iter().map(|e| e.neg()).collect();
        }
    }
    best
}

/// `v` times the lcm of its denominators, divided by the gcd of the numerators.
#[allow(clippy::expect_used)] // a gcd divides its arguments exactly
pub(crate) fn primitive_vector(ctx: &mut Ctx, v: &[RatFun]) -> Vec<RatFun> {
    let mut lcm = Poly::one();
    for e in v.iter().filter(|e| !e.is_zero()) {
        let g = obsan_expr::gcds::gcd(&lcm, e.denominator());
        lcm = lcm.mul(&e.denominator().div_exact(&g).expect("gcd divides"));
    }
    let l = RatFun::from_poly(lcm);
    let polys: Vec<RatFun> = v.iter().map(|e| ctx.rf_mul(e, &l)).collect();
    let mut g = Poly::zero();
    for e in &polys {
        g = obsan_expr::gcds::gcd(&g, e.numerator());
    }
    if g.is_zero() {
        return polys;
    }
    // Exact division, not multiplication by 1/g: g may contain sin leaves,
    // and rationalising 1/g would multiply by conjugates. The quotient of a
    // reduced numerator by a factor of it is reduced.
    let sign = if g.lc_is_negative() { -1 } else { 1 };
    let _ = ctx;
    polys
        .iter()
        .map(|e| {
            RatFun::from_poly(
                e.numerator()
                    .div_exact(&g)
                    .expect("gcd divides")
                    .scale(&sign.into()),
            )
        })
        .collect()
}
