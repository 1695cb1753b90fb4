//! The rank test's null vectors cost what the outputs reach,
//! not the number of params. A param no basis function depends on is a
//! symmetry on its own (`d/dp`, exactly: every gradient column of it is 0),
//! found without a gradient or an SVD column for it; past the stated limit
//! of reached variables the test is refused with its error, never a dense
//! SVD in the number of params squared.

use obsan_diagnose::{identifiability::stacked_rank, identifiability::InputClass, DiagnoseError};
use obsan_model::System;

/// `x' = -k x + u` observed as `y = 2 x + EXTRA`, with `unused` more params
/// declared (`p0`, `p1`, ...) of which `EXTRA` may use some.
fn system(unused: usize, extra: &str) -> System {
    let names: Vec<String> = (0..unused).map(|i| format!("p{i}")).collect();
    let src = format!(
        "system decay\nstate x\nparam k, {}\ninput u\nx' = -k*x + u\noutput y = 2*x{extra}\n",
        names.join(", ")
    );
    System::parse(&src, "decay.sys").unwrap()
}

fn rank(
    sys: &System,
    n_params: usize,
) -> Result<obsan_diagnose::identifiability::Identifiability, DiagnoseError> {
    // Two different input values: u varies on the trajectory.
    let class = InputClass {
        samples: vec![vec![vec![1.0], vec![2.0]]],
        varying: vec![true],
    };
    let pv: Vec<f64> = (0..n_params).map(|i| 0.5 + 0.001 * i as f64).collect();
    stacked_rank(
        sys,
        &class,
        &[vec![]],
        &[vec![true]],
        &[0],
        (&pv, &[vec![0.3]]),
    )
}

#[test]
fn unreached_params_are_their_own_symmetry() {
    // 3,000 params the outputs never see; k and the state are observable
    // (y = 2x, y' = 2(-k x + u) with u varying).
    let sys = system(3000, "");
    let id = rank(&sys, 3001).unwrap();
    assert!(id.param_observable("k"));
    for p in ["p0", "p1234", "p2999"] {
        assert!(!id.param_observable(p));
        let (_, terms) = id.symmetries.iter().find(|s| s.0 == p).unwrap();
        assert_eq!(terms, &vec![(p.to_string(), 1.0)]);
    }
    assert_eq!(id.symmetries.len(), 3000);
}

#[test]
fn a_reached_null_vector_still_mixes_the_reached_params() {
    // y = 2x + p0 - p1: p0 and p1 enter only as p0 - p1, so the null vector
    // of p0 is d/dp0 + d/dp1 (the sum is invisible); p2.. are unreached.
    let sys = system(50, " + p0 - p1");
    let id = rank(&sys, 51).unwrap();
    let (_, terms) = id.symmetries.iter().find(|s| s.0 == "p0").unwrap();
    assert_eq!(terms.len(), 2, "{terms:?}");
    assert_eq!(terms[0].0, "p0");
    assert!((terms[0].1 - 1.0).abs() < 1e-12);
    assert_eq!(terms[1].0, "p1");
    assert!((terms[1].1 - 1.0).abs() < 1e-9, "{terms:?}");
    let (_, terms) = id.symmetries.iter().find(|s| s.0 == "p7").unwrap();
    assert_eq!(terms, &vec![("p7".to_string(), 1.0)]);
}

#[test]
fn more_reached_variables_than_the_limit_is_refused() {
    let limit = obsan_diagnose::identifiability::MAX_NULL_COLUMNS;
    // Every extra param reached (and all but one direction of them hidden).
    let extra: String = (0..limit).map(|i| format!(" + p{i}")).collect();
    let sys = system(limit, &extra);
    let e = rank(&sys, limit + 1).unwrap_err();
    assert!(
        matches!(e, DiagnoseError::TooManyReached { reached, limit: l, .. } if reached > l && l == limit),
        "{e:?}"
    );
    assert!(e.to_string().contains("too large"), "{e}");
}

/// The reproducer, generated: an effect declaring 6,000 params.
/// Used by its output in 1,001 of them, it is refused before anything is
/// built, with its file, line and name; declaring them and using one
/// passes (an unused param costs nothing).
#[test]
fn an_effect_using_more_params_than_the_limit_is_refused_where_it_is() {
    let limit = obsan_diagnose::identifiability::MAX_NULL_COLUMNS;
    let names: Vec<String> = (0..6000).map(|i| format!("p{i}")).collect();
    let eff = |used: usize| {
        let terms: String = (0..used).map(|i| format!(" + p{i}*sin(beta)")).collect();
        format!(
            "model calib\n\neffect ok\nparam a2\noutput beta = beta + a2*sin(2*beta)\n\n\
             effect many\ndescription many params\nparam {}\noutput beta = beta{terms}\n",
            names.join(", ")
        )
    };
    let lib = obsan_model::EffectLibrary::parse(&eff(1), "many.eff").unwrap();
    obsan_diagnose::identifiability::check_effect_sizes(&lib).unwrap();
    let lib = obsan_model::EffectLibrary::parse(&eff(limit + 1), "many.eff").unwrap();
    let e = obsan_diagnose::identifiability::check_effect_sizes(&lib).unwrap_err();
    assert!(
        matches!(&e, DiagnoseError::EffectTooLarge { params, limit: l, at }
            if *params == limit + 1 && *l == limit && at == "many.eff:7: effect 'many'"),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("many.eff:7: effect 'many': too large"),
        "{e}"
    );
}
