//! Whether two effects extend a model in the same way: the extended
//! right-hand sides evaluated at fixed pseudo-random points.

use super::ORIGIN_GENERATED;
use obsan_expr::{parse_ast, FloatExpr};
use obsan_model::{substitute_names, Effect, Kind, System};

/// The extended model's right-hand sides (dynamics of the model's and the
/// new states, outputs) evaluated at two fixed pseudo-random points, with
/// the effect's params and states renamed by position and its derived
/// inputs replaced by their definitions: two effects with equal signatures
/// extend the model in the same way. `None` when it does not extend.
pub(super) fn signature(sys: &System, e: &Effect) -> Option<Vec<f64>> {
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

pub(super) fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-9 * (1.0 + x.abs().max(y.abs()))
        })
}
