//! The dimensional analysis on hand-written effect forms: each expected
//! unit is read off the form (a bias has the unit of what it is added to,
//! a scale none, a time constant s, a rate per s).

use super::*;
use crate::generate::generate;

/// A robot with a range and a bearing (atan2: an angle, rad) and two
/// measured inputs; `xi` is a model param nobody gave a unit.
const SYS: &str = "system robot
state x, y, th
input v, omega
param xi
const q
x' = v*cos(th)
y' = v*sin(th)
th' = xi*omega
output r = sqrt(x^2 + y^2)
output beta = atan2(-y, -x) - th
";

fn sys() -> System {
    System::parse(SYS, "robot.sys").expect("valid system")
}

/// Angle outputs as the fit finds them: built on atan/atan2.
fn angular(sys: &System) -> impl Fn(&str) -> bool {
    let nf = sys.normal_form(None, &[]).expect("normal form");
    let angles: Vec<String> = (nf.outputs.iter())
        .filter(|(_, h)| nf.ctx.is_angle_valued(*h))
        .map(|(y, _)| y.clone())
        .collect();
    move |y: &str| angles.iter().any(|a| a == y)
}

/// Each param's unit as text ("-": none derived) for the effect `body`,
/// after the file's `head` (unit declarations).
fn units_of(head: &str, body: &str, generated: bool) -> Vec<String> {
    let s = sys();
    let lib = EffectLibrary::parse(&format!("{head}effect e\n{body}"), "t.eff").expect("valid");
    lib.check(&s).expect("extends the model");
    effect_units(&s, &lib.effects[0], generated, &lib.units, &angular(&s))
        .into_iter()
        .map(|(p, u)| format!("{p} {}", u.map_or("-".into(), |u| u.to_string())))
        .collect()
}

#[test]
fn a_bias_takes_its_outputs_unit_and_a_scale_is_a_pure_number() {
    let a = angular(&sys());
    assert!(a("beta") && !a("r"));
    assert_eq!(
        units_of("", "param b\noutput beta = beta + b\n", false),
        ["b rad"]
    );
    // A harmonic's amplitude: sin(2 beta) is a number.
    assert_eq!(
        units_of("", "param a2\noutput beta = beta + a2*sin(2*beta)\n", false),
        ["a2 rad"]
    );
    assert_eq!(
        units_of(
            "",
            "param kb\noutput beta = (1 + kb)*atan2(sin(beta), cos(beta))\n",
            false
        ),
        ["kb 1"]
    );
    assert_eq!(
        units_of("", "param k\nsubst v = (1 + k)*v\n", false),
        ["k 1"]
    );
    // A range's unit is the data's: declared, or its column's own.
    assert_eq!(
        units_of("unit r = m\n", "param c\noutput r = r + c\n", false),
        ["c m"]
    );
    assert_eq!(
        units_of("", "param c\noutput r = r + c\n", false),
        ["c [r]"]
    );
    assert_eq!(
        units_of("unit r = m\n", "param c\noutput r = r + c*r^2\n", false),
        ["c 1/m"]
    );
    // A bias that follows the heading: cos and sin are numbers.
    assert_eq!(
        units_of(
            "",
            "param b, c\noutput beta = beta + b*cos(th) + c*sin(th)\n",
            false
        ),
        ["b rad", "c rad"]
    );
}

#[test]
fn times_are_in_seconds_and_rates_per_second() {
    assert_eq!(units_of("", "param tau\ndelay tau\n", false), ["tau s"]);
    // (v - va)/T = va' = [v]/s, so T is in s.
    assert_eq!(
        units_of(
            "",
            "param T = 0.2\nstate va = v\nva' = (v - va)/T\nsubst v = va\n",
            false
        ),
        ["T s"]
    );
    // A first-order delay: tau rate(v) has v's unit.
    assert_eq!(
        units_of(
            "",
            "param tau\ninput dv = rate(v)\nsubst v = v - tau*dv\n",
            false
        ),
        ["tau s"]
    );
    // A drift of v's scale in session time: k v t has v's unit.
    let drift = "param k\ninput session_t_v\ninput g = v*session_t_v\nsubst v = v + k*g\n";
    assert_eq!(units_of("", drift, true), ["k 1/s"]);
    // Written by a user, the undefined input is a data column of its own.
    assert_eq!(units_of("", drift, false), ["k 1/[session_t_v]"]);
    // A coupling: c |omega| is a number; declared, c is in s/rad.
    let coupling = "param c\ninput g = v*sqrt(omega^2)\nsubst v = v + c*g\n";
    assert_eq!(units_of("", coupling, false), ["c 1/[omega]"]);
    assert_eq!(
        units_of("unit omega = rad/s\n", coupling, false),
        ["c s/rad"]
    );
    // An out-of-round wheel: the phase state starts at 0 (any unit).
    assert_eq!(
        units_of(
            "",
            "param a\nstate ph = 0\nph' = v\nsubst v = v*(1 + a*cos(ph))\n",
            false
        ),
        ["a 1"]
    );
}

#[test]
fn what_cannot_be_derived_is_none_and_a_declaration_wins() {
    // Beside a model param and constant nobody gave a unit: unknown.
    assert_eq!(
        units_of("", "param e\nsubst omega = omega*(1 + e*xi)\n", false),
        ["e -"]
    );
    assert_eq!(
        units_of("", "param dq\ncompare v = (q + dq)*omega\n", false),
        ["dq -"]
    );
    // Declared, the same relation gives dq its unit.
    assert_eq!(
        units_of(
            "unit q = m/rad, v = m/s, omega = rad/s\n",
            "param dq\ncompare v = (q + dq)*omega\n",
            false
        ),
        ["dq m/rad"]
    );
    assert_eq!(
        units_of("unit b = deg\n", "param b\noutput beta = beta + b\n", false),
        ["b deg"]
    );
    // A sum of terms in different units says nothing.
    assert_eq!(
        units_of("", "param g\nsubst v = v + g + omega\n", false),
        ["g -"]
    );
    // Two places that disagree: reported as none, not either one.
    assert_eq!(
        units_of(
            "",
            "param b\noutput beta = beta + b\noutput r = r + b\n",
            false
        ),
        ["b -"]
    );
}

/// The generated candidates of calib.sys, every family at once: the units
/// their forms give (generate.rs writes them).
#[test]
fn generated_candidates_of_calib_have_their_forms_units() {
    let text = std::fs::read_to_string(format!(
        "{}/../../systems/calib.sys",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("calib.sys");
    let s = System::parse(&text, "calib.sys").expect("valid");
    let g = generate(&s, &[]);
    let u = param_units(&s, None, &g.candidates, &angular(&s));
    let get = |p: &str| u.get(p).map(|u| u.to_string());
    assert_eq!(get("gd_wR").as_deref(), Some("1/s"), "{u:?}");
    assert_eq!(get("gT_wR").as_deref(), Some("s"));
    assert_eq!(get("gk_wR").as_deref(), Some("1"));
    assert_eq!(get("gb_wR").as_deref(), Some("[wR]"));
    assert_eq!(get("gb_beta").as_deref(), Some("rad"));
    assert_eq!(get("gk_beta").as_deref(), Some("1"));
    // calib.sys has no delay of its own; its params have no units.
    assert_eq!(get("xi"), None);
}

/// Two effects with a param of one name: the name has a unit only when
/// both give it the same one.
#[test]
fn a_param_name_two_effects_give_two_units_has_none() {
    let s = sys();
    let read = |text: &str| EffectLibrary::parse(text, "t.eff").expect("valid");
    let a = "effect a\nparam k\noutput beta = beta + k\n";
    let b = "effect b\nparam k\nsubst v = (1 + k)*v\n";
    let c = "effect c\nparam k\noutput beta = beta + 2*k\n";
    let units = |t: &str| param_units(&s, Some(&read(t)), &[], &angular(&s));
    assert_eq!(units(&format!("{a}{b}")).get("k"), None);
    let d = "effect d\nparam k\nsubst omega = (1 + k)*omega\n";
    assert_eq!(units(&format!("{b}{a}{d}")).get("k"), None);
    assert_eq!(
        units(&format!("{b}{d}"))
            .get("k")
            .map(|u| u.to_string())
            .as_deref(),
        Some("1")
    );
    assert_eq!(
        units(&format!("{a}{c}"))
            .get("k")
            .map(|u| u.to_string())
            .as_deref(),
        Some("rad")
    );
}

/// mrclam.eff with its declared units (ranges in m, v in m/s, omega in
/// rad/s): each effect's param in the unit its form gives.
#[test]
fn mrclam_effects_have_their_units() {
    let read = |p: &str| {
        std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).expect(p)
    };
    let s = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").expect("valid");
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").expect("valid");
    lib.check(&s).expect("checked");
    let u = param_units(&s, Some(&lib), &[], &angular(&s));
    let get = |p: &str| u.get(p).map(|u| u.to_string());
    // kv, kw, kr scale; bw is added to omega; bb to the bearings (atan2);
    // br to the ranges; tau a delay; T the lag's time constant.
    for (p, want) in [
        ("kv", "1"),
        ("kw", "1"),
        ("kr", "1"),
        ("bw", "rad/s"),
        ("bb", "rad"),
        ("br", "m"),
        ("tau", "s"),
        ("T", "s"),
    ] {
        assert_eq!(get(p).as_deref(), Some(want), "{p}: {u:?}");
    }
}
