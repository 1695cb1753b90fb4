//! The PEtab importer: the input framed as six files separated by U+0001 (the YAML, the SBML
//! model, the parameter, observable, condition and measurement tables). Oracles: no panic
//! (here or in obsan-model); every refusal lies inside the file it names.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_import::PetabFile as F;

fuzz_target!(|data: &[u8]| {
    let Ok(src) = obsan_model::decode_text(data, "fuzz.petab") else {
        return;
    };
    let mut parts: Vec<&str> = src.split('\u{1}').collect();
    parts.resize(6, "");
    let lines = |s: &str| s.split('\n').count();
    if let Err(e) = obsan_import::petab_files(parts[0]) {
        assert!(e.line >= 1 && e.line <= lines(parts[0]), "line outside the YAML: {e}");
    }
    let t = obsan_import::PetabTexts {
        sbml: parts[1],
        parameters: parts[2],
        observables: parts[3],
        conditions: parts[4],
        measurements: vec![parts[5]],
    };
    match obsan_import::petab_to_sys(&t, "fuzz.yaml", None) {
        Err(e) => {
            let text = match e.file {
                F::Yaml => parts[0],
                F::Sbml => parts[1],
                F::Parameters => parts[2],
                F::Observables => parts[3],
                F::Conditions => parts[4],
                F::Measurements(_) => parts[5],
            };
            let l = e.error.line;
            assert!(l >= 1 && l <= lines(text), "line outside {:?}: {}", e.file, e.error);
        }
        Ok(c) => {
            if let Ok(s) = obsan_model::System::parse(&c.sys_text, "fuzz.sys") {
                let _ = s.normal_form(None, &[]);
            }
        }
    }
});
