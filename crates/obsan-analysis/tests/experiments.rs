//! Several experiments and known initial conditions, against what the paper
//! implies and derivations written here (never obsan's own output).

use obsan_analysis::{
    multi_experiment::experiments_auto, multi_experiment::rank_known,
    multi_experiment::AutoOptions, multi_experiment::Known, multi_experiment::KnownOptions, rank,
    RankOptions,
};
use obsan_expr::Q;
use obsan_model::{Experiment, System};

fn calib() -> System {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/calib.sys"
    ))
    .unwrap();
    System::parse(&src, "calib.sys").unwrap()
}

fn q(n: i64, d: i64) -> Q {
    Q::new(n.into(), d.into())
}

fn circle(v: Option<Q>) -> Experiment {
    Experiment {
        restriction: Some("q".into()),
        set: v.map(|v| vec![("q".to_string(), v)]).unwrap_or_default(),
    }
}

fn stacked_rank(sys: &System, exps: &[Experiment]) -> (usize, usize) {
    let mut nf = sys.stacked_normal_form(exps).unwrap();
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    (r.rank, r.n)
}

// By hand, from the paper (Table I and section V): on one circle (eq. 17)
// the observable modes are A_q, V_q (functions of the states mu, gamma and
// the params) and xi_q = xi (1 - q delta), L_q = psi - atan(Psi1_q) with
// Psi1_q = (xi_q - eta_q sin phi) / (eta_q cos phi), eta_q = eta (1 + q delta)
// (functions of the params only): rank 4 of 7, three directions lost.
// Stacking k circles: each adds its own 2 states, fixed by A_q, V_q given the
// params (a = 2), and the param functions xi_q, L_q. The xi_q of every q lie
// in span{d xi, d(xi delta)} (linear in q): 2 directions in all. So
//   k = 1: 2 + 2 = 4 of 7;
//   k = 2: 4 + (2 from xi_q1, xi_q2) + (2 from L_q1, L_q2) = 8 of 9, never
//          9: the 5 params get at most 4 functions;
//   k = 3: 6 + 5 = 11 of 11 (xi_q3 adds nothing, L_q3 the last direction),
// which is the paper's design: three circles (section VI-A runs q = 0.9, 0,
// -1) calibrate everything, and fewer cannot.
#[test]
fn calib_circles_rank_as_the_paper_implies() {
    let sys = calib();
    assert_eq!(stacked_rank(&sys, &[circle(Some(q(9, 10)))]), (4, 7));
    assert_eq!(
        stacked_rank(&sys, &[circle(Some(q(9, 10))), circle(Some(q(0, 1)))]),
        (8, 9)
    );
    assert_eq!(
        stacked_rank(
            &sys,
            &[
                circle(Some(q(9, 10))),
                circle(Some(q(0, 1))),
                circle(Some(q(-1, 1)))
            ]
        ),
        (11, 11)
    );
    // Unrestricted, one experiment is already enough (appendix A: rank 7).
    assert_eq!(stacked_rank(&sys, &[Experiment::default()]), (7, 7));
}

// The same design found from the model alone. Special values: the circle
// degenerates where eta_q or xi_q vanish, i.e. q = -1/delta (turning in
// place) and q = 1/delta (a straight line): with delta an unknown param no
// rational q does that, so q = 1 and q = -1 are ordinary circles for calib
// (q = 1 is straight only if rL = rR), and q = 0, -1 are in the paper's own
// design.
#[test]
fn calib_auto_finds_three_circles() {
    let sys = calib();
    let r = experiments_auto(&sys, Some("q"), &[], AutoOptions::default()).unwrap();
    assert_eq!(r.state_rank, 2);
    assert_eq!(r.experiments, 3);
    assert_eq!((r.rank, r.n), (11, 11));
    assert_eq!(r.param_rank, 5);
    let ranks: Vec<usize> = r.ranks.iter().map(|x| x.1).collect();
    assert_eq!(&ranks[..3], &[4, 8, 11]);
    assert_eq!(r.constants, vec!["q".to_string()]);
    for v in [q(0, 1), q(1, 1), q(-1, 1)] {
        let s = r.special.iter().find(|s| s.value == v).unwrap();
        assert!(!s.degenerate, "q = {v}: {s:?}");
    }
    // Unrestricted: one experiment, full rank (appendix A).
    let r = experiments_auto(&sys, None, &[], AutoOptions::default()).unwrap();
    assert_eq!((r.experiments, r.rank, r.n), (1, 7, 7));
}

// calib with equal wheel radii (delta = 1 known): now q = 1 is a straight
// line (xi_q = xi (1 - q) = 0, the wheel base disappears from the
// dynamics). Along a straight line, bearings to a fixed point from a sensor
// moving at an unknown speed (rR unknown, so the known nu does not fix it)
// determine only cross-track/speed, along-track/speed and the heading
// offset: at most 3 functions, below a generic circle's 4 (A_q, V_q, L_q,
// xi_q). So q = 1 is degenerate.
#[test]
fn equal_wheels_straight_line_is_degenerate() {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/calib.sys"
    ))
    .unwrap()
    .replace(
        "param phi, psi, eta, delta, xi",
        "param phi, psi, eta, xi\nconst delta = 1",
    );
    let sys = System::parse(&src, "calib_equal.sys").unwrap();
    let r = experiments_auto(&sys, Some("q"), &[], AutoOptions::default()).unwrap();
    assert_eq!(r.ranks[0].1, 4);
    let s = r.special.iter().find(|s| s.value == q(1, 1)).unwrap();
    assert!(s.degenerate);
    assert!(s.single_rank <= 3, "{s:?}");
}

fn riccati() -> System {
    System::parse(
        "system riccati\nstate S\nparam a\nS' = 1 + a*S^2\noutput y = S\n",
        "riccati.sys",
    )
    .unwrap()
}

// A known-initial-condition example from STRIKE-GOLDD's tracker: S' = 1 + a S^2,
// y = S, S(0) = 0. By hand:
//   y = S, y' = 1 + a S^2, y'' = 2 a S S' = 2 a S (1 + a S^2),
//   y''' = 2 a S' (1 + a S^2) + 2 a S d/dt(1 + a S^2) = 2a at S = 0.
// d/da of y, y', y'' at S = 0 are 0, S^2 = 0, 2 S (1 + 2 a S^2) = 0: a is
// invisible up to order 2 and identifiable from order 3.
#[test]
fn riccati_known_zero_initial_state() {
    let mut nf = riccati().normal_form(None, &[]).unwrap();
    let r = rank_known(
        &mut nf,
        &[Known {
            index: 0,
            value: Some(Q::zero()),
        }],
        KnownOptions::default(),
    )
    .unwrap();
    assert_eq!(r.unknown, vec![1]);
    assert_eq!(r.point_rank, Some(1));
    assert!(r.full() && r.determined);
    assert_eq!(r.order_checked, 3);
    assert_eq!(r.basis[0].order(), 3);
    assert_eq!(r.observable, vec![true]);
    // Known but generic: a already in y' = 1 + a S^2.
    let r = rank_known(
        &mut nf,
        &[Known {
            index: 0,
            value: None,
        }],
        KnownOptions::default(),
    )
    .unwrap();
    assert_eq!((r.rank, r.point_rank), (1, None));
    // Stopping before order 3 finds nothing: a lower bound, not determined
    // (the generic upper bound is 1).
    let r = rank_known(
        &mut nf,
        &[Known {
            index: 0,
            value: Some(Q::zero()),
        }],
        KnownOptions {
            max_order: 2,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((r.rank, r.generic_rank, r.determined), (0, 1, false));
}

fn compartments() -> System {
    System::parse(
        "system c2\nstate x1, x2\nparam k01, k02, k12, k21\n\
         x1' = -(k01 + k21)*x1 + k12*x2\nx2' = k21*x1 - (k02 + k12)*x2\noutput y = x1\n",
        "c2.sys",
    )
    .unwrap()
}

// Two compartments, no input, y = x1, A = [[-(k01+k21), k12], [k21, -(k02+k12)]].
// y^(k)(0) = e1' A^k x0. Started empty (x0 = 0): y = 0 for ever, every
// derivative is 0 and linear in x0, so its gradient in the params is 0:
// rank 0, all four rate constants lost. Known generic x0: the s_k = e1' A^k x0
// satisfy the order-2 recurrence of A's characteristic polynomial, so all are
// functions of s_1, s_2, s_3, which are functions of (tr A, det A,
// a11 x1 + a12 x2) and back: rank 3 of 4 (tr has a22, det a21, s_1 a11 and
// a12: independent).
#[test]
fn compartments_started_empty_lose_everything() {
    let mut nf = compartments().normal_form(None, &[]).unwrap();
    let zero = |i| Known {
        index: i,
        value: Some(Q::zero()),
    };
    let r = rank_known(&mut nf, &[zero(0), zero(1)], KnownOptions::default()).unwrap();
    assert_eq!(r.unknown, vec![2, 3, 4, 5]);
    // x = 0 is an equilibrium for every rate: the known coordinates never
    // move, so the answer is exact, not just the point's lower bound.
    assert!(r.invariant && r.determined);
    assert_eq!(r.rank, 0);
    assert_eq!(r.generic_rank, 3);
    assert_eq!(r.observable, vec![false; 4]);
    let generic = |i| Known {
        index: i,
        value: None,
    };
    let r = rank_known(&mut nf, &[generic(0), generic(1)], KnownOptions::default()).unwrap();
    assert_eq!(r.rank, 3);
    assert_eq!(r.observable, vec![false; 4]);
}

#[test]
fn known_value_inside_a_function_is_refused() {
    let mut nf = calib().normal_form(None, &[]).unwrap();
    let e = rank_known(
        &mut nf,
        &[Known {
            index: 1,
            value: Some(Q::zero()),
        }],
        KnownOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("gamma"), "{e}");
}
