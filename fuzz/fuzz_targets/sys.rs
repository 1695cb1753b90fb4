//! The `.sys` reader: bytes are decoded as a file is (`decode_text`), read,
//! put in normal form without and with each declared restriction, printed
//! back with `to_sys_text` and re-read. Oracles: no panic; every rejection
//! names the file and, when located, a line and column inside the text; the
//! printed system re-reads to an equivalent one (same names, kinds,
//! restrictions, and the same normal form, compared exactly).
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_model::{decode_text, ModelError, NormalForm, System};

const ORIGIN: &str = "fuzz.sys";

fn located(e: &ModelError, text: &str) {
    let shown = e.to_string();
    assert!(shown.starts_with(ORIGIN), "origin not named: {shown}");
    if let (Some(l), Some(c)) = (e.line, e.col) {
        let lines: Vec<&str> = text.split('\n').collect();
        assert!(
            l >= 1 && l <= lines.len(),
            "line {l} outside the text: {shown}"
        );
        let len = lines[l - 1].chars().count();
        assert!(
            c >= 1 && c <= len + 1,
            "column {c} outside line {l}: {shown}"
        );
    }
}

/// Same normal form: each entry of `a` re-read in `b`'s context equals `b`'s.
fn same(a: &mut NormalForm, b: &mut NormalForm, what: &str) {
    assert_eq!(a.state, b.state, "{what}: state");
    assert_eq!(a.inputs, b.inputs, "{what}: inputs");
    assert_eq!(a.outputs.len(), b.outputs.len(), "{what}: outputs");
    let mut pairs: Vec<(Id2, Id2)> = Vec::new();
    for k in 0..a.f0.len() {
        pairs.push((a.f0[k], b.f0[k]));
        for i in 0..a.fields.len() {
            pairs.push((a.fields[i][k], b.fields[i][k]));
        }
    }
    for (x, y) in a.outputs.iter().zip(&b.outputs) {
        assert_eq!(x.0, y.0, "{what}: output names");
        pairs.push((x.1, y.1));
    }
    for (x, y) in pairs {
        let text = a.ctx.to_text(x);
        let xb = match b.parse_expr(&text, true) {
            Ok(id) => id,
            Err(e) => panic!("{what}: printed '{text}' does not re-parse: {e}"),
        };
        let d = b.ctx.sub(xb, y);
        assert!(
            b.ctx.is_identically_zero(d),
            "{what}: '{text}' differs after printing and re-reading"
        );
    }
}

type Id2 = obsan_expr::Id;

fuzz_target!(|data: &[u8]| {
    let src = match decode_text(data, ORIGIN) {
        Ok(s) => s,
        Err(e) => {
            let lossy = String::from_utf8_lossy(data);
            located(&e, &obsan_model::normalize_text(&lossy));
            return;
        }
    };
    let sys = match System::parse(&src, ORIGIN) {
        Ok(s) => s,
        Err(e) => {
            located(&e, &src);
            return;
        }
    };
    let printed = sys.to_sys_text();
    let back = match System::parse(&printed, "printed.sys") {
        Ok(s) => s,
        Err(e) => panic!("the printed system does not re-read: {e}\n{printed}"),
    };
    assert_eq!(sys.name, back.name);
    let kinds = |s: &System| -> Vec<(String, obsan_model::Kind)> {
        s.decls.iter().map(|d| (d.name.clone(), d.kind)).collect()
    };
    assert_eq!(kinds(&sys), kinds(&back), "declarations");
    assert_eq!(sys.output_names(), back.output_names());
    let mut names: Vec<Option<String>> = vec![None];
    names.extend(sys.restrictions.iter().map(|r| Some(r.name.clone())));
    assert_eq!(
        names.len(),
        back.restrictions.len() + 1,
        "restrictions after printing"
    );
    for r in &names {
        let (a, b) = (
            sys.normal_form(r.as_deref(), &[]),
            back.normal_form(r.as_deref(), &[]),
        );
        match (a, b) {
            (Ok(mut a), Ok(mut b)) => same(&mut a, &mut b, &format!("restriction {r:?}")),
            (Err(_), Err(_)) => {}
            (a, b) => panic!(
                "restriction {r:?}: original {:?} but printed {:?}",
                a.err(),
                b.err()
            ),
        }
    }
});
