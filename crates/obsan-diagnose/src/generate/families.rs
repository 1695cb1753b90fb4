//! What real sensors and wheels do beside constant errors: a slow drift of
//! an input's scale in session time (a wheel radius wearing), a quadratic
//! in an output that is not an angle (a range reading that bends with
//! range), a periodic error in an input's integral (an out-of-round wheel,
//! periodic in the wheel's angle) and an output bias that follows an angle
//! state (a bearing bias with heading), and wheels that slip in
//! proportion to their own speed. Each is chosen by the model's
//! structure, never by names, and carries its physical range.

use super::basic::Group;
use super::limits::{Limit, Reading, SESSION_CLOCK};
use super::{Draft, Names};
use obsan_expr::parse_ast;
use obsan_model::{Kind, System};

/// A fitted drift may change an input's scale by at most this fraction
/// over the session; a wobble's amplitude, at most this fraction of the
/// speed; a quadratic term, at most this fraction of the largest reading;
/// a state-dependent bias, at most this fraction of the output's spread;
/// a wheel's slip with its own speed, at most this fraction of its
/// rotation at its largest measured speed. Beyond it the "wheel" would lose half its radius: a failed fit.
const HALF: f64 = 0.5;

/// A drift may change an input's scale by at most this fraction over the
/// session: wear and warming change a wheel's radius by a few percent in an
/// hour, not by a third in minutes. A larger trend is something else (a fit
/// stopped short, a scale error of another input read as a trend): a failed
/// fit, not a finding.
const DRIFT_MAX: f64 = 0.1;

/// Every new family, in the order: drifts, quadratics, wobbles, biases
/// with an angle state, slip with the wheels' own speeds.
pub(super) fn drafts(
    sys: &System,
    inputs: &[String],
    groups: &[Group],
    n: &mut Names,
) -> Vec<Draft> {
    let mut d = drifts(inputs, n);
    d.extend(quadratics(groups, n));
    d.extend(wobbles(sys, inputs, n));
    d.extend(state_biases(sys, groups, n));
    d.extend(own_speed_slip(sys, inputs, n));
    d
}

/// Whether the measured inputs are wheel speeds: no state integrates an
/// input by itself. A state that does (`th' = omega`) makes the inputs a
/// body's velocities: a travelled distance has no period, a body speed no
/// wheel slip.
fn wheel_speeds(sys: &System, inputs: &[String]) -> bool {
    let squash = |s: &str| s.chars().filter(|c| !c.is_whitespace()).collect::<String>();
    let integrated: Vec<String> = sys
        .decls_of(Kind::State)
        .filter_map(|d| sys.rhs_text(&d.name).map(squash))
        .collect();
    !inputs.iter().any(|u| integrated.contains(u))
}

/// When the inputs are wheel speeds: each wheel loses the fraction
/// `s_u |u|` of its rotation, `u (1 - s_u |u|)`, one `s_u` per wheel, all
/// in one candidate. A tyre's slip grows with its own speed: neither a
/// scale (a constant fraction, absorbed by the radii) nor a coupling with
/// another wheel's speed has this form, and a candidate for one wheel
/// alone leaves the other's slip to a stand-in (on varying-speed circles
/// whose wheels both slip so, `wR (1 + c |wL|)` won by LR 27 and stayed
/// established beside the file's turn-rate slip). `|u|` as `sqrt(u^2)` in
/// a derived input, as the couplings. Range: the slip at the largest
/// measured speed, `|s_u| max|u|`, at most HALF.
fn own_speed_slip(sys: &System, inputs: &[String], n: &mut Names) -> Vec<Draft> {
    if inputs.is_empty() || !wheel_speeds(sys, inputs) {
        return Vec::new();
    }
    let s: Vec<String> = inputs.iter().map(|u| n.fresh(&format!("gs_{u}"))).collect();
    let g: Vec<String> = (inputs.iter())
        .map(|u| n.fresh(&format!("g_{u}_abs_{u}")))
        .collect();
    let mut body = format!("param {}\n", s.join(", "));
    for (u, g) in inputs.iter().zip(&g) {
        body += &format!("input {g} = {u}*sqrt({u}^2)\n");
    }
    let substs: Vec<String> = (inputs.iter().zip(s.iter().zip(&g)))
        .map(|(u, (s, g))| format!("{u} = {u} - {s}*{g}"))
        .collect();
    body += &format!("subst {}\n", substs.join(", "));
    let each: Vec<String> = (inputs.iter().zip(&s))
        .map(|(u, s)| format!("{u}_eff = {u} (1 - {s} |{u}|)"))
        .collect();
    let mut d = Draft::plain(
        n.fresh("own_speed_slip"),
        body,
        each.join(", "),
        (
            "the wheels slip in proportion to their own speed".into(),
            "the wheels act larger in proportion to their own speed".into(),
        ),
    );
    for (u, s) in inputs.iter().zip(s) {
        d.limits.push(Limit {
            param: s,
            bound: HALF,
            per_second: false,
            columns: Some((vec![u.clone()], Reading::MaxAbs)),
            what: format!("the slip of {u} at its largest measured speed"),
        });
    }
    vec![d]
}

/// Per measured input `u`: `u (1 + d t)`, t the session clock (s since the
/// dataset's first input row). A param that only scales `u` (a wheel
/// radius r in `r wR`) drifting as `r (1 + d t)` is this same extension.
/// The clock is an input filled by `prepare` and the product `u t` a
/// derived input, so the extension stays input-affine and adds no state:
/// a clock state's free start would be a constant scale, confounded with
/// any param that scales `u` (calib.sys's eta, delta, xi), and the fit's
/// Fisher matrix singular. An output's drift is not generated: outputs
/// may not read inputs, and a clock state's start is then a bias.
/// The random walk that an input's noise leaves in the integrated states
/// is itself a trend: at white input noise a drift is credited with it
/// (clean constant-speed circles, seed 6: LR 13.3, named; under the
/// estimated input noise 2.5), so a drift is weighed only at the
/// estimated noise, never also at white noise as other candidates are.
fn drifts(inputs: &[String], n: &mut Names) -> Vec<Draft> {
    let mut out = Vec::new();
    for u in inputs {
        let k = n.fresh(&format!("gd_{u}"));
        let clock = n.fresh(&format!("{SESSION_CLOCK}_{u}"));
        let g = n.fresh(&format!("g_{u}_by_t"));
        let mut d = Draft::plain(
            n.fresh(&format!("{u}_drift")),
            format!(
                "param {k}\ninput {clock}\ninput {g} = {u}*{clock}\nsubst {u} = {u} + {k}*{g}\n"
            ),
            format!("{u}_eff = {u} (1 + {k} t), t the session time in s"),
            (
                format!("{u} acts larger as the session goes on"),
                format!("{u} acts smaller as the session goes on"),
            ),
        );
        d.limits.push(Limit {
            param: k,
            bound: DRIFT_MAX,
            per_second: true,
            columns: None,
            what: format!("the change of {u}'s scale over the session"),
        });
        d.estimated_noise_only = true;
        out.push(d);
    }
    out
}

/// Per group of outputs that are not angles: `y + c y^2`.
fn quadratics(groups: &[Group], n: &mut Names) -> Vec<Draft> {
    let mut out = Vec::new();
    for (label, members, angle) in groups.iter().filter(|g| !g.2) {
        debug_assert!(!angle);
        let c = n.fresh(&format!("gq_{label}"));
        let body: String = members
            .iter()
            .map(|y| format!("output {y} = {y} + {c}*{y}^2\n"))
            .collect();
        let mut d = Draft::plain(
            n.fresh(&format!("{label}_quadratic")),
            format!("param {c}\n{body}"),
            format!(
                "{label}_meas = {label} + {c} {label}^2, {}",
                which(label, members)
            ),
            (
                format!("{label} reads increasingly high with {label}"),
                format!("{label} reads increasingly low with {label}"),
            ),
        );
        d.limits.push(Limit {
            param: c,
            bound: HALF,
            per_second: false,
            columns: Some((members.clone(), Reading::MaxAbs)),
            what: format!("the quadratic term's share of the largest {label}"),
        });
        out.push(d);
    }
    out
}

/// Per measured input `u`, when no state integrates an input by itself:
/// `u (1 + a cos(phi_u))` with a new state `phi_u' = u`, the input's
/// integral, an angle when `u` is a wheel's angular speed in rad/s. A state
/// that integrates an input by itself (`th' = omega`) makes the inputs a
/// body's velocities, not wheel speeds: the heading's periodic effects are
/// the state-dependent biases, and a travelled distance has no period (a
/// unicycle's heading random walk was named as `v`'s periodic error, K + 1
/// free values soaking it up: tests/common_mode.rs). The free start of
/// `phi_u` in each trajectory is the wheel's phase there, so one amplitude
/// serves trajectories recorded apart; a cosine and a sine beside a free
/// phase would be a continuous symmetry. At `a = 0` the phase has no
/// sensitivity: the screen scores the pair `a cos + b sin` with the state
/// held, which sees any phase.
fn wobbles(sys: &System, inputs: &[String], n: &mut Names) -> Vec<Draft> {
    let mut out = Vec::new();
    if !wheel_speeds(sys, inputs) {
        return out;
    }
    for u in inputs {
        let a = n.fresh(&format!("gw_{u}"));
        let b = n.fresh(&format!("gw_{u}_sin"));
        let phi = n.fresh(&format!("g_{u}_angle"));
        let state = format!("state {phi} = 0\n{phi}' = {u}\n");
        let mut d = Draft::plain(
            n.fresh(&format!("{u}_periodic")),
            format!("param {a}\n{state}subst {u} = {u}*(1 + {a}*cos({phi}))\n"),
            format!("{u}_eff = {u} (1 + {a} cos(angle)), angle' = {u} (an out-of-round wheel)"),
            (
                format!("{u} varies periodically with its integral"),
                format!("{u} varies periodically with its integral"),
            ),
        );
        d.screen = Some(Some(format!(
            "param {a}, {b}\n{state}subst {u} = {u}*(1 + {a}*cos({phi}) + {b}*sin({phi}))\n"
        )));
        d.limits.push(Limit {
            param: a,
            bound: HALF,
            per_second: false,
            columns: None,
            what: format!("the periodic share of {u}"),
        });
        out.push(d);
    }
    out
}

/// Per output group and per angle state `x` (a state inside a `sin` or
/// `cos` of the model): `y + b cos(x) + c sin(x)`, a bias that follows the
/// angle with any phase.
fn state_biases(sys: &System, groups: &[Group], n: &mut Names) -> Vec<Draft> {
    let angles = angle_states(sys);
    let mut out = Vec::new();
    for (label, members, _) in groups {
        for x in &angles {
            let b = n.fresh(&format!("gb_{label}_cos_{x}"));
            let c = n.fresh(&format!("gb_{label}_sin_{x}"));
            let body: String = members
                .iter()
                .map(|y| format!("output {y} = {y} + {b}*cos({x}) + {c}*sin({x})\n"))
                .collect();
            let mut d = Draft::plain(
                n.fresh(&format!("{label}_bias_with_{x}")),
                format!("param {b}, {c}\n{body}"),
                format!(
                    "{label}_meas = {label} + {b} cos({x}) + {c} sin({x}), {}",
                    which(label, members)
                ),
                (
                    format!("{label}'s bias follows {x}"),
                    format!("{label}'s bias follows {x}"),
                ),
            );
            for p in [b, c] {
                d.limits.push(Limit {
                    param: p,
                    bound: HALF,
                    per_second: false,
                    columns: Some((members.clone(), Reading::Spread)),
                    what: format!("the bias's share of the spread of {label}"),
                });
            }
            out.push(d);
        }
    }
    out
}

fn which(label: &str, members: &[String]) -> String {
    if members.len() == 1 {
        format!("output {label}")
    } else {
        format!("every {label} output ({})", members.len())
    }
}

/// The states that appear in the argument of a `sin` or `cos` of a
/// dynamics right-hand side or an output: angles (a heading).
pub(super) fn angle_states(sys: &System) -> Vec<String> {
    let states: Vec<String> = sys.decls_of(Kind::State).map(|d| d.name.clone()).collect();
    let mut texts: Vec<&str> = states.iter().filter_map(|s| sys.rhs_text(s)).collect();
    let outs = sys.output_names();
    texts.extend(outs.iter().filter_map(|y| sys.rhs_text(y)));
    let mut found: Vec<String> = Vec::new();
    for t in texts {
        for arg in trig_args(t) {
            let Ok(ast) = parse_ast(&arg) else { continue };
            for (name, _) in ast.idents() {
                if states.iter().any(|s| s == name) && !found.iter().any(|f| f == name) {
                    found.push(name.to_string());
                }
            }
        }
    }
    // In declaration order, whatever the order of discovery.
    states.into_iter().filter(|s| found.contains(s)).collect()
}

/// The arguments of every `sin(...)` and `cos(...)` call in `text`.
fn trig_args(text: &str) -> Vec<String> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    for f in ["sin(", "cos("] {
        for (i, _) in text.match_indices(f) {
            let word = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
            if word {
                continue;
            }
            let start = i + f.len();
            let mut depth = 1;
            for (j, c) in text[start..].char_indices() {
                match c {
                    '(' => depth += 1,
                    ')' => depth -= 1,
                    _ => {}
                }
                if depth == 0 {
                    out.push(text[start..start + j].to_string());
                    break;
                }
            }
        }
    }
    out
}
