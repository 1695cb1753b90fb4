//! The rank test by jets against the older symbolic route (an independent
//! computation: Lie derivatives built on the graph and differentiated), and
//! the paper's published ranks.

use obsan_analysis::{rank, rank_symbolic, RankOptions, RankReport};
use obsan_model::System;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn load(path: &str) -> System {
    let src = std::fs::read_to_string(format!("{ROOT}/{path}")).unwrap();
    System::parse(&src, path).unwrap()
}

fn both(sys: &System, input: Option<&str>, seed: u64) -> (RankReport, RankReport) {
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let a = rank(
        &mut nf,
        RankOptions {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let b = rank_symbolic(
        &mut nf,
        RankOptions {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    (a, b)
}

fn assert_same(what: &str, a: &RankReport, b: &RankReport) {
    assert_eq!(a.rank, b.rank, "{what}: rank");
    assert_eq!(a.basis, b.basis, "{what}: basis words");
    assert_eq!(a.observable, b.observable, "{what}: verdicts");
    assert_eq!(a.pivots, b.pivots, "{what}: pivots");
    assert_eq!(a.max_order, b.max_order, "{what}: order");
    // A rank equal to the number of columns the outputs reach (all n, or
    // fewer when some variable is in no Lie derivative) is exact: a non-zero
    // minor proves it, no bound is involved and no second point is drawn.
    // Below it, a bound of at least 1.
    if a.rank == a.n {
        assert_eq!(a.degree_bound, 0, "{what}: full rank, bound");
    }
    if a.degree_bound == 0 {
        assert_eq!(a.error_bound, 0.0, "{what}: exact, error bound");
    } else {
        assert!(a.error_bound < 1e-6, "{what}: bound {}", a.degree_bound);
    }
    // The symbolic route keeps every column, so it knows a rank exact only
    // when it is n; the jets also when it is the number of reached columns.
    assert!(
        b.degree_bound != 0 || a.degree_bound == 0,
        "{what}: exact by the symbolic route, not by the jets"
    );
}

#[test]
fn jets_agree_with_the_symbolic_route_on_every_shipped_system() {
    let mut files: Vec<String> = Vec::new();
    for dir in ["systems", "systems/classic"] {
        for e in std::fs::read_dir(format!("{ROOT}/{dir}")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "sys") {
                files.push(format!(
                    "{dir}/{}",
                    p.file_name().unwrap().to_str().unwrap()
                ));
            }
        }
    }
    files.sort();
    assert!(files.len() >= 15, "{files:?}");
    for f in &files {
        let sys = load(f);
        let mut restrictions: Vec<Option<String>> = vec![None];
        restrictions.extend(sys.restrictions.iter().map(|r| Some(r.name.clone())));
        for r in &restrictions {
            let (a, b) = both(&sys, r.as_deref(), 1);
            assert_same(&format!("{f} {r:?}"), &a, &b);
            println!(
                "{f} {r:?}: rank {} of {}, order {}, degree bound {} (symbolic route {}), error {:.1e}",
                a.rank, a.n, a.max_order, a.degree_bound, b.degree_bound, a.error_bound
            );
        }
    }
}

fn rank_of(path: &str, input: Option<&str>) -> RankReport {
    let mut nf = load(path).normal_form(input, &[]).unwrap();
    rank(&mut nf, RankOptions::default()).unwrap()
}

#[test]
fn paper_ranks() {
    // Eq. (3): the unicycle observing the origin by bearing, rank 2 of 3.
    let r = rank_of("systems/localization.sys", None);
    assert_eq!((r.rank, r.n), (2, 3));
    // Eq. (16): the calibration problem, rank 7 of 7 with generic inputs
    // (the basis of Appendix A: orders up to 2) ...
    let r = rank_of("systems/calib.sys", None);
    assert_eq!((r.rank, r.n, r.max_order), (7, 7, 2));
    assert!(r.observable.iter().all(|&o| o));
    // ... and 4 of 7 on circles (eq. 17, wL = q wR): three symmetries.
    let r = rank_of("systems/calib.sys", Some("q"));
    assert_eq!((r.rank, r.n), (4, 7));
    // Eq. (20)-(21): the reduced system with psi, rank 4 of 5.
    let r = rank_of("systems/psi.sys", None);
    assert_eq!((r.rank, r.n), (4, 5));
}

#[test]
fn set_constants_and_delays_agree_with_the_symbolic_route() {
    let sys = load("systems/calib.sys");
    let set = vec![("q".to_string(), obsan_expr::Q::new(9.into(), 10.into()))];
    let mut nf = sys.normal_form(Some("q"), &set).unwrap();
    let a = rank(&mut nf, RankOptions::default()).unwrap();
    let mut nf = sys.normal_form(Some("q"), &set).unwrap();
    let b = rank_symbolic(&mut nf, RankOptions::default()).unwrap();
    assert_same("calib q = 9/10", &a, &b);
    assert_eq!(a.rank, 4);
    // A delayed input: u(t - tau) to first order adds the fields -tau f_i.
    let src = "system lag\nstate x, v\nparam k, tau\ninput u\ndelay tau\n\
               x' = v\nv' = -k*v + u\noutput y = x\n";
    let sys = System::parse(src, "lag.sys").unwrap();
    let (a, b) = both(&sys, None, 3);
    assert_same("delay", &a, &b);
    assert!(a.fields.names.iter().any(|f| f == "rate_u"));
}

/// The Michaelis-Menten-type pharmacokinetic model (tests/data): rank 11 of
/// 11, one output, no input, so the basis is y, L y, ..., L^10 y.
#[test]
fn pharmacokinetics_needs_order_ten() {
    let r = rank_of(
        "crates/obsan-analysis/tests/data/pharmacokinetics.sys",
        None,
    );
    assert_eq!((r.rank, r.n, r.max_order), (11, 11, 10));
    for (k, w) in r.basis.iter().enumerate() {
        assert_eq!(w.fields, vec![0; k]);
    }
    assert!(r.observable.iter().all(|&o| o));
}

/// Gradients of Lie derivatives by jets against the graph route (built,
/// differentiated, evaluated) at one point, for every word up to order 6 of
/// the pharmacokinetic model and up to order 3 of calib with both fields.
#[test]
fn jet_rows_equal_graph_rows() {
    use obsan_analysis::{Fields, LieWord};
    use obsan_expr::{lie::LieJets, SplitMix};
    for (path, max) in [
        ("crates/obsan-analysis/tests/data/pharmacokinetics.sys", 6),
        ("systems/calib.sys", 3),
        ("systems/ekf.sys", 3),
    ] {
        let mut nf = load(path).normal_form(None, &[]).unwrap();
        let fields = Fields::of(&mut nf);
        let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let jets = LieJets::new(&nf.ctx, &nf.state_vars, &fields.vectors, &outs);
        let mut rng = SplitMix(11);
        let pt = nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap();
        let m = fields.vectors.len();
        let base = rank(&mut nf, RankOptions::default()).unwrap();
        let mut words: Vec<Vec<usize>> = vec![vec![]];
        let mut checked = 0;
        while let Some(w) = words.pop() {
            if w.len() < max {
                for k in 0..m {
                    let mut v = w.clone();
                    v.push(k);
                    words.push(v);
                }
            }
            let report = RankReport {
                basis: vec![LieWord {
                    output: 0,
                    fields: w.clone(),
                }],
                ..base.clone()
            };
            let g = report.basis_functions(&mut nf).unwrap()[0];
            let vars = nf.state_vars.clone();
            let grad: Vec<_> = vars.iter().map(|&x| nf.ctx.diff(g, x)).collect();
            let want = nf.ctx.eval_fp(&grad, &pt).unwrap();
            let value = nf.ctx.eval_fp(&[g], &pt).unwrap()[0];
            let row = jets.row(0, &w, &pt, true).unwrap();
            let fast = jets.row(0, &w, &pt, false).unwrap();
            assert_eq!((&fast.gradient, fast.value), (&row.gradient, row.value));
            assert_eq!(row.gradient, want, "{path} {w:?}");
            assert_eq!(row.value, value, "{path} {w:?}");
            checked += 1;
        }
        assert!(checked > max, "{path}");
    }
}

/// A random small input-affine system: 2-3 states, 1-2 params, 0-2 inputs,
/// right-hand sides and an output from a few polynomial, rational and
/// transcendental terms.
fn random_system(rng: &mut obsan_expr::SplitMix) -> String {
    let mut pick = |n: u64| (rng.next_u64() % n) as usize;
    let ns = 2 + pick(2);
    let np = 1 + pick(2);
    let ni = pick(3);
    let states: Vec<String> = (0..ns).map(|i| format!("x{i}")).collect();
    let params: Vec<String> = (0..np).map(|i| format!("k{i}")).collect();
    let inputs: Vec<String> = (0..ni).map(|i| format!("u{i}")).collect();
    let vars: Vec<String> = states.iter().chain(&params).cloned().collect();
    let term = |pick: &mut dyn FnMut(u64) -> usize| -> String {
        let a = &vars[pick(vars.len() as u64)];
        let b = &vars[pick(vars.len() as u64)];
        match pick(9) {
            0 => format!("{a}*{b}"),
            1 => format!("{a}/(1 + {b}^2)"),
            2 => format!("sin({a})"),
            3 => format!("exp({a})*{b}"),
            4 => format!("atan({a} - {b})"),
            5 => format!("{a}^2 - {}", 1 + pick(3)),
            6 => format!("sqrt(1 + {a}^2)"),
            7 => format!("cos({a})*{b}"),
            _ => a.to_string(),
        }
    };
    let mut src = format!(
        "system random\nstate {}\nparam {}\n",
        states.join(", "),
        params.join(", ")
    );
    if ni > 0 {
        src.push_str(&format!("input {}\n", inputs.join(", ")));
    }
    for x in &states {
        let mut rhs = term(&mut pick);
        if pick(2) == 0 {
            rhs = format!("{rhs} + {}", term(&mut pick));
        }
        for u in &inputs {
            if pick(2) == 0 {
                rhs = format!("{rhs} + ({})*{u}", term(&mut pick));
            }
        }
        src.push_str(&format!("{x}' = {rhs}\n"));
    }
    src.push_str(&format!("output y = {}\n", term(&mut pick)));
    if pick(3) == 0 {
        src.push_str(&format!("output z = {}\n", term(&mut pick)));
    }
    src
}

#[test]
fn random_systems_agree_with_the_symbolic_route() {
    let mut rng = obsan_expr::SplitMix(2026);
    let mut ran = 0;
    for case in 0..60 {
        let src = random_system(&mut rng);
        let Ok(sys) = System::parse(&src, "random.sys") else {
            panic!("generator made a bad system:\n{src}");
        };
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let a = rank(
            &mut nf,
            RankOptions {
                seed: case,
                ..Default::default()
            },
        );
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let b = rank_symbolic(
            &mut nf,
            RankOptions {
                seed: case,
                ..Default::default()
            },
        );
        match (a, b) {
            (Ok(a), Ok(b)) => {
                assert_same(&src, &a, &b);
                ran += 1;
            }
            (a, b) => assert_eq!(a.is_err(), b.is_err(), "{src}"),
        }
    }
    assert!(ran >= 50, "only {ran} systems compared");
}

/// Lin-log kinetics with an exponential, for the bounds of log and exp.
const LIN_LOG_EXP: &str = "system linlogexp\nstate x1, x2\nparam a, b, c\n\
    x1' = a*(1 + b*log(x2) - c*log(x1))\n\
    x2' = x1 - exp(c*x2)\n\
    output y1 = x1*log(x1)\n";

/// The degree bound of each row against the true degree: with the row over
/// its least common denominator, every numerator's total degree (in the
/// random coordinates: symbols, and t = tan(x/2) for angles) is at most the
/// bound (a bound `P / prod B^e` reduces to `N / D` with `deg N <= deg P`).
#[test]
fn row_degree_bounds_cover_the_true_degrees() {
    use obsan_analysis::{canonical_lie, Fields, LieWord};
    use obsan_expr::{lie::LieJets, RatFun, SplitMix};
    for (path, max) in [
        ("systems/classic/hiv.sys", 3),
        ("systems/classic/fitzhugh_nagumo.sys", 4),
        ("systems/classic/michaelis_menten_pk.sys", 3),
        ("crates/obsan-analysis/tests/data/pharmacokinetics.sys", 3),
        ("crates/obsan-analysis/tests/data/seir.sys", 3),
        ("systems/localization.sys", 2),
        ("systems/calib.sys", 2),
        // Logs and exponentials (log and exp atoms are coordinates too):
        // their series' bounds by grade, one sweep of bounds per run.
        ("lin-log", 4),
    ] {
        let sys = match path {
            "lin-log" => System::parse(LIN_LOG_EXP, "lin-log.sys").unwrap(),
            _ => load(path),
        };
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let fields = Fields::of(&mut nf);
        let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let jets = LieJets::new(&nf.ctx, &nf.state_vars, &fields.vectors, &outs);
        let pt = nf.ctx.random_fp_point(&mut SplitMix(3), &|_| None).unwrap();
        let th = nf.ctx.tan_half();
        let vars = nf.state_vars.clone();
        let mut words: Vec<Vec<usize>> = vec![vec![]];
        while let Some(w) = words.pop() {
            if w.len() < max {
                for k in 0..fields.vectors.len() {
                    let mut v = w.clone();
                    v.push(k);
                    words.push(v);
                }
            }
            let bound = jets.row(0, &w, &pt, true).unwrap().degree.unwrap_or(0);
            let word = LieWord {
                output: 0,
                fields: w.clone(),
            };
            let g = canonical_lie(&mut nf, &fields, &word);
            let row: Vec<RatFun> = vars
                .iter()
                .map(|&x| {
                    let d = nf.ctx.rf_diff(&g, x);
                    nf.ctx.to_tan_half(&th, &d)
                })
                .collect();
            let mut lcm = obsan_expr::Poly::one();
            for e in row.iter().filter(|e| !e.is_zero()) {
                let gg = obsan_expr::gcds::gcd(&lcm, e.denominator());
                lcm = lcm.mul(&e.denominator().div_exact(&gg).unwrap());
            }
            let l = RatFun::from_poly(lcm);
            let true_deg = row
                .iter()
                .map(|e| nf.ctx.rf_mul(e, &l).numerator().total_degree())
                .max()
                .unwrap_or(0);
            assert!(
                true_deg <= bound,
                "{path} {w:?}: degree {true_deg} > bound {bound}"
            );
        }
    }
}

/// Parameters no output reaches cost nothing. calib.sys
/// (rank 7 of 7, eq. 16 of the paper) with 3,000 unused params declared
/// after its states: the rank stays 7, exactly the 7 original variables are
/// observable and hold the pivots, and the test runs under the default
/// budget, whose memory limit the dense jets over all 3,007 variables
/// (3 x 3007^2 support bits + 8 x 3008 x 9022 bytes, about 240 MB) would
/// trip. The symbolic route, which keeps every column, agrees.
#[test]
fn unused_params_cost_nothing() {
    let src = std::fs::read_to_string(format!("{ROOT}/systems/calib.sys")).unwrap();
    let names: Vec<String> = (0..3000).map(|i| format!("unused{i}")).collect();
    let src = format!("{src}\nparam {}\n", names.join(", "));
    let sys = System::parse(&src, "calib+unused.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let r = obsan_expr::within_thread_budget(&obsan_expr::Budget::default(), || {
        rank(&mut nf, RankOptions::default())
    })
    .expect("no budget limit")
    .expect("no analysis error");
    assert_eq!((r.rank, r.n), (7, 3007));
    let state: Vec<&str> = nf.state.iter().map(|s| s.as_str()).collect();
    for (i, name) in state.iter().enumerate() {
        assert_eq!(r.observable[i], !name.starts_with("unused"), "{name}");
    }
    assert!(r.pivots.iter().all(|&p| !state[p].starts_with("unused")));
    // Independent: every column kept, Lie derivatives on the graph.
    let (a, b) = both(&sys, None, 1);
    assert_same("calib + 3000 unused params", &a, &b);
}

/// The memory budget bounds the dense jets: an output that reaches 6,000
/// params needs 8 x 6001 x 18001 bytes (about 820 MiB) for its first sweep,
/// past the default 200 MiB, so the rank test stops before allocating with
/// a "too large" error naming the flag that raises the limit.
#[test]
fn dense_jets_past_the_memory_budget_are_refused() {
    let names: Vec<String> = (0..6000).map(|i| format!("p{i}")).collect();
    let src = format!(
        "system wide\nstate x\ninput u\nparam {}\nx' = u\noutput y = x + {}\n",
        names.join(", "),
        names.join(" + ")
    );
    let sys = System::parse(&src, "wide.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let r = obsan_expr::within_thread_budget(&obsan_expr::Budget::default(), || {
        rank(&mut nf, RankOptions::default())
    })
    .expect("no engine limit");
    match r {
        Err(obsan_analysis::AnalysisError::Invalid(msg)) => {
            assert!(
                msg.contains("too large") && msg.contains("--max-terms"),
                "{msg}"
            )
        }
        other => panic!("expected the memory limit, got {other:?}"),
    }
}

/// The incremental sweeps (each Picard pass computes only its new
/// coefficients; one sweep of a run gives every shorter run) against the
/// symbolic route, an independent computation: on random systems with
/// rational and transcendental terms and 0-2 inputs, random words up to
/// order 6 (single-field runs and mixed words), the value and gradient of
/// every Lie derivative at a random point equal those of the Lie
/// derivative built on the graph and differentiated there, exactly; the
/// rows of one sweep of a run (`run_rows`) equal the rows of each prefix
/// swept alone (`row`), degree bounds included.
#[test]
fn random_words_agree_with_graph_rows() {
    use obsan_analysis::{Fields, LieWord};
    use obsan_expr::{lie::LieJets, SplitMix};
    let mut rng = SplitMix(77);
    let mut checked = 0;
    for _ in 0..25 {
        let src = random_system(&mut rng);
        let sys = System::parse(&src, "random.sys").unwrap();
        let mut nf = sys.normal_form(None, &[]).unwrap();
        let Ok(base) = rank(&mut nf, RankOptions::default()) else {
            continue;
        };
        let fields = Fields::of(&mut nf);
        let m = fields.vectors.len();
        if m == 0 {
            continue;
        }
        let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let jets = LieJets::new(&nf.ctx, &nf.state_vars, &fields.vectors, &outs);
        let Ok(pt) = nf.ctx.random_fp_point(&mut rng, &|_| None) else {
            continue;
        };
        let vars = nf.state_vars.clone();
        for _ in 0..6 {
            let len = 1 + (rng.next_u64() % 6) as usize;
            let one = rng
                .next_u64()
                .is_multiple_of(2)
                .then(|| (rng.next_u64() % m as u64) as usize);
            let w: Vec<usize> = (0..len)
                .map(|_| one.unwrap_or_else(|| (rng.next_u64() % m as u64) as usize))
                .collect();
            let report = RankReport {
                basis: vec![LieWord {
                    output: 0,
                    fields: w.clone(),
                }],
                ..base.clone()
            };
            let g = report.basis_functions(&mut nf).unwrap()[0];
            let grad: Vec<_> = vars.iter().map(|&x| nf.ctx.diff(g, x)).collect();
            let (Ok(want), Ok(value)) = (nf.ctx.eval_fp(&grad, &pt), nf.ctx.eval_fp(&[g], &pt))
            else {
                continue;
            };
            let row = jets.row(0, &w, &pt, true).unwrap();
            assert_eq!(row.gradient, want, "{src}\n{w:?}");
            assert_eq!(row.value, value[0], "{src}\n{w:?}");
            checked += 1;
            if let Some(f) = one {
                let rows = jets.run_rows(0, f, len, &pt, true).unwrap();
                for (j, r) in rows.iter().enumerate() {
                    let alone = jets.row(0, &vec![f; j], &pt, true).unwrap();
                    let what = format!("{src}\nrun of {f} to {len}, prefix {j}");
                    assert_eq!(
                        (&r.gradient, r.value),
                        (&alone.gradient, alone.value),
                        "{what}"
                    );
                    assert_eq!(r.degree, alone.degree, "{what}");
                }
            }
        }
    }
    assert!(checked >= 60, "only {checked} words compared");
}

/// A lin-log model (logs of the states, as BioPreDyn's CHO) with an
/// exponential and a sine, three outputs and a rank below n (`b` and `d`
/// enter only as `b - d`).
const LIN_LOG: &str = "system linlog\nstate x1, x2, x3\nparam a, b, c, d, k\n\
    x1' = a*(1 + b*log(x2) - d*log(x2) - c*log(x1)) - x1\n\
    x2' = x1 - k*x2*(1 + log(x3))\n\
    x3' = exp(x1/10) - sin(x3)\n\
    output y1 = x1\noutput y2 = x2 + x3\noutput y3 = exp(x3)*x1\n";

/// Each sweep reuses the flow of the word at the point for another output
/// (the rank test asks every output on the same word in turn): rows asked in
/// an order that hits and misses that reuse (outputs in turn, words and
/// points alternating) equal the graph's, on the lin-log model.
#[test]
fn jet_rows_of_every_output_reuse_one_flow() {
    use obsan_analysis::{Fields, LieWord};
    use obsan_expr::{lie::LieJets, SplitMix};
    let sys = System::parse(LIN_LOG, "linlog.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let fields = Fields::of(&mut nf);
    let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
    let jets = LieJets::new(&nf.ctx, &nf.state_vars, &fields.vectors, &outs);
    let mut rng = SplitMix(5);
    let pts: Vec<_> = (0..2)
        .map(|_| nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap())
        .collect();
    let base = rank(&mut nf, RankOptions::default()).unwrap();
    let mut checked = 0;
    for order in [3usize, 1, 4, 0, 2] {
        let w = vec![0; order];
        for pt in [&pts[0], &pts[1], &pts[0]] {
            for o in [2usize, 0, 1, 2] {
                let report = RankReport {
                    basis: vec![LieWord {
                        output: o,
                        fields: w.clone(),
                    }],
                    ..base.clone()
                };
                let g = report.basis_functions(&mut nf).unwrap()[0];
                let vars = nf.state_vars.clone();
                let grad: Vec<_> = vars.iter().map(|&x| nf.ctx.diff(g, x)).collect();
                let want = nf.ctx.eval_fp(&grad, pt).unwrap();
                let row = jets.row(o, &w, pt, false).unwrap();
                assert_eq!(row.gradient, want, "output {o}, order {order}");
                assert_eq!(row.value, nf.ctx.eval_fp(&[g], pt).unwrap()[0]);
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 5 * 3 * 4);
}

/// The rank test on the lin-log model by jets (degree bounds through the
/// series of log, exp and sin, one sweep of bounds per run) against the
/// symbolic route: same rank, basis, verdicts; a bound, and a small error.
#[test]
fn lin_log_model_agrees_with_the_symbolic_route() {
    let sys = System::parse(LIN_LOG, "linlog.sys").unwrap();
    for seed in [1, 2] {
        let (a, b) = both(&sys, None, seed);
        assert_same("linlog", &a, &b);
        // b and d enter only as b - d: rank 7 of 8, both unobservable.
        assert_eq!((a.rank, a.n), (7, 8));
        assert!(a.degree_bound > 0, "a bound below full rank");
    }
}
