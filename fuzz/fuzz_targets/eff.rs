//! The `.eff` reader: bytes decoded as a file is, read as an effect library,
//! then each effect applied to systems/calib.sys (`System::extend`) and the
//! library checked against it. Oracles: no panic; every rejection names the
//! file; an extended system is a valid system (its normal form exists).
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_model::{decode_text, EffectLibrary, System};

const ORIGIN: &str = "fuzz.eff";

fuzz_target!(|data: &[u8]| {
    let calib = match System::parse(include_str!("../../systems/calib.sys"), "calib.sys") {
        Ok(s) => s,
        Err(e) => panic!("systems/calib.sys: {e}"),
    };
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
                assert!(c >= 1 && c <= lines[l - 1].chars().count() + 1, "column: {e}");
            }
            return;
        }
    };
    let _ = lib.check(&calib);
    for e in &lib.effects {
        match calib.extend(&[e], ORIGIN) {
            Ok(ext) => {
                if let Err(err) = ext.normal_form(None, &[]) {
                    panic!("effect {} extends calib into a system without normal form: {err}", e.name);
                }
            }
            Err(err) => assert!(err.to_string().starts_with(ORIGIN), "{err}"),
        }
    }
});
