//! The StructuralIdentifiability.jl (@ODEmodel) importer: any bytes decoded as
//! a file is, every model found converted and its .sys read back. Oracles: no
//! panic (here or in obsan-model); every refusal lies inside the text.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = obsan_model::decode_text(data, "fuzz.jl") else {
        return;
    };
    let lines = src.split('\n').count();
    let inside = |e: &obsan_import::ImportError| {
        assert!(e.line >= 1 && e.line <= lines, "line outside the text: {e}");
        let len = src.split('\n').nth(e.line - 1).map_or(0, |l| l.chars().count());
        assert!(e.col >= 1 && e.col <= len + 1, "column outside line: {e}");
    };
    match obsan_import::si_jl_models(&src) {
        Err(e) => inside(&e),
        Ok(models) => {
            for m in &models {
                match obsan_import::si_jl_convert(&src, m, "fuzz.jl") {
                    Err(e) => inside(&e),
                    Ok(c) => {
                        if let Ok(s) = obsan_model::System::parse(&c.sys_text, "fuzz.sys") {
                            let _ = s.normal_form(None, &[]);
                        }
                    }
                }
            }
        }
    }
});
