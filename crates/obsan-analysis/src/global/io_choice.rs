//! `--route auto`'s early stop (issue 36): the Taylor route is first tried
//! under a bound on the F4 eliminations' work (multiply-adds, a
//! deterministic measure of time: `GbBudget::max_work`), so that a system
//! whose Gröbner basis is long to compute costs a part of the attempt
//! before the input-output route, not all of it (mod.rs, `auto_route`).
//!
//! Why a work bound and neither a size estimate made before F4 nor a
//! fraction of the memory budget: SIAN's system after the linear presolve
//! does not tell them apart (on the 64 SI.jl benchmarks, session 32,
//! /work/briefs/s32/iofast-perf.md: Goodwin, 43 unknowns, 42 equations,
//! Bézout 2^40.6, against HIV's 45, 45, 2^44.6), and since F4 holds its
//! monomials once (obsan-groebner's table) Goodwin's basis fits the memory
//! budget but takes 9.3e9 multiply-adds (49 s) where its input-output
//! relations answer in 0.3 s. Measured work of every other SI.jl benchmark
//! the Taylor route answers (docs/performance.md, "Session 32"): HIV 3.0e8,
//! Bilirubin 3.0e7, Fujita 1.2e7, SIRC_forced 1.3e7, the rest below 4e6.
//! The bound leaves HIV a factor 2.

/// Work (`GbBudget::max_work`) the first attempt's F4 eliminations may take
/// (session 38): most SI.jl benchmarks the Taylor route answers take less
/// (MAPK_6out 9.1e5, MAPK_5out_bis 1.5e6, cLV1 3.3e6), and past it a cheap
/// input-output attempt ([`QUICK_IO_WORK`]) answers Goodwin, HIV,
/// SIWR_multiout and Bilirubin in a fraction of what [`FIRST_WORK`] alone
/// cost them (Goodwin's 6e7 took 0.45 s of its 0.6 s). The same bound holds
/// that attempt's bounded eliminations and its count's Gröbner basis.
pub(super) const QUICK_WORK: u64 = 5_000_000;

/// The multiply-adds of that cheap attempt's kernels
/// (`GlobalOptions::max_io_work`, io.rs `IoModel::max_work`): Goodwin's,
/// HIV's and SIWR_multiout's relations fit; past it (SIRC_forced, Fujita,
/// St) the attempt stops within about a second.
pub(super) const QUICK_IO_WORK: u64 = 200_000_000;

/// The work of auto's last input-output attempt, the one that finds a
/// relation past the ansatz by elimination (session 39): its Gröbner bases
/// under about six times SIWR_orig's elimination (1.7e7 units; EAIHRD's
/// 6.7e5), its kernels under twice SIWR_orig's (216 kernels of 771
/// monomials, 5.0e10 as charged), so that a model no route answers is
/// refused after a bounded time.
pub(super) const ELIM_WORK: u64 = 100_000_000;
pub(super) const ELIM_IO_WORK: u64 = 100_000_000_000;

/// Multiply-adds the second attempt's F4 eliminations may take (session 36):
/// twice Bilirubin's 3.0e7, the largest SI.jl benchmark the Taylor route
/// answers but HIV and Goodwin, whose input-output relations answer first
/// (HIV in 0.13 s where its Taylor basis takes 1 s), their initial states
/// then by [`EARLY_WORK`] on the smaller system.
pub(super) const FIRST_WORK: u64 = 60_000_000;

/// Multiply-adds the initial states' attempt after the io route may take
/// (mod.rs, `states_after_io`).
pub(super) const EARLY_WORK: u64 = 600_000_000;

/// Whether the Taylor route's error is the early attempt's work bound.
pub(super) fn stopped_early(why: &str) -> bool {
    why.contains("work (multiply-adds")
}

/// The `fallback` reason when the early attempt stopped: says that the
/// attempt was cut short, at which bound, and when the full one runs.
pub(super) fn early_reason(why: &str, bound: u64) -> String {
    format!(
        "long for the early attempt, stopped at {bound:.1e} multiply-adds of its Gröbner basis (docs/engine.md, \"Input-output route\"); the full attempt runs only when the input-output route does not answer: {why}"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_early_reason_names_the_bound() {
        let r = early_reason(
            "global: Gröbner basis budget exhausted: work (multiply-adds of the F4 eliminations)",
            FIRST_WORK,
        );
        assert!(r.starts_with("long for the early attempt"), "{r}");
        assert!(r.contains("6.0e7 multiply-adds"), "{r}");
        assert!(stopped_early(&r));
        assert!(!stopped_early("too large: the Groebner basis"));
    }
}
