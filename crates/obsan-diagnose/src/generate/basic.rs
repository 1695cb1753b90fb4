//! The first generated families: per measured input a scale, a bias,
//! couplings with the others' magnitudes, a lag and a delay; per output
//! group a scale, a bias and, for angles, four harmonics.

use super::{Draft, Names};
use obsan_model::{substitute_names, Kind, System};

/// An output group: (label, members, angle-valued).
pub(super) type Group = (String, Vec<String>, bool);

/// Per measured input: scale, bias, couplings `u (1 + c |w|)`, first-order
/// lag, delay; with several inputs also one delay of them all.
pub(super) fn input_drafts(inputs: &[String], names: &mut Names) -> Vec<Draft> {
    let mut drafts: Vec<Draft> = Vec::new();
    for u in inputs {
        let k = names.fresh(&format!("gk_{u}"));
        drafts.push(Draft {
            name: names.fresh(&format!("{u}_scale")),
            body: format!("param {k}\nsubst {u} = (1 + {k})*{u}\n"),
            formula: format!("{u}_eff = (1 + {k}) {u}"),
            positive: format!("{u} acts larger than measured"),
            negative: format!("{u} acts smaller than measured"),
            screen: None,
            limits: Vec::new(),
            estimated_noise_only: false,
        });
        let b = names.fresh(&format!("gb_{u}"));
        drafts.push(Draft {
            name: names.fresh(&format!("{u}_bias")),
            body: format!("param {b}\nsubst {u} = {u} + {b}\n"),
            formula: format!("{u}_eff = {u} + {b}"),
            positive: format!("{u} acts with a positive offset"),
            negative: format!("{u} acts with a negative offset"),
            screen: None,
            limits: Vec::new(),
            estimated_noise_only: false,
        });
        for w in inputs.iter().filter(|w| *w != u) {
            let c = names.fresh(&format!("gc_{u}_{w}"));
            let d = names.fresh(&format!("g_{u}_abs_{w}"));
            drafts.push(Draft {
                name: names.fresh(&format!("{u}_with_abs_{w}")),
                // |w| as sqrt(w^2): a derived input, evaluated in floating
                // point (the exact engine never sees the absolute value).
                body: format!(
                    "param {c}\ninput {d} = {u}*sqrt({w}^2)\nsubst {u} = {u} + {c}*{d}\n"
                ),
                formula: format!("{u}_eff = {u} (1 + {c} |{w}|)"),
                positive: format!("{u} rises with |{w}|"),
                negative: format!("{u} falls with |{w}|"),
                screen: None,
                limits: Vec::new(),
                estimated_noise_only: false,
            });
        }
        let t = names.fresh(&format!("gT_{u}"));
        let s = names.fresh(&format!("g_{u}_lagged"));
        let r0 = names.fresh(&format!("g_lagrate_{u}"));
        drafts.push(Draft {
            name: names.fresh(&format!("{u}_lag")),
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
            limits: Vec::new(),
            estimated_noise_only: false,
        });
        let tau = names.fresh(&format!("gtau_{u}"));
        if inputs.len() == 1 {
            drafts.push(Draft {
                name: names.fresh(&format!("{u}_delay")),
                body: format!("param {tau}\ndelay {tau}\n"),
                formula: format!("{u}_eff(t) = {u}(t - {tau})"),
                positive: format!("{u} acts late"),
                negative: format!("{u} acts early"),
                screen: Some(None),
                limits: Vec::new(),
                estimated_noise_only: false,
            });
        } else {
            // One input of several: `delay` shifts them all, so this one is
            // the first-order expansion u(t - tau) = u - tau du/dt (the rate
            // telescopes over each step, see effects-format.md).
            let r = names.fresh(&format!("g_rate_{u}"));
            drafts.push(Draft {
                name: names.fresh(&format!("{u}_delay")),
                body: format!("param {tau}\ninput {r} = rate({u})\nsubst {u} = {u} - {tau}*{r}\n"),
                formula: format!("{u}_eff(t) = {u}(t - {tau}), to first order in {tau}"),
                positive: format!("{u} acts late"),
                negative: format!("{u} acts early"),
                screen: None,
                limits: Vec::new(),
                estimated_noise_only: false,
            });
        }
    }
    if inputs.len() > 1 {
        let tau = names.fresh("gtau_inputs");
        drafts.push(Draft {
            name: names.fresh("inputs_delay"),
            body: format!("param {tau}\ndelay {tau}\n"),
            formula: format!("every input acts at t - {tau}"),
            positive: "the inputs act late (or the outputs' clock is ahead)".into(),
            negative: "the inputs act early (or the outputs' clock is behind)".into(),
            screen: Some(None),
            limits: Vec::new(),
            estimated_noise_only: false,
        });
    }
    drafts
}

/// Per output group: scale and bias; for angle groups the harmonics
/// `sin y`, `cos y`, `sin 2y`, `cos 2y`.
pub(super) fn output_drafts(groups: &[Group], names: &mut Names) -> Vec<Draft> {
    let mut drafts: Vec<Draft> = Vec::new();
    for (label, members, angle) in groups {
        let angle = *angle;
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
        let k = names.fresh(&format!("gk_{label}"));
        let wrapped = |y: &str| {
            if angle {
                format!("atan2(sin({y}), cos({y}))")
            } else {
                y.to_string()
            }
        };
        drafts.push(Draft {
            name: names.fresh(&format!("{label}_scale")),
            body: format!(
                "param {k}\n{}",
                each(&|y| format!("(1 + {k})*{}", wrapped(y)))
            ),
            formula: format!("{label}_meas = (1 + {k}) {label}, {which}"),
            positive: format!("{label} reads large"),
            negative: format!("{label} reads small"),
            screen: None,
            limits: Vec::new(),
            estimated_noise_only: false,
        });
        let b = names.fresh(&format!("gb_{label}"));
        drafts.push(Draft {
            name: names.fresh(&format!("{label}_bias")),
            body: format!("param {b}\n{}", each(&|y| format!("{y} + {b}"))),
            formula: format!("{label}_meas = {label} + {b}, {which}"),
            positive: format!("{label} reads high"),
            negative: format!("{label} reads low"),
            screen: None,
            limits: Vec::new(),
            estimated_noise_only: false,
        });
        if !angle {
            continue;
        }
        for (n, f) in [(1, "sin"), (1, "cos"), (2, "sin"), (2, "cos")] {
            let a = names.fresh(&format!("ga_{label}_{f}{n}"));
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
                name: names.fresh(&format!("{label}_{f}{n}")),
                body: format!(
                    "param {a}\n{}",
                    each(&|y| format!("{y} + {a}*{f}({})", arg(y)))
                ),
                formula: format!("{label}_meas = {label} + {a} {shown}, {which}"),
                positive: format!("{label} is distorted by a harmonic"),
                negative: format!("{label} is distorted by a harmonic"),
                screen: None,
                limits: Vec::new(),
                estimated_noise_only: false,
            });
        }
    }
    drafts
}

/// The outputs grouped by form: (label, members, angle-valued). The label
/// is the members' common name with trailing digits dropped (`r` for r18,
/// r45, ...), or the name of a single output.
pub(super) fn output_groups(sys: &System) -> Vec<(String, Vec<String>, bool)> {
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
