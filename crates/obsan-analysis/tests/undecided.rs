//! Certificates that rest on nonzero forms (the rank's minor, Gauss-Jordan
//! pivots, the modes' independence, "no more symmetries") are certified only
//! over atoms the engine proves independent; zero forms prove zero always.
//! The expected values are derived by hand beside each system.

use obsan_analysis::{
    check_modes, derive_modes, rank, symmetries_with, verify_decomposition, verify_derivation,
    Decomposition, DeriveOptions, RankOptions, RankReport, Route, SymmetryOptions, SymmetryReport,
};
use obsan_model::{NormalForm, System};

fn nf_of(src: &str) -> NormalForm {
    System::parse(src, "t.sys")
        .unwrap()
        .normal_form(None, &[])
        .unwrap()
}

fn sym_of(nf: &mut NormalForm, route: Route) -> (RankReport, SymmetryReport) {
    let r = rank(nf, RankOptions::default()).unwrap();
    let opts = SymmetryOptions {
        deadline: None,
        route,
    };
    let s = symmetries_with(nf, &r, &opts).unwrap();
    (r, s)
}

/// x' = 0, y' = 0, h1 = x, h2 = y (log(x y) - log(x) - log(y)). For x, y > 0
/// h2 = 0, so y is unobservable and d/dy is a true symmetry (true rank 1).
/// Over independent logarithms dh2/dy = log(x y) - log(x) - log(y) looks
/// nonzero: the rank is 2 of 2 and no symmetry is found. That must not be
/// certified: the report names the logarithms.
const HIDDEN: &str = "system hidden\nstate x, y\nx' = 0\ny' = 0\n\
    output h1 = x\noutput h2 = y*(log(x*y) - log(x) - log(y))\n";

/// x' = 0, y' = 0, h1 = log(x), h2 = log(x y) - log(y): h2 = h1 for x, y > 0.
/// Here the gradients, (1/x, 0) both, need no relation: rank 1, d/dy found;
/// but the atoms of the outputs are related, so completeness is not claimed.
const LOGS: &str = "system logs\nstate x, y\nx' = 0\ny' = 0\n\
    output h1 = log(x)\noutput h2 = log(x*y) - log(y)\n";

/// Martinelli 2011, eq. (3): rank 2 of 3, symmetry [0, 1, 1], modes D and
/// thetaR - phiR; no transcendental atom but sin, cos of one argument.
const LOCALIZATION: &str = "system localization\nstate D, phiR, thetaR\ninput v, omega\n\
    D' = v*cos(thetaR - phiR)\nphiR' = v*sin(thetaR - phiR)/D\nthetaR' = omega\noutput y = D\n";

fn has_logs(atoms: &[String]) -> bool {
    atoms.iter().any(|a| a == "log(x)") && atoms.iter().any(|a| a == "log(x*y)")
}

#[test]
fn no_symmetry_over_related_atoms_is_not_certified() {
    for route in [Route::Auto, Route::Exact] {
        let mut nf = nf_of(HIDDEN);
        let (r, s) = sym_of(&mut nf, route);
        // The formal answer: full rank, nothing found...
        assert_eq!((r.rank, r.n, s.count()), (2, 2, 0));
        // ...which is not decided.
        assert!(!s.decided(), "{:?}", s.undecided);
        assert!(has_logs(&s.undecided), "{:?}", s.undecided);
    }
}

#[test]
fn a_symmetry_found_over_related_atoms_is_not_called_complete() {
    let mut nf = nf_of(LOGS);
    let (r, s) = sym_of(&mut nf, Route::Exact);
    assert_eq!((r.rank, s.count()), (1, 1));
    // The vector is d/dy: its x component is zero (a zero form: proven).
    assert!(s.vectors[0][0].is_zero());
    assert!(!s.decided() && has_logs(&s.undecided), "{:?}", s.undecided);
    // log(x) satisfies eq. (11) (a zero residual, proven) but its
    // completeness rests on the rank: not decided.
    let g = nf.parse_expr("log(x)", false).unwrap();
    let rep = check_modes(&mut nf, &s, &[g], 1).unwrap();
    assert!(rep.checks[0].is_mode && rep.complete);
    assert!(!rep.decided() && has_logs(&rep.undecided));
}

#[test]
fn decided_systems_stay_certified() {
    let mut nf = nf_of(LOCALIZATION);
    let (r, s) = sym_of(&mut nf, Route::Exact);
    assert_eq!((r.rank, s.count(), s.exact), (2, 1, true));
    assert!(s.decided(), "{:?}", s.undecided);
    let ids: Vec<_> = ["D", "thetaR - phiR"]
        .iter()
        .map(|m| nf.parse_expr(m, false).unwrap())
        .collect();
    let rep = check_modes(&mut nf, &s, &ids, 1).unwrap();
    assert!(rep.complete && rep.independent && rep.decided());
    // The derived modes are proven by closure.
    let d = derive_modes(&mut nf, &r, &s, &DeriveOptions::default()).unwrap();
    let dec = d.decomposition_text("t.sys", None, &[]).unwrap();
    let checks = verify_derivation(&mut nf, &dec, "derived", 1, (&r, &s)).unwrap();
    assert!(checks.iter().all(|c| c.undecided.is_empty()));
    assert!(d.closure_proves(&checks));
}

/// x, y, z constant, h1 = x y, h2 = z (log(2 z) - log(z) - log(2)): h2 = 0 for
/// z > 0, so the true rank is 1 (only x y is observable, z is not). Over
/// independent logarithms the rank is 2 and the decomposition (z, x y)
/// closes: every output is written in it (zero forms, proven). Its closure
/// certificate would prove rank 2 and z observable, which is false: the
/// completeness check rests on the rank and must name the logarithms; the
/// independence of z and x y (gradients (0, 0, 1), (y, x, 0)) has no
/// logarithm and stays decided.
#[test]
fn closure_over_related_atoms_does_not_prove() {
    let src = "system closing\nstate x, y, z\nx' = 0\ny' = 0\nz' = 0\n\
        output h1 = x*y\noutput h2 = z*(log(2*z) - log(z) - log(2))\n";
    let dec = "system closing.sys\nlet m = x*y\nstate z, m\nz' = 0\nm' = 0\n\
        output h1 = m\noutput h2 = z*(log(2*z) - log(z) - log(2))\n";
    let mut nf = nf_of(src);
    let d = Decomposition::parse(dec, "c.dec").unwrap();
    let checks = verify_decomposition(&mut nf, &d, 1).unwrap();
    assert!(checks.iter().all(|c| c.pass), "{checks:?}");
    let complete = checks.iter().find(|c| c.name.contains("complete")).unwrap();
    assert!(
        complete.undecided.iter().any(|a| a == "log(z)"),
        "{complete:?}"
    );
    let indep = checks
        .iter()
        .find(|c| c.name.contains("independent"))
        .unwrap();
    assert!(indep.undecided.is_empty(), "{indep:?}");
    assert!(!d.closure_proves(&nf, &checks));
}
