//! `obsan rank`, `symmetries`, `lie`, `check`, `verify`.

use crate::cli::{
    deadline_after, AnalysisArgs, CheckArgs, LieArgs, OutputArgs, RankArgs, SymArgs, VerifyArgs,
};
use crate::expr_cmds::{not_decided_note, parse_arg_in};
use crate::json;
use crate::show::{load_normal_form, load_system};
use crate::Failure;
use obsan_analysis::{
    canonical_lie, check_modes, rank as rank_test, rank_by_blocks, symmetries_with,
    verify_decomposition_with, Certificate, Decomposition, Fields, LieWord, RankOptions,
    RankReport, Route, SymmetryOptions, SymmetryReport,
};
use obsan_expr::RatFun;
use obsan_model::NormalForm;
use std::process::ExitCode;
use std::time::Instant;

/// Formulas for people: partially factored (exact; parses back to the same form).
fn fmt_rf(nf: &NormalForm, r: &RatFun, out: &OutputArgs) -> String {
    if out.latex {
        nf.ctx.ratfun_latex_factored(r)
    } else {
        nf.ctx.ratfun_text_factored(r)
    }
}

/// Run the rank test with progress (src/progress.rs) and the deadline;
/// `blocks`: independent blocks ranked apart ([`rank_by_blocks`]).
fn run_rank(
    nf: &mut NormalForm,
    an: &AnalysisArgs,
    deadline: Option<Instant>,
    blocks: bool,
) -> Result<RankReport, Failure> {
    // The shared progress display: a bar on a terminal, plain lines in a log
    // (a long rank test in a batch job shows it is alive), none from Python.
    let bar = crate::progress::Progress::new("rank", nf.state.len() as u64, "directions");
    let mut progress = |level: usize, r: usize, _n: usize| {
        bar.set_position(r as u64);
        bar.set_message(&format!("Lie derivative order {level}"));
    };
    let opts = RankOptions {
        seed: an.seed,
        deadline,
        progress: Some(&mut progress),
    };
    let report = if blocks {
        rank_by_blocks(nf, opts)
    } else {
        rank_test(nf, opts)
    };
    drop(bar);
    report.map_err(|e| Failure(e.to_string()))
}

/// The root leaves (`sqrt`, `u^(1/q)`) of the system, as text.
fn root_atom_texts(nf: &NormalForm) -> Vec<String> {
    let roots: Vec<obsan_expr::Var> = (0..nf.ctx.leaf_count() as obsan_expr::Var)
        .filter(|&v| nf.ctx.root_arg(v).is_some())
        .collect();
    nf.ctx.atom_texts(&roots)
}

fn word_text(nf: &NormalForm, fields: &Fields, w: &LieWord) -> String {
    let outs: Vec<String> = nf.outputs.iter().map(|o| o.0.clone()).collect();
    w.display(&fields.names, &outs)
}

fn system_title(nf: &NormalForm) -> String {
    let mut t = format!("system {}", nf.name);
    if let Some(r) = &nf.restriction {
        t.push_str(&format!(" with restriction {r}"));
    }
    let set: Vec<String> = nf
        .consts
        .iter()
        .filter_map(|(n, v)| v.as_ref().map(|q| format!("{n} = {q}")))
        .collect();
    if !set.is_empty() {
        t.push_str(&format!(" ({})", set.join(", ")));
    }
    t
}

pub fn rank(a: &RankArgs) -> Result<ExitCode, Failure> {
    if a.along.is_some() {
        return crate::along_cmd::run(a);
    }
    if a.sys.experiments.as_deref() == Some("auto") {
        return crate::experiments_cmd::auto_cmd(a);
    }
    let (_, mut nf) = load_normal_form(&a.sys)?;
    if !nf.unknown_inputs.is_empty() {
        return crate::unknown_input_cmd::rank(a, &nf);
    }
    if !a.known.is_empty() || !a.known_generic.is_empty() {
        return crate::experiments_cmd::rank_known_cmd(a, nf);
    }
    let experiments =
        crate::show::experiments_of(&a.sys)?.map(|e| crate::experiments_cmd::describe_typed(&e));
    let deadline = deadline_after(Instant::now(), a.an.timeout);
    let mut r = run_rank(&mut nf, &a.an, deadline, false)?;
    // The ranks are of the formal field in which the atoms are independent;
    // a relation among them can only lower the true rank, so full rank is
    // certified only over independent atoms.
    let mut undecided = obsan_analysis::certify::undecided_atoms_of(&mut nf, &[]);
    if r.free_roots {
        // The roots took free values (no point satisfies their relations mod
        // p): the rank is an upper bound, as over undecided atoms.
        undecided.extend(root_atom_texts(&nf));
        undecided.sort();
        undecided.dedup();
    }
    // Explicit time: report the user's states, not the clock.
    crate::clock::hide_in_rank(&nf, &mut r);
    let nf = crate::clock::user_view(&nf).unwrap_or(nf);
    let words: Vec<String> = r
        .basis
        .iter()
        .map(|w| word_text(&nf, &r.fields, w))
        .collect();
    let obs: Vec<&String> = nf
        .state
        .iter()
        .zip(&r.observable)
        .filter(|(_, o)| **o)
        .map(|(s, _)| s)
        .collect();
    let unobs: Vec<&String> = nf
        .state
        .iter()
        .zip(&r.observable)
        .filter(|(_, o)| !**o)
        .map(|(s, _)| s)
        .collect();
    let full = r.rank == r.n;
    let exact = full && undecided.is_empty();
    if a.out.json {
        crate::json::print(&json::Rank {
            basis: r
                .basis
                .iter()
                .zip(&words)
                .map(|(w, t)| json::BasisWord {
                    lie_derivative: t.clone(),
                    order: w.order(),
                })
                .collect(),
            decided: undecided.is_empty(),
            degree_bound: r.degree_bound,
            error_bound: if exact { 0.0 } else { r.error_bound },
            evaluated: r.evaluated,
            exact,
            experiments: experiments.map(|e| e.0),
            max_order: r.max_order,
            measured_inputs: nf.measured_inputs.clone(),
            n: r.n,
            observable_variables: obs.into_iter().cloned().collect(),
            rank: r.rank,
            restriction: nf.restriction.clone(),
            roots_field_degree: r.roots_field,
            seed: r.seed,
            state: nf.state.clone(),
            system: nf.name.clone(),
            weakly_locally_observable: (undecided.is_empty() || !full).then_some(full),
            undecided_atoms: undecided,
            unobservable_variables: unobs.into_iter().cloned().collect(),
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = String::new();
    o.push_str(&format!(
        "{}: state [{}]\n",
        system_title(&nf),
        nf.state.join(", ")
    ));
    if let Some((_, t)) = &experiments {
        o.push_str(&format!(
            "experiments (params shared, states x@k per experiment): {t}\n"
        ));
    }
    let verdict = if exact {
        "weakly locally observable"
    } else if full {
        "weakly locally observable if the atoms below are independent (not decided)"
    } else {
        "not weakly locally observable"
    };
    if let Some(note) = crate::clock::measured_note(&nf) {
        o.push_str(&format!("{note}\n"));
    }
    o.push_str(&format!("rank {} of {}: {verdict}\n", r.rank, r.n));
    o.push_str(&format!(
        "basis of the codistribution (Lie derivatives up to order {}; L_a L_b h = L_a(L_b(h))):\n",
        r.max_order
    ));
    for w in &words {
        o.push_str(&format!("  d {w}\n"));
    }
    let list = |v: &[&String]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        }
    };
    // Over undecided atoms the per-variable verdicts are those of the system
    // with the atoms independent: a relation among them restricts the
    // Jacobian to a subvariety, which bounds the rank but can move a unit
    // vector into or out of the row space (`cos(2 pi/5) - (sqrt 5 - 1)/4`
    // is 0, so `x1 + (that) x2` reads x1 alone).
    let qual = if undecided.is_empty() {
        ""
    } else {
        " (with the atoms below independent; not certified)"
    };
    o.push_str(&format!("observable on their own{qual}: {}\n", list(&obs)));
    o.push_str(&format!(
        "not observable on their own{qual}: {}\n",
        list(&unobs)
    ));
    if let Some(k) = r.roots_field {
        o.push_str(&format!("no point mod p = 2^61-1 satisfies the roots' relations together (their radicands multiply to a constant that is no power there): the rank was certified at a point of the field of p^{k} elements, where every root has its value\n"));
    }
    if r.free_roots {
        o.push_str("no point mod 2^61-1 satisfies the roots' relations together (their radicands multiply to a constant that is no power there): the roots took free values\n");
    }
    if !undecided.is_empty() {
        o.push_str(&format!(
            "not decided: the atoms {} may be related in ways the engine does not detect; the rank above is that of the system with them independent, an upper bound on the true rank (a rank below n proves the system not weakly locally observable); which variables are observable on their own is certified neither way, a relation can change it\n",
            undecided.join(", ")
        ));
    }
    if exact {
        o.push_str("exact: a non-singular minor of full rank was found (a non-zero value at a point proves it)\n");
    } else if full {
        o.push_str("a non-singular minor of full rank was found at a point where the atoms above take independent values\n");
    } else if r.degree_bound == 0 && undecided.is_empty() {
        // The rank equals the number of variables the outputs reach: the
        // others have zero columns exactly, so the minor proves the rank.
        o.push_str("exact: a non-singular minor over every variable the outputs reach was found (a non-zero value at a point proves the rank); the other variables are in no Lie derivative\n");
    } else {
        o.push_str(&format!(
            "probabilistic: exact arithmetic mod 2^61-1 at 2 random points (seed {}); the rank is never too high, and too low with probability <= {:.1e} (Schwartz-Zippel, degree bound {}); `obsan symmetries --exact` proves it exactly\n",
            r.seed, r.error_bound, r.degree_bound
        ));
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

/// What certified the symmetries, as JSON: the kind's name (the suite bench reads it) and,
/// for a random certificate, its figures.
fn certificate_json(s: &SymmetryReport) -> (json::SymCertificate, Option<json::Certification>) {
    match &s.certificate {
        Certificate::Closure => (json::SymCertificate::Closure, None),
        Certificate::Invariance(_) => (json::SymCertificate::Invariance, None),
        Certificate::Span => (json::SymCertificate::Span, None),
        Certificate::Random(c) => (
            json::SymCertificate::Random,
            Some(json::Certification {
                degree: c.degree,
                error_bound: c.error_bound,
                identities: c.identities,
                points: c.points,
                primes: c.primes,
            }),
        ),
    }
}

fn symmetry_json(nf: &NormalForm, r: &RankReport, s: &SymmetryReport) -> json::Symmetries {
    let (certificate, certification) = certificate_json(s);
    json::Symmetries {
        blocks: s.blocks,
        certificate,
        certification,
        decided: s.decided(),
        // `exact` is the whole answer: vectors, count and independence. Over
        // undecided atoms only the annihilation (zero forms) is proven.
        exact: s.exact && s.decided(),
        // Unreached variables: each d/dx is a symmetry, listed by name (a unit
        // vector each would make the output quadratic in the state).
        free_directions: s.free.iter().map(|&j| nf.state[j].clone()).collect(),
        n: r.n,
        rank: r.rank,
        restriction: nf.restriction.clone(),
        rows_checked: s.rows_checked,
        state: nf.state.clone(),
        symmetries: s.vectors.iter().map(|v| json::vector(nf, v)).collect(),
        system: nf.name.clone(),
        undecided_atoms: s.undecided.clone(),
    }
}

/// The rank and the symmetries for `check`/`verify`: the default route
/// (cheap structure, else reconstruction certified at random points) unless
/// `exact`; the residuals of eq. (11) against them are exact either way.
fn compute_symmetries(
    nf: &mut NormalForm,
    an: &AnalysisArgs,
    exact: bool,
) -> Result<(RankReport, SymmetryReport), Failure> {
    let deadline = deadline_after(Instant::now(), an.timeout);
    let r = run_rank(nf, an, deadline, true)?;
    let opts = SymmetryOptions {
        deadline,
        route: if exact { Route::Exact } else { Route::Auto },
    };
    let s = symmetries_with(nf, &r, &opts).map_err(|e| Failure(e.to_string()))?;
    Ok((r, s))
}

/// What certified the symmetries, for people; and its error bound (0 when exact).
fn sym_certificate(s: &SymmetryReport) -> (String, f64) {
    let n = s.count();
    match &s.certificate {
        _ if n == 0 && s.decided() => ("none to find: the rank is full (exact)".into(), 0.0),
        _ if n == 0 => (
            "none found: the rank is full with the atoms independent (not decided)".into(),
            0.0,
        ),
        Certificate::Closure => ("exact Gauss-Jordan, proven by the exact closure check".into(), 0.0),
        Certificate::Invariance(_) => ("cheap structure, proven exactly by invariance".into(), 0.0),
        Certificate::Span => ("reconstructed, proven exactly by the span certificate".into(), 0.0),
        Certificate::Random(c) => (
            format!(
                "reconstructed, certified at {} random points over {} primes: wrong with probability <= {:.1e}",
                c.points, c.primes, c.error_bound
            ),
            c.error_bound,
        ),
    }
}

/// The free directions of a symmetry report, one line (empty when none):
/// `w_{k+1} .. w_{k+f}` are `d/dx` for the variables no output reaches.
pub(crate) fn free_line(nf: &NormalForm, s: &SymmetryReport) -> String {
    if s.free.is_empty() {
        return String::new();
    }
    let k = s.vectors.len();
    let names: Vec<&str> = s.free.iter().map(|&j| nf.state[j].as_str()).collect();
    let which = if names.len() == 1 {
        format!("w{} = d/d{}", k + 1, names[0])
    } else {
        format!("w{} .. w{} = d/dx", k + 1, k + names.len())
    };
    format!(
        "{which} for the {} variable{} no output reaches (unobservable, exact: {} in no Lie derivative): {}\n",
        names.len(),
        if names.len() == 1 { "" } else { "s" },
        if names.len() == 1 { "it is" } else { "each is" },
        names.join(", ")
    )
}

pub fn symmetries(a: &SymArgs) -> Result<ExitCode, Failure> {
    let (_, mut nf) = load_normal_form(&a.sys)?;
    if !nf.unknown_inputs.is_empty() {
        return crate::unknown_input_cmd::symmetries(a, &mut nf);
    }
    // The whole --timeout: the stages poll this deadline and stop on it with
    // a message saying how far they got (the watchdog waits a second more).
    let deadline = deadline_after(Instant::now(), Some(a.timeout()));
    let r = run_rank(&mut nf, &a.an, deadline, true)?;
    let opts = SymmetryOptions {
        deadline,
        route: if a.exact { Route::Exact } else { Route::Auto },
    };
    let mut s = symmetries_with(&mut nf, &r, &opts).map_err(|e| Failure(e.to_string()))?;
    // Explicit time: report the user's states, not the clock.
    let mut r = r;
    crate::clock::hide_in_symmetries(&nf, &mut r, &mut s);
    let nf = crate::clock::user_view(&nf).unwrap_or(nf);
    if a.out.json {
        crate::json::print(&symmetry_json(&nf, &r, &s))?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = format!(
        "{}: rank {} of {}, {} {}symmetr{}{}\n",
        system_title(&nf),
        r.rank,
        r.n,
        s.count(),
        if s.decided() { "independent " } else { "" },
        if s.count() == 1 { "y" } else { "ies" },
        if s.decided() {
            ""
        } else {
            " found (not decided: see below)"
        }
    );
    o.push_str(&format!("state order: [{}]\n", nf.state.join(", ")));
    if let Some(note) = crate::clock::measured_note(&nf) {
        // Each such input is an output: every symmetry leaves it fixed.
        o.push_str(&format!("{note}; no symmetry moves them\n"));
    }
    for (k, v) in s.vectors.iter().enumerate() {
        let comps: Vec<String> = v.iter().map(|e| fmt_rf(&nf, e, &a.out)).collect();
        o.push_str(&format!("w{} = [{}]\n", k + 1, comps.join(", ")));
    }
    o.push_str(&free_line(&nf, &s));
    if !s.decided() {
        o.push_str(&sym_not_decided(&s));
    } else if s.count() == 0 {
        o.push_str("no continuous symmetry: the state is weakly locally observable (exact)\n");
    } else if let obsan_analysis::Certificate::Invariance(kinds) = &s.certificate {
        let names: Vec<String> = kinds
            .iter()
            .map(|k| match k {
                obsan_analysis::SymmetryKind::Free(j) => {
                    format!("{} appears nowhere", nf.state[*j])
                }
                obsan_analysis::SymmetryKind::Translation => "translation".into(),
                obsan_analysis::SymmetryKind::Scaling => "scaling".into(),
            })
            .collect();
        o.push_str(&format!(
            "exact: cheap structure ({}); each symmetry {}leaves every output invariant and commutes with every field ({} identities checked in canonical form), so it annihilates every Lie derivative, which proves the rank {} exactly\n",
            names.join(", "),
            if s.free.is_empty() {
                ""
            } else {
                "on the reached variables "
            },
            s.rows_checked,
            r.rank
        ));
    } else if let Certificate::Span = &s.certificate {
        o.push_str(&format!(
            "exact: reconstructed modulo 2^61-1, then proven in canonical form: each symmetry leaves every output invariant and its bracket with every field lies in the span of the symmetries ({} identities), so the span is invariant under the fields and annihilates every Lie derivative, which proves the rank {} exactly\n",
            s.rows_checked, r.rank
        ));
    } else if let Certificate::Random(c) = &s.certificate {
        o.push_str(&format!(
            "certified: found by reconstruction modulo 2^61-1; each symmetry annihilates the gradients of the outputs, of the basis Lie derivatives and of all their Lie derivatives ({} identities), checked at {} random points modulo {} fresh random 62-bit primes; error probability below {:.0e} (Schwartz-Zippel, degree bound {}; a prime dividing a content below 2^{})\n",
            c.identities, c.points, c.primes, c.error_bound.max(1e-300), c.degree, c.content_bits
        ));
    } else if s.exact {
        o.push_str(&format!(
            "exact: each symmetry annihilates the gradients of the basis Lie derivatives and of all their Lie derivatives ({} products checked), which proves the rank {} exactly\n",
            s.rows_checked, r.rank
        ));
    } else {
        o.push_str("warning: a one-step Lie derivative is not annihilated: the rank test was unlucky; run again with another --seed\n");
    }
    if s.blocks > 1 {
        o.push_str(&format!(
            "solved as {} blocks (parts that share only common variables, or none), each certified on its own; the counts and bounds above are their sums\n",
            s.blocks
        ));
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

/// What a symmetry report over undecided atoms still proves, and what not.
fn sym_not_decided(s: &SymmetryReport) -> String {
    let shown = if s.vectors.is_empty() {
        String::new()
    } else {
        format!(
            "each w above annihilates the gradients of every Lie derivative where its components are defined ({}: zero canonical forms prove zero); ",
            match &s.certificate {
                Certificate::Random(c) => format!("certified at random points, error below {:.0e}", c.error_bound.max(1e-300)),
                _ => "exact".into(),
            }
        )
    };
    format!(
        "not decided: the atoms {} may be related in ways the engine does not detect; {shown}the rank {} is that of the system with them independent, an upper bound on the true rank, so there may be more symmetries than listed{}\n",
        s.undecided.join(", "),
        s.rank,
        if s.vectors.len() > 1 {
            ", and the independence of the w (nonzero pivots over these atoms) is not proven"
        } else {
            ""
        }
    )
}

pub fn lie(a: &LieArgs) -> Result<ExitCode, Failure> {
    if a.order > 8 {
        return Err(Failure(format!(
            "--order {} is too high: at most 8 (the number of words grows as inputs^order)",
            a.order
        )));
    }
    let (_, mut nf) = load_normal_form(&a.sys)?;
    crate::unknown_input_cmd::refuse_because(
        &nf,
        "lie",
        "it prints Lie derivatives along the known fields only",
    )?;
    let fields = obsan_analysis::Fields::of(&mut nf);
    // outputs x (1 + F + ... + F^order) derivatives, each at least one
    // printed term: past the term budget the answer cannot fit in it, so it
    // is refused before any word is built (vins at order 8 is
    // 13 million words).
    let n_words = (0..=a.order)
        .try_fold(0usize, |acc, k| {
            let fk = fields.names.len().checked_pow(k as u32)?;
            acc.checked_add(nf.outputs.len().checked_mul(fk)?)
        })
        .unwrap_or(usize::MAX);
    if n_words > a.limit.max_terms {
        return Err(Failure(format!(
            "{}: too large: {} Lie derivatives up to order {} ({} outputs x {} fields^k), more \
             than the term budget {} (raise it with --max-terms, or lower --order)",
            a.sys.system,
            if n_words == usize::MAX {
                "more than 2^64".to_string()
            } else {
                n_words.to_string()
            },
            a.order,
            nf.outputs.len(),
            fields.names.len(),
            a.limit.max_terms
        )));
    }
    let mut words: Vec<LieWord> = (0..nf.outputs.len())
        .map(|o| LieWord {
            output: o,
            fields: vec![],
        })
        .collect();
    let mut level = words.clone();
    for _ in 0..a.order {
        let mut next = Vec::new();
        for w in &level {
            for k in 0..fields.names.len() {
                let mut w2 = w.clone();
                w2.fields.push(k);
                next.push(w2);
            }
        }
        words.extend(next.iter().cloned());
        level = next;
    }
    let mut rows = Vec::new();
    for w in &words {
        let f = canonical_lie(&mut nf, &fields, w);
        rows.push((word_text(&nf, &fields, w), w.order(), f));
    }
    if a.out.json {
        let lie_derivatives = rows
            .iter()
            .map(|(t, k, f)| crate::json::LieDerivative {
                latex: nf.ctx.ratfun_latex(f),
                lie_derivative: t.clone(),
                order: *k,
                text: nf.ctx.ratfun_text(f),
            })
            .collect();
        crate::json::print(&crate::json::Lie {
            exact: true,
            lie_derivatives,
            restriction: nf.restriction.clone(),
            system: nf.name.clone(),
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = format!(
        "{}: Lie derivatives up to order {} (exact; L_a L_b h = L_a(L_b(h)))\n",
        system_title(&nf),
        a.order
    );
    for (t, _, f) in &rows {
        o.push_str(&format!("{t} = {}\n", fmt_rf(&nf, f, &a.out)));
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

pub fn check(a: &CheckArgs) -> Result<ExitCode, Failure> {
    let (_, mut nf) = load_normal_form(&a.sys)?;
    crate::unknown_input_cmd::refuse_because(
        &nf,
        "check",
        "the residuals of eq. (11) are taken against the known-input symmetries",
    )?;
    let mut ids = Vec::new();
    for m in &a.modes {
        ids.push(parse_arg_in(&mut nf, m)?);
    }
    let (_, s) = compute_symmetries(&mut nf, &a.an, a.exact)?;
    let rep = check_modes(&mut nf, &s, &ids, a.an.seed).map_err(|e| Failure(e.to_string()))?;
    let all_pass = rep.checks.iter().all(|c| c.is_mode) && rep.independent;
    let (cert, bound) = sym_certificate(&s);
    // Independence (a nonzero minor) and completeness (the rank) rest on
    // nonzero forms; a dependence found is formal, hence true.
    let decided = rep.decided() && s.decided();
    if a.out.json {
        let checks = a
            .modes
            .iter()
            .zip(&rep.checks)
            .map(|(m, c)| {
                let undecided = mode_undecided(&mut nf.ctx, c);
                json::ModeCheck {
                    decided: undecided.is_empty(),
                    mode: m.clone(),
                    observable_mode: undecided.is_empty().then_some(c.is_mode),
                    residuals: c.residuals.iter().map(|r| nf.ctx.ratfun_text(r)).collect(),
                    undecided_atoms: undecided,
                }
            })
            .collect();
        let (certificate, certification) = certificate_json(&s);
        crate::json::print(&json::Check {
            certificate,
            certification,
            checks,
            complete: decided.then_some(rep.complete),
            exact: bound == 0.0 && decided,
            independent: (decided || !rep.independent).then_some(rep.independent),
            independent_count: rep.independent_count,
            rank: rep.rank,
            restriction: nf.restriction.clone(),
            symmetries: s.count(),
            system: nf.name.clone(),
        })?;
    } else {
        let mut o = format!(
            "{}: rank {}, {} symmetr{}\n",
            system_title(&nf),
            rep.rank,
            s.count(),
            if s.count() == 1 { "y" } else { "ies" }
        );
        o.push_str(&format!("symmetries: {cert}\n"));
        for (m, c) in a.modes.iter().zip(&rep.checks) {
            if c.is_mode {
                o.push_str(&format!(
                    "PASS {m}: satisfies eq. (11) for every symmetry ({})\n",
                    if !decided {
                        "exact residuals against the symmetries found; see \"not decided\" below"
                    } else if bound == 0.0 {
                        "exact"
                    } else {
                        "exact residuals; the symmetries as certified above"
                    }
                ));
            } else {
                let undecided = mode_undecided(&mut nf.ctx, c);
                // A failed mode has a non-zero residual; 0 keeps the line well-formed regardless.
                let k = c.residuals.iter().position(|r| !r.is_zero()).unwrap_or(0);
                // Past the vectors, the residuals are against the free d/dx.
                let w = match k.checked_sub(s.vectors.len()) {
                    Some(f) => format!("d/d{}", nf.state[s.free[f]]),
                    None => format!("w{}", k + 1),
                };
                o.push_str(&format!(
                    "{} {m}: grad({m}) . {w} = {}\n",
                    if undecided.is_empty() {
                        "FAIL"
                    } else {
                        "NOT DECIDED"
                    },
                    fmt_rf(&nf, &c.residuals[k], &a.out)
                ));
                if !undecided.is_empty() {
                    o.push_str(&format!("  {}\n", not_decided_note(&undecided)));
                }
            }
        }
        let accepted = rep.checks.iter().filter(|c| c.is_mode).count();
        o.push_str(&format!(
            "accepted modes: {accepted}; independent: {} (gradient rank {}){}\n",
            if !rep.independent {
                "no"
            } else if decided {
                "yes"
            } else {
                "not decided"
            },
            rep.independent_count,
            if rep.independent {
                String::new()
            } else {
                format!(", wrong with probability <= {:.1e}", rep.dependence_error)
            }
        ));
        o.push_str(&format!(
            "complete: {} ({} independent modes for rank {})\n",
            match (decided, rep.complete) {
                (false, _) => "not decided",
                (true, true) => "yes",
                (true, false) => "no",
            },
            rep.independent_count,
            rep.rank
        ));
        if !decided {
            let mut atoms = rep.undecided.clone();
            atoms.extend(s.undecided.iter().cloned());
            atoms.sort();
            atoms.dedup();
            o.push_str(&format!(
                "not decided: the atoms {} may be related in ways the engine does not detect; the zero residuals above are proofs, but the rank and the modes' independence are nonzero forms over these atoms, so the true rank may be lower, with more symmetries than those checked\n",
                atoms.join(", ")
            ));
        }
        out!("{o}");
    }
    Ok(if all_pass {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The atoms that leave a failed mode undecided: none when one nonzero
/// residual is provably nonzero (or the mode passed).
fn mode_undecided(ctx: &mut obsan_expr::Ctx, c: &obsan_analysis::ModeCheck) -> Vec<String> {
    let mut all = Vec::new();
    for r in c.residuals.iter().filter(|r| !r.is_zero()) {
        let atoms = ctx.undecided_atom_texts(r);
        if atoms.is_empty() {
            return Vec::new();
        }
        all.extend(atoms);
    }
    all.sort();
    all.dedup();
    all
}

pub fn verify(a: &VerifyArgs) -> Result<ExitCode, Failure> {
    let src = crate::fsio::read_text(&a.file)?;
    let d = Decomposition::parse(&src, &a.file).map_err(|e| Failure(e.to_string()))?;
    let base = std::path::Path::new(&a.file)
        .parent()
        .unwrap_or(std::path::Path::new("."));
    let sys_path = base.join(&d.system);
    let sys_path = sys_path.to_string_lossy().to_string();
    let sys = load_system(&sys_path)?;
    let mut nf = sys
        .normal_form(d.restriction.as_deref(), &d.set)
        .map_err(|e| Failure(format!("{}: {e}", a.file)))?;
    // With unknown inputs: the checks over the model with them as inputs,
    // against the certified symmetries; the rank (the modes' count) has a bound.
    let (checks, s, rank_bound) = if nf.unknown_inputs.is_empty() {
        d.without_jets_or_combinations()
            .map_err(|e| Failure(e.to_string()))?;
        let (r, s) = compute_symmetries(&mut nf, &a.an, a.exact)?;
        let checks = verify_decomposition_with(&mut nf, &d, a.an.seed, Some((&r, &s)))
            .map_err(|e| Failure(e.to_string()))?;
        (checks, s, None)
    } else {
        let (_, s, checks, b) = crate::unknown_input_cmd::verify_checks(a, &d, &mut nf)?;
        (checks, s, Some(b))
    };
    let ok = checks.iter().all(|c| c.pass);
    let closure = d.closure_proves(&nf, &checks);
    let (cert, bound) = sym_certificate(&s);
    // With unknown inputs the vectors are the exactly certified kernel; the
    // count of modes rests on the rank test, so the verdict is probabilistic.
    let cert = match rank_bound {
        Some(_) => "the unknown-input symmetries, each certified exactly (docs/engine.md)".into(),
        None => cert,
    };
    // What the verdict rests on: closure needs no symmetry; otherwise the
    // exact eq. (11) residuals are only as sure as the symmetries.
    let verdict = if closure {
        "exact by closure: every output and every field's dynamics written in the new state, as many independent new variables as the rank".to_string()
    } else if bound == 0.0 {
        "exact: eq. (11) residuals against exactly certified symmetries".to_string()
    } else {
        format!("eq. (11) residuals exact, the symmetries wrong with probability <= {bound:.1e}")
    };
    // A failure whose residuals hold only related-looking atoms is not a
    // proof, nor a pass resting on a minor or the rank over such atoms, nor
    // symmetries whose count is not proven.
    let failure_certain = checks.iter().any(|c| !c.pass && c.undecided.is_empty());
    let mut undecided: Vec<String> = s.undecided.clone();
    undecided.extend(checks.iter().flat_map(|c| c.undecided.iter().cloned()));
    undecided.sort();
    undecided.dedup();
    let decided = if ok {
        undecided.is_empty()
    } else {
        failure_certain
    };
    let exact = (closure || bound == 0.0) && decided && rank_bound.is_none();
    let verdict = match rank_bound {
        Some(b) => format!("eq. (11) residuals exact against the certified unknown-input symmetries{}; the rank with unknown inputs (the count of modes) is the rank test's, wrong with probability <= {b:.1e}", if closure { ", every output and every field's dynamics written in the new state by exact substitution" } else { "" }),
        None => verdict,
    };
    let verdict = if ok && !decided {
        format!(
            "not decided: every check passed with the atoms {} independent, but they may be related in ways the engine does not detect (the independence and completeness checks rest on nonzero forms over them)",
            undecided.join(", ")
        )
    } else {
        verdict
    };
    if a.out.json {
        let (certificate, certification) = certificate_json(&s);
        let checks = checks
            .iter()
            .map(|c| json::DecompositionCheck {
                check: c.name.clone(),
                decided: c.undecided.is_empty(),
                detail: c.detail.clone(),
                pass: c.pass,
                undecided_atoms: c.undecided.clone(),
            })
            .collect();
        crate::json::print(&json::Verify {
            certificate,
            certification,
            checks,
            decided,
            decomposition: a.file.clone(),
            exact: ok && exact,
            pass: ok,
            restriction: nf.restriction.clone(),
            symmetries: s.count(),
            system: nf.name.clone(),
            undecided_atoms: undecided,
            verdict,
        })?;
    } else {
        let mut o = format!(
            "{} -> new state [{}] ({})\n",
            system_title(&nf),
            d.new_state.join(", "),
            a.file
        );
        for c in &checks {
            let undecided = !c.undecided.is_empty();
            o.push_str(&format!(
                "{} {}\n",
                if c.pass && undecided {
                    "PASS (not decided)"
                } else if c.pass {
                    "PASS"
                } else if undecided {
                    "NOT DECIDED"
                } else {
                    "FAIL"
                },
                c.name
            ));
            if !c.pass && !c.detail.is_empty() {
                o.push_str(&format!("     {}\n", c.detail));
            }
            if undecided && c.pass {
                o.push_str(&format!(
                    "     not decided: this rests on a nonzero minor or rank over the atoms {}, which may be related in ways the engine does not detect\n",
                    c.undecided.join(", ")
                ));
            } else if undecided {
                o.push_str(&format!("     {}\n", not_decided_note(&c.undecided)));
            }
        }
        o.push_str(&format!("symmetries: {} ({cert})\n", s.count()));
        o.push_str(&if ok && !decided {
            format!("decomposition verified only with the atoms independent ({verdict})\n")
        } else if !ok && !decided {
            "decomposition not decided: no check failed for certain, and the ones marked NOT DECIDED may hold\n".to_string()
        } else if !ok {
            "decomposition NOT verified\n".to_string()
        } else if exact {
            format!("decomposition verified (exact)\ncertificate: {verdict}\n")
        } else {
            format!("decomposition verified (probabilistic)\ncertificate: {verdict}\n")
        });
        out!("{o}");
    }
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

#[cfg(test)]
mod tests {
    use crate::cli::deadline_after;
    use std::time::{Duration, Instant};

    /// The command's deadline is its start plus the whole --timeout (no
    /// reserve, no undershoot), from an injected start instant; every stage
    /// receives this one instant.
    #[test]
    fn the_deadline_is_the_whole_timeout() {
        let t0 = Instant::now();
        for secs in [0.0, 0.25, 10.0, 30.0, 118.0] {
            let d = deadline_after(t0, Some(secs)).unwrap();
            assert_eq!(d - t0, Duration::from_secs_f64(secs));
        }
        assert_eq!(deadline_after(t0, None), None);
        assert_eq!(deadline_after(t0, Some(-1.0)), Some(t0));
    }
}
