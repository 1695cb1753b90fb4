//! `obsan global` on the trig systems of systems/global/: the counts derived
//! by hand in each file, and each printed map checked by applying it to the
//! model (its outputs invariant, its dynamics carried along) at random
//! points in this test, not by its text.

use crate::util::*;
use serde_json::Value;
use std::collections::HashMap;
use std::f64::consts::PI;

/// f64 evaluation of sums of products of sin/cos at arguments of size
/// below 10 rounds to about 1e-15 relative; the bearing's quotient has a
/// denominator kept above 0.1 by the sampling: 1e-9 leaves a margin of 10^5.
const TOL: f64 = 1e-9;

/// One moved variable: `var -> sign * image (+ pi)`.
#[derive(Debug)]
struct Image {
    var: String,
    sign: f64,
    image: String,
    plus_pi: bool,
}

/// Parses `a -> b` or `(a, b) -> (c, d)`, each image `v`, `-v`, `v + pi`
/// or `pi - v` (the printed forms of `MapImage`, docs/engine.md).
fn parse_map(s: &str) -> Vec<Image> {
    let (l, r) = s.split_once(" -> ").unwrap_or_else(|| panic!("{s}"));
    let strip = |t: &str| {
        t.trim()
            .trim_start_matches('(')
            .trim_end_matches(')')
            .to_string()
    };
    let (l, r) = (strip(l), strip(r));
    let lhs: Vec<&str> = l.split(", ").collect();
    let rhs: Vec<&str> = r.split(", ").collect();
    assert_eq!(lhs.len(), rhs.len(), "{s}");
    lhs.iter()
        .zip(&rhs)
        .map(|(v, im)| {
            let (sign, image, plus_pi) = if let Some(x) = im.strip_prefix("pi - ") {
                (-1.0, x, true)
            } else if let Some(x) = im.strip_suffix(" + pi") {
                (1.0, x, true)
            } else if let Some(x) = im.strip_prefix('-') {
                (-1.0, x, false)
            } else {
                (1.0, *im, false)
            };
            Image {
                var: v.to_string(),
                sign,
                image: image.to_string(),
                plus_pi,
            }
        })
        .collect()
}

type Vals = HashMap<&'static str, f64>;

/// A model written out by hand from its .sys file: its variables, its
/// outputs and, per state, its right-hand side.
struct Model {
    file: &'static str,
    vars: &'static [&'static str],
    outputs: fn(&Vals) -> Vec<f64>,
    rhs: fn(&Vals) -> Vec<(&'static str, f64)>,
}

fn apply(map: &[Image], v: &Vals) -> Vals {
    let mut out = v.clone();
    for im in map {
        let key = *v
            .keys()
            .find(|k| **k == im.var)
            .unwrap_or_else(|| panic!("map moves unknown {}", im.var));
        let x = im.sign * v[im.image.as_str()] + if im.plus_pi { PI } else { 0.0 };
        out.insert(key, x);
    }
    out
}

/// Deterministic points in [0.5, 2] (SplitMix64).
fn point(vars: &[&'static str], seed: &mut u64) -> Vals {
    vars.iter()
        .map(|&n| {
            *seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = *seed;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            (n, 0.5 + 1.5 * (z >> 11) as f64 / (1u64 << 53) as f64)
        })
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= TOL * (1.0 + a.abs().max(b.abs()))
}

/// The map leaves the outputs unchanged and carries the dynamics along:
/// for a state `s -> sign * t (+ pi)`, `f_s(map(p)) = sign * f_t(p)`.
fn check_map(m: &Model, map: &[Image]) {
    let mut seed = 17;
    for _ in 0..20 {
        let p = point(m.vars, &mut seed);
        let q = apply(map, &p);
        assert!(
            map.iter()
                .any(|im| !close(p[im.var.as_str()], q[im.var.as_str()])),
            "{}: the map fixes the point",
            m.file
        );
        for (a, b) in (m.outputs)(&p).iter().zip((m.outputs)(&q)) {
            assert!(close(*a, b), "{}: output {a} -> {b}", m.file);
        }
        let fp: HashMap<&str, f64> = (m.rhs)(&p).into_iter().collect();
        for (s, fq) in (m.rhs)(&q) {
            let (sign, t) = map
                .iter()
                .find(|im| im.var == s)
                .map_or((1.0, s), |im| (im.sign, im.image.as_str()));
            let want = sign * fp.get(t).copied().unwrap_or(0.0);
            assert!(close(fq, want), "{}: {s}' {fq} vs {want}", m.file);
        }
    }
}

/// Runs `obsan global FILE --json`; checks the hand-derived counts (2 joint
/// solutions, `two` with 2 values, the rest global), one map moving exactly
/// `moved`, a group of order 2; then applies the map to the model.
fn two_solutions(m: &Model, two: &[&str], moved: &[&str]) {
    let v: Value = serde_json::from_str(&ok(&["global", m.file, "--json"])).unwrap();
    assert_eq!(v["solutions"], 2, "{}", m.file);
    assert_eq!(v["group_order"], 2, "{}", m.file);
    for x in v["variables"].as_array().unwrap() {
        let name = x["name"].as_str().unwrap();
        let k = if two.contains(&name) { 2 } else { 1 };
        assert_eq!(x["values"], k, "{}: {name}", m.file);
    }
    let maps = v["maps"].as_array().unwrap();
    assert_eq!(maps.len(), 1, "{}: {maps:?}", m.file);
    let map = parse_map(maps[0].as_str().unwrap());
    let mut names: Vec<&str> = map.iter().map(|i| i.var.as_str()).collect();
    names.sort();
    let mut want = moved.to_vec();
    want.sort();
    assert_eq!(names, want, "{}", m.file);
    check_map(m, &map);
}

#[test]
fn line_direction_theta_modulo_pi() {
    // Hand derivation in the file: (cos 2 theta, sin 2 theta) fixes theta
    // modulo pi; x(0) and k from y1 = x.
    let m = Model {
        file: "systems/global/line_direction.sys",
        vars: &["x", "k", "theta"],
        outputs: |v| vec![v["x"], (2.0 * v["theta"]).cos(), (2.0 * v["theta"]).sin()],
        rhs: |v| vec![("x", -v["k"] * v["x"])],
    };
    two_solutions(&m, &["theta"], &["theta"]);
}

#[test]
fn angle_mod_pi_map() {
    // Hand derivation in the file: tan(theta) fixes theta modulo pi.
    let m = Model {
        file: "systems/global/angle_mod_pi.sys",
        vars: &["x", "k", "theta"],
        outputs: |v| vec![v["x"], v["theta"].sin() / v["theta"].cos()],
        rhs: |v| vec![("x", -v["k"] * v["x"])],
    };
    two_solutions(&m, &["theta"], &["theta"]);
}

#[test]
fn bearing_with_heading_modulo_pi() {
    // Hand derivation in the file: two branches of theta(0), on each a
    // unique (x0, y0); the picture turned by pi about the landmark.
    let m = Model {
        file: "systems/global/bearing_heading_mod_pi.sys",
        vars: &["x", "y", "theta", "v", "w"],
        outputs: |p| {
            let (x, y, t) = (p["x"], p["y"], p["theta"]);
            vec![
                t.sin() / t.cos(),
                (x * t.sin() - y * t.cos()) / (-(x * t.cos() + y * t.sin())),
            ]
        },
        rhs: |p| {
            vec![
                ("x", p["v"] * p["theta"].cos()),
                ("y", p["v"] * p["theta"].sin()),
                ("theta", p["w"]),
            ]
        },
    };
    two_solutions(&m, &["x", "y", "theta"], &["x", "y", "theta"]);
}

#[test]
fn wall_reflection_mirror() {
    // Hand derivation in the file: sin(theta) known, so theta or pi - theta;
    // x0 cos(theta) known, so x0 changes sign with cos(theta).
    let m = Model {
        file: "systems/global/wall_reflection.sys",
        vars: &["x", "y", "theta", "v"],
        outputs: |p| vec![p["y"], p["x"] * p["x"] + p["y"] * p["y"]],
        rhs: |p| {
            vec![
                ("x", p["v"] * p["theta"].cos()),
                ("y", p["v"] * p["theta"].sin()),
            ]
        },
    };
    two_solutions(&m, &["x", "theta"], &["x", "theta"]);
}

#[test]
fn parse_map_reads_every_printed_form() {
    // The four forms of MapImage's Display, by hand.
    let m = parse_map("(a, b, c, d) -> (b, -a, c + pi, pi - d)");
    let got: Vec<(&str, f64, &str, bool)> = m
        .iter()
        .map(|i| (i.var.as_str(), i.sign, i.image.as_str(), i.plus_pi))
        .collect();
    assert_eq!(
        got,
        vec![
            ("a", 1.0, "b", false),
            ("b", -1.0, "a", false),
            ("c", 1.0, "c", true),
            ("d", -1.0, "d", true)
        ]
    );
    let one = parse_map("theta -> theta + pi");
    assert_eq!((one[0].var.as_str(), one[0].plus_pi), ("theta", true));
}
