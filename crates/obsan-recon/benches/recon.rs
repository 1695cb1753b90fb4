//! Reconstruction figures: black-box points, primes and time for random
//! sparse rational functions in 3, 6 and 10 variables, and for a vector of
//! five functions sharing calls. Run: `cargo bench -p obsan-recon --bench recon`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use common::{eval, same_function, Terms};
use dashu_int::IBig;
use obsan_recon::{reconstruct_vec, Options};

struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        obsan_recon::splitmix64(&mut self.0)
    }
}

/// `terms` random terms of total degree <= deg (one of exactly deg), with
/// coefficients of up to `bits` bits.
fn random_poly(rng: &mut SplitMix, n: usize, terms: usize, deg: u32, bits: u32) -> Terms {
    let mut out = Vec::new();
    for k in 0..terms {
        let target = if k == 0 {
            deg
        } else {
            (rng.next() % (deg as u64 + 1)) as u32
        };
        let mut e = vec![0u32; n];
        for _ in 0..target {
            e[(rng.next() % n as u64) as usize] += 1;
        }
        let mag = (rng.next() >> (64 - bits.min(63))) + 1;
        let c = if rng.next() & 1 == 0 {
            IBig::from(mag)
        } else {
            -IBig::from(mag)
        };
        out.push((e, c));
    }
    out
}

fn run(name: &str, n: usize, fs: &[(Terms, Terms)], reps: usize) {
    let mut times = Vec::new();
    let mut last = None;
    for rep in 0..reps {
        let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, ()> {
            Ok(fs.iter().map(|(a, b)| eval(a, b, x, p)).collect())
        };
        let opts = Options {
            seed: rep as u64 + 1,
            ..Options::default()
        };
        let t0 = Instant::now();
        let r = reconstruct_vec(n, fs.len(), &mut bb, &opts);
        times.push(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    times.sort_by(|a, b| a.total_cmp(b));
    let Some(Ok(r)) = last else {
        println!("{name:<24} FAILED: {last:?}");
        return;
    };
    for (f, (a, b)) in r.functions.iter().zip(fs) {
        assert!(same_function(f, a, b), "{name}: wrong result");
    }
    let terms: usize = r
        .functions
        .iter()
        .map(|f| f.num().terms().len() + f.den().terms().len())
        .sum();
    let degs: Vec<String> = r
        .stats
        .degrees
        .iter()
        .map(|(a, b)| format!("{a}/{b}"))
        .collect();
    println!(
        "{name:<24} n={n:<2} m={:<2} deg {:<16} terms {terms:<4} points {:<8} primes {:<2} median {:>9.2} ms  (min {:.2}, {} runs)  bound {:.1e}",
        fs.len(),
        degs.join(","),
        r.stats.points,
        r.stats.primes,
        times[times.len() / 2] * 1e3,
        times[0] * 1e3,
        reps,
        r.certificate.error_bound,
    );
}

/// The input-output route's kernels: `n - 1` random rows of `n` columns
/// (rank `n - 1`, one null vector), inserted one by one and by blocks on
/// one and two threads; the same null space every way. Modulo a 62-bit
/// prime (the `u128` pass) and a 52-bit one (AVX-512 IFMA where the CPU
/// has it, else the `u128` pass too).
fn kernels(rng: &mut SplitMix) {
    use obsan_recon::fp::{RowEchelon, Zp};
    println!("AVX-512 IFMA on this CPU: {}", obsan_recon::fp::ifma());
    for (p, n) in [62u32, 52].into_iter().flat_map(|bits| {
        let p = if bits == 62 {
            obsan_recon::PRIMES[0]
        } else {
            obsan_recon::PRIMES52[0]
        };
        [200usize, 771, 1465].map(|n| (p, n))
    }) {
        let rows: Vec<Vec<u64>> = (0..n - 1)
            .map(|_| (0..n).map(|_| rng.next() % p).collect())
            .collect();
        let mut null = None;
        let mut line = format!("dense kernel {n:>4} cols, {}-bit p", 64 - p.leading_zeros());
        for way in ["one by one", "blocks, 1 thread", "blocks, 2 threads"] {
            let mut times = Vec::new();
            for _ in 0..3 {
                let t0 = Instant::now();
                let mut e = RowEchelon::new(Zp(p));
                match way {
                    "one by one" => rows.iter().for_each(|r| {
                        e.insert(r.clone());
                    }),
                    "blocks, 1 thread" => {
                        e.insert_all(rows.clone(), 1);
                    }
                    _ => {
                        e.insert_all(rows.clone(), 2);
                    }
                }
                let ns = e.null_space(n);
                times.push(t0.elapsed().as_secs_f64());
                assert_eq!(*null.get_or_insert_with(|| ns.clone()), ns, "{way}");
            }
            times.sort_by(|a, b| a.total_cmp(b));
            line += &format!(" | {way} {:>8.2} ms", times[1] * 1e3);
        }
        println!("{line}");
    }
}

fn main() {
    let mut rng = SplitMix(2026);
    kernels(&mut rng);
    let f3 = (
        random_poly(&mut rng, 3, 8, 6, 20),
        random_poly(&mut rng, 3, 6, 5, 20),
    );
    let f6 = (
        random_poly(&mut rng, 6, 10, 8, 30),
        random_poly(&mut rng, 6, 6, 6, 30),
    );
    let f10 = (
        random_poly(&mut rng, 10, 12, 10, 40),
        random_poly(&mut rng, 10, 8, 8, 40),
    );
    let f10big = (
        random_poly(&mut rng, 10, 12, 10, 62),
        random_poly(&mut rng, 10, 8, 8, 62),
    );
    run("3 vars", 3, &[f3], 9);
    run("6 vars", 6, &[f6], 5);
    run("10 vars", 10, &[f10], 3);
    run("10 vars, 62-bit coeffs", 10, &[f10big], 3);
    // A null-vector-like vector: five components over one denominator.
    let den = random_poly(&mut rng, 6, 5, 4, 16);
    let vec6: Vec<(Terms, Terms)> = (0..5)
        .map(|_| (random_poly(&mut rng, 6, 6, 5, 16), den.clone()))
        .collect();
    run("6 vars, vector of 5", 6, &vec6, 5);
}
