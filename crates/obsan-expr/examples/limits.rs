//! Times the engine's limits on the issue-14 reproducers:
//! `cargo run --release -p obsan-expr --example limits`.

use obsan_expr::Ctx;
use std::time::Instant;

fn main() {
    let chain = |n: usize, f: &dyn Fn(usize) -> String, sep: &str| {
        (0..n).map(f).collect::<Vec<_>>().join(sep)
    };
    let cases: Vec<String> = vec![
        chain(22, &|i| format!("(a{i} + 1)"), "*"),
        chain(20, &|i| format!("(a{i} + 1)"), "*"),
        chain(17, &|i| format!("(a{i} + 1)"), "*"),
        ["x^10000"; 7].join("*"),
        "((x^10000)^10000)^100".to_string(),
        chain(100_000, &|i| format!("v{i}"), "+"),
        vec!["x"; 100_000].join("+"),
    ];
    for src in &cases {
        let t = Instant::now();
        let mut ctx = Ctx::new();
        let out = match ctx.parse(src) {
            Err(e) => format!("parse error: {e}"),
            Ok(id) => match ctx.try_canon(id) {
                Ok(r) => format!("ok, {} terms", r.term_count()),
                Err(l) => format!("error: {l}"),
            },
        };
        let head: String = src.chars().take(30).collect();
        println!("{:>8.3} s  {head}...  {out}", t.elapsed().as_secs_f64());
    }
}
