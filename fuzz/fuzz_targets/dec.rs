//! The `.dec` reader (obsan_analysis::Decomposition::parse): bytes decoded
//! as a file is, then read as a decomposition. Oracles: no panic; every
//! rejection names the file, at a line and column inside the text.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_analysis::Decomposition;
use obsan_model::decode_text;

const ORIGIN: &str = "fuzz.dec";

fuzz_target!(|data: &[u8]| {
    let src = match decode_text(data, ORIGIN) {
        Ok(s) => s,
        Err(e) => {
            assert!(e.to_string().starts_with(ORIGIN), "{e}");
            return;
        }
    };
    if let Err(e) = Decomposition::parse(&src, ORIGIN) {
        let m = e.to_string();
        assert!(m.starts_with(ORIGIN), "{m}");
        // ORIGIN:LINE:COL: with the line inside the text.
        let mut it = m[ORIGIN.len()..].split(':');
        let _ = it.next();
        if let Some(Ok(l)) = it.next().map(|l| l.parse::<usize>()) {
            assert!(
                l >= 1 && l <= src.split('\n').count(),
                "line outside the text: {m}"
            );
        }
    }
});
