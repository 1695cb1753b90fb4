//! `obsan modes` closes the reduced system whenever a closed form exists.
//! Each system here is written so that one exists by
//! construction; the test checks the written reduced system itself: at random
//! rational points (angles at rational points of the circle) the reduced
//! field `F_k(z(x), u)` equals the chain rule `d/dt z_k = grad z_k . f(x, u)`
//! of the mode formulas, and each output equals its form in the modes.

use crate::util::{obsan, temp_file};
use obsan_expr::{evaluate::rational_angle, parse_ast, Ctx, FloatExpr, SplitMix, Q};
use serde_json::Value;
use std::collections::HashMap;

/// A system as the test wrote it: the analysed state (states, then params)
/// with each right-hand side (`0` for a param), the inputs, the constants
/// and the outputs; `angles` enter only through cos/sin.
struct Model {
    state: Vec<(String, String)>,
    params: Vec<String>,
    inputs: Vec<String>,
    /// Unmeasured inputs (`unknown input`): the reduced system may carry a
    /// combination of one (`reduced_inputs` in the JSON), evaluated here
    /// from its stated factor and offset.
    unknown: Vec<String>,
    consts: Vec<String>,
    angles: Vec<String>,
    outputs: Vec<(String, String)>,
}

impl Model {
    fn sys_text(&self, name: &str) -> String {
        let mut o = format!("system {name}\n");
        let st: Vec<&str> = self.state.iter().map(|s| s.0.as_str()).collect();
        o.push_str(&format!("state {}\n", st.join(", ")));
        if !self.params.is_empty() {
            o.push_str(&format!("param {}\n", self.params.join(", ")));
        }
        if !self.consts.is_empty() {
            o.push_str(&format!("const {}\n", self.consts.join(", ")));
        }
        if !self.inputs.is_empty() {
            o.push_str(&format!("input {}\n", self.inputs.join(", ")));
        }
        if !self.unknown.is_empty() {
            o.push_str(&format!("unknown input {}\n", self.unknown.join(", ")));
        }
        for (x, f) in &self.state {
            o.push_str(&format!("{x}' = {f}\n"));
        }
        for (y, h) in &self.outputs {
            o.push_str(&format!("output {y} = {h}\n"));
        }
        o
    }
}

fn small_q(rng: &mut SplitMix) -> Q {
    let n = (rng.next_u64() % 19) as i64 - 9;
    let d = (rng.next_u64() % 7) as i64 + 1;
    Q::from_i64(n).div(&Q::from_i64(d)).expect("d > 0")
}

/// Runs `obsan modes` and checks the reduced system at `points` random
/// rational points; returns the JSON for further checks.
fn assert_closes(m: &Model, name: &str, seed: u64) -> Value {
    let path = temp_file(&format!("{name}.sys"), &m.sys_text(name));
    let r = obsan(&["modes", &path, "--json"]);
    assert_eq!(r.code, 0, "{}\n{}{}", m.sys_text(name), r.stdout, r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    // With unknown inputs the certificate is a text and `verified` top-level.
    let verified = v["certificate"]["verified"]
        .as_bool()
        .or(v["verified"].as_bool());
    assert_eq!(verified, Some(true), "{v}");
    check_reduced(m, &v, seed);
    v
}

/// The chain rule and the outputs at random rational points (see module doc).
fn check_reduced(m: &Model, v: &Value, seed: u64) {
    let mut ctx = Ctx::new();
    let modes: Vec<(String, String)> = v["modes"]
        .as_array()
        .expect("modes")
        .iter()
        .map(|z| {
            (
                z["name"].as_str().unwrap().to_string(),
                z["expr"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    let dynamics: HashMap<String, String> = v["reduced"]["dynamics"]
        .as_array()
        .expect("dynamics")
        .iter()
        .map(|d| {
            (
                d["name"].as_str().unwrap().to_string(),
                d["rhs"].as_str().expect("closed").to_string(),
            )
        })
        .collect();
    let all_state: Vec<(String, String)> = m
        .state
        .iter()
        .cloned()
        .chain(m.params.iter().map(|p| (p.clone(), "0".to_string())))
        .collect();
    let mut rng = SplitMix(seed);
    // Comparisons made: a point where a mode has a pole is skipped, but the
    // check must not be vacuous.
    let mut compared = 0;
    let mut per_mode: HashMap<String, usize> = HashMap::new();
    for _ in 0..6 {
        // A point: every symbol a small rational, each angle at the point
        // t of the circle (cos, sin) = ((1-t^2), 2t)/(1+t^2).
        let mut val: HashMap<String, Q> = HashMap::new();
        let mut fval: HashMap<String, f64> = HashMap::new();
        let mut leaf_q: HashMap<u32, Q> = HashMap::new();
        for (x, _) in &all_state {
            let q = small_q(&mut rng);
            if m.angles.contains(x) {
                let (s, c) = rational_angle(&q);
                for (f, w) in [("cos", c), ("sin", s)] {
                    let id = ctx.parse(&format!("{f}({x})")).unwrap();
                    let vs = ctx.canon(id).vars();
                    leaf_q.insert(vs[0], w);
                }
                fval.insert(x.clone(), 2.0 * q.to_f64().atan());
            } else {
                fval.insert(x.clone(), q.to_f64());
                val.insert(x.clone(), q);
            }
        }
        for u in m.inputs.iter().chain(&m.unknown).chain(&m.consts) {
            let q = small_q(&mut rng);
            fval.insert(u.clone(), q.to_f64());
            val.insert(u.clone(), q);
        }
        let eval = |ctx: &mut Ctx, text: &str, val: &HashMap<String, Q>| -> Option<Q> {
            let id = ctx.parse(text).unwrap();
            let r = ctx.eval_q(&[id], &|v| {
                leaf_q
                    .get(&v)
                    .cloned()
                    .or_else(|| ctx.symbol_name(v).and_then(|n| val.get(n).cloned()))
            });
            // A pole of a mode's domain: skip the point.
            r.ok().map(|mut x| x.remove(0))
        };
        // The modes' values at the point, then the chain rule of each.
        let mut zval = val.clone();
        let mut zs: Vec<Option<Q>> = Vec::new();
        for (zn, ze) in &modes {
            let z = eval(&mut ctx, ze, &val);
            if let Some(z) = &z {
                zval.insert(zn.clone(), z.clone());
            }
            zs.push(z);
        }
        if zs.iter().any(|z| z.is_none()) {
            continue;
        }
        // A combination `factor * w + offset` of an unknown input, at the
        // point (its definition as the JSON states it).
        let mut pole = false;
        for c in v["reduced_inputs"].as_array().into_iter().flatten() {
            let (Some(name), Some(w)) = (c["name"].as_str(), c["input"].as_str()) else {
                continue;
            };
            let text = match (c["factor"].as_str(), c["offset"].as_str()) {
                (Some(f), Some(o)) => format!("({f})*{w} + ({o})"),
                (Some(f), None) => format!("({f})*{w}"),
                _ => w.to_string(),
            };
            match eval(&mut ctx, &text, &val) {
                Some(q) => {
                    zval.insert(name.to_string(), q);
                }
                None => pole = true,
            }
        }
        if pole {
            continue;
        }
        for (zn, ze) in &modes {
            let zid = ctx.parse(ze).unwrap();
            let mut terms = Vec::new();
            for (x, f) in &all_state {
                let xv = ctx.symbol(x).var;
                let d = ctx.diff(zid, xv);
                let fid = ctx.parse(f).unwrap();
                terms.push(ctx.mul(&[d, fid]));
            }
            let chain = ctx.add(&terms);
            let chain_text = ctx.to_text(chain);
            let (Some(lhs), Some(rhs)) = (
                eval(&mut ctx, &chain_text, &val),
                eval(&mut ctx, &dynamics[zn], &zval),
            ) else {
                continue;
            };
            assert_eq!(
                lhs, rhs,
                "{zn}' = {} is not d/dt ({ze}) = {chain_text} at {val:?}",
                dynamics[zn]
            );
            compared += 1;
            *per_mode.entry(zn.clone()).or_default() += 1;
        }
        // Outputs: exactly when rational, an angle modulo 2 pi in f64.
        for o in v["reduced"]["outputs"].as_array().unwrap() {
            let on = o["name"].as_str().unwrap();
            let oe = o["expr"].as_str().expect("closed");
            let h = &m.outputs.iter().find(|p| p.0 == on).unwrap().1;
            if h.contains("atan") {
                let fe = |t: &str, vals: &HashMap<String, f64>| {
                    let f = FloatExpr::new(parse_ast(t).unwrap());
                    let xs: Vec<f64> = f.names().iter().map(|n| vals[n]).collect();
                    f.eval(&xs)
                };
                let mut zf = fval.clone();
                for ((zn, _), z) in modes.iter().zip(&zs) {
                    zf.insert(zn.clone(), z.as_ref().unwrap().to_f64());
                }
                let d = fe(h, &fval) - fe(oe, &zf);
                assert!(
                    d.sin().abs() < 1e-9 && d.cos() > 0.0,
                    "output {on} = {oe}: off by {d} at {fval:?}"
                );
            } else if let (Some(a), Some(b)) = (eval(&mut ctx, h, &val), eval(&mut ctx, oe, &zval))
            {
                assert_eq!(a, b, "output {on} = {oe} at {val:?}");
            }
        }
    }
    assert!(
        compared >= 2 * modes.len(),
        "only {compared} comparisons for {} modes",
        modes.len()
    );
    // Every mode's own dynamics compared at least once (a form that never
    // evaluates, say over an input name the point lacks, proves nothing).
    for (zn, _) in &modes {
        assert!(
            per_mode.get(zn).is_some_and(|&k| k > 0),
            "{zn}' never compared"
        );
    }
}

fn model(
    state: &[(&str, &str)],
    params: &[&str],
    inputs: &[&str],
    consts: &[&str],
    angles: &[&str],
    outputs: &[(&str, &str)],
) -> Model {
    let own = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    Model {
        state: state
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect(),
        params: own(params),
        inputs: own(inputs),
        unknown: Vec::new(),
        consts: own(consts),
        angles: own(angles),
        outputs: outputs
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect(),
    }
}

/// Shape a: a scaling (x, y, c) -> (l x, l y, c / l^2) whose monomial
/// invariants x^2 c and y^2 c do not generate x y c (= sqrt of their product),
/// which a rotation of (x, y) needs. A generating set closes, by hand: with
/// z1 = x^2 c, z2 = x/y, z1' = 2 c x y u = 2 u z1/z2, z2' = u (1 + z2^2),
/// h = z1 (or with z2 = x y c: z1' = 2 u z2, z2' = u (z2^2/z1 - z1)).
#[test]
fn shape_a_scaling_whose_first_monomials_miss_the_product_closes() {
    let m = model(
        &[("x", "u*y"), ("y", "-u*x")],
        &["c"],
        &["u"],
        &[],
        &[],
        &[("h", "c*x^2")],
    );
    let v = assert_closes(&m, "shape_a", 11);
    assert_eq!(v["rank"], 2);
}

/// Shape b: a derivative z1 m T'(x)/T(x)^2 with T = 1 + a x^2 + x^4 (degree
/// 8 in the denominator, over the blocks x, m, z1, a): the monomial factor
/// m z1 is peeled and T'/T^2 written in x and a alone. By hand: with
/// z1 = k y, z1' = k y' = -z1 m (2 a x + 4 x^3)/T^2.
#[test]
fn shape_b_derivative_with_a_monomial_factor_and_a_high_degree_quotient_closes() {
    let m = model(
        &[
            ("x", "u"),
            ("y", "-y*m*(2*a*x + 4*x^3)/(1 + a*x^2 + x^4)^2"),
        ],
        &["k", "m"],
        &["u"],
        &["a"],
        &[],
        &[("h1", "x"), ("h2", "k*y")],
    );
    let v = assert_closes(&m, "shape_b", 12);
    assert_eq!(v["rank"], 3);
}

/// Shape c: a unicycle (x, y, psi) bearing a landmark (lx, ly) from a sensor
/// offset by (dx, dy) in the world frame: translations and a rotation about
/// the offset point leave b = atan2(ly - y - dy, lx - x - dx) - psi. By hand:
/// with (z1, z2) = R(-psi) (lx - x - dx, ly - y - dy), z1' = -v + w z2,
/// z2' = -w z1 and b = atan2(z2, z1) (modulo 2 pi).
#[test]
fn shape_c_bearing_from_an_offset_sensor_closes() {
    let m = model(
        &[("x", "v*cos(psi)"), ("y", "v*sin(psi)"), ("psi", "w")],
        &["lx", "ly"],
        &["v", "w"],
        &["dx", "dy"],
        &["psi"],
        &[("b", "atan2(ly - y - dy, lx - x - dx) - psi")],
    );
    let v = assert_closes(&m, "shape_c", 13);
    assert_eq!(v["rank"], 2);
    assert_eq!(v["symmetries"], 3);
}

/// Shape d: StructuralIdentifiability.jl's KD1999 (a jacketed CSTR, Kravaris-
/// Daoutidis 1999): six scalings of the params and of Ca, Arr; the mode
/// z = Ca Arr k0 has the drift `-k0 Arr_p z - E/R z/T^2 (z DH/(ro cp) + UA (Tj -
/// T)/(V ro cp))`, a quotient of degree 5 in 8 modes, past the dense ansatz:
/// it is written through the cross-section of the scalings (pivots set to 1,
/// the other variables to their invariant monomials). By hand, with z1 = k0
/// Arr_p, z3 = DH/UA, z4 = E/R, z6 = ro cp/DH:
/// `L_f0 z = -z1 z - z4 z (V z3 z + Tj - T)/(T^2 V z3 z6)`; the test checks
/// the written system by the chain rule at rational points, whichever modes
/// are chosen.
#[test]
fn shape_d_a_cstr_closes_through_the_cross_section_of_its_scalings() {
    let m = model(
        &[
            ("Ca", "u1*(Ca0 - Ca)/V - k0*Arr_p*Ca"),
            ("Cb", "-u1*Cb/V + k0*Arr*Ca"),
            (
                "T",
                "u1*(Ta - T)/V - (k0*Arr*Ca*DH + UA*(Tj - T)/V)/(ro*cp)",
            ),
            ("Tj", "u2*(Th - Tj)/Vh - UA/(roh*cph)*(Tj - T)/Vh"),
            (
                "Arr",
                "E*Arr/(R*T^2)*(u1*(Ta - T)/V - (k0*Arr*Ca*DH + UA*(Tj - T)/V)/(ro*cp))",
            ),
        ],
        &[
            "Ca0", "V", "k0", "Arr_p", "Ta", "DH", "UA", "ro", "cp", "Th", "Vh", "roh", "cph", "E",
            "R",
        ],
        &["u1", "u2"],
        &[],
        &[],
        &[("y1", "Cb"), ("y2", "T")],
    );
    let v = assert_closes(&m, "shape_d", 17);
    // The independent verdict of systems/benchmarks/si-jl/KD1999.sys (symident): rank 14.
    assert_eq!(v["rank"], 14);
}

/// SI.jl's EAIHRD epidemic (systems/benchmarks/si-jl/EAIHRD.sys): its four
/// symmetries are not scalings, and the independent invariants the lattice
/// and ansatz searches find (A c1, I c2, H d, I h d, E a c1, E s c2, a + s,
/// h + r2, r3 + d) leave the dynamics of E a c1 needing the susceptibles
/// S = N - A - I - H - R - D - E, which the symmetries only scale. By hand,
/// with m = a c1 S: S' = -S (c1 A + c2 I), so m' = -m (z1 + z2) and
/// (E a c1)' = m (z1 + z2) - (a + s) E a c1: closed; E/S or any product of
/// S with variables the symmetries scale inversely does as well. The test
/// checks whatever modes are chosen by the chain rule at rational points.
#[test]
fn eaihrd_closes_through_a_written_sum_the_symmetries_scale() {
    let m = model(
        &[
            ("A", "a*E - r1*A"),
            ("I", "s*E - (h + r2)*I"),
            ("H", "h*I - (r3 + d)*H"),
            ("R", "r1*A + r2*I + r3*H"),
            ("D", "d*H"),
            ("E", "(N - A - I - H - R - D - E)*(c1*A + c2*I) - (a + s)*E"),
        ],
        &["a", "r1", "s", "h", "r2", "r3", "d", "N", "c1", "c2"],
        &[],
        &[],
        &[],
        &[("y", "D")],
    );
    let v = assert_closes(&m, "eaihrd", 29);
    // The independent verdict of the suite file (symident): rank 12.
    assert_eq!(v["rank"], 12);
}

/// STRIKE-GOLDD's pharmacokinetic model with the dose an unknown input
/// (systems/benchmarks/unknown-inputs/pk.sys): its four symmetries are not
/// scalings, and the derivative of the mode `k5/(s2 x2')` needs the input's
/// combination another mode's derivative defines. With one unknown input
/// every mode's derivative is, once that combination is named, a function
/// of the modes (the certificate's argument, unknown_input_modes.rs), so the
/// reduced system closes; the test checks whatever forms are printed by the
/// chain rule at rational points, the combination evaluated from its stated
/// factor and offset. Before session 29 `L_f0 z6` was not found.
#[test]
fn pk_with_an_unknown_dose_closes_through_the_slice_of_its_free_columns() {
    let mut m = model(
        &[
            ("x1", "u1 - (k1 + k2)*x1"),
            ("x2", "k1*x1 - (k3 + k6 + k7)*x2 + k5*x4"),
            ("x3", "k2*x1 + k3*x2 - k4*x3"),
            ("x4", "k6*x2 - k5*x4"),
        ],
        &["k1", "k2", "k3", "k4", "k5", "k6", "k7", "s2", "s3"],
        &[],
        &[],
        &[],
        &[("y1", "s2*x2"), ("y2", "s3*x3")],
    );
    m.unknown = vec!["u1".to_string()];
    let v = assert_closes(&m, "pk_ui", 41);
    // The suite file's verdict (the SymPy oracle): 9 observable directions.
    assert_eq!(v["rank"], 9);
}

/// A random polynomial of degree <= 2 in `vars` (text), small integer
/// coefficients, at least one non-constant term.
fn random_poly(rng: &mut SplitMix, vars: &[String]) -> String {
    let mut terms: Vec<String> = Vec::new();
    let k = vars.len();
    for _ in 0..3 {
        let c = (rng.next_u64() % 5) as i64 + 1;
        let c = if rng.next_u64().is_multiple_of(2) {
            c
        } else {
            -c
        };
        let a = &vars[(rng.next_u64() as usize) % k];
        let t = match rng.next_u64() % 3 {
            0 => format!("{c}*{a}"),
            1 => {
                let b = &vars[(rng.next_u64() as usize) % k];
                format!("{c}*{a}*{b}")
            }
            _ => format!("{c}"),
        };
        terms.push(t);
    }
    if terms.iter().all(|t| !t.contains('*')) {
        terms.push(vars[0].clone());
    }
    format!("({})", terms.join(" + "))
}

/// One system with a known invariant set, and the rank that set implies:
/// - scaling: x_i -> l^w_i x_i; fields x_i R_i(m) with R_i polynomials in
///   invariant monomials m, outputs polynomials in them;
/// - translation: x_i -> x_i + t_i s; fields and outputs polynomials in the
///   differences t_k x_i - t_i x_k;
/// - rotation and translation: a unicycle and a landmark; the relative
///   position in the robot's frame (X, Y) drives everything.
fn random_model(rng: &mut SplitMix) -> (Model, usize) {
    let s = |v: &str| v.to_string();
    match rng.next_u64() % 3 {
        0 => {
            let n = 3 + (rng.next_u64() % 2) as usize;
            let xs: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
            // Weights: x1 weight 1, the others -2..2 with one negative.
            let mut w: Vec<i64> = vec![1];
            for _ in 1..n {
                w.push((rng.next_u64() % 5) as i64 - 2);
            }
            if w.iter().all(|&x| x >= 0) {
                w[n - 1] = -1;
            }
            // Invariant monomials: w_j x_i^... pairs, as text.
            let mut inv: Vec<String> = Vec::new();
            for j in 1..n {
                let b = w[j];
                let e = if b == 0 {
                    xs[j].clone()
                } else {
                    // x1^(-b) xj^(a) has weight -b + a b = 0 with a = 1.
                    format!("{}^({})*{}", xs[0], -b, xs[j])
                };
                inv.push(format!("({e})"));
            }
            let mut state = Vec::new();
            for (i, x) in xs.iter().enumerate() {
                let u = if i % 2 == 0 { "u1" } else { "u2" };
                let r = random_poly(rng, &inv);
                state.push((x.clone(), format!("{u}*{x}*{r}")));
            }
            let h = random_poly(rng, &inv);
            let m = Model {
                state,
                params: vec![],
                inputs: vec![s("u1"), s("u2")],
                unknown: vec![],
                consts: vec![],
                angles: vec![],
                outputs: vec![(s("h1"), h), (s("h2"), inv[0].clone())],
            };
            (m, n - 1)
        }
        1 => {
            let n = 3 + (rng.next_u64() % 2) as usize;
            let xs: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
            let t: Vec<i64> = (0..n).map(|_| (rng.next_u64() % 3) as i64 + 1).collect();
            let d: Vec<String> = (1..n)
                .map(|i| format!("({}*{} - {}*{})", t[0], xs[i], t[i], xs[0]))
                .collect();
            let mut state = Vec::new();
            for (i, x) in xs.iter().enumerate() {
                // t_i times one shared drift keeps d's drift a function of d.
                let u = if i % 2 == 0 { "u1" } else { "u2" };
                state.push((x.clone(), format!("{u}*{}", random_poly(rng, &d))));
            }
            let m = Model {
                state,
                params: vec![],
                inputs: vec![s("u1"), s("u2")],
                unknown: vec![],
                consts: vec![],
                angles: vec![],
                outputs: vec![(s("h1"), random_poly(rng, &d)), (s("h2"), d[0].clone())],
            };
            (m, n - 1)
        }
        _ => {
            let big_x = s("(cos(psi)*(lx - x) + sin(psi)*(ly - y))");
            let big_y = s("(-sin(psi)*(lx - x) + cos(psi)*(ly - y))");
            let xy = vec![big_x.clone(), big_y.clone()];
            let a = random_poly(rng, &xy);
            let b = random_poly(rng, &xy);
            let (ox, oy) = (small_q(rng), small_q(rng));
            let out = if rng.next_u64().is_multiple_of(2) {
                format!("atan2(ly - y - ({oy}), lx - x - ({ox})) - psi")
            } else {
                format!("{big_x}^2 + {big_y}^2")
            };
            let m = Model {
                state: vec![
                    (s("x"), format!("v*(cos(psi)*{a} - sin(psi)*{b})")),
                    (s("y"), format!("v*(sin(psi)*{a} + cos(psi)*{b})")),
                    (s("psi"), s("w")),
                ],
                params: vec![s("lx"), s("ly")],
                inputs: vec![s("v"), s("w")],
                unknown: vec![],
                consts: vec![],
                angles: vec![s("psi")],
                outputs: vec![(s("b"), out)],
            };
            (m, 2)
        }
    }
}

/// Systems built from a random invariant set of a scaling, a translation or
/// a rotation with translations (so a closed reduced system exists by
/// construction): whenever obsan's rank is the one the invariant set implies,
/// `modes` must close, and the closed system passes the chain-rule check.
#[test]
fn random_invariant_systems_always_close() {
    let mut rng = SplitMix(0x39_0002);
    let mut checked = 0;
    let mut drawn = 0;
    while checked < 30 {
        drawn += 1;
        assert!(drawn < 200, "too few systems of the implied rank");
        let (m, rank) = random_model(&mut rng);
        let name = format!("rand{drawn}");
        let path = temp_file(&format!("{name}.sys"), &m.sys_text(&name));
        let r = obsan(&["rank", &path, "--json"]);
        let Ok(rv) = serde_json::from_str::<Value>(&r.stdout) else {
            panic!("{}\n{}{}", m.sys_text(&name), r.stdout, r.stderr);
        };
        if rv["rank"] != rank {
            continue;
        }
        assert_closes(&m, &name, drawn);
        checked += 1;
    }
}

/// `text` (a form over the mode names) with each non-variable mode replaced
/// by its expression, in canonical form, against `want` over the variables.
fn same_after_substitution(v: &Value, text: &str, want: &str) -> bool {
    let mut ctx = Ctx::new();
    let mut map = Vec::new();
    for z in v["modes"].as_array().expect("modes") {
        let (name, expr) = (z["name"].as_str().unwrap(), z["expr"].as_str().unwrap());
        if name != expr {
            let var = ctx.symbol(name).var;
            map.push((var, ctx.parse(expr).unwrap()));
        }
    }
    let t = ctx.parse(text).unwrap();
    let t = ctx.substitute(t, &map).unwrap();
    let w = ctx.parse(want).unwrap();
    ctx.canon(t) == ctx.canon(w)
}

/// Richards' growth in STRIKE-GOLDD's radiotherapy model
/// (systems/benchmarks/strike-goldd/tumour_radiotherapy_richards.sys): `V`,
/// `lambda`, `K`, `theta` are modes themselves and the drift
/// `lambda V (1 - (V/K)^theta)` is a function of them alone, though not a
/// rational one; by hand the reduced field is the model's own, with the
/// dose term through `alpha d + beta d^2` (rank 5 of 7: the two symmetries
/// move alpha, beta, d only).
#[test]
fn a_drift_in_variable_modes_is_written_as_it_is() {
    let r = obsan(&[
        "modes",
        "systems/benchmarks/strike-goldd/tumour_radiotherapy_richards.sys",
        "--json",
    ]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    let dyn_v = v["reduced"]["dynamics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|d| d["name"] == "V")
        .expect("V is a mode");
    let rhs = dyn_v["rhs"].as_str().unwrap();
    assert!(
        same_after_substitution(
            &v,
            rhs,
            "lambda*V*(1 - (V/K)^theta) - (alpha*d + beta*d^2)*V*delta_ti"
        ),
        "V' = {rhs}"
    );
}

/// An encoder difference `y = th1 - th2` (systems/global/relative_angle.sys):
/// the rotation `(1, 1, 0, 0, 0)` leaves the angle difference as the mode, and
/// the output is that mode up to its sign, by hand (an integer combination of
/// angle modes, not a function of their cos and sin).
#[test]
fn an_angle_output_is_a_combination_of_the_angle_modes() {
    let r = obsan(&["modes", "systems/global/relative_angle.sys", "--json"]);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    let y = v["reduced"]["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|o| o["name"] == "y")
        .expect("y");
    let text = y["expr"].as_str().unwrap();
    assert!(
        !text.contains("sin") && !text.contains("atan"),
        "y = {text}"
    );
    assert!(same_after_substitution(&v, text, "th1 - th2"), "y = {text}");
}
