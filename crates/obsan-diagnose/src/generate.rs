//! Candidate effects nobody wrote: generated from the model's
//! structure alone, as `.eff` text, so the rank test, the fit and the
//! likelihood ratio treat them exactly as the user's effects.
//!
//! Per measured input `u`: a scale `(1 + k) u`, a bias `u + b`, a coupling
//! with every other measured input `w`, `u (1 + c |w|)`, a first-order lag
//! (time constant T), a delay. Per group of outputs of one form (the
//! outputs whose expressions agree once the known constants are blanked:
//! the 15 ranges of mrclam.sys are one group), a scale and a bias, and for
//! angle outputs (those built on `atan`/`atan2`) the harmonics `sin y`,
//! `cos y`, `sin 2y`, `cos 2y`. A candidate that extends the model exactly
//! as a user effect does (compared numerically, params matched in order)
//! is left out: the user's file is the first-class source.

use obsan_expr::{parse_ast, FloatExpr};
use obsan_model::{substitute_names, Effect, EffectLibrary, Kind, System};

/// [`crate::Named::origin`] and [`crate::CandidateResult::origin`] of a
/// generated candidate.
pub const ORIGIN_GENERATED: &str = "generated";

/// One generated candidate with the words that name it.
#[derive(Clone, Debug)]
pub struct Generated {
    pub effect: Effect,
    /// The patch in words, e.g. `v_eff = v (1 + c |omega|)`.
    pub formula: String,
    /// What a positive and a negative value of the new param mean, e.g.
    /// `v rises with |omega|`, `v falls with |omega|`.
    pub positive: String,
    pub negative: String,
    /// The effect whose score statistic at zero new params screens this
    /// candidate before its fit (`screen.rs`): the effect itself, or
    /// for a lag its limit as T -> 0, `u - T rate(u)` (a lag at T = 0 is
    /// singular, and its state is held at the first input: no transient).
    /// `None`: always fitted (an exact `delay`, whose sensitivity the
    /// screen does not take).
    pub screen: Option<Effect>,
}

impl Generated {
    /// The readable name at a fitted value of the new param: "v falls with
    /// |omega|: v_eff = v (1 + c |omega|)".
    pub fn words(&self, value: f64) -> String {
        let what = if value < 0.0 {
            &self.negative
        } else {
            &self.positive
        };
        format!("{what}: {}", self.formula)
    }
}

/// The generated candidates, and the ones left out with the reason.
#[derive(Clone, Debug, Default)]
pub struct Generation {
    pub candidates: Vec<Generated>,
    pub dropped: Vec<(String, String)>,
}

/// The effects file's share of the per-round false-alarm probability when
/// candidates are generated: half, whatever their number, so a file of 8
/// effects is tested at alpha / 16 per candidate against, on mrclam.sys,
/// alpha / 24 for each of the 12 generated ones.
pub const FILE_SHARE: f64 = 0.5;

/// Per-candidate significance levels (file, generated): a weighted
/// Bonferroni split of `alpha` over `n_file + n_generated` candidates, the
/// file's `FILE_SHARE` over its own, the rest over the generated ones. The
/// probability that a round names anything on data without an effect stays
/// below `alpha`; without generated candidates the file keeps all of it.
pub fn levels(alpha: f64, n_file: usize, n_generated: usize) -> (f64, f64) {
    match (n_file, n_generated) {
        (u, 0) => (alpha / u.max(1) as f64, alpha),
        (0, g) => (alpha, alpha / g as f64),
        (u, g) => (
            alpha * FILE_SHARE / u as f64,
            alpha * (1.0 - FILE_SHARE) / g as f64,
        ),
    }
}

struct Draft {
    name: String,
    body: String,
    formula: String,
    positive: String,
    negative: String,
    /// The screen's stand-in (see [`Generated::screen`]): `None` the effect
    /// itself, `Some(None)` no screen, `Some(Some(body))` this body.
    screen: Option<Option<String>>,
}

/// Candidates generated from `sys`'s structure, without those that
/// duplicate one of `user` (the effects file's model-side effects).
pub fn generate(sys: &System, user: &[&Effect]) -> Generation {
    let mut taken: Vec<String> = sys.decls.iter().map(|d| d.name.clone()).collect();
    taken.extend(sys.output_names().iter().map(|s| s.to_string()));
    for e in user {
        taken.push(e.name.clone());
        taken.extend(e.params.iter().cloned());
        taken.extend(e.states.iter().cloned());
        taken.extend(e.consts.iter().cloned());
        taken.extend(e.inputs.iter().map(|i| i.0.clone()));
    }
    let mut fresh = |base: &str| -> String {
        let mut n = base.to_string();
        while taken.contains(&n) {
            n.push('_');
        }
        taken.push(n.clone());
        n
    };
    let mut drafts: Vec<Draft> = Vec::new();
    let inputs: Vec<String> = sys
        .decls_of(Kind::Input)
        .filter(|d| d.derived.is_none())
        .map(|d| d.name.clone())
        .collect();
    for u in &inputs {
        let k = fresh(&format!("gk_{u}"));
        drafts.push(Draft {
            name: fresh(&format!("{u}_scale")),
            body: format!("param {k}\nsubst {u} = (1 + {k})*{u}\n"),
            formula: format!("{u}_eff = (1 + {k}) {u}"),
            positive: format!("{u} acts larger than measured"),
            negative: format!("{u} acts smaller than measured"),
            screen: None,
        });
        let b = fresh(&format!("gb_{u}"));
        drafts.push(Draft {
            name: fresh(&format!("{u}_bias")),
            body: format!("param {b}\nsubst {u} = {u} + {b}\n"),
            formula: format!("{u}_eff = {u} + {b}"),
            positive: format!("{u} acts with a positive offset"),
            negative: format!("{u} acts with a negative offset"),
            screen: None,
        });
        for w in inputs.iter().filter(|w| *w != u) {
            let c = fresh(&format!("gc_{u}_{w}"));
            let d = fresh(&format!("g_{u}_abs_{w}"));
            drafts.push(Draft {
                name: fresh(&format!("{u}_with_abs_{w}")),
                // |w| as sqrt(w^2): a derived input, evaluated in floating
                // point (the exact engine never sees the absolute value).
                body: format!(
                    "param {c}\ninput {d} = {u}*sqrt({w}^2)\nsubst {u} = {u} + {c}*{d}\n"
                ),
                formula: format!("{u}_eff = {u} (1 + {c} |{w}|)"),
                positive: format!("{u} rises with |{w}|"),
                negative: format!("{u} falls with |{w}|"),
                screen: None,
            });
        }
        let t = fresh(&format!("gT_{u}"));
        let s = fresh(&format!("g_{u}_lagged"));
        let r0 = fresh(&format!("g_lagrate_{u}"));
        drafts.push(Draft {
            name: fresh(&format!("{u}_lag")),
            body: format!(
                "param {t} = 0.2\nstate {s} = {u}\n{s}' = ({u} - {s})/{t}\nsubst {u} = {s}\n"
            ),
            formula: format!("{u}_eff' = ({u} - {u}_eff)/{t}"),
            positive: format!("{u} acts through a first-order lag"),
            negative: format!("{u} acts through a first-order lead (negative time constant)"),
            // s = u - T du/dt + O(T^2) with s(0) = u(0): the lag's
            // sensitivity to T at T = 0, its initial state held.
            screen: Some(Some(format!(
                "param {t}\ninput {r0} = rate({u})\nsubst {u} = {u} - {t}*{r0}\n"
            ))),
        });
        let tau = fresh(&format!("gtau_{u}"));
        if inputs.len() == 1 {
            drafts.push(Draft {
                name: fresh(&format!("{u}_delay")),
                body: format!("param {tau}\ndelay {tau}\n"),
                formula: format!("{u}_eff(t) = {u}(t - {tau})"),
                positive: format!("{u} acts late"),
                negative: format!("{u} acts early"),
                screen: Some(None),
            });
        } else {
            // One input of several: `delay` shifts them all, so this one is
            // the first-order expansion u(t - tau) = u - tau du/dt (the rate
            // telescopes over each step, see effects-format.md).
            let r = fresh(&format!("g_rate_{u}"));
            drafts.push(Draft {
                name: fresh(&format!("{u}_delay")),
                body: format!("param {tau}\ninput {r} = rate({u})\nsubst {u} = {u} - {tau}*{r}\n"),
                formula: format!("{u}_eff(t) = {u}(t - {tau}), to first order in {tau}"),
                positive: format!("{u} acts late"),
                negative: format!("{u} acts early"),
                screen: None,
            });
        }
    }
    if inputs.len() > 1 {
        let tau = fresh("gtau_inputs");
        drafts.push(Draft {
            name: fresh("inputs_delay"),
            body: format!("param {tau}\ndelay {tau}\n"),
            formula: format!("every input acts at t - {tau}"),
            positive: "the inputs act late (or the outputs' clock is ahead)".into(),
            negative: "the inputs act early (or the outputs' clock is behind)".into(),
            screen: Some(None),
        });
    }
    for (label, members, angle) in output_groups(sys) {
        let which = if members.len() == 1 {
            format!("output {label}")
        } else {
            format!("every {label} output ({})", members.len())
        };
        let each = |f: &dyn Fn(&str) -> String| -> String {
            members
                .iter()
                .map(|y| format!("output {y} = {}\n", f(y)))
                .collect()
        };
        let k = fresh(&format!("gk_{label}"));
        let wrapped = |y: &str| {
            if angle {
                format!("atan2(sin({y}), cos({y}))")
            } else {
                y.to_string()
            }
        };
        drafts.push(Draft {
            name: fresh(&format!("{label}_scale")),
            body: format!(
                "param {k}\n{}",
                each(&|y| format!("(1 + {k})*{}", wrapped(y)))
            ),
            formula: format!("{label}_meas = (1 + {k}) {label}, {which}"),
            positive: format!("{label} reads large"),
            negative: format!("{label} reads small"),
            screen: None,
        });
        let b = fresh(&format!("gb_{label}"));
        drafts.push(Draft {
            name: fresh(&format!("{label}_bias")),
            body: format!("param {b}\n{}", each(&|y| format!("{y} + {b}"))),
            formula: format!("{label}_meas = {label} + {b}, {which}"),
            positive: format!("{label} reads high"),
            negative: format!("{label} reads low"),
            screen: None,
        });
        if !angle {
            continue;
        }
        for (n, f) in [(1, "sin"), (1, "cos"), (2, "sin"), (2, "cos")] {
            let a = fresh(&format!("ga_{label}_{f}{n}"));
            let arg = |y: &str| {
                if n == 1 {
                    y.to_string()
                } else {
                    format!("{n}*{y}")
                }
            };
            let shown = if n == 1 {
                format!("{f}({label})")
            } else {
                format!("{f}({n} {label})")
            };
            drafts.push(Draft {
                name: fresh(&format!("{label}_{f}{n}")),
                body: format!(
                    "param {a}\n{}",
                    each(&|y| format!("{y} + {a}*{f}({})", arg(y)))
                ),
                formula: format!("{label}_meas = {label} + {a} {shown}, {which}"),
                positive: format!("{label} is distorted by a harmonic"),
                negative: format!("{label} is distorted by a harmonic"),
                screen: None,
            });
        }
    }
    let mut out = Generation::default();
    let user_named: Vec<(&str, Option<Vec<f64>>)> = user
        .iter()
        .map(|e| (e.name.as_str(), signature(sys, e)))
        .collect();
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for d in drafts {
        let text = format!(
            "effect {}\ndescription {} (generated)\n{}",
            d.name, d.formula, d.body
        );
        let lib = match EffectLibrary::parse(&text, ORIGIN_GENERATED) {
            Ok(l) => l,
            Err(e) => {
                out.dropped.push((d.name, e.to_string()));
                continue;
            }
        };
        let Some(effect) = lib.effects.into_iter().next() else {
            continue;
        };
        if let Err(e) = sys.extend(&[&effect], ORIGIN_GENERATED) {
            out.dropped.push((d.name, e.to_string()));
            continue;
        }
        let Some(sig) = signature(sys, &effect) else {
            out.dropped.push((d.name, "cannot be evaluated".into()));
            continue;
        };
        if let Some((u, _)) = user_named
            .iter()
            .find(|(_, s)| s.as_ref().is_some_and(|s| same(s, &sig)))
        {
            out.dropped
                .push((d.name, format!("the same as '{u}' of the effects file")));
            continue;
        }
        if kept.iter().any(|s| same(s, &sig)) {
            out.dropped
                .push((d.name, "the same as another generated candidate".into()));
            continue;
        }
        let screen = match &d.screen {
            None => Some(effect.clone()),
            Some(None) => None,
            Some(Some(body)) => {
                let text = format!("effect {}\n{body}", d.name);
                match EffectLibrary::parse(&text, ORIGIN_GENERATED) {
                    Ok(l) => l.effects.into_iter().next(),
                    Err(_) => None,
                }
            }
        };
        kept.push(sig);
        out.candidates.push(Generated {
            effect,
            formula: d.formula,
            positive: d.positive,
            negative: d.negative,
            screen,
        });
    }
    out
}

/// The outputs grouped by form: (label, members, angle-valued). The label
/// is the members' common name with trailing digits dropped (`r` for r18,
/// r45, ...), or the name of a single output.
fn output_groups(sys: &System) -> Vec<(String, Vec<String>, bool)> {
    let consts: Vec<(String, String)> = sys
        .decls_of(Kind::Const)
        .map(|d| (d.name.clone(), "_".to_string()))
        .collect();
    let mut groups: Vec<(String, Vec<String>)> = Vec::new();
    for y in sys.output_names() {
        let text = sys.rhs_text(y).unwrap_or_default();
        let shape: String = substitute_names(text, &consts)
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
        match groups.iter_mut().find(|g| g.0 == shape) {
            Some(g) => g.1.push(y.to_string()),
            None => groups.push((shape, vec![y.to_string()])),
        }
    }
    groups
        .into_iter()
        .map(|(shape, members)| {
            let angle = shape.contains("atan(") || shape.contains("atan2(");
            let label = if members.len() == 1 {
                members[0].clone()
            } else {
                let stem = |s: &str| s.trim_end_matches(|c: char| c.is_ascii_digit()).to_string();
                let first = stem(&members[0]);
                if !first.is_empty() && members.iter().all(|m| stem(m) == first) {
                    first
                } else {
                    format!("{}_group", members[0])
                }
            };
            (label, members, angle)
        })
        .collect()
}

/// The extended model's right-hand sides (dynamics of the model's and the
/// new states, outputs) evaluated at two fixed pseudo-random points, with
/// the effect's params and states renamed by position and its derived
/// inputs replaced by their definitions: two effects with equal signatures
/// extend the model in the same way. `None` when it does not extend.
fn signature(sys: &System, e: &Effect) -> Option<Vec<f64>> {
    let ext = sys.extend(&[e], ORIGIN_GENERATED).ok()?;
    let mut map: Vec<(String, String)> = Vec::new();
    for (i, p) in e.params.iter().enumerate() {
        map.push((p.clone(), format!("zp{i}zz")));
    }
    for (i, s) in e.states.iter().enumerate() {
        map.push((s.clone(), format!("zs{i}zz")));
    }
    let renamed = |t: &str, map: &[(String, String)]| substitute_names(t, map);
    let mut derived: Vec<(String, String)> = Vec::new();
    for d in ext.decls_of(Kind::Input) {
        if let (Some(def), true) = (&d.derived, e.inputs.iter().any(|i| i.0 == d.name)) {
            let def = renamed(def, &map);
            // `rate(u)` is no function of one row: a placeholder named by
            // its definition, so equal definitions still compare equal.
            let value = if parse_ast(&def).is_ok() && !def.contains("rate(") {
                def
            } else {
                format!("zh{:x}zz", fnv(&def, 0))
            };
            derived.push((d.name.clone(), value));
        }
    }
    let mut texts: Vec<String> = Vec::new();
    let states: Vec<String> = ext.decls_of(Kind::State).map(|d| d.name.clone()).collect();
    for s in &states {
        texts.push(ext.rhs_text(s)?.to_string());
    }
    for y in ext.output_names() {
        texts.push(ext.rhs_text(y)?.to_string());
    }
    let mut sig = vec![
        e.params.len() as f64,
        e.states.len() as f64,
        f64::from(u8::from(ext.delay.is_some() && sys.delay.is_none())),
    ];
    for t in texts {
        let t = renamed(&renamed(&t, &map), &derived);
        let f = FloatExpr::new(parse_ast(&t).ok()?);
        for seed in [1u64, 2] {
            let vals: Vec<f64> = f.names().iter().map(|n| point(n, seed)).collect();
            sig.push(f.eval(&vals));
        }
    }
    Some(sig)
}

/// FNV-1a of a text, from a seed.
fn fnv(text: &str, seed: u64) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325 ^ seed;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// A value in (0.3, 1.7) fixed by a name and a seed.
fn point(name: &str, seed: u64) -> f64 {
    0.3 + 1.4 * ((fnv(name, seed) >> 11) as f64 / (1u64 << 53) as f64)
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-9 * (1.0 + x.abs().max(y.abs()))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(p: &str) -> String {
        std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
    }

    fn names(g: &Generation) -> Vec<&str> {
        g.candidates
            .iter()
            .map(|c| c.effect.name.as_str())
            .collect()
    }

    #[test]
    fn mrclam_candidates_skip_what_the_file_has() {
        let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
        let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
        let user: Vec<&Effect> = lib.effects.iter().collect();
        let all = generate(&sys, &[]);
        let g = generate(&sys, &user);
        let n = names(&g);
        // The file's speed and turn scales, turn bias, time offset, bearing
        // bias, range scale and bias are written differently but extend the
        // model in the same way: left out, each said so.
        for dup in [
            "v_scale",
            "omega_scale",
            "omega_bias",
            "inputs_delay",
            "b_bias",
            "r_scale",
            "r_bias",
        ] {
            assert!(
                names(&all).contains(&dup),
                "{dup} generated: {:?}",
                names(&all)
            );
            assert!(!n.contains(&dup), "{dup} kept: {n:?}");
            assert!(g
                .dropped
                .iter()
                .any(|d| d.0 == dup && d.1.contains("effects file")));
        }
        assert!(
            g.dropped.iter().all(|d| d.1.contains("the same as")),
            "{:?}",
            g.dropped
        );
        for new in [
            "v_delay",
            "omega_delay",
            "v_with_abs_omega",
            "omega_with_abs_v",
            "v_lag",
            "v_bias",
            "b_scale",
            "b_sin2",
        ] {
            assert!(n.contains(&new), "{new} missing: {n:?}");
        }
        // Grouped by form: one bearing scale for the 15 bearings.
        let bs = g
            .candidates
            .iter()
            .find(|c| c.effect.name == "b_scale")
            .unwrap();
        assert_eq!(bs.effect.outputs.len(), 15);
        let c = g
            .candidates
            .iter()
            .find(|c| c.effect.name == "v_with_abs_omega")
            .unwrap();
        assert_eq!(
            c.words(-0.1),
            "v falls with |omega|: v_eff = v (1 + gc_v_omega |omega|)"
        );
    }

    #[test]
    fn calib_harmonics_and_scale_match_the_file() {
        let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
        let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
        let user: Vec<&Effect> = lib.effects.iter().filter(|e| !e.is_input_side()).collect();
        let g = generate(&sys, &user);
        let n = names(&g);
        for dup in ["beta_scale", "beta_bias", "beta_sin2"] {
            assert!(!n.contains(&dup), "{dup} kept: {n:?}");
        }
        for new in [
            "beta_sin1",
            "beta_cos1",
            "beta_cos2",
            "wR_scale",
            "wR_with_abs_wL",
        ] {
            assert!(n.contains(&new), "{new} missing: {n:?}");
        }
    }
}
