//! Gcd benchmark: the engine's gcd (heuristic on small images, else
//! modular), the modular gcd alone, the engine's gcd before the modular one
//! (heuristic up to 2^26-bit images, then PRS), and zippel-gcd's Zippel routine, on families of random
//! polynomials with a planted common factor. Prints the median of REPS runs
//! of each family (a budget of 10 s per call stops a blow-up: "timeout").
//!
//! Run: `cargo bench -p obsan-expr --bench gcd` (optionally `-- REPS`).

use obsan_expr::{
    gcds::EngineGcd, gcds::HeuristicGcd, gcds::ModularGcd, gcds::PolyGcd, within_thread_budget,
    Budget, Int, Mono, Poly, SplitMix, Var,
};
use polycore::{Order, Ring};
use std::time::{Duration, Instant};

fn rand_poly(rng: &mut SplitMix, nvars: u32, nterms: usize, maxdeg: u32, words: usize) -> Poly {
    loop {
        let p = Poly::from_terms((0..nterms).map(|_| {
            let m = Mono::from_pairs(
                (0..nvars).map(|v| (v as Var, (rng.next_u64() % (maxdeg as u64 + 1)) as u32)),
            );
            let mut c = Int::from(1 + rng.next_u64() % 9);
            for _ in 0..words {
                c = (c << 64) + Int::from(rng.next_u64());
            }
            if rng.next_u64().is_multiple_of(2) {
                c = -c;
            }
            (m, c)
        }));
        if !p.is_constant() {
            return p;
        }
    }
}

fn text(p: &Poly) -> String {
    let mut s = String::new();
    for (i, (m, c)) in p.terms().iter().enumerate() {
        if i > 0 {
            s.push_str(" + ");
        }
        s.push_str(&format!("({c})"));
        for (v, e) in m.iter() {
            s.push_str(&format!("*x{v}^{e}"));
        }
    }
    s
}

struct Family {
    name: &'static str,
    nvars: u32,
    terms: usize,
    deg: u32,
    words: usize,
    /// Planted factor, or coprime inputs.
    planted: bool,
}

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

fn time_ours(gcd: &dyn PolyGcd, cases: &[(Poly, Poly)]) -> Option<Duration> {
    let budget = Budget {
        deadline: Some(Instant::now() + Duration::from_secs(10)),
        ..Budget::default()
    };
    let t0 = Instant::now();
    let ok = within_thread_budget(&budget, || {
        for (a, b) in cases {
            std::hint::black_box(gcd.gcd(a, b));
        }
    });
    ok.ok().map(|_| t0.elapsed())
}

fn main() {
    let reps: usize = std::env::args()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(3);
    let families = [
        Family {
            name: "2 vars, deg 3, coprime",
            nvars: 2,
            terms: 6,
            deg: 3,
            words: 0,
            planted: false,
        },
        Family {
            name: "3 vars, deg 2, planted",
            nvars: 3,
            terms: 5,
            deg: 2,
            words: 0,
            planted: true,
        },
        Family {
            name: "4 vars, deg 3, planted",
            nvars: 4,
            terms: 6,
            deg: 3,
            words: 0,
            planted: true,
        },
        Family {
            name: "2 vars, deg 8, planted",
            nvars: 2,
            terms: 8,
            deg: 8,
            words: 0,
            planted: true,
        },
        Family {
            name: "1 var, deg 20, planted",
            nvars: 1,
            terms: 10,
            deg: 20,
            words: 0,
            planted: true,
        },
        Family {
            name: "3 vars, 640-bit coeffs",
            nvars: 3,
            terms: 4,
            deg: 2,
            words: 10,
            planted: true,
        },
        Family {
            name: "2 vars, deg 6, 3200-bit",
            nvars: 2,
            terms: 6,
            deg: 6,
            words: 50,
            planted: true,
        },
        Family {
            name: "6 vars, deg 2, planted",
            nvars: 6,
            terms: 4,
            deg: 2,
            words: 0,
            planted: true,
        },
        Family {
            name: "8 vars, deg 1, planted",
            nvars: 8,
            terms: 4,
            deg: 1,
            words: 0,
            planted: true,
        },
    ];
    println!(
        "{:<26} {:>12} {:>12} {:>12} {:>12}",
        "family (10 cases)", "engine", "modular", "before", "zippel-gcd"
    );
    for fam in &families {
        let mut rng = SplitMix(0xbe7c_4000 + fam.nvars as u64 * 31 + fam.deg as u64);
        let cases: Vec<(Poly, Poly)> = (0..10)
            .map(|_| {
                let g = if fam.planted {
                    rand_poly(&mut rng, fam.nvars, fam.terms, fam.deg, fam.words)
                } else {
                    Poly::one()
                };
                let a = rand_poly(&mut rng, fam.nvars, fam.terms, fam.deg, fam.words);
                let b = rand_poly(&mut rng, fam.nvars, fam.terms, fam.deg, fam.words);
                (g.mul(&a), g.mul(&b))
            })
            .collect();
        let fmt = |d: Option<Duration>| match d {
            Some(d) => format!("{:.3} ms", d.as_secs_f64() * 1e3),
            None => "timeout".to_string(),
        };
        let run = |g: &dyn PolyGcd| {
            let v: Vec<Option<Duration>> = (0..reps).map(|_| time_ours(g, &cases)).collect();
            if v.iter().any(|d| d.is_none()) {
                None
            } else {
                Some(median(v.into_iter().flatten().collect()))
            }
        };
        let e = run(&EngineGcd);
        let m = run(&ModularGcd);
        let h = run(&HeuristicGcd);
        let ring = Ring::new((0..fam.nvars).map(|i| format!("x{i}")), Order::Lex);
        let zc: Vec<_> = cases
            .iter()
            .map(|(a, b)| {
                (
                    ring.parse(&text(a)).expect("bench text parses"),
                    ring.parse(&text(b)).expect("bench text parses"),
                )
            })
            .collect();
        let z = median(
            (0..reps)
                .map(|_| {
                    let t0 = Instant::now();
                    for (a, b) in &zc {
                        std::hint::black_box(zippel_gcd::zippel(a, b));
                    }
                    t0.elapsed()
                })
                .collect(),
        );
        println!(
            "{:<26} {:>12} {:>12} {:>12} {:>12}",
            fam.name,
            fmt(e),
            fmt(m),
            fmt(h),
            fmt(Some(z))
        );
    }
}
