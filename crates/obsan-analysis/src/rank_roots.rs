//! Ranks over root leaves no point of F_p satisfies together, certified at
//! points of an extension field (docs/engine.md, "Roots in an extension
//! field").
//!
//! The rank test's own points then give the roots free values, an upper bound
//! on the true rank (`RankReport::free_roots`). Here the basis it found is
//! evaluated again where every root is a root of its radicand, in
//! `F_p[t]/(t^k - g)`: the symbolic gradients of the basis (the jets are F_p
//! only), one elimination over that field. A rank equal to the free one there
//! is a lower bound at a true point (a non-zero minor), so the free bound is
//! met and the rank is the true one; the per-variable verdicts are read at
//! that point.

use obsan_expr::evaluate::ExtField;
use obsan_expr::{Id, SplitMix};
use obsan_model::NormalForm;
use obsan_recon::fp::Echelon;

/// Points of the extension tried before the free bound is kept.
const EXT_POINTS: usize = 3;

/// What a certified point says: the field's degree, per state variable
/// whether it is observable on its own, and the pivot columns.
pub(crate) struct Certified {
    pub degree: u32,
    pub observable: Vec<bool>,
    pub pivots: Vec<usize>,
}

/// The rank of the gradients of `basis` (the basis Lie derivatives on the
/// graph) at points of the extension field in which every root of the system
/// has a value: `Some` when it reaches `rank` (the free-root rank, an upper
/// bound), with the per-variable verdicts at that point. `None` when the
/// indices need a field of degree above `EXT_MAX` or not dividing `p - 1`,
/// when a root's radicand leaves F_p (roots of roots), or when no point
/// reaches `rank`.
pub(crate) fn certify_in_extension(
    nf: &mut NormalForm,
    basis: &[Id],
    rank: usize,
    seed: u64,
) -> Option<Certified> {
    let field = ExtField::for_indices(nf.ctx.root_indices()?)?;
    let vars = nf.state_vars.clone();
    let n = vars.len();
    let mut grads = Vec::with_capacity(basis.len() * n);
    for &f in basis {
        for &x in &vars {
            grads.push(nf.ctx.diff(f, x));
        }
    }
    let mut rng = SplitMix(seed ^ 0x5eed_e47e_4510_0f17);
    for _ in 0..EXT_POINTS {
        let Ok(point) = nf.ctx.random_ext_point(&mut rng, &field, &|_| None) else {
            continue;
        };
        let Ok(vals) = nf.ctx.eval_ext(&grads, &field, &point) else {
            continue;
        };
        let ech = Echelon::of_rows(field, vals.chunks(n.max(1)).map(|c| c.to_vec()));
        if ech.rank() != rank {
            continue;
        }
        let mut pivots: Vec<usize> = ech.pivots().collect();
        pivots.sort_unstable();
        return Some(Certified {
            degree: field.degree(),
            observable: (0..n).map(|i| ech.contains_unit(i, n)).collect(),
            pivots,
        });
    }
    None
}
