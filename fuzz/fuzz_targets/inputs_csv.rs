//! The inputs time course of `obsan simulate MODEL.sys --inputs FILE.csv`
//! (obsan_cli::read_input_table). Oracles: no panic; a rejection starts with
//! `file:line:column:` and the line is inside the text; an accepted table has
//! finite values, non-decreasing times with at most two rows at one time,
//! one value per column in every row, and a piece for every column.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_cli::read_input_table;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match read_input_table(text, "f.csv") {
        Ok(t) => {
            assert!(t.t.windows(2).all(|w| w[0] <= w[1]), "time goes back");
            assert!(t.t.windows(3).all(|w| w[0] < w[2]), "three rows at one time");
            for r in &t.rows {
                assert_eq!(r.len(), t.names.len());
                assert!(r.iter().all(|v| v.is_finite()));
            }
            // Every piece is found without a panic.
            let (a, b) = (t.t[0], t.t[t.t.len() - 1]);
            if a < b {
                let piece = t.piece(a + (b - a) / 2.0, b);
                assert_eq!(piece.len(), t.names.len());
            }
        }
        Err(e) => {
            let rest = e.0.strip_prefix("f.csv:").expect("names the file");
            let mut p = rest.splitn(3, ':');
            let line: usize = p.next().and_then(|x| x.parse().ok()).expect("a line");
            let col: usize = p.next().and_then(|x| x.parse().ok()).expect("a column");
            let lines = text.split(['\n', '\r']).count();
            assert!(line >= 1 && line <= lines && col >= 1, "{}", e.0);
        }
    }
});
