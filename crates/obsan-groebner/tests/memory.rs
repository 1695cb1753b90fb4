//! The memory budget (`GbBudget::max_bytes`): refused with a located
//! error below what a computation needs, the same basis above it. (The
//! per-term count itself is checked against the stored structures in
//! `src/mem.rs`; the peak RSS it bounds is measured in docs/performance.md.)

use obsan_groebner::{f4, Field, GbBudget, GbError, Mono, Order, Poly, Ring};

const P: u64 = 0x3fff_ffff_ffff_ffc7;

/// Cyclic-n: the elementary cyclic sums of x_0..x_{n-1}, the last one minus 1.
fn cyclic(r: &Ring, n: usize) -> Vec<Poly> {
    (1..=n)
        .map(|d| {
            let mut t: Vec<(Mono, u64)> = (0..n)
                .map(|s| {
                    let mut e = vec![0u32; n];
                    for k in 0..d {
                        e[(s + k) % n] = 1;
                    }
                    (Mono::from_exponents(e).unwrap(), 1)
                })
                .collect();
            if d == n {
                t.truncate(1);
                t.push((Mono::one(n), r.field.from_i64(-1)));
            }
            r.from_terms(t)
        })
        .collect()
}

#[test]
fn the_budget_stops_f4_before_it_is_passed() {
    // Cyclic-6 (156 solutions, a basis of about 1,500 terms over 6
    // variables): no budget, then budgets from 64 KiB to 4 MiB.
    let n = 6;
    let r = Ring::new(Field::new(P).unwrap(), n, Order::Grevlex);
    let gens = cyclic(&r, n);
    let full = f4(&r, &gens, GbBudget::default()).unwrap();
    let stored: usize = full.polys.iter().map(|p| p.stored_bytes(n)).sum();
    let mut stages = Vec::new();
    let mut answered = None;
    for kib in [64usize, 128, 256, 512, 1024, 2048, 4096, 1 << 16] {
        let max = kib << 10;
        let budget = GbBudget {
            max_bytes: max,
            ..GbBudget::default()
        };
        match f4(&r, &gens, budget) {
            Err(GbError::Memory {
                bytes,
                max: m,
                what,
            }) => {
                assert!(answered.is_none(), "refused at {kib} KiB after an answer");
                assert_eq!(m, max as u128);
                assert!(bytes > m, "{bytes} {m}");
                assert!(what.starts_with("the Groebner basis ("), "{what}");
                stages.push(what);
            }
            Ok(b) => {
                assert_eq!(b.polys, full.polys, "{kib} KiB");
                answered.get_or_insert(kib);
            }
            Err(e) => panic!("{kib} KiB: {e:?}"),
        }
    }
    // The final basis alone is below any budget that lets the run finish.
    let first = answered.expect("answered under 64 MiB");
    assert!(stored <= first << 10, "{stored} {first}");
    // The small budgets stop at the matrix, the stage that holds the most.
    assert!(
        stages.iter().any(|w| w.contains("F4 matrix of")),
        "{stages:?}"
    );
}
