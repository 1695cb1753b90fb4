//! `obsan global`: global identifiability and discrete symmetries.

use crate::cli::GlobalArgs;
use crate::json;
use crate::show::load_normal_form;
use crate::Failure;
use obsan_analysis::global_id::{
    global_identifiability, GlobalOptions, Identifiability, OutputForm, Route,
};
use std::process::ExitCode;
use std::time::{Duration, Instant};

pub fn run(a: &GlobalArgs) -> Result<ExitCode, Failure> {
    let (_, mut nf) = load_normal_form(&a.sys)?;
    crate::unknown_input_cmd::refuse(&nf, "global")?;
    let opts = GlobalOptions {
        seed: a.an.seed,
        deadline: a
            .an
            .timeout
            .map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0))),
        // The engine's memory budget, as every other stage counts it.
        max_bytes: usize::try_from(
            (a.an.max_terms as u128).saturating_mul(obsan_expr::Budget::BYTES_PER_TERM),
        )
        .unwrap_or(usize::MAX),
        route: match a.route.as_str() {
            "taylor" => Route::Taylor,
            "io" => Route::InputOutput,
            "lie" => Route::Lie,
            _ => Route::Auto,
        },
        multi_experiment: a.multi_experiment,
        ..GlobalOptions::default()
    };

    let mut r = global_identifiability(&mut nf, &opts).map_err(|e| Failure(e.to_string()))?;
    // A measured input's initial value is its own output at time 0
    // (globally identifiable, fixed by every map): not a variable of the user's.
    r.variables
        .retain(|v| v.param || !nf.measured_inputs.contains(&v.name));
    let verdict = |v: Identifiability| match v {
        Identifiability::Global => (json::Verdict::Global, Some(1)),
        Identifiability::Local(k) => (json::Verdict::Local, Some(k)),
        Identifiability::NotIdentifiable => (json::Verdict::NotIdentifiable, None),
    };
    // Maps that keep every output (exact symmetries of the model as
    // written), and those proven only on the angle outputs' tangents: each
    // turns an angle output by pi, or is not decided on the angles.
    let maps: Vec<String> = r
        .maps
        .iter()
        .filter(|m| m.keeps_angles == Some(true) && !m.params_only)
        .map(|m| m.to_string())
        .collect();
    // Maps of the parameters alone (the input-output relations' exact
    // symmetries; the states' images not sought).
    let maps_params: Vec<String> = r
        .maps
        .iter()
        .filter(|m| m.params_only)
        .map(|m| m.to_string())
        .collect();
    let maps_pi: Vec<(String, bool)> = r
        .maps
        .iter()
        .filter(|m| m.keeps_angles != Some(true))
        .map(|m| (m.to_string(), m.keeps_angles == Some(false)))
        .collect();
    let form_text = |f: &OutputForm| match f {
        OutputForm::Direct => "direct".to_string(),
        OutputForm::Argument(k) => format!("{k} argument"),
        OutputForm::Tangent => "tangent".to_string(),
    };
    if a.out.json {
        let variables = r
            .variables
            .iter()
            .map(|v| json::GlobalVariable {
                angle: v.angle,
                kind: if v.param {
                    json::VariableKind::Param
                } else {
                    json::VariableKind::State
                },
                at_most: v.at_most,
                name: v.name.clone(),
                values: verdict(v.verdict).1,
                verdict: verdict(v.verdict).0,
            })
            .collect();
        let output_orders = r
            .output_orders
            .iter()
            .map(|(n, k)| json::OutputOrder {
                order: *k,
                output: n.clone(),
            })
            .collect();
        crate::json::print(&json::Global {
            all_local: r.all_local,
            degree_bound_local: r.delta_local,
            equations: r.equations,
            error_bound: r.error_bound,
            exact: false,
            group_order: r.group_order,
            log10_degree_bound_global: r.log10_delta_global,
            maps,
            maps_modulo_pi: maps_pi.iter().map(|m| m.0.clone()).collect(),
            maps_of_parameters: maps_params.clone(),
            method: if r.route == Route::InputOutput {
                "input-output relations: kernels of monomials in the outputs' jets at numeric parameters, coefficients reconstructed over Q and verified, Gröbner basis over F_p of c(theta) = c(theta*); two independent points and primes agree".into()
            } else if r.route == Route::Lie {
                "Lie derivatives: exact iterated Lie derivatives of the outputs along the drift and each input's field (indistinguishable for every input, Hermann-Krener), equated at a random point, Gröbner basis over F_p; two independent points and primes agree".into()
            } else {
                "SIAN: Taylor coefficients of the outputs at a random point, Gröbner basis over F_p; two independent points and primes agree".into()
            },
            multi_experiment: r.multi_experiment,
            order: r.order,
            output_forms: r
                .output_forms
                .iter()
                .map(|(o, f)| json::OutputFormJson {
                    counted_as: form_text(f),
                    output: o.clone(),
                })
                .collect(),
            output_orders,
            primes: r.primes.to_vec(),
            rank_order: r.rank_order,
            restriction: nf.restriction.clone(),
            route: if r.route == Route::InputOutput {
                "input-output".into()
            } else if r.route == Route::Lie {
                "lie".into()
            } else {
                "taylor".into()
            },
            fallback: r.fallback.clone(),
            solutions: r.solutions,
            solutions_at_most: r.solutions_at_most,
            states_after_io: r
                .states_after_io
                .as_ref()
                .map(|st| json::StatesAfterIoJson {
                    counted: st.counted,
                    equations: st.equations,
                    error_bound: st.error_bound,
                    fixed_params: st.fixed.clone(),
                    output_orders: st
                        .output_orders
                        .iter()
                        .map(|(n, k)| json::OutputOrder {
                            order: *k,
                            output: n.clone(),
                        })
                        .collect(),
                    unknowns: st.unknowns,
                    why_not: st.why_not.clone(),
                }),
            system: nf.name.clone(),
            unknowns: r.unknowns,
            variables,
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = String::new();
    o.push_str(&format!("system {}: global identifiability\n", nf.name));
    if let Some(note) = crate::clock::measured_note(&nf) {
        o.push_str(&format!("{note}\n"));
    }
    let orders: Vec<String> = r
        .output_orders
        .iter()
        .map(|(n, k)| format!("{n} to order {k}"))
        .collect();
    if r.route == Route::InputOutput {
        if let Some(why) = &r.fallback {
            o.push_str(&format!(
                "the Taylor route did not answer ({why})
"
            ));
        }
        let sizes: Vec<String> = r
            .output_orders
            .iter()
            .zip(&r.io_sizes)
            .map(|((n, _), s)| {
                // A generating part of the coefficients settled the count
                // (docs/engine.md, "Input-output route", step 3).
                let part = if s.support > 1 && s.reconstructed + 1 < s.support {
                    let why = if s.checked_solutions > 1 {
                        format!(
                            "a part; its {} solutions at the random points kept where the whole relation's kernel is that of the point",
                            s.checked_solutions
                        )
                    } else {
                        "a part that generates the parameters' field".to_string()
                    };
                    format!(
                        ", {} of its {} coefficients reconstructed ({why})",
                        s.reconstructed,
                        s.support - 1
                    )
                } else {
                    String::new()
                };
                // No coefficient is a monomial: the quotients times their
                // common denominator (docs/engine.md, step 3).
                let den = if s.common_denominator > 0 {
                    format!(
                        ", over a common denominator of {} terms",
                        s.common_denominator
                    )
                } else {
                    String::new()
                };
                format!(
                    "{n}: order {}, degree {} in {} jets, {} monomials{part}{den}",
                    s.order, s.degree, s.variables, s.support
                )
            })
            .collect();
        // Under --route auto the initial states follow (states_after_io).
        let states = match &r.states_after_io {
            Some(st) if st.counted => {
                let orders: Vec<String> = st
                    .output_orders
                    .iter()
                    .map(|(n, k)| format!("{n} to order {k}"))
                    .collect();
                format!(
                    " for the parameters; the initial states by the Taylor route with {} known: orders {}, {} unknowns, {} equations",
                    if st.fixed.is_empty() {
                        "no parameter".to_string()
                    } else {
                        format!("the globally identifiable {}", st.fixed.join(", "))
                    },
                    orders.join(", "),
                    st.unknowns,
                    st.equations
                )
            }
            Some(st) => format!(
                "; parameters only, initial states not counted (the Taylor route{}: {})",
                if st.fixed.is_empty() {
                    String::new()
                } else {
                    format!(" with {} known", st.fixed.join(", "))
                },
                st.why_not.as_deref().unwrap_or("no answer")
            ),
            None => "; parameters only, initial states not assessed".to_string(),
        };
        o.push_str(&format!(
            "route: input-output relations ({}){states}\n",
            sizes.join("; ")
        ));
        let bound = r
            .io_sizes
            .iter()
            .map(|s| s.recon_error_bound)
            .fold(0.0, f64::max);
        o.push_str(&format!(
            "their coefficients reconstructed over Q and verified at fresh points (wrong with probability <= {bound:.1e})\n"
        ));
    } else if r.route == Route::Lie {
        if let Some(why) = &r.fallback {
            o.push_str(&format!("the Taylor route did not answer ({why})\n"));
        }
        let words: Vec<String> = r
            .output_orders
            .iter()
            .map(|(n, k)| format!("{n} to length {k}"))
            .collect();
        o.push_str(&format!(
            "route: Lie derivatives along the drift and each input's field: indistinguishable for every input (Hermann-Krener){}\nwords {} (the first length at which no derivative raises the rank: proven sufficient, docs/engine.md, \"Lie route\"), {} unknowns, {} equations\n",
            if nf.inputs.is_empty() {
                ", here the same question as one experiment (no inputs)"
            } else {
                "; one generic experiment can leave more values"
            },
            words.join(", "),
            r.unknowns,
            r.equations
        ));
    } else {
        o.push_str(&format!(
        "Taylor orders {} (each the first whose row of the Jacobian is dependent: proven sufficient, docs/engine.md), {} unknowns, {} equations\n",
        orders.join(", "),
        r.unknowns,
        r.equations
    ));
    }
    // How an output not read as written is counted (outputs.rs).
    for (name, f) in &r.output_forms {
        match f {
            OutputForm::Direct => {}
            OutputForm::Argument(k) => o.push_str(&format!(
                "output {name} is counted through the argument of its {k} (one-to-one: the same values)\n"
            )),
            OutputForm::Tangent => o.push_str(&format!(
                "output {name} is an angle, counted through its tangent: modulo pi, so a count above 1 is an upper bound unless the symmetries settle it\n"
            )),
        }
    }
    let w = r.variables.iter().map(|v| v.name.len()).max().unwrap_or(0);
    for v in &r.variables {
        let kind = if v.param { "param" } else { "state" };
        let text = match v.verdict {
            Identifiability::Global => "globally identifiable".to_string(),
            Identifiability::Local(k) if v.at_most => {
                format!("locally identifiable, at most {k} values")
            }
            Identifiability::Local(k) => format!("locally identifiable, {k} values"),
            Identifiability::NotIdentifiable => "not identifiable".to_string(),
        };
        // An angle in sin/cos is counted as tan(theta/2): modulo 2 pi.
        let angle = if v.angle {
            " (angle, counted modulo 2 pi)"
        } else {
            ""
        };
        o.push_str(&format!("  {:w$}  {kind}  {text}{angle}\n", v.name));
    }
    let states_counted = r.states_after_io.as_ref().is_some_and(|s| s.counted);
    let scope = if r.route == Route::InputOutput && r.all_local && !states_counted {
        "parameter values"
    } else if r.all_local {
        "(params, initial states)"
    } else {
        "values of the locally identifiable variables"
    };
    let any_local = r
        .variables
        .iter()
        .any(|v| v.verdict != Identifiability::NotIdentifiable);
    match r.solutions {
        // Nothing to count jointly: say so rather than "1 values of none".
        Some(_) if !any_local => {
            o.push_str("no variable is locally identifiable: each takes infinitely many values\n")
        }
        Some(1) => o.push_str(&format!(
            "1 {scope} gives the output of a generic one\n",
            scope = scope.replacen("values", "value", 1)
        )),
        Some(k) if r.solutions_at_most => o.push_str(&format!(
            "at most {k} {scope} give the output of a generic one\n"
        )),
        Some(k) => o.push_str(&format!("{k} {scope} give the output of a generic one\n")),
        None => o.push_str(&format!("infinitely many {scope} give the same output\n")),
    }
    if !maps.is_empty() {
        o.push_str("discrete symmetries (each checked exactly on the equations):\n");
        for m in &maps {
            o.push_str(&format!("  {m}\n"));
        }
    }
    if !maps_params.is_empty() {
        o.push_str("discrete symmetries of the parameters (each keeps every input-output relation's coefficients, checked exactly over Q; the initial states' images not sought):\n");
        for m in &maps_params {
            o.push_str(&format!("  {m}\n"));
        }
    }
    if !maps_pi.is_empty() {
        o.push_str("symmetries of the angle outputs' tangents only (not of the angles as read):\n");
        for (m, turns) in &maps_pi {
            let why = if *turns {
                "turns an angle output by pi"
            } else {
                "not decided on the angles themselves"
            };
            o.push_str(&format!("  {m}  ({why})\n"));
        }
    }
    if !r.maps.is_empty() && maps_pi.is_empty() {
        let all = r.solutions == Some(r.group_order);
        o.push_str(&format!(
            "they generate a group of order {}{}\n",
            r.group_order,
            match (all, maps_params.is_empty()) {
                (true, true) => ": it maps the generic point onto every solution",
                (true, false) => ": it maps the generic parameters onto every solution's",
                _ => "",
            }
        ));
    } else if !r.maps.is_empty() {
        o.push_str(&format!(
            "all the maps above generate a group of order {} (the tangents' solutions{})\n",
            r.group_order,
            match (r.solutions_at_most, r.solutions) {
                (false, Some(k)) => format!("; the outputs as read keep {k} of them"),
                _ => String::new(),
            }
        ));
    }
    o.push_str(&format!(
        "counted over the complex numbers at two independent random points modulo {} and {}, which agree\n",
        r.primes[0], r.primes[1]
    ));
    if r.route == Route::Lie {
        o.push_str("probabilistic: the counts are the agreement of the two runs (no degree bound on the random points for this route yet; docs/engine.md, \"Lie route\")\n");
    } else if r.route == Route::InputOutput {
        let dependent: Vec<&str> = r
            .output_orders
            .iter()
            .zip(&r.io_sizes)
            .filter(|(_, s)| !s.single)
            .map(|((n, _), _)| n.as_str())
            .collect();
        if dependent.is_empty() {
            o.push_str(&format!(
                "each relation's monomials are linearly independent along an output (non-zero Wronskian), so one experiment fixes its coefficients: these are single-experiment counts{}\n",
                if a.multi_experiment { " (and multi-experiment ones)" } else { "" }
            ));
        } else {
            o.push_str(&format!(
                "multi-experiment counts: the param values that give the same outputs in every one of enough independent experiments, each from its own generic initial state; the monomials of {}'s relation are dependent along an output (zero Wronskian), so one experiment may leave more values\n",
                dependent.join(", ")
            ));
        }
        o.push_str("probabilistic: the counts are the agreement of the two runs (no degree bound on the random points yet; docs/engine.md, \"Input-output route\")\n");
        if let Some(st) = r.states_after_io.as_ref().filter(|s| s.counted) {
            let bound = if st.error_bound < 1.0 {
                format!("wrong with probability <= {:.1e}", st.error_bound)
            } else {
                "no useful bound".to_string()
            };
            o.push_str(&format!(
                "the initial states' count: SIAN's degree bounds on the smaller Taylor system, {bound}, given the parameters' counts (a parameter found global is fixed at the point's value)\n"
            ));
        }
    } else {
        let bound = if r.error_bound < 1.0 {
            format!("wrong with probability <= {:.1e}", r.error_bound)
        } else {
            "without a useful bound (SIAN's degree bound exceeds the prime)".to_string()
        };
        o.push_str(&format!(
            "probabilistic: the verdicts (global / local / not identifiable) are {bound} (SIAN's degree bounds {:.1e} and 10^{:.1} at each point, Schwartz-Zippel; both runs would have to err); a count k > 1 is the agreement of the two runs\n",
            r.delta_local,
            if r.log10_delta_global.is_finite() { r.log10_delta_global } else { 0.0 }
        ));
    }
    outln!("{}", o.trim_end());
    Ok(ExitCode::SUCCESS)
}
