//! `obsan design` (docs/experiments.md, "Which sensor, which trajectory"):
//! reads the model and the candidates file, calls the analysis, prints.

use crate::cli::DesignArgs;
use crate::show::parse_sets;
use crate::{json, Failure};
use obsan_analysis::{
    sensor_design::design_inputs, sensor_design::design_outputs, sensor_design::Candidate,
    sensor_design::DesignOptions, sensor_design::DesignReport, sensor_design::InputDesignReport,
};
use obsan_model::{ModelError, NormalForm, System};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Statements a candidates file may not hold (they belong in the model).
const MODEL_ONLY: [&str; 11] = [
    "system",
    "description",
    "state",
    "param",
    "const",
    "input",
    "unknown",
    "varying",
    "restrict",
    "delay",
    "known",
];

/// A candidate read from the file: name, cost, output names, its line.
struct CandText {
    name: String,
    cost: f64,
    outputs: Vec<String>,
    line: usize,
}

fn bad(path: &str, line: usize, msg: String) -> Failure {
    Failure(format!("{path}:{line}: {msg}"))
}

/// Byte offset of 1-based (line, column in characters) in `text`.
fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let start: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    let rest = &text[start.min(text.len())..];
    start
        + rest
            .char_indices()
            .nth(col.saturating_sub(1))
            .map_or(rest.len(), |(i, _)| i)
}

/// The model with the candidates' outputs appended, and the candidates.
/// The file: `candidate NAME [cost C]` lines, each followed by the `output`
/// statements (the .sys syntax) of that sensor; `#` comments.
fn read_candidates(
    model_path: &str,
    model_src: &str,
    path: &str,
) -> Result<(System, Vec<CandText>), Failure> {
    let text = crate::fsio::read_text(path)?;
    let mut cands: Vec<CandText> = Vec::new();
    let mut blanked = String::new();
    for (i, raw) in text.split_inclusive('\n').enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        let first = line.split_whitespace().next().unwrap_or("");
        if first == "candidate" {
            let words: Vec<&str> = line.split_whitespace().collect();
            let name = words.get(1).copied().unwrap_or("");
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(bad(
                    path,
                    i + 1,
                    "expected `candidate NAME` or `candidate NAME cost C`".into(),
                ));
            }
            let cost = match &words[2..] {
                [] => 1.0,
                ["cost", c] => match c.parse::<f64>() {
                    Ok(v) if v.is_finite() && v >= 0.0 => v,
                    _ => {
                        return Err(bad(
                            path,
                            i + 1,
                            format!("cost '{c}' is not a non-negative number"),
                        ))
                    }
                },
                _ => {
                    return Err(bad(
                        path,
                        i + 1,
                        "expected `candidate NAME` or `candidate NAME cost C`".into(),
                    ))
                }
            };
            if cands.iter().any(|c| c.name == name) {
                return Err(bad(
                    path,
                    i + 1,
                    format!("candidate '{name}' is declared twice"),
                ));
            }
            cands.push(CandText {
                name: name.to_string(),
                cost,
                outputs: vec![],
                line: i + 1,
            });
            // Keep the line count: errors in outputs point into this file.
            blanked.push_str(if raw.ends_with('\n') { "\n" } else { "" });
            continue;
        }
        let is_dynamics = first.ends_with('\'')
            || line
                .split('=')
                .next()
                .is_some_and(|l| l.trim_end().ends_with('\''));
        if MODEL_ONLY.contains(&first) || is_dynamics {
            return Err(bad(
                path,
                i + 1,
                format!("'{first}' belongs in the model: a candidates file holds `candidate NAME [cost C]` lines and `output` statements"),
            ));
        }
        if first == "output" {
            let Some(c) = cands.last_mut() else {
                return Err(bad(
                    path,
                    i + 1,
                    "an output before the first `candidate NAME` line".into(),
                ));
            };
            let name = line["output".len()..]
                .split('=')
                .next()
                .unwrap_or("")
                .trim()
                .to_string();
            c.outputs.push(name);
        }
        blanked.push_str(raw);
    }
    if cands.is_empty() {
        return Err(Failure(format!(
            "{path}: no candidates (expected `candidate NAME [cost C]` lines, each followed by `output` statements)"
        )));
    }
    if let Some(c) = cands.iter().find(|c| c.outputs.is_empty()) {
        return Err(bad(
            path,
            c.line,
            format!("candidate '{}' has no output statement", c.name),
        ));
    }
    let before = model_src.matches('\n').count() + 1;
    let combined = format!("{model_src}\n{blanked}");
    let relocate = |e: ModelError| match (e.line, e.col) {
        (Some(l), Some(c)) if l > before => {
            let o = offset_of(&text, l - before, c);
            Failure(ModelError::at(path, &text, o, o + 1, e.message.clone()).to_string())
        }
        _ => Failure(e.to_string()),
    };
    let sys = System::parse(&combined, model_path).map_err(relocate)?;
    if let Some(e) = sys.time_refusal("`obsan design`") {
        return Err(relocate(e));
    }
    if let Some(e) = sys.input_output_refusal("`obsan design`") {
        return Err(relocate(e));
    }
    Ok((sys, cands))
}

/// `--target` names as state indices.
fn resolve_target(nf: &NormalForm, names: &[String]) -> Result<Vec<usize>, Failure> {
    names
        .iter()
        .map(|n| {
            nf.state.iter().position(|s| s == n.trim()).ok_or_else(|| {
                Failure(format!(
                    "--target {n}: not a state or param of {} (its state: {})",
                    nf.name,
                    nf.state.join(", ")
                ))
            })
        })
        .collect()
}

pub fn run(a: &DesignArgs) -> Result<ExitCode, Failure> {
    let start = Instant::now();
    let deadline = a
        .timeout
        .map(|s| start + Duration::from_secs_f64(s.max(0.0)));
    let opts = DesignOptions {
        seed: a.seed,
        deadline,
        max_subsets: a.max_subsets,
        symmetries: true,
    };
    let src = crate::fsio::read_text(&a.system)?;
    let model = System::parse(&src, &a.system).map_err(|e| Failure(e.to_string()))?;
    crate::clock::refuse_time(&model)?;
    crate::clock::refuse_measured(&model)?;
    let sets = parse_sets(&a.set)?;
    if a.candidates.is_none() && !a.target.is_empty() {
        return Err(Failure(
            "--target names what the candidate sensors must make observable: give --candidates FILE".into(),
        ));
    }
    let families = a.families || a.candidates.is_none();
    if families && model.restrictions.is_empty() && a.candidates.is_none() {
        return Err(Failure(format!(
            "{}: no `restrict` statements, so no input families to compare; give --candidates FILE for sensors",
            a.system
        )));
    }
    let mut text = String::new();
    let mut sensors = None;
    if let Some(cpath) = &a.candidates {
        let (sys, cands) = read_candidates(&a.system, &src, cpath)?;
        let nf = sys
            .normal_form(a.restriction.as_deref(), &sets)
            .map_err(|e| Failure(e.to_string()))?;
        let base = model.output_names().len();
        let candidates: Vec<Candidate> = cands
            .iter()
            .map(|c| Candidate {
                name: c.name.clone(),
                cost: c.cost,
                outputs: c
                    .outputs
                    .iter()
                    .filter_map(|o| nf.outputs.iter().position(|x| &x.0 == o))
                    .collect(),
            })
            .collect();
        let target = if a.target.is_empty() {
            None
        } else {
            Some(resolve_target(&nf, &a.target)?)
        };
        let r = design_outputs(&nf, base, &candidates, target.as_deref(), &opts)
            .map_err(|e| Failure(e.to_string()))?;
        let (j, t) = report_outputs(&nf, &cands, &r, a);
        sensors = Some(j);
        text.push_str(&t);
    }
    let mut inputs = None;
    if families {
        let r = design_inputs(&model, &sets, &opts).map_err(|e| Failure(e.to_string()))?;
        let (j, t) = report_inputs(&r);
        inputs = Some(j);
        text.push_str(&t);
    }
    if a.json {
        json::print(&json::Design {
            inputs,
            restriction: a.restriction.clone(),
            seed: a.seed,
            sensors,
            system: model.name.clone(),
        })?;
    } else {
        out!("system {}\n{text}", model.name);
    }
    Ok(ExitCode::SUCCESS)
}

fn list(v: &[String]) -> String {
    if v.is_empty() {
        "(none)".into()
    } else {
        v.join(", ")
    }
}

fn report_outputs(
    nf: &NormalForm,
    cands: &[CandText],
    r: &DesignReport,
    a: &DesignArgs,
) -> (json::Sensors, String) {
    let wname = |j: &usize| format!("w{}", j + 1);
    let symmetries = r.symmetries.as_ref().map_or_else(Vec::new, |s| {
        s.vectors
            .iter()
            .map(|v| {
                nf.state
                    .iter()
                    .zip(v)
                    .map(|(n, e)| (n.clone(), nf.ctx.ratfun_text_factored(e)))
                    .collect()
            })
            .collect()
    });
    let names = |v: &[usize]| -> Vec<String> { v.iter().map(|&i| nf.state[i].clone()).collect() };
    let unobs = |obs: &[bool]| -> Vec<String> {
        (0..r.n)
            .filter(|&i| !obs[i])
            .map(|i| nf.state[i].clone())
            .collect()
    };
    let goal = if a.target.is_empty() {
        "every variable observable".to_string()
    } else {
        format!("{} observable", names(&r.target).join(", "))
    };
    let sets = r
        .sets
        .iter()
        .map(|s| json::SensorSet {
            breaks: s.breaks.iter().map(wname).collect(),
            candidates: s.members.iter().map(|&c| cands[c].name.clone()).collect(),
            cost: s.cost,
            count: s.members.len(),
            error_bound: s.error_bound,
            exact: s.rank == r.n,
            n: r.n,
            rank: s.rank,
            unobservable_variables: unobs(&s.observable),
        })
        .collect();
    let candidates = cands
        .iter()
        .zip(&r.candidates)
        .map(|(c, e)| json::SensorCandidate {
            breaks: e.breaks.iter().map(wname).collect(),
            cost: c.cost,
            name: c.name.clone(),
            outputs: c.outputs.clone(),
            rank: e.rank,
        })
        .collect();
    let j = json::Sensors {
        all_rank: r.all_rank,
        already: r.already,
        base_rank: r.base_rank,
        base_unobservable_variables: unobs(&r.base_observable),
        candidates,
        complete_to_size: r.complete_to_size,
        error_bound: r.error_bound,
        exhaustive: r.exhaustive,
        n: r.n,
        outputs: nf.outputs.iter().map(|o| o.0.clone()).collect(),
        reachable: r.reachable,
        sets,
        state: nf.state.clone(),
        subsets_screened: r.subsets_screened,
        symmetries,
        symmetry_note: r.symmetry_note.clone(),
        target: names(&r.target),
    };
    let mut o = format!(
        "sensors{}: rank {} of {} with the model's outputs; {} with every candidate\ngoal: {goal}\n",
        a.restriction
            .as_ref()
            .map(|x| format!(" (restriction {x})"))
            .unwrap_or_default(),
        r.base_rank,
        r.n,
        r.all_rank
    );
    if let Some(s) = &r.symmetries {
        o.push_str(&format!(
            "symmetries of the model (state order [{}]):\n",
            nf.state.join(", ")
        ));
        for (k, v) in s.vectors.iter().enumerate() {
            let comps: Vec<String> = v.iter().map(|e| nf.ctx.ratfun_text_factored(e)).collect();
            o.push_str(&format!("  w{} = [{}]\n", k + 1, comps.join(", ")));
        }
    }
    if let Some(n) = &r.symmetry_note {
        o.push_str(&format!("({n})\n"));
    }
    o.push_str("candidates alone:\n");
    for (c, e) in cands.iter().zip(&r.candidates) {
        let br: Vec<String> = e.breaks.iter().map(wname).collect();
        o.push_str(&format!(
            "  {} (cost {}; {}): rank {}{}\n",
            c.name,
            c.cost,
            c.outputs.join(", "),
            e.rank,
            if r.symmetries.is_some() {
                format!(", breaks {}", list(&br))
            } else {
                String::new()
            }
        ));
    }
    if r.already {
        o.push_str("the model's own outputs already meet the goal: nothing to add\n");
    } else if !r.reachable {
        o.push_str(&format!(
            "no set of candidates meets the goal: with all of them, rank {} of {}\n",
            r.all_rank, r.n
        ));
    } else {
        o.push_str("minimal sets (by count, then cost):\n");
        for (k, s) in r.sets.iter().enumerate() {
            let members: Vec<String> = s.members.iter().map(|&c| cands[c].name.clone()).collect();
            let br: Vec<String> = s.breaks.iter().map(wname).collect();
            let un = unobs(&s.observable);
            o.push_str(&format!(
                "  {}. {} (cost {}): rank {} of {}{}{}\n",
                k + 1,
                members.join(" + "),
                s.cost,
                s.rank,
                r.n,
                if r.symmetries.is_some() {
                    format!(", breaks {}", list(&br))
                } else {
                    String::new()
                },
                if un.is_empty() {
                    String::new()
                } else {
                    format!("; still unobservable: {}", un.join(", "))
                }
            ));
        }
    }
    o.push_str(&format!(
        "{} subsets screened{}; ",
        r.subsets_screened,
        if r.exhaustive {
            " (every subset not a superset of a set found)".to_string()
        } else {
            format!(
                " (stopped at --max-subsets: complete up to {} candidates)",
                r.complete_to_size
            )
        }
    ));
    if r.error_bound > 0.0 {
        o.push_str(&format!(
            "each set confirmed by the rank test; ranks below full are never too high, too low with probability <= {:.1e}\n",
            r.error_bound
        ));
    } else {
        o.push_str("each set confirmed by the rank test: full rank, exact\n");
    }
    (j, o)
}

fn report_inputs(r: &InputDesignReport) -> (json::Inputs, String) {
    let fname = |f: &Option<String>| f.clone().unwrap_or_else(|| "unrestricted".into());
    let j = json::Inputs {
        combinations: r
            .combinations
            .iter()
            .map(|c| json::FamilyCombination {
                families: c
                    .families
                    .iter()
                    .map(|&i| fname(&r.families[i].restriction))
                    .collect(),
                n: c.n,
                rank: c.rank,
            })
            .collect(),
        combinations_complete: r.combinations_complete,
        combinations_tried: r.combinations_tried,
        error_bound: r.error_bound,
        families: r
            .families
            .iter()
            .map(|f| json::Family {
                experiments: f.experiments,
                full: f.full(),
                n: f.n,
                rank: f.rank,
                restriction: f.restriction.clone(),
                single_full: f.single_full(),
                single_n: f.single_n,
                single_rank: f.single_rank,
            })
            .collect(),
    };
    let mut o =
        String::from("input families (restrictions of the model; experiments share the params):\n");
    for f in &r.families {
        let several = if f.single_full() {
            "everything observable from one experiment".to_string()
        } else if f.full() {
            format!(
                "{} experiments of it: rank {} of {}: everything observable",
                f.experiments, f.rank, f.n
            )
        } else {
            format!(
                "never, however many: the rank stops growing after {} (rank {} of {})",
                f.experiments, f.rank, f.n
            )
        };
        o.push_str(&format!(
            "  {}: one experiment rank {} of {}; {several}\n",
            fname(&f.restriction),
            f.single_rank,
            f.single_n
        ));
    }
    let combos: Vec<String> = r
        .combinations
        .iter()
        .map(|c| {
            let n: Vec<String> = c
                .families
                .iter()
                .map(|&i| fname(&r.families[i].restriction))
                .collect();
            format!("{} (rank {} of {})", n.join(" + "), c.rank, c.n)
        })
        .collect();
    o.push_str(&format!(
        "minimal combinations of distinct families not sufficient alone, one experiment each: {}\n",
        list(&combos)
    ));
    if !r.combinations_complete {
        o.push_str("(more than 12 such families: combinations not tried)\n");
    }
    if r.error_bound > 0.0 {
        o.push_str(&format!(
            "ranks below full are never too high, too low with probability <= {:.1e}; full ranks are exact\n",
            r.error_bound
        ));
    }
    (j, o)
}
