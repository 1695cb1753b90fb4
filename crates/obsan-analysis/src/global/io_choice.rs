//! `--route auto`'s early stop (issue 36): the Taylor route is first tried
//! under a fraction of the memory budget, so that a system whose Gröbner
//! basis passes the budget costs a part of the attempt before the
//! input-output route, not all of it (mod.rs, `auto_route`).
//!
//! Why a memory fraction and not a size estimate made before F4: SIAN's
//! system after the linear presolve does not tell them apart. On the 64
//! SI.jl benchmarks (session 32, /work/briefs/s32/iofast-perf.md) Goodwin
//! (43 unknowns, 42 equations, Bézout 2^40.6, 282 terms) is refused while
//! HIV (45, 45, 2^44.6, 271) is answered, QWWC (42, 42, 2^32) is refused
//! while CRN (44, 46, 2^32) is answered. The memory the Gröbner basis needs
//! separates them: every system the Taylor route answers within the default
//! budget (195 MiB) passes with 25,000 `--max-terms` (49 MiB, HIV and
//! Bilirubin the largest), so half the budget leaves a factor 2.

/// The numerator and denominator of the budget's fraction tried first.
pub(super) const EARLY_BUDGET: (usize, usize) = (1, 2);

/// The memory budget of the early attempt.
pub(super) fn early_budget(max_bytes: usize) -> usize {
    max_bytes / EARLY_BUDGET.1 * EARLY_BUDGET.0
}

/// The `fallback` reason when the early attempt stopped: says that the
/// attempt was cut short, at which budget, and when the full one runs.
pub(super) fn early_reason(why: &str, early: usize, full: usize) -> String {
    const MIB: usize = 1 << 20;
    format!(
        "too large for the early attempt, stopped at {} of the memory budget ({} of {} MiB), which every SI.jl benchmark the Taylor route answers stays under; the full attempt runs only when the input-output route does not answer: {why}",
        fraction_words(),
        early / MIB,
        full / MIB
    )
}

fn fraction_words() -> String {
    match EARLY_BUDGET {
        (1, 2) => "half".into(),
        (a, b) => format!("{a}/{b}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn early_budget_is_the_fraction() {
        // 195 MiB default (100,000 terms of 2048 bytes): half is 97.66 MiB.
        let full = 100_000 * 2048;
        assert_eq!(early_budget(full), 102_400_000);
        assert!(early_budget(full) < full);
        let r = early_reason("too large: x", early_budget(full), full);
        assert!(r.starts_with("too large for the early attempt"), "{r}");
        assert!(r.contains("(97 of 195 MiB)"), "{r}");
        assert!(r.ends_with(": too large: x"), "{r}");
    }
}
