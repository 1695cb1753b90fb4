//! `obsan rank` and `obsan symmetries` on a model with unknown inputs
//! (docs/engine.md, "Unknown inputs"), and the refusal of the commands that
//! do not handle them yet.

use crate::cli::{ModesArgs, RankArgs, SymArgs, VerifyArgs};
use crate::json;
use crate::unknown_input_modes_text::{order_text, ui_modes_certificate, ui_modes_text};
use crate::Failure;
use obsan_analysis::{
    unknown_inputs::unknown_input_modes,
    unknown_inputs::unknown_input_rank,
    unknown_inputs::unknown_input_symmetries,
    unknown_inputs::UnknownInputOptions,
    unknown_inputs::UnknownInputReport,
    unknown_inputs::{
        combination_checks, inputs_driving_modes, jet_check_text, unknown_input_view_jets,
    },
    verify_decomposition_with, Check, Decomposition, DeriveOptions, RankReport, SymmetryReport,
};
use obsan_model::NormalForm;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Commands other than `rank` and `symmetries` would treat the unknown
/// inputs as absent.
pub fn refuse(nf: &NormalForm, command: &str) -> Result<(), Failure> {
    refuse_because(nf, command, "it treats every input as known")
}

/// [`refuse`] saying what the command lacks.
pub fn refuse_because(nf: &NormalForm, command: &str, why: &str) -> Result<(), Failure> {
    if nf.unknown_inputs.is_empty() {
        return Ok(());
    }
    Err(Failure(format!(
        "{} has unknown inputs ({}): `obsan {command}` does not handle them yet ({why}); `obsan rank` and `obsan symmetries` do",
        nf.name,
        nf.unknown_inputs.join(", ")
    )))
}

/// `obsan symmetries` with unknown inputs: the kernel of the observable
/// codistribution, each vector certified exactly (docs/engine.md,
/// "Symmetries with unknown inputs").
pub fn symmetries(a: &SymArgs, nf: &mut NormalForm) -> Result<ExitCode, Failure> {
    let deadline = Some(Instant::now() + Duration::from_secs_f64(a.timeout().max(0.0)));
    let s = unknown_input_symmetries(
        nf,
        UnknownInputOptions {
            seed: a.an.seed,
            deadline,
            max_order: None,
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    // Explicit time: report the user's states, not the clock.
    let mut s = s;
    crate::clock::hide_in_unknown_input_symmetries(nf, &mut s);
    let view = crate::clock::user_view(nf);
    let nf: &NormalForm = view.as_ref().unwrap_or(nf);
    let r = &s.report;
    let moved: Vec<bool> = (0..r.n)
        .map(|i| s.vectors.iter().any(|v| !v[i].is_zero()))
        .collect();
    let names = |keep: bool| -> Vec<String> {
        nf.state
            .iter()
            .zip(&moved)
            .filter(|p| *p.1 != keep)
            .map(|p| p.0.clone())
            .collect()
    };
    let (observable, unobservable) = (names(true), names(false));
    let rec: Vec<String> = nf
        .unknown_inputs
        .iter()
        .zip(&r.reconstructable)
        .filter(|p| p.1.is_some())
        .map(|p| p.0.clone())
        .collect();
    // The jets' symbols: `u`, `u'`, `u''` (unknown_input_jets.rs).
    let jets: Vec<String> = s
        .input_jets
        .iter()
        .map(|&(i, l)| format!("{}{}", nf.inputs[i], "'".repeat(l)))
        .collect();
    if a.out.json {
        crate::json::print(&json::SymmetriesUnknownInputs {
            certificate: "unknown_input_invariance".into(),
            error_bound: r.error_bound,
            exact: true,
            identities: s.identities,
            input_dependent: s.input_dependent(),
            input_jets: jets,
            made_states: s.made_states.clone(),
            n: r.n,
            observable_variables: observable,
            rank: r.rank,
            reconstructable_inputs: rec,
            restriction: nf.restriction.clone(),
            seed: r.seed,
            state: nf.state.clone(),
            symmetries: s.vectors.iter().map(|v| json::vector(nf, v)).collect(),
            system: nf.name.clone(),
            unknown_inputs: nf.unknown_inputs.clone(),
            unobservable_variables: unobservable,
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let k = s.vectors.len();
    let mut o = format!(
        "system {}: state [{}], unknown inputs [{}]\nrank {} of {} with unknown inputs, {} independent symmetr{}\n",
        nf.name,
        nf.state.join(", "),
        nf.unknown_inputs.join(", "),
        r.rank,
        r.n,
        k,
        if k == 1 { "y" } else { "ies" }
    );
    o.push_str(&format!("state order: [{}]\n", nf.state.join(", ")));
    for (j, v) in s.vectors.iter().enumerate() {
        let comps: Vec<String> = v
            .iter()
            .map(|e| {
                if a.out.latex {
                    nf.ctx.ratfun_latex_factored(e)
                } else {
                    nf.ctx.ratfun_text_factored(e)
                }
            })
            .collect();
        o.push_str(&format!("w{} = [{}]\n", j + 1, comps.join(", ")));
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.join(", ")
        }
    };
    o.push_str(&format!(
        "unobservable (moved by a symmetry, exact): {}\n",
        list(&unobservable)
    ));
    o.push_str(&format!("observable: {}\n", list(&observable)));
    o.push_str(&format!("unknown inputs reconstructable: {}\n", list(&rec)));
    if k == 0 {
        o.push_str(&format!(
            "no continuous symmetry: the state is weakly locally observable with unknown inputs (probability of error <= {:.1e}, the rank test's bound)\n",
            r.error_bound
        ));
    } else {
        if !s.made_states.is_empty() {
            o.push_str(&format!(
                "an output holds {}: the certificate is the system's with {} made a state (its derivative the unknown input), the same output trajectories; each symmetry below is the state part of one of that system's\n",
                s.made_states.join(", "),
                if s.made_states.len() == 1 { "it" } else { "each" }
            ));
        }
        if s.input_dependent() {
            o.push_str(&format!(
                "the symmetries move with the known inputs: {} in the components are the inputs' values and time derivatives along the trajectory\n",
                jets.join(", ")
            ));
            o.push_str(&format!(
                "exact: each symmetry xi leaves every output invariant, and [F, xi] + d_t xi, with F = f0 + sum f_i u_i and d_t xi = sum u^(l+1) dxi/du^(l), and the bracket of every unknown input's field with it lie in the span of the symmetries and the unknown inputs' fields ({} identities checked in canonical form); so every variable a symmetry moves is unobservable whatever the unknown inputs, and the rank is at most {}. That it is not lower (the variables no symmetry moves are observable) is the rank test's verdict: wrong with probability <= {:.1e}\n",
                s.identities, r.rank, r.error_bound
            ));
        } else {
            o.push_str(&format!(
            "exact: each symmetry leaves every output invariant, and the bracket of every field (f0, the known and the unknown inputs' fields) with it lies in the span of the symmetries and the unknown inputs' fields ({} identities checked in canonical form); so every variable a symmetry moves is unobservable whatever the unknown inputs, and the rank is at most {}. That it is not lower (the variables no symmetry moves are observable) is the rank test's verdict: wrong with probability <= {:.1e}\n",
            s.identities, r.rank, r.error_bound
        ));
        }
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

pub fn rank(a: &RankArgs, nf: &NormalForm) -> Result<ExitCode, Failure> {
    let deadline =
        a.an.timeout
            .map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0)));
    let r = unknown_input_rank(
        nf,
        UnknownInputOptions {
            seed: a.an.seed,
            deadline,
            max_order: a.order,
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    // The ranks treat the atoms as independent (as `rank` does without unknown
    // inputs): an "observable" verdict is certified only when they are.
    let undecided_atoms = obsan_analysis::certify::undecided_atoms_of(&mut nf.clone(), &[]);
    // Explicit time: report the user's states, not the clock.
    let mut r = r;
    crate::clock::hide_in_unknown_input(nf, &mut r);
    let view = crate::clock::user_view(nf);
    let nf: &NormalForm = view.as_ref().unwrap_or(nf);
    let outs: Vec<String> = nf.outputs.iter().map(|o| o.0.clone()).collect();
    // Every basis function is a time derivative y^(m) of an output (the
    // words have the one drift field).
    let words: Vec<String> = r
        .basis
        .iter()
        .map(|w| match w.order() {
            0..=3 => format!("{}{}", outs[w.output], "'".repeat(w.order())),
            m => format!("{}^({m})", outs[w.output]),
        })
        .collect();
    let split = |names: &[String], v: &[Option<usize>]| {
        let yes: Vec<(String, usize)> = names
            .iter()
            .zip(v)
            .filter_map(|(s, o)| o.map(|m| (s.clone(), m)))
            .collect();
        let no: Vec<String> = names
            .iter()
            .zip(v)
            .filter(|(_, o)| o.is_none())
            .map(|(s, _)| s.clone())
            .collect();
        (yes, no)
    };
    let (obs, unobs) = split(&nf.state, &r.observable);
    let (rec, unrec) = split(&nf.unknown_inputs, &r.reconstructable);
    if a.out.json {
        crate::json::print(&rank_json(nf, &r, &words, undecided_atoms))?;
        return Ok(ExitCode::SUCCESS);
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.join(", ")
        }
    };
    let with_order = |v: &[(String, usize)]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.iter()
                .map(|(s, m)| format!("{s} ({})", order_text(Some(*m))))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let mut o = String::new();
    o.push_str(&format!(
        "system {}: state [{}], unknown inputs [{}]\n",
        nf.name,
        nf.state.join(", "),
        nf.unknown_inputs.join(", ")
    ));
    // Over undecided atoms the ranks are upper bounds: a full one proves
    // nothing, and the per-variable verdicts are certified neither way (see
    // analysis_cmds.rs, `rank`).
    let qual = if undecided_atoms.is_empty() {
        ""
    } else {
        " (with the atoms below independent; not certified)"
    };
    let verdict = if r.rank == r.n && !undecided_atoms.is_empty() {
        "weakly locally observable with unknown inputs if the atoms below are independent (not decided)"
    } else if r.rank == r.n {
        "weakly locally observable with unknown inputs"
    } else {
        "not weakly locally observable with unknown inputs"
    };
    o.push_str(&format!(
        "rank {} of {} (output derivatives up to order {}): {verdict}\n",
        r.rank, r.n, r.max_order
    ));
    o.push_str(&format!("observable{qual}: {}\n", with_order(&obs)));
    o.push_str(&format!("not observable{qual}: {}\n", list(&unobs)));
    o.push_str(&format!(
        "unknown inputs reconstructable{qual}: {}\n",
        with_order(&rec)
    ));
    o.push_str(&format!(
        "unknown inputs not reconstructable{qual}: {}\n",
        list(&unrec)
    ));
    o.push_str("order by order (rank in the extended space / of the state part):");
    for s in &r.steps {
        o.push_str(&format!(" {}: {}/{}", s.order, s.rank, s.state_rank));
    }
    o.push('\n');
    o.push_str(
        "basis of the codistribution (gradients in the state and the unknown inputs' derivatives):\n",
    );
    for w in &words {
        o.push_str(&format!("  d {w}\n"));
    }
    let m = &r.martinelli;
    let steps: Vec<String> = m
        .steps
        .iter()
        .map(|s| format!("degree {}: {}", s.degree, s.action))
        .collect();
    o.push_str(&format!(
        "Martinelli's algorithm (arXiv 2201.07610, Alg. 5.1): {}; stopped after {} rounds of Lie derivatives, the last adding nothing: rank {} of {} is final\n",
        steps.join(", "),
        m.rounds,
        m.rank,
        m.n
    ));
    let open_inputs: Vec<String> = nf
        .unknown_inputs
        .iter()
        .zip(&m.reconstructable)
        .filter(|p| p.1.is_none())
        .map(|p| p.0.clone())
        .collect();
    if r.agree {
        o.push_str("both routes agree: every verdict is final at every derivative order");
        if !open_inputs.is_empty() {
            o.push_str(&format!(
                " (except: {} not reconstructable up to order {} only, the state not being observable)",
                open_inputs.join(", "),
                r.max_order
            ));
        }
        o.push('\n');
    } else {
        o.push_str(&format!(
            "the two routes DISAGREE (Martinelli: observable [{}]); the orders above are those of the extended-state route up to order {}\n",
            nf.state
                .iter()
                .zip(&m.observable)
                .filter(|p| *p.1)
                .map(|p| p.0.clone())
                .collect::<Vec<_>>()
                .join(", "),
            r.max_order
        ));
    }
    o.push_str(&format!(
        "probabilistic: exact arithmetic mod 2^61-1 at random points (2 for the orders, 1 plus 1 per extension in Martinelli's algorithm; seed {}); a verdict is wrong with probability <= {:.1e} (Schwartz-Zippel, degree bound {})\n",
        r.seed, r.error_bound, r.degree_bound
    ));
    if let Some(k) = r.roots_field {
        o.push_str(&format!("no point mod p = 2^61-1 satisfies the roots' relations together (their radicands multiply to a constant that is no power there): both routes ran where the roots take free values, and every decision that does not carry over from there (a value not zero, a rank) was proven at a point of the field of p^{k} elements, where every root has its value\n"));
    }
    if !undecided_atoms.is_empty() {
        o.push_str(&format!(
            "not decided: the atoms {} may be related in ways the engine does not detect; the ranks above are those of the system with them independent, upper bounds on the true ones (a rank below n proves the system not weakly locally observable); the per-variable and per-input verdicts are certified neither way, a relation can change them\n",
            undecided_atoms.join(", ")
        ));
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

/// The unknown-input rank as the binary's JSON.
/// The JSON view; `undecided` are the atoms whose independence the engine
/// cannot prove (a formal full rank over them is not claimed).
fn rank_json(
    nf: &NormalForm,
    r: &UnknownInputReport,
    words: &[String],
    undecided: Vec<String>,
) -> json::RankUnknownInputs {
    let orders = |names: &[String], v: &[Option<usize>]| -> Vec<json::NamedOrder> {
        names
            .iter()
            .zip(v)
            .filter_map(|(s, o)| {
                o.map(|order| json::NamedOrder {
                    name: s.clone(),
                    order,
                })
            })
            .collect()
    };
    let missing = |names: &[String], v: &[Option<usize>]| -> Vec<String> {
        names
            .iter()
            .zip(v)
            .filter(|(_, o)| o.is_none())
            .map(|(s, _)| s.clone())
            .collect()
    };
    let inputs_where = |want: bool| -> Vec<String> {
        nf.unknown_inputs
            .iter()
            .zip(&r.martinelli.reconstructable)
            .filter(|p| *p.1 == Some(want))
            .map(|p| p.0.clone())
            .collect()
    };
    let m = &r.martinelli;
    let martinelli = json::Martinelli {
        codistribution_rank: m.codistribution_rank,
        dimension: m.dimension,
        error_bound: m.error_bound,
        input_jets: m.input_jets,
        not_reconstructable: inputs_where(false),
        observable: nf
            .state
            .iter()
            .zip(&m.observable)
            .filter(|p| *p.1)
            .map(|p| p.0.clone())
            .collect(),
        rank: m.rank,
        reconstructable: inputs_where(true),
        rounds: m.rounds,
        steps: m
            .steps
            .iter()
            .map(|s| json::MartinelliStep {
                action: s.action.clone(),
                degree: s.degree,
            })
            .collect(),
    };
    let outs: Vec<&String> = nf.outputs.iter().map(|o| &o.0).collect();
    // The ranks are of the formal field in which the atoms are independent; a relation
    // among them can only lower the true rank: a rank below n stands, full rank does not.
    let full = r.rank == r.n;
    let weakly_locally_observable = (undecided.is_empty() || !full).then_some(full);
    json::RankUnknownInputs {
        agree: r.agree,
        basis: r
            .basis
            .iter()
            .zip(words)
            .map(|(w, t)| json::UnknownInputWord {
                derivative: t.clone(),
                order: w.order(),
                output: outs[w.output].clone(),
            })
            .collect(),
        complete: r.complete(),
        converged: r.converged,
        decided: undecided.is_empty(),
        degree_bound: r.degree_bound,
        error_bound: r.error_bound,
        evaluated: r.evaluated,
        martinelli,
        max_order: r.max_order,
        n: r.n,
        observable_variables: orders(&nf.state, &r.observable),
        rank: r.rank,
        reconstructable_inputs: orders(&nf.unknown_inputs, &r.reconstructable),
        restriction: nf.restriction.clone(),
        roots_field_degree: r.roots_field,
        seed: r.seed,
        state: nf.state.clone(),
        steps: r
            .steps
            .iter()
            .map(|s| json::UnknownInputStep {
                extended_rank: s.rank,
                order: s.order,
                state_rank: s.state_rank,
            })
            .collect(),
        system: nf.name.clone(),
        undecided_atoms: undecided,
        unknown_inputs: nf.unknown_inputs.clone(),
        unobservable_variables: missing(&nf.state, &r.observable),
        unreconstructable_inputs: missing(&nf.unknown_inputs, &r.reconstructable),
        weakly_locally_observable,
    }
}

/// How `obsan modes --out` writes its pair of files (prefix, force, sys, dec).
pub type WritePair = fn(&str, bool, &str, &str) -> Result<(), Failure>;

/// `obsan modes` with unknown inputs: the first integrals of the certified
/// symmetries and the reduced system driven by the reconstructable inputs or
/// input combinations (docs/engine.md, "Modes with unknown inputs").
/// `write` writes PREFIX.sys and PREFIX.dec as `obsan modes --out` does.
pub fn modes(a: &ModesArgs, nf: &mut NormalForm, write: WritePair) -> Result<ExitCode, Failure> {
    let deadline = crate::cli::deadline_after(Instant::now(), a.timeout);
    let opts = DeriveOptions {
        seed: a.seed,
        deadline,
        ..DeriveOptions::default()
    };
    let mut m = unknown_input_modes(
        nf,
        UnknownInputOptions {
            seed: a.seed,
            deadline,
            max_order: None,
        },
        &opts,
    )
    .map_err(|e| Failure(format!("{}: {e}", a.sys.system)))?;
    let r = &m.symmetries.report;
    // With explicit time the clock `t` is an analysed state and a mode
    // (src/clock.rs): counted out of the rank, n and modes shown.
    let clk = usize::from(nf.clock().is_some());
    let (rank, n, bound) = (r.rank - clk.min(r.rank), r.n - clk, r.error_bound);
    let nsym = m.symmetries.vectors.len();
    let view = &mut m.view;
    let (sys_path, sets) = crate::reduced_text::dec_source(&a.sys);
    let title = match &nf.restriction {
        Some(q) => format!("{} (input {q})", nf.name),
        None => nf.name.clone(),
    };
    let mut undecided = m.sym.undecided.clone();
    let (mut dec, mut sys_text, mut checks) = (None, None, None);
    if let Some(d) = &m.derivation {
        undecided.extend(d.mode_report.undecided.iter().cloned());
        // A combination input has no name in the model: the file read
        // against the model defines it (`combination d_z2 = ...`), and
        // declares the inputs' derivatives it reads (`derivative u3_d1 = u3'`).
        dec = d
            .decomposition_text(&sys_path, nf.restriction.as_deref(), &sets)
            .map(|t| with_combinations(&t, &m.inputs));
        sys_text = d
            .sys_text(&nf.name, &format!("observable modes of {title}"))
            .map(|t| unknown_inputs_declared(&t, &nf.inputs));
        // Checked over the view the derivation ran on (a combination is an
        // input there), the jets added as the reader adds them.
        let text = d.decomposition_text(&sys_path, nf.restriction.as_deref(), &sets);
        if let Some(t) = &text {
            let internal = |e: obsan_analysis::AnalysisError| {
                Failure(format!("internal: the derived decomposition: {e}"))
            };
            let dj = Decomposition::parse(t, "derived decomposition")
                .and_then(|x| x.with_input_jets(view, &m.jets))
                .map_err(internal)?;
            let cs = obsan_analysis::verify_decomposition_with(
                view,
                &dj,
                a.seed,
                Some((&m.rank, &m.sym)),
            )
            .map_err(internal)?;
            for c in &cs {
                undecided.extend(c.undecided.iter().cloned());
            }
            checks = Some(cs);
        }
    }
    // Checked over the view's names: now the jets as shown (`u3'`).
    m.show_input_jets();
    if let Some(cs) = checks.as_mut() {
        for c in cs.iter_mut() {
            c.name = jet_check_text(&c.name, &m.jets).unwrap_or_else(|| m.show(&c.name));
            c.detail = m.show(&c.detail);
        }
    }
    undecided.sort();
    undecided.dedup();
    let decided = undecided.is_empty();
    let full = m.derivation.is_none();
    let verified = full || checks.as_ref().is_some_and(|c| c.iter().all(|c| c.pass));
    let modes_ok = m.derivation.as_ref().is_none_or(|d| {
        d.mode_report.checks.iter().all(|c| c.is_mode)
            && d.mode_report.independent
            && d.mode_report.complete
    });
    let certificate = ui_modes_certificate(&m, full, verified, modes_ok, &checks, bound);
    let certificate = if decided {
        certificate
    } else {
        format!(
            "{certificate}; not decided: the atoms {} may be related, so the rank {rank} is an upper bound (zero residuals and substitutions are still proofs)",
            undecided.join(", ")
        )
    };
    if let (Some(prefix), Some(dec), Some(sys_text)) = (&a.out_prefix, &dec, &sys_text) {
        write(prefix, a.force, sys_text, dec)?;
    }
    let modes: Vec<json::DerivedMode> = match &m.derivation {
        None => nf
            .state
            .iter()
            .filter(|s| clk == 0 || s.as_str() != obsan_model::TIME)
            .map(|s| json::DerivedMode {
                angle: false,
                domain: "everywhere".into(),
                expr: s.clone(),
                kind: "variable".into(),
                name: s.clone(),
            })
            .collect(),
        Some(d) => d
            .shown()
            .into_iter()
            .map(|k| &d.modes[k])
            .map(|m| json::DerivedMode {
                angle: m.angle,
                domain: m.domain.clone(),
                expr: m.text.clone(),
                kind: m.kind.word().to_string(),
                name: m.name.clone(),
            })
            .collect(),
    };
    let reduced_inputs: Vec<json::ReducedUnknownInput> = m
        .inputs
        .iter()
        .map(|i| json::ReducedUnknownInput {
            factor: i.factor.clone(),
            input: i.input.clone(),
            mode: i.mode.clone(),
            name: i.name.clone(),
            offset: i.offset.clone(),
            order: i.order,
        })
        .collect();
    if a.out.json {
        let reduced = m.derivation.as_ref().map(|d| json::Reduced {
            closed: d.closed(),
            dynamics: d
                .shown()
                .into_iter()
                .map(|k| json::ReducedDynamics {
                    name: d.modes[k].name.clone(),
                    rhs: d.dynamics(k),
                })
                .collect(),
            inputs: nf
                .inputs
                .iter()
                .cloned()
                .chain(m.input_derivatives())
                .collect(),
            missing: d.missing(),
            outputs: d
                .shown_outputs()
                .map(|(n, e)| json::ReducedOutput {
                    expr: e.clone(),
                    name: n.clone(),
                })
                .collect(),
        });
        crate::json::print(&json::ModesUnknownInputs {
            certificate,
            checks: checks.as_ref().map(|cs| {
                cs.iter()
                    .map(|c| json::PassCheck {
                        check: c.name.clone(),
                        detail: c.detail.clone(),
                        pass: c.pass,
                    })
                    .collect()
            }),
            dec: dec.clone(),
            decided,
            error_bound: bound,
            full_rank: full,
            modes,
            n,
            rank,
            reduced,
            reduced_inputs,
            restriction: nf.restriction.clone(),
            seed: a.seed,
            symmetries: nsym,
            sys: sys_text.clone(),
            system: nf.name.clone(),
            undecided_atoms: undecided,
            unknown_inputs: nf.unknown_inputs.clone(),
            verified,
        })?;
    } else {
        let latex: Vec<String> = match (&m.derivation, a.out.latex) {
            (Some(d), true) => d
                .shown()
                .into_iter()
                .map(|k| m.view.ctx.to_latex(d.modes[k].expr))
                .collect(),
            _ => modes.iter().map(|x| x.expr.clone()).collect(),
        };
        out!(
            "{}",
            ui_modes_text(
                a,
                nf,
                &m,
                (&title, (rank, n)),
                &latex,
                &reduced_inputs,
                &certificate
            )
        );
    }
    if full {
        if let Some(prefix) = &a.out_prefix {
            eprintln!(
                "note: nothing written to {prefix}.sys or {prefix}.dec: every variable is observable, so the reduced system is {} itself",
                a.sys.system
            );
        }
    } else if a.out_prefix.is_some() && dec.is_none() {
        eprintln!("note: nothing written: the reduced system is not closed");
    }
    if !modes_ok || !verified {
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// `obsan verify` with unknown inputs: the decomposition's checks over the
/// model with the unknown inputs read as inputs, against the certified
/// symmetries and the unknown-input rank, plus one check per unknown input
/// that drives the reduced dynamics (its field outside the symmetries' span):
/// it must be reconstructable. Returns the rank report and symmetries the
/// checks used, the checks and the rank test's bound; `nf` becomes the view.
pub fn verify_checks(
    a: &VerifyArgs,
    d: &Decomposition,
    nf: &mut NormalForm,
) -> Result<(RankReport, SymmetryReport, Vec<Check>, f64), Failure> {
    let deadline =
        a.an.timeout
            .map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0)));
    let (s, mut view, rr, sym, jets) = unknown_input_view_jets(
        nf,
        UnknownInputOptions {
            seed: a.an.seed,
            deadline,
            max_order: None,
        },
    )
    .map_err(|e| Failure(format!("{}: {e}", a.file)))?;
    let d = &d
        .with_input_jets(&view, &jets)
        .map_err(|e| Failure(e.to_string()))?;
    let mut checks = verify_decomposition_with(&mut view, d, a.an.seed, Some((&rr, &sym)))
        .map_err(|e| Failure(e.to_string()))?;
    for c in checks.iter_mut() {
        if let Some(t) = jet_check_text(&c.name, &jets) {
            c.name = t;
        }
    }
    // An unknown input a combination reads is recovered through it.
    let (combos, covered) =
        combination_checks(&mut view, d, &nf.unknown_inputs).map_err(|e| Failure(e.to_string()))?;
    checks.extend(combos);
    let drives = inputs_driving_modes(nf, &s.vectors, a.an.seed);
    for (j, w) in nf.unknown_inputs.iter().enumerate() {
        if !drives[j] || covered.contains(w) {
            continue;
        }
        let order = s.report.reconstructable[j];
        checks.push(Check {
            name: format!(
                "unknown input {w}, which drives the reduced dynamics, is reconstructable"
            ),
            pass: order.is_some(),
            detail: match order {
                Some(_) => String::new(),
                None => {
                    format!("{w} is not reconstructable (obsan rank): the reduced dynamics need it")
                }
            },
            undecided: vec![],
        });
    }
    let bound = s.report.error_bound;
    *nf = view;
    Ok((rr, sym, checks, bound))
}

/// The decomposition text with each unknown-input combination the reduced
/// system reads defined (`combination w_z2 = (factor)*w + (offset)`, the
/// view's names), before the `state` line.
fn with_combinations(
    text: &str,
    inputs: &[obsan_analysis::unknown_inputs::ReducedInput],
) -> String {
    let mut defs = String::new();
    for i in inputs {
        let Some(f) = &i.factor else { continue };
        let off = match i.offset.as_deref() {
            Some(o) if o != "0" => format!(" + ({o})"),
            _ => String::new(),
        };
        defs.push_str(&format!(
            "combination {} = ({f})*{}{off}\n",
            i.name, i.input
        ));
    }
    match text.find("\nstate ") {
        Some(k) => format!("{}{defs}{}", &text[..=k], &text[k + 1..]),
        None => format!("{text}{defs}"),
    }
}

/// The reduced `.sys` text with the inputs that are not the model's known
/// ones (the unknown inputs and their combinations) declared `unknown input`.
fn unknown_inputs_declared(text: &str, known: &[String]) -> String {
    let mut o = String::new();
    for line in text.lines() {
        match line.strip_prefix("input ") {
            Some(list) => {
                let names: Vec<&str> = list.split(',').map(str::trim).collect();
                // A derived input (`u3_d1 = rate(u3)`) is known.
                let (k, u): (Vec<&str>, Vec<&str>) = names
                    .iter()
                    .partition(|n| n.contains('=') || known.iter().any(|x| x == *n));
                if !k.is_empty() {
                    o.push_str(&format!("input {}\n", k.join(", ")));
                }
                if !u.is_empty() {
                    o.push_str(&format!("unknown input {}\n", u.join(", ")));
                }
            }
            None => {
                o.push_str(line);
                o.push('\n');
            }
        }
    }
    o
}
