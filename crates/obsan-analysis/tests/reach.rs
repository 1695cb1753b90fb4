//! Variables no output reaches: the symmetries and the
//! mode checks of a system with unused parameters and unreached states are
//! those of the system without them plus one `d/dx` per extra variable
//! (compared by span), and the dense work is bounded by the memory budget.

mod common;

use common::rank_fp;
use obsan_analysis::{
    check_modes, rank, restrict_to_reached, symmetries, symmetries_with, AnalysisError,
    Certificate, RankOptions, Route, SymmetryOptions, SymmetryReport,
};
use obsan_expr::{evaluate::FpPoint, Fp, SplitMix};
use obsan_model::{NormalForm, System};

/// Martinelli 2011, Section II, eq. (3): rank 2 of 3, one symmetry
/// [0, 1, 1] (a rotation about the feature), modes D and thetaR - phiR.
const LOCALIZATION: &str = "system localization\nstate D, phiR, thetaR\ninput v, omega\n\
    D' = v*cos(thetaR - phiR)\nphiR' = v*sin(thetaR - phiR)/D\nthetaR' = omega\noutput y = D\n";

/// The same system with extras no output reaches: `z` (moved by the
/// reached D), `z2` (moved by phiR, which the symmetry moves, so the
/// symmetry does not commute with this field component) and unused params.
fn extended(params: usize) -> String {
    let ps: Vec<String> = (0..params).map(|i| format!("p{i}")).collect();
    format!(
        "system localization\nstate D, phiR, thetaR, z, z2\nparam {}\ninput v, omega\n\
         D' = v*cos(thetaR - phiR)\nphiR' = v*sin(thetaR - phiR)/D\nthetaR' = omega\n\
         z' = v*D + p1\nz2' = omega*phiR\noutput y = D\n",
        ps.join(", ")
    )
}

fn nf_of(src: &str) -> NormalForm {
    System::parse(src, "t.sys")
        .unwrap()
        .normal_form(None, &[])
        .unwrap()
}

fn point(nf: &mut NormalForm) -> FpPoint {
    nf.ctx
        .random_fp_point(&mut SplitMix(11), &|_| None)
        .unwrap()
}

/// The basis of `s` as rows at `pt`: its vectors, then a unit row per free
/// direction.
fn rows(nf: &mut NormalForm, s: &SymmetryReport, pt: &FpPoint) -> Vec<Vec<Fp>> {
    let mut out = Vec::new();
    for v in &s.vectors {
        let ids: Vec<_> = v.iter().map(|e| nf.ctx.from_canonical(e)).collect();
        out.push(nf.ctx.eval_fp(&ids, pt).unwrap());
    }
    for &j in &s.free {
        let mut e = vec![Fp::ZERO; s.n];
        e[j] = Fp::ONE;
        out.push(e);
    }
    out
}

fn sym_of(nf: &mut NormalForm, route: Route) -> SymmetryReport {
    let r = rank(nf, RankOptions::default()).unwrap();
    symmetries_with(
        nf,
        &r,
        &SymmetryOptions {
            deadline: None,
            route,
        },
    )
    .unwrap()
}

#[test]
fn unreached_variables_add_their_own_directions_only() {
    let params = 40;
    let mut base = nf_of(LOCALIZATION);
    let sb = sym_of(&mut base, Route::Auto);
    assert_eq!((sb.n, sb.rank, sb.count()), (3, 2, 1));
    for route in [Route::Auto, Route::Exact, Route::Reconstruct] {
        let mut nf = nf_of(&extended(params));
        let n = nf.state.len();
        assert_eq!(n, 5 + params);
        let s = sym_of(&mut nf, route);
        // The same rank; the extras z, z2, p0.. are exactly the free directions.
        assert_eq!(s.rank, 2);
        assert_eq!(s.free, (3..n).collect::<Vec<_>>(), "{route:?}");
        assert_eq!(s.count(), n - 2);
        assert!(s.exact || matches!(s.certificate, Certificate::Random(_)));
        // By span: the found basis and the known one (the paper's [0, 1, 1]
        // and e_j for every extra variable) have the same rank n - 2.
        let pt = point(&mut nf);
        let mut all = rows(&mut nf, &s, &pt);
        assert_eq!(rank_fp(all.clone()), n - 2);
        let mut w = vec![Fp::ZERO; n];
        (w[1], w[2]) = (Fp::ONE, Fp::ONE);
        all.push(w);
        for j in 3..n {
            let mut e = vec![Fp::ZERO; n];
            e[j] = Fp::ONE;
            all.push(e);
        }
        assert_eq!(rank_fp(all), n - 2, "span differs ({route:?})");
        // Restricted to the base state, the vectors are the base system's.
        for v in &s.vectors {
            assert!(v[3..].iter().all(|e| e.is_zero()));
        }
    }
}

/// z2' = omega*phiR: the rotation does not commute with that field
/// component, so the invariance certificate of the reached part does not
/// extend; the vectors are still proven (they annihilate every Lie
/// derivative, which lives on D, phiR, thetaR).
#[test]
fn invariance_is_claimed_only_when_it_holds_on_the_whole_fields() {
    let mut nf = nf_of(&extended(3));
    let s = sym_of(&mut nf, Route::Auto);
    assert!(s.exact);
    assert_eq!(s.certificate, Certificate::Closure);
    // Without z2 every unreached component commutes: invariance stands.
    let src = extended(3)
        .replace(", z2\n", "\n")
        .replace("z2' = omega*phiR\n", "");
    let mut nf = nf_of(&src);
    let s = sym_of(&mut nf, Route::Auto);
    assert!(matches!(s.certificate, Certificate::Invariance(_)));
    assert_eq!(s.free, vec![3, 4, 5, 6]);
}

#[test]
fn modes_are_checked_against_the_free_directions() {
    let mut nf = nf_of(&extended(5));
    let s = sym_of(&mut nf, Route::Auto);
    let ids: Vec<_> = ["D", "thetaR - phiR", "p1", "D + z"]
        .iter()
        .map(|e| nf.parse_expr(e, false).unwrap())
        .collect();
    let m = check_modes(&mut nf, &s, &ids, 1).unwrap();
    let verdicts: Vec<bool> = m.checks.iter().map(|c| c.is_mode).collect();
    assert_eq!(verdicts, vec![true, true, false, false]);
    assert!(m.complete, "D and thetaR - phiR are the paper's modes");
    // p1 fails against d/dp1 (residual 1), D + z against d/dz.
    let k = s.vectors.len();
    let at = |c: &obsan_analysis::ModeCheck| c.residuals.iter().position(|r| !r.is_zero());
    assert_eq!(
        at(&m.checks[2]),
        Some(k + s.free.iter().position(|&j| j == 6).unwrap())
    );
    assert_eq!(
        at(&m.checks[3]),
        Some(k + s.free.iter().position(|&j| j == 3).unwrap())
    );
    assert_eq!(m.checks[2].residuals.len(), s.count());
}

#[test]
fn the_reached_subsystem_keeps_the_rank() {
    let mut nf = nf_of(&extended(7));
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    let red = restrict_to_reached(&mut nf).unwrap();
    assert_eq!(red.keep, vec![0, 1, 2]);
    assert_eq!(red.unreached, (3..12).collect::<Vec<_>>());
    let mut sub = red.nf;
    assert_eq!(sub.state, vec!["D", "phiR", "thetaR"]);
    let rs = rank(&mut sub, RankOptions::default()).unwrap();
    assert_eq!((r.rank, rs.rank, rs.n), (2, 2, 3));
    // Every variable reached: nothing to restrict.
    let mut base = nf_of(LOCALIZATION);
    assert!(restrict_to_reached(&mut base).is_none());
}

/// The dense work of the symmetry routes is bounded by the memory budget:
/// an output reaching 400 params (rank 1, 399 symmetries: 32 x 404 x 400
/// bytes of F_p rows and 399 x 400 canonical forms, over 10 MiB) is refused
/// under a budget of 5,000 terms (5,000 x 2,048 bytes), before anything is
/// built, with the "too large" error naming the flag that raises it.
#[test]
fn dense_symmetries_past_the_memory_budget_are_refused() {
    let names: Vec<String> = (0..400).map(|i| format!("p{i}")).collect();
    let src = format!(
        "system wide\nparam {}\noutput y = {}\n",
        names.join(", "),
        names.join(" + ")
    );
    let mut nf = nf_of(&src);
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    assert_eq!((r.rank, r.n), (1, 400));
    let budget = obsan_expr::Budget {
        max_terms: 5000,
        ..obsan_expr::Budget::default()
    };
    let res = obsan_expr::within_thread_budget(&budget, || symmetries(&mut nf, &r))
        .expect("no other engine limit");
    match res {
        Err(AnalysisError::Invalid(msg)) => {
            assert!(
                msg.contains("too large") && msg.contains("--max-terms"),
                "{msg}"
            );
            assert!(msg.contains("symmetries"), "{msg}");
        }
        other => panic!(
            "expected the memory limit, got {:?}",
            other.map(|s| s.count())
        ),
    }
}
