//! The STRIKE-GOLDD importer: any bytes decoded as a file is, translated, and the .sys read
//! back. Oracles: no panic (here or in obsan-model); every refusal lies inside the text.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = obsan_model::decode_text(data, "fuzz.m") else {
        return;
    };
    let lines = src.split('\n').count();
    match obsan_import::strike_goldd_to_sys(&src, "z_create_fuzz.m") {
        Err(e) => assert!(e.line >= 1 && e.line <= lines, "line outside the text: {e}"),
        Ok(c) => {
            if let Ok(s) = obsan_model::System::parse(&c.sys_text, "fuzz.sys") {
                let _ = s.normal_form(None, &[]);
            }
        }
    }
});
