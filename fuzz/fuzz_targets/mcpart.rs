//! `obsan montecarlo merge` on Monte Carlo part files (the reader lives in
//! the binary's command code, reached through obsan_cli::run_json).
//!
//! Framing: the input is split on the first NUL byte into two part files
//! (one part if there is none). Oracles: no panic (a panic is an "internal
//! error"); a rejection is a message (exit code 2), and an accepted merge
//! prints one JSON list of tables.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("obsan-fuzz-mcpart-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let mut argv = vec!["montecarlo".to_string(), "merge".to_string()];
    let parts: Vec<&[u8]> = match data.iter().position(|&b| b == 0) {
        Some(i) => vec![&data[..i], &data[i + 1..]],
        None => vec![data],
    };
    for (k, p) in parts.iter().enumerate() {
        let path = dir.join(format!("part{k}.json"));
        std::fs::write(&path, p).expect("the temp folder is writable");
        argv.push(path.display().to_string());
    }
    argv.push("--json".into());
    match obsan_cli::run_json(&argv, None) {
        Ok(o) => {
            let v: serde_json::Value = serde_json::from_str(&o.json).expect("one JSON value");
            assert!(v.is_array(), "{}", o.json);
        }
        Err(e) => assert!(!e.0.contains("internal error"), "{}", e.0),
    }
});
