//! Observable modes: a function g is one iff `sum_i w_i dg/dS_i = 0` for
//! every symmetry w (eq. 11). The test is exact.

use crate::rank::{gradient, random_point, AnalysisError};
use crate::sym_report::SymmetryReport;
use obsan_expr::{Fp, Id, RatFun, SplitMix, P};
use obsan_model::NormalForm;

/// The verdict on one candidate mode.
#[derive(Clone, Debug)]
pub struct ModeCheck {
    pub mode: Id,
    /// Per symmetry (`vectors`, then `free`), the residual `grad(g) . w`
    /// (zero when the PDE holds).
    pub residuals: Vec<RatFun>,
    pub is_mode: bool,
}

/// The verdicts, and whether the accepted modes are independent and complete.
#[derive(Clone, Debug)]
pub struct ModeReport {
    pub checks: Vec<ModeCheck>,
    /// Rank of the gradients of the accepted modes.
    pub independent_count: usize,
    /// The accepted modes are independent (exact when true: a non-zero minor
    /// was found; when false, wrong with probability at most `dependence_error`).
    pub independent: bool,
    pub dependence_error: f64,
    /// As many independent accepted modes as the rank of the system.
    pub complete: bool,
    pub rank: usize,
    /// Atoms of the system and of the accepted modes the engine cannot prove
    /// independent ([`crate::certify::undecided_atoms_of`]). Not empty: the residuals
    /// that are zero still prove eq. (11) for the symmetries given, but
    /// `independent` and `complete` rest on nonzero forms over these atoms
    /// (a minor, the rank) and are not proven; nor is a failure whose every
    /// nonzero residual holds only such atoms.
    pub undecided: Vec<String>,
}

impl ModeReport {
    /// `independent` and `complete` are proven (no undecided atom).
    pub fn decided(&self) -> bool {
        self.undecided.is_empty()
    }
}

/// Rank of the gradients of `fs` at a random point (a lower bound, equal to
/// the generic rank except with probability at most D/p).
pub(crate) fn gradient_rank(
    nf: &mut NormalForm,
    fs: &[Id],
    seed: u64,
) -> Result<(usize, f64), AnalysisError> {
    let mut rows = Vec::new();
    let mut deg = 0u64;
    for &f in fs {
        let g = gradient(nf, f);
        let d = obsan_expr::evaluate::degree_bounds(&nf.ctx, &g);
        deg = deg.saturating_add(
            d.iter().map(|x| x.0).max().unwrap_or(0) + d.iter().map(|x| x.1).sum::<u64>(),
        );
        rows.push(g);
    }
    let mut rng = SplitMix(seed ^ 0x6d6f_6465);
    let mut best = 0;
    for _ in 0..2 {
        // Roots no point mod p satisfies: the gradients may still avoid
        // them, and then evaluate exactly where the roots have no value.
        let pt = match random_point(&mut nf.ctx, &mut rng) {
            Ok(pt) => pt,
            Err(AnalysisError::NoPoint) => nf
                .ctx
                .random_fp_point_root_free(&mut rng, &|_| None)
                .map_err(|_| AnalysisError::NoPoint)?,
            Err(e) => return Err(e),
        };
        let mut m: Vec<Vec<Fp>> = Vec::new();
        for g in &rows {
            m.push(nf.ctx.eval_fp(g, &pt).map_err(|_| AnalysisError::NoPoint)?);
        }
        best = best.max(Fp::matrix_rank(m));
    }
    let per = (deg.max(1) as f64 / P as f64).min(1.0);
    Ok((best, per * per))
}

/// Check candidate modes against every symmetry.
pub fn check_modes(
    nf: &mut NormalForm,
    sym: &SymmetryReport,
    modes: &[Id],
    seed: u64,
) -> Result<ModeReport, AnalysisError> {
    let vars = nf.state_vars.clone();
    let mut checks = Vec::new();
    for &g in modes {
        let c = nf.ctx.canon(g);
        let grad: Vec<RatFun> = vars.iter().map(|&x| nf.ctx.rf_diff(&c, x)).collect();
        let mut residuals = Vec::new();
        for w in &sym.vectors {
            let mut acc = RatFun::zero();
            for (a, b) in w.iter().zip(&grad) {
                let t = nf.ctx.rf_mul(a, b);
                acc = nf.ctx.rf_add(&acc, &t);
            }
            residuals.push(acc);
        }
        // The free directions d/dx_j (unreached variables): the residual is
        // dg/dx_j (through leaves too: sin(x_j) is a leaf of its own).
        for &j in &sym.free {
            residuals.push(nf.ctx.rf_diff(&c, vars[j]));
        }
        let is_mode = residuals.iter().all(|r| r.is_zero());
        checks.push(ModeCheck {
            mode: g,
            residuals,
            is_mode,
        });
    }
    let accepted: Vec<Id> = checks
        .iter()
        .filter(|c| c.is_mode)
        .map(|c| c.mode)
        .collect();
    let (independent_count, dependence_error) = gradient_rank(nf, &accepted, seed)?;
    let independent = independent_count == accepted.len();
    let undecided = crate::decided::undecided_atoms_of(nf, &accepted);
    Ok(ModeReport {
        undecided,
        complete: independent && accepted.len() == sym.rank,
        independent,
        independent_count,
        dependence_error,
        rank: sym.rank,
        checks,
    })
}
