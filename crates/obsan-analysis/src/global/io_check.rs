//! A part's count carried to the whole relation (io_count.rs).
//!
//! Over a generating part of a relation's coefficients the count bounds the
//! whole's from above: the whole adds equations, so its solutions at
//! `theta*` are some of the part's. When every one of the part's solutions
//! lies in `F_q`, the black box (io.rs) tells which of them solve the whole
//! as well: those where the whole relation's kernel is the one at
//! `theta*`. Counted over those, the answer is the whole's, without the
//! thousands of quotients its reconstruction would need (SEAIJRC: a part of
//! 49 quotients, where the whole's 1,464 pass the sparse interpolation's
//! term cap; the part's second solution changes the whole relation, so every
//! locally identifiable parameter is global). A solution outside `F_q`, or a
//! kernel the black box cannot give, leaves the question to the whole's
//! reconstruction.
//!
//! Why this is the whole's count: a solution of the part either solves the
//! whole at a generic `theta*` or solves it only on a proper closed subset
//! of the `theta*`s, which a random point misses but with a probability
//! that vanishes with `1/q`; a kernel that differs rules a solution out.
//! The filter runs at both of the count's independent points and primes,
//! which must agree, as the count's own.

use super::io::IoModel;
use super::io_count::{udeg, udiv, ugcd, umul, urem};
use super::model::ZModel;
use super::run::Rng;
use super::types::{gb_err, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::{distinct_roots, groebner, Poly, Ring};
use obsan_recon::fp;

/// Tries of the equal-degree split per factor: each splits a factor of
/// degree 2 or more with probability at least 1/2, so 64 fail together with
/// probability at most `2^-64`; a failure only leaves the check undone.
const SPLIT_TRIES: usize = 64;

/// `a^e` modulo `f` and `p` (coefficients lowest first; `f` of degree 1 or
/// more).
fn upowmod(a: &[u64], mut e: u64, f: &[u64], p: u64) -> Vec<u64> {
    let mut base = urem(a, f, p);
    let mut acc = vec![1u64];
    while e > 0 {
        if e & 1 == 1 {
            acc = urem(&umul(&acc, &base, p), f, p);
        }
        base = urem(&umul(&base, &base, p), f, p);
        e >>= 1;
    }
    acc
}

/// The distinct roots in `F_p` of `f` (dense, lowest first, not zero):
/// `gcd(f, x^p - x)` holds one linear factor per root, split by
/// `gcd(g, (x + a)^((p-1)/2) - 1)` at random `a` (Cantor-Zassenhaus).
/// `None` only if the split fails [`SPLIT_TRIES`] times in a row.
pub(super) fn roots(f: &[u64], p: u64, rng: &mut Rng) -> Option<Vec<u64>> {
    if udeg(f) == 0 {
        return Some(Vec::new());
    }
    let mut xp = upowmod(&[0, 1], p, f, p);
    xp.resize(xp.len().max(2), 0);
    xp[1] = fp::sub(xp[1], 1, p);
    let g = ugcd(f, &xp, p);
    let mut out = Vec::new();
    let mut todo = vec![g];
    while let Some(g) = todo.pop() {
        match udeg(&g) {
            0 => {}
            1 => out.push(fp::mul(fp::sub(0, g[0], p), fp::inv(g[1], p)?, p)),
            d => {
                let mut split = None;
                for _ in 0..SPLIT_TRIES {
                    let a = rng.next() % p;
                    let mut h = upowmod(&[a, 1], (p - 1) / 2, &g, p);
                    h[0] = fp::sub(h[0], 1, p);
                    let c = ugcd(&g, &h, p);
                    if (1..d).contains(&udeg(&c)) {
                        split = Some(c);
                        break;
                    }
                }
                let c = split?;
                todo.push(udiv(&g, &c, p));
                todo.push(c);
            }
        }
    }
    out.sort_unstable();
    Some(out)
}

/// The zeros of the zero-dimensional system `gens` (variables `0..n`; the
/// first `np` reported), when all of them lie in `F_q`: the roots of the
/// minimal polynomial `mp` of the separating linear form `lf`, each one's
/// point read off the system with `lf = r` added. `None` when some zero
/// lies outside `F_q` (or a root could not be split off).
pub(super) fn zeros(
    ring: &Ring,
    gens: &[Poly],
    (lf, mp): (&Poly, &[u64]),
    np: usize,
    opts: &GlobalOptions,
    rng: &mut Rng,
) -> Result<Option<Vec<Vec<u64>>>, AnalysisError> {
    let q = ring.field.modulus();
    let Some(rs) = roots(mp, q, rng) else {
        return Ok(None);
    };
    if rs.len() != distinct_roots(ring.field, mp) {
        return Ok(None);
    }
    let mut out = Vec::with_capacity(rs.len());
    for r in rs {
        let mut g = gens.to_vec();
        g.push(ring.sub(lf, &ring.constant(r)));
        let b = groebner(ring, &g, opts.gb_budget()).map_err(gb_err)?;
        if b.is_unit() || !b.is_zero_dimensional() {
            return Ok(None);
        }
        let mut pt = Vec::with_capacity(np);
        for t in 0..np {
            let m = b
                .minimal_polynomial(&ring.var(t), opts.max_solutions)
                .map_err(gb_err)?;
            // `lf` separates the zeros: one value per coordinate.
            match roots(&m, q, rng).as_deref() {
                Some([c]) => pt.push(*c),
                _ => return Ok(None),
            }
        }
        out.push(pt);
    }
    Ok(Some(out))
}

/// Per point of `zeros`, whether relation `i`'s kernel modulo `q` there is
/// the one at `star` (the count's random point), each computed by the same
/// black box the reconstruction samples; `None` when the black box gives
/// no kernel at one of them.
pub(super) fn same_kernel(
    m: &ZModel,
    (orders, i, support): (&[usize], usize, &[Vec<u32>]),
    opts: &GlobalOptions,
    seed: u64,
    q: u64,
    star: &[u64],
    zeros: &[Vec<u64>],
) -> Result<Option<Vec<bool>>, AnalysisError> {
    let mut io = IoModel::new(m, q)?;
    io.deadline = opts.deadline;
    io.max_bytes = opts.max_bytes;
    io.max_work = opts.max_io_work;
    let mut rng = Rng::new(seed ^ q ^ 0xc4ec);
    let Some(at_star) = io.on_support(star, orders, i, support, &mut rng)? else {
        return Ok(None);
    };
    let mut same = Vec::with_capacity(zeros.len());
    for z in zeros {
        if z.as_slice() == star {
            same.push(true);
            continue;
        }
        match io.on_support(z, orders, i, support, &mut rng)? {
            Some(v) => same.push(v == at_star),
            None => return Ok(None),
        }
    }
    Ok(Some(same))
}

/// The counts over the points kept (`None` for a parameter that is not
/// locally identifiable, as `local` says): per parameter its distinct
/// values, jointly the points.
pub(super) fn counts_over(kept: &[&Vec<u64>], local: &[bool]) -> (Vec<Option<usize>>, usize) {
    let per = local
        .iter()
        .enumerate()
        .map(|(t, &loc)| {
            loc.then(|| {
                let mut v: Vec<u64> = kept.iter().map(|z| z[t]).collect();
                v.sort_unstable();
                v.dedup();
                v.len()
            })
        })
        .collect();
    (per, kept.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Roots by construction: `(x - 3)(x - 7)^2 (x^2 - n)` with `n` a
    /// non-square modulo `p` (Euler's criterion), so `x^2 - n` has no root:
    /// the roots are 3 and 7, once each.
    #[test]
    fn roots_of_a_planted_product() {
        let p = super::super::io_count::P0;
        let n = (2..)
            .find(|&n| fp::pow(n, (p - 1) / 2, p) == p - 1)
            .unwrap();
        let irreducible = vec![fp::sub(0, n, p), 0, 1];
        let lin = |r: u64| vec![fp::sub(0, r, p), 1];
        let f = umul(
            &umul(&lin(3), &umul(&lin(7), &lin(7), p), p),
            &irreducible,
            p,
        );
        let mut rng = Rng::new(5);
        assert_eq!(roots(&f, p, &mut rng), Some(vec![3, 7]));
        // Without rational roots: none.
        assert_eq!(roots(&irreducible, p, &mut rng), Some(vec![]));
        // Many roots, split repeatedly.
        let rs: Vec<u64> = (10..30).map(|r| r * 1_000_003).collect();
        let f = rs.iter().fold(vec![1u64], |a, &r| umul(&a, &lin(r), p));
        assert_eq!(roots(&f, p, &mut rng), Some(rs));
    }
}
