//! `--experiment`, `--experiments FILE|auto`, `--known`, `--known-generic`
//! (docs/experiments.md): reading the specs, and `obsan rank`'s reports for
//! the known-initial-condition test and the automatic design.

use crate::cli::RankArgs;
use crate::show::{experiments_of, load_system, parse_sets, rational};
use crate::{json, Failure};
use obsan_analysis::{
    multi_experiment::experiments_auto, multi_experiment::rank_known,
    multi_experiment::AutoOptions, multi_experiment::AutoReport, multi_experiment::Known,
    multi_experiment::KnownOptions, multi_experiment::KnownReport,
};
use obsan_model::{Experiment, NormalForm};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// The experiments in the binary's JSON types and as one line of text.
pub(crate) fn describe_typed(exps: &[Experiment]) -> (Vec<json::Experiment>, String) {
    let j = exps
        .iter()
        .map(|e| json::Experiment {
            restriction: e.restriction.clone(),
            set: e
                .set
                .iter()
                .map(|(n, q)| (n.clone(), q.to_string()))
                .collect(),
        })
        .collect::<Vec<_>>();
    let t = exps
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let vals: Vec<String> = e.set.iter().map(|(n, q)| format!("{n} = {q}")).collect();
            format!(
                "{}: {}{}",
                i + 1,
                e.restriction.as_deref().unwrap_or("unrestricted"),
                if vals.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", vals.join(", "))
                }
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    (j, t)
}

/// `--known`/`--known-generic` names as state indices (a bare state name in
/// a stacked problem means every experiment's copy).
fn resolve_known(nf: &NormalForm, a: &RankArgs) -> Result<Vec<Known>, Failure> {
    let mut out: Vec<Known> = Vec::new();
    let find = |name: &str, flag: &str| -> Result<Vec<usize>, Failure> {
        let exact: Vec<usize> = nf
            .state
            .iter()
            .enumerate()
            .filter(|(_, s)| s.as_str() == name)
            .map(|(i, _)| i)
            .collect();
        if !exact.is_empty() {
            return Ok(exact);
        }
        let copies: Vec<usize> = nf
            .state
            .iter()
            .enumerate()
            .filter(|(_, s)| s.split_once('@').is_some_and(|(b, _)| b == name))
            .map(|(i, _)| i)
            .collect();
        if copies.is_empty() {
            return Err(Failure(format!(
                "{flag} {name}: not a state or param of {} (its state: {})",
                nf.name,
                nf.state.join(", ")
            )));
        }
        Ok(copies)
    };
    for s in &a.known {
        let Some((n, v)) = s.split_once('=') else {
            return Err(Failure(format!(
                "--known {s}: expected NAME=VALUE, e.g. --known S=0 (or --known-generic S)"
            )));
        };
        let q = rational(v.trim()).map_err(|e| Failure(format!("--known {s}: {e}")))?;
        for i in find(n.trim(), "--known")? {
            out.retain(|k| k.index != i);
            out.push(Known {
                index: i,
                value: Some(q.clone()),
            });
        }
    }
    for n in &a.known_generic {
        for i in find(n.trim(), "--known-generic")? {
            if out.iter().any(|k| k.index == i) {
                return Err(Failure(format!(
                    "--known-generic {n}: {} is already given a value by --known",
                    nf.state[i]
                )));
            }
            out.push(Known {
                index: i,
                value: None,
            });
        }
    }
    out.sort_by_key(|k| k.index);
    Ok(out)
}

fn deadline(a: &RankArgs) -> Option<Instant> {
    a.an.timeout
        .map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0)))
}

/// `obsan rank --known ... / --known-generic ...`.
pub fn rank_known_cmd(a: &RankArgs, mut nf: NormalForm) -> Result<ExitCode, Failure> {
    let known = resolve_known(&nf, a)?;
    let r = rank_known(
        &mut nf,
        &known,
        KnownOptions {
            seed: a.an.seed,
            deadline: deadline(a),
            max_order: a.known_order,
            ..Default::default()
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    let outs: Vec<String> = nf.outputs.iter().map(|o| o.0.clone()).collect();
    let words: Vec<String> = r
        .basis
        .iter()
        .map(|w| w.display(&r.fields.names, &outs))
        .collect();
    let names = |pick: bool| -> Vec<String> {
        r.unknown
            .iter()
            .zip(&r.observable)
            .filter(|(_, o)| **o == pick)
            .map(|(&i, _)| nf.state[i].clone())
            .collect()
    };
    let (obs, unobs) = (names(true), names(false));
    let known_text: Vec<String> = known
        .iter()
        .map(|k| match &k.value {
            Some(q) => format!("{} = {q}", nf.state[k.index]),
            None => format!("{} (generic)", nf.state[k.index]),
        })
        .collect();
    let certificate = certificate_text(&r);
    let experiments = experiments_of(&a.sys)?.map(|e| describe_typed(&e).0);
    if a.out.json {
        let basis = r.basis.iter().zip(&words);
        json::print(&json::RankKnown {
            basis: basis
                .map(|(w, t)| json::BasisWord {
                    lie_derivative: t.clone(),
                    order: w.order(),
                })
                .collect(),
            certificate,
            determined: r.determined,
            error_bound: if r.full() { 0.0 } else { r.generic_error_bound },
            exact: r.full(),
            experiments,
            generic_rank: r.generic_rank,
            identifiable: r.full(),
            invariant: r.invariant,
            known: known
                .iter()
                .map(|k| json::KnownValue {
                    name: nf.state[k.index].clone(),
                    value: k.value.as_ref().map(|q| q.to_string()),
                })
                .collect(),
            n: r.unknown.len(),
            observable_variables: obs,
            order_checked: r.order_checked,
            point_rank: r.point_rank,
            rank: r.rank,
            restriction: nf.restriction.clone(),
            seed: a.an.seed,
            state: nf.state.clone(),
            system: nf.name.clone(),
            unknowns: r.unknown.iter().map(|&i| nf.state[i].clone()).collect(),
            unobservable_variables: unobs,
            words_evaluated: r.words_evaluated,
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = format!(
        "system {}: state [{}]; known: {}\n",
        nf.name,
        nf.state.join(", "),
        known_text.join(", ")
    );
    let verdict = if r.full() {
        "identifiable"
    } else if r.determined {
        "not identifiable"
    } else {
        "undecided"
    };
    let unknown_names: Vec<&str> = r.unknown.iter().map(|&i| nf.state[i].as_str()).collect();
    if r.determined {
        o.push_str(&format!(
            "unknowns [{}]: rank {} of {}: {verdict}\n",
            unknown_names.join(", "),
            r.rank,
            r.unknown.len()
        ));
    } else {
        o.push_str(&format!(
            "unknowns [{}]: rank between {} and {} of {}: {verdict}\n",
            unknown_names.join(", "),
            r.rank,
            r.generic_rank,
            r.unknown.len()
        ));
    }
    if !words.is_empty() {
        o.push_str("basis (gradients in the unknowns):\n");
        for w in &words {
            o.push_str(&format!("  d {w}\n"));
        }
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.join(", ")
        }
    };
    o.push_str(&format!("identifiable on their own: {}\n", list(&obs)));
    o.push_str(&format!(
        "not identifiable on their own: {}\n",
        list(&unobs)
    ));
    o.push_str(&certificate);
    o.push('\n');
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}

fn certificate_text(r: &KnownReport) -> String {
    let prob = format!(
        "too low with probability <= {:.1e} (Schwartz-Zippel at random points mod 2^61-1)",
        r.generic_error_bound
    );
    match r.point_rank {
        None => {
            if r.full() {
                "exact: a non-zero minor in the unknown columns at a point proves full rank".into()
            } else {
                format!("probabilistic: the rank in the unknown columns is never too high, {prob}")
            }
        }
        Some(p) => {
            let found = if p == 0 {
                "every gradient was zero in the unknown columns there".to_string()
            } else {
                format!("a non-zero minor of size {p} there proves rank >= {p} at these values (certified)")
            };
            let mut t = format!(
                "at the known values: every Lie derivative up to order {} evaluated there ({} in all), the other coordinates random mod 2^61-1; {found}",
                r.order_checked, r.words_evaluated
            );
            if r.full() {
                t.push_str("; full rank: identifiable, proven");
            } else if r.invariant {
                t.push_str(&format!(
                    "; the known coordinates never move (every field vanishes there), so the rank is that of the system restricted to them: {} ({prob})",
                    r.rank
                ));
            } else if r.determined {
                t.push_str(&format!(
                    "; it meets the upper bound {} (the rank with the known values generic, {prob})",
                    r.generic_rank
                ));
            } else {
                t.push_str(&format!(
                    "; upper bound {} (the rank with the known values generic); higher orders may raise the rank at this point (--known-order)",
                    r.generic_rank
                ));
            }
            t
        }
    }
}

/// `obsan rank --experiments auto`.
pub fn auto_cmd(a: &RankArgs) -> Result<ExitCode, Failure> {
    if !a.known.is_empty() || !a.known_generic.is_empty() {
        return Err(Failure(
            "--experiments auto takes no --known/--known-generic: give the experiments to test known initial conditions".into(),
        ));
    }
    let sys = load_system(&a.sys.system)?;
    let sets = parse_sets(&a.sys.set)?;
    let r = experiments_auto(
        &sys,
        a.sys.restriction.as_deref(),
        &sets,
        AutoOptions {
            seed: a.an.seed,
            deadline: deadline(a),
            ..Default::default()
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    print_auto(&sys.name, a, &r)
}

fn print_auto(name: &str, a: &RankArgs, r: &AutoReport) -> Result<ExitCode, Failure> {
    let exact = r.rank == r.n;
    if a.out.json {
        json::print(&json::RankAuto {
            constants: r.constants.clone(),
            error_bound: r.error_bound,
            exact: exact && r.error_bound == 0.0,
            experiments: r.experiments,
            full_rank: exact,
            n: r.n,
            n_params: r.n_params,
            param_rank: r.param_rank,
            poles: r
                .poles
                .iter()
                .map(|(c, q)| json::ConstantValue {
                    constant: c.clone(),
                    value: q.to_string(),
                })
                .collect(),
            rank: r.rank,
            ranks: r
                .ranks
                .iter()
                .map(|&(experiments, rank, n)| json::RankStep {
                    experiments,
                    n,
                    rank,
                })
                .collect(),
            restriction: a.sys.restriction.clone(),
            seed: a.an.seed,
            special_values: r
                .special
                .iter()
                .map(|s| json::SpecialValue {
                    constant: s.constant.clone(),
                    degenerate: s.degenerate,
                    design_rank: s.design_rank,
                    single_rank: s.single_rank,
                    value: s.value.to_string(),
                })
                .collect(),
            state_rank: r.state_rank,
            system: name.to_string(),
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let mut o = format!(
        "system {name}: generic experiments{}\n",
        match &a.sys.restriction {
            Some(r) => format!(" under restriction {r}"),
            None => " (inputs unrestricted)".into(),
        }
    );
    for (k, rk, n) in &r.ranks {
        o.push_str(&format!("  {k} experiment(s): rank {rk} of {n}\n"));
    }
    o.push_str(&format!(
        "smallest number of experiments: {} (rank {} of {}{})\n",
        r.experiments,
        r.rank,
        r.n,
        if exact {
            ": everything identifiable"
        } else {
            ""
        }
    ));
    o.push_str(&format!(
        "why it stops: each experiment's own states add {} (the rank of one experiment in its state columns); the params get {} of {} directions, and one more generic experiment adds none, so no number of experiments adds more (docs/experiments.md)\n",
        r.state_rank, r.param_rank, r.n_params
    ));
    if !r.constants.is_empty() {
        let deg: Vec<String> = r
            .special
            .iter()
            .filter(|s| s.degenerate)
            .map(|s| {
                format!(
                    "{} = {} (alone rank {}, in the design {})",
                    s.constant, s.value, s.single_rank, s.design_rank
                )
            })
            .collect();
        let tried: Vec<String> = r.special.iter().map(|s| format!("{}", s.value)).collect();
        o.push_str(&format!(
            "special values of {} tried: {}; degenerate: {}\n",
            r.constants.join(", "),
            tried.join(", "),
            if deg.is_empty() {
                "none".to_string()
            } else {
                deg.join("; ")
            }
        ));
        for (c, q) in &r.poles {
            o.push_str(&format!(
                "  {c} = {q}: a denominator of the system is zero there\n"
            ));
        }
    }
    if r.error_bound > 0.0 {
        o.push_str(&format!(
            "probabilistic: ranks below full are never too high, too low with probability <= {:.1e} each (seed {})\n",
            r.error_bound, a.an.seed
        ));
    } else {
        o.push_str("exact: every rank used is full (a non-zero minor at a point)\n");
    }
    out!("{o}");
    Ok(ExitCode::SUCCESS)
}
