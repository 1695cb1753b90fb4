//! The `.eff` reader: bytes decoded as a file is, read as an effect library,
//! then each effect applied to systems/calib.sys (`System::extend`) and the
//! library checked against it. Oracles: no panic; every rejection names the
//! file; an extended system is a valid system (its normal form exists), and
//! `check` passes only if every effect extends. A checked library's params
//! get their units (obsan-diagnose's dimensional analysis) without a panic,
//! a declared param its declaration.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_model::{decode_text, EffectLibrary, System};

const ORIGIN: &str = "fuzz.eff";

thread_local! {
    /// Read once: every input extends the same system.
    static CALIB: System = match System::parse(include_str!("../../systems/calib.sys"), "calib.sys") {
        Ok(s) => s,
        Err(e) => panic!("systems/calib.sys: {e}"),
    };
}

fuzz_target!(|data: &[u8]| CALIB.with(|calib| run(calib, data)));

fn run(calib: &System, data: &[u8]) {
    let src = match decode_text(data, ORIGIN) {
        Ok(s) => s,
        Err(e) => {
            assert!(e.to_string().starts_with(ORIGIN), "{e}");
            return;
        }
    };
    let lib = match EffectLibrary::parse(&src, ORIGIN) {
        Ok(l) => l,
        Err(e) => {
            assert!(e.to_string().starts_with(ORIGIN), "{e}");
            if let (Some(l), Some(c)) = (e.line, e.col) {
                let lines: Vec<&str> = src.split('\n').collect();
                assert!(l >= 1 && l <= lines.len(), "line outside the text: {e}");
                assert!(
                    c >= 1 && c <= lines[l - 1].chars().count() + 1,
                    "column: {e}"
                );
            }
            return;
        }
    };
    let checked = lib.check(calib);
    if let Err(e) = &checked {
        assert!(e.to_string().starts_with(ORIGIN), "{e}");
    }
    if checked.is_ok() {
        let units =
            obsan_diagnose::dimensions::param_units(calib, Some(&lib), &[], &|y| y == "beta");
        for d in &lib.units {
            if let Some(u) = units.get(&d.name) {
                assert_eq!(*u, d.unit, "declared unit of {}", d.name);
            }
        }
    }
    for e in &lib.effects {
        match calib.extend(&[e], ORIGIN) {
            Ok(ext) => {
                if let Err(err) = ext.normal_form(None, &[]) {
                    panic!(
                        "effect {} extends calib into a system without normal form: {err}",
                        e.name
                    );
                }
            }
            Err(err) => {
                assert!(
                    checked.is_err(),
                    "check passed but extending by {} fails: {err}",
                    e.name
                );
                assert!(err.to_string().starts_with(ORIGIN), "{err}");
            }
        }
    }
}
