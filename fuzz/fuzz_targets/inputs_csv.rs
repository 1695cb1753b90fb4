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
            // Every piece is found without a panic, asked as the integrator
            // asks (an interval inside one piece: it stops at every row time),
            // and gives the rows' values at its ends.
            for (i, w) in t.t.windows(2).enumerate() {
                if w[0] < w[1] {
                    let mid = w[0] + (w[1] - w[0]) / 2.0;
                    let piece = t.piece(mid, w[1]);
                    assert_eq!(piece.len(), t.names.len());
                    for (k, &(v, slope)) in piece.iter().enumerate() {
                        let (a, b) = (t.rows[i][k], t.rows[i + 1][k]);
                        let end = v + slope * (w[1] - mid);
                        let tol = 1e-9 * (1.0 + a.abs().max(b.abs()));
                        assert!((end - b).abs() <= tol || !end.is_finite(), "{end} vs {b}");
                    }
                }
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
