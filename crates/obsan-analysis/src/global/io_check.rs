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

use super::io::elem;
use super::io::IoModel;
use super::io_count::system_at;
use super::io_count::{udeg, udiv, ugcd, umul, urem};
use super::model::ZModel;
use super::run::Rng;
use super::types::{gb_err, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::{distinct_roots, groebner, Field, GbError, Mono, Order, Poly, Ring};
use obsan_recon::fp;
use obsan_recon::{reconstruct_vec, Options, Poly as RPoly, PrimeList, Rational, ReconError, Term};

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

/// The zeros of a zero-dimensional system that lie in `F_q`, and whether
/// they are all of them.
pub(super) struct Zeros {
    pub(super) points: Vec<Vec<u64>>,
    pub(super) complete: bool,
}

/// The zeros in `F_q` of the zero-dimensional system `gens` (variables
/// `0..n`; the first `np` reported): the roots in `F_q` of the minimal
/// polynomial `mp` of the separating linear form `lf`, each one's point read
/// off the system with `lf = r` added. A root in `F_q` gives a zero in
/// `F_q`: its Frobenius conjugate has the same value of `lf`, which
/// separates the zeros. `complete` when every zero is among them.
pub(super) fn zeros(
    ring: &Ring,
    gens: &[Poly],
    (lf, mp): (&Poly, &[u64]),
    np: usize,
    opts: &GlobalOptions,
    rng: &mut Rng,
) -> Result<Zeros, AnalysisError> {
    let q = ring.field.modulus();
    let Some(rs) = roots(mp, q, rng) else {
        return Ok(Zeros {
            points: Vec::new(),
            complete: false,
        });
    };
    let mut complete = rs.len() == distinct_roots(ring.field, mp);
    let mut points = Vec::with_capacity(rs.len());
    'roots: for r in rs {
        let mut g = gens.to_vec();
        g.push(ring.sub(lf, &ring.constant(r)));
        let b = match soft(groebner(ring, &g, opts.gb_budget()))? {
            Some(b) if !b.is_unit() && b.is_zero_dimensional() => b,
            _ => {
                complete = false;
                continue;
            }
        };
        let mut pt = Vec::with_capacity(np);
        for t in 0..np {
            let m = soft(b.minimal_polynomial(&ring.var(t), opts.max_solutions))?;
            // `lf` separates the zeros: one value per coordinate.
            match m.and_then(|m| roots(&m, q, rng)).as_deref() {
                Some([c]) => pt.push(*c),
                _ => {
                    complete = false;
                    continue 'roots;
                }
            }
        }
        points.push(pt);
    }
    Ok(Zeros { points, complete })
}

/// A Gröbner step of [`zeros`], which only adds to an answer already
/// found: past a budget it is left out (`None`: the zeros incomplete), the
/// deadline alone stops the command.
fn soft<T>(r: Result<T, GbError>) -> Result<Option<T>, AnalysisError> {
    match r {
        Ok(v) => Ok(Some(v)),
        Err(GbError::Budget("deadline")) => Err(gb_err(GbError::Budget("deadline"))),
        Err(_) => Ok(None),
    }
}

/// A map of the parameters: entry `v` is `(w, s)`, `theta_v -> s theta_w`.
pub(super) type ParamMap = Vec<(usize, i8)>;

/// The signed permutations of the parameters that send `star` to one of
/// `zeros` (each coordinate of the zero equal to plus or minus one of
/// `star`'s, which random coordinates make unambiguous) and keep every
/// coefficient `n / d` of `fns` exactly: `n(phi) d = n d(phi)` over Z. A
/// zero that is no signed permutation of `star` (an affine or rational
/// map) gives none.
pub(super) fn param_maps(
    fns: &[(RPoly, RPoly)],
    zeros: &[Vec<u64>],
    star: &[u64],
    q: u64,
) -> Vec<ParamMap> {
    let mut out: Vec<ParamMap> = Vec::new();
    for z in zeros.iter().filter(|z| z.as_slice() != star) {
        let map: Option<ParamMap> = z
            .iter()
            .map(|&c| {
                (0..star.len()).find_map(|w| {
                    if c == star[w] {
                        Some((w, 1))
                    } else if c == fp::sub(0, star[w], q) {
                        Some((w, -1))
                    } else {
                        None
                    }
                })
            })
            .collect();
        let Some(map) = map else { continue };
        let mut seen = vec![false; map.len()];
        let bijective = map
            .iter()
            .all(|&(w, _)| !std::mem::replace(&mut seen[w], true));
        if bijective && !out.contains(&map) && keeps(fns, &map) {
            out.push(map);
        }
    }
    out
}

/// Most black-box points (each a count's system solved at one point) the
/// reconstruction of a rational map may take.
const MAP_POINTS: u64 = 2000;

/// Most terms of the coefficients (numerators and denominators) whose count
/// system a rational map is sought on (SI.jl's models: 31-126): each of up
/// to [`MAP_POINTS`] points solves that system once (a bound on sizes, not
/// time, so the same model always takes the same path).
pub(super) const MAP_FN_TERMS: usize = 500;

/// Most terms [`compose`] may build while checking a rational map exactly.
const MAP_TERMS: usize = 200_000;

/// A joint count of 2 with no signed permutation between the two solutions:
/// the other solution as rational functions of the parameters, read at
/// points `theta` (the count's system at `theta`, its two solutions over
/// `F_p`, the one that is not `theta`) and reconstructed over Q
/// (obsan-recon), then checked exactly on every coefficient ([`keeps_map`]).
/// Why one map: with two solutions, the other is fixed by every field
/// automorphism that fixes `theta`, so it is rational in `theta` (when it
/// lies in `F_p` at random points, as the black box needs). `None` when the
/// points are not found, the reconstruction passes its budget or the check
/// its size.
pub(super) fn rational_map(
    fns: &[(RPoly, RPoly)],
    np: usize,
    opts: &GlobalOptions,
    seed: u64,
) -> Result<Option<Vec<Rational>>, AnalysisError> {
    let mut rng = Rng::new(seed ^ 0x3a9);
    let mut other = |theta: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
        let Some(field) = Field::new(p) else {
            return Ok(None);
        };
        let ring = Ring::new(field, np + 1, Order::Grevlex);
        let Some((gens, local)) = system_at(fns, &ring, theta, opts)? else {
            return Ok(None);
        };
        let b = match soft(groebner(&ring, &gens, opts.gb_budget()))? {
            Some(b) if !b.is_unit() && b.is_zero_dimensional() => b,
            _ => return Ok(None),
        };
        let lf = ring.from_terms(
            (0..np)
                .filter(|&t| local[t])
                .map(|t| (Mono::var(np + 1, t, 1), elem(&mut rng, p))),
        );
        let Some(mp) = soft(b.minimal_polynomial(&lf, opts.max_solutions))? else {
            return Ok(None);
        };
        if distinct_roots(field, &mp) != 2 {
            return Ok(None);
        }
        let z = zeros(&ring, &gens, (&lf, &mp), np, opts, &mut rng)?;
        if !z.complete || z.points.len() != 2 {
            return Ok(None);
        }
        Ok(z.points.into_iter().find(|pt| pt.as_slice() != theta))
    };
    let ropts = Options {
        deadline: opts.deadline,
        seed: seed ^ 0x3a9,
        prime_list: PrimeList::Bits52,
        max_points: MAP_POINTS,
        ..Options::default()
    };
    let map = match reconstruct_vec(np, np, &mut other, &ropts) {
        Ok(r) => r.functions,
        Err(ReconError::BlackBox(e)) => return Err(e),
        Err(_) => return Ok(None),
    };
    Ok(keeps_map(fns, &map).then_some(map))
}

/// Whether coordinate `v` of a rational map is `theta_v` itself.
pub(super) fn is_identity(r: &Rational, v: usize) -> bool {
    let unit = |p: &RPoly, var: Option<usize>| {
        matches!(p.terms(), [t] if t.coeff == 1.into()
            && t.exps.iter().enumerate().all(|(w, &e)| e == u32::from(Some(w) == var)))
    };
    unit(r.num(), Some(v)) && unit(r.den(), None)
}

/// `p(phi)` as `N / D` for a rational map `phi` (coordinate `w` is `n_w /
/// d_w`): `D = prod_w d_w^E_w`, `E_w` the degree of `p` in `w`, and each
/// term `c prod_w n_w^e_w d_w^(E_w - e_w)`; `None` past [`MAP_TERMS`].
fn compose(p: &RPoly, map: &[Rational]) -> Option<(RPoly, RPoly)> {
    let deg: Vec<u32> = (0..map.len())
        .map(|w| {
            p.terms()
                .iter()
                .map(|t| t.exps.get(w).copied().unwrap_or(0))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let one = RPoly::from_terms([Term {
        exps: vec![0; map.len()],
        coeff: 1.into(),
    }]);
    // Powers 0..=E_w of each n_w and d_w.
    let powers = |f: &RPoly, e: u32| -> Option<Vec<RPoly>> {
        let mut v = vec![one.clone()];
        for _ in 0..e {
            let next = v.last()?.times(f);
            if next.terms().len() > MAP_TERMS {
                return None;
            }
            v.push(next);
        }
        Some(v)
    };
    let mut nums = Vec::with_capacity(map.len());
    let mut dens = Vec::with_capacity(map.len());
    for (r, &e) in map.iter().zip(&deg) {
        nums.push(powers(r.num(), e)?);
        dens.push(powers(r.den(), e)?);
    }
    let mut terms = Vec::new();
    for t in p.terms() {
        let mut prod = RPoly::from_terms([Term {
            exps: vec![0; map.len()],
            coeff: t.coeff.clone(),
        }]);
        for w in 0..map.len() {
            let e = t.exps.get(w).copied().unwrap_or(0);
            for f in [&nums[w][e as usize], &dens[w][(deg[w] - e) as usize]] {
                prod = prod.times(f);
                if prod.terms().len() > MAP_TERMS {
                    return None;
                }
            }
        }
        terms.extend(prod.terms().iter().cloned());
        if terms.len() > MAP_TERMS {
            return None;
        }
    }
    let den = dens
        .iter()
        .zip(&deg)
        .try_fold(one.clone(), |acc, (d, &e)| {
            let next = acc.times(&d[e as usize]);
            (next.terms().len() <= MAP_TERMS).then_some(next)
        })?;
    Some((RPoly::from_terms(terms), den))
}

/// Whether every fraction `n / d` of `fns` is the same after the rational
/// map `phi`: `n(phi) / d(phi) = N_n D_d / (D_n N_d)` equals `n / d`, i.e.
/// `N_n D_d d = n D_n N_d` as polynomials over Z; false past the size
/// bound (never a map unchecked).
fn keeps_map(fns: &[(RPoly, RPoly)], map: &[Rational]) -> bool {
    fns.iter().all(|(n, d)| {
        let (Some((nn, dn)), Some((nd, dd))) = (compose(n, map), compose(d, map)) else {
            return false;
        };
        nn.times(&dd).times(d) == n.times(&dn).times(&nd)
    })
}

/// `p(phi(theta))` for a signed permutation `phi` of the parameters.
fn substitute(p: &RPoly, map: &[(usize, i8)]) -> RPoly {
    RPoly::from_terms(p.terms().iter().map(|t| {
        let mut exps = vec![0u32; map.len()];
        let mut odd = false;
        for (&e, &(w, s)) in t.exps.iter().zip(map) {
            exps[w] = e;
            odd ^= s < 0 && e % 2 == 1;
        }
        Term {
            exps,
            coeff: if odd {
                -t.coeff.clone()
            } else {
                t.coeff.clone()
            },
        }
    }))
}

/// Whether every fraction `n / d` of `fns` is the same after `phi`: the
/// identity `n(phi) d = n d(phi)` of polynomials over Z, exact.
fn keeps(fns: &[(RPoly, RPoly)], map: &[(usize, i8)]) -> bool {
    fns.iter()
        .all(|(n, d)| substitute(n, map).times(d) == n.times(&substitute(d, map)))
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

    /// `x + y = 11, x y = 30` over `F_q` (by hand: `(5, 6)` and `(6, 5)`),
    /// the form `x + 2 y` separating them (17 and 16): both zeros read off;
    /// with no room for one more basis element, none and incomplete, never
    /// an error (the count they would add to is already found).
    #[test]
    fn zeros_read_off_or_left_out_past_a_budget() {
        use obsan_groebner::{Field, Mono, Order};
        let q = super::super::io_count::P0;
        let ring = Ring::new(Field::new(q).unwrap(), 2, Order::Grevlex);
        let (x, y) = (ring.var(0), ring.var(1));
        let gens = vec![
            ring.sub(&ring.add(&x, &y), &ring.constant(11)),
            ring.sub(&ring.mul(&x, &y).unwrap(), &ring.constant(30)),
        ];
        let lf = ring.from_terms([(Mono::var(2, 0, 1), 1), (Mono::var(2, 1, 1), 2)]);
        let opts = GlobalOptions::default();
        let b = groebner(&ring, &gens, opts.gb_budget()).unwrap();
        let mp = b.minimal_polynomial(&lf, 100).unwrap();
        let mut rng = Rng::new(1);
        let z = zeros(&ring, &gens, (&lf, &mp), 2, &opts, &mut rng).unwrap();
        assert!(z.complete);
        let mut pts = z.points;
        pts.sort();
        assert_eq!(pts, vec![vec![5, 6], vec![6, 5]]);
        let tight = GlobalOptions {
            max_basis: 0,
            ..GlobalOptions::default()
        };
        let z = zeros(&ring, &gens, (&lf, &mp), 2, &tight, &mut rng).unwrap();
        assert!(!z.complete);
        assert!(z.points.is_empty());
    }

    fn poly(terms: &[([u32; 2], i64)]) -> RPoly {
        RPoly::from_terms(terms.iter().map(|(e, c)| Term {
            exps: e.to_vec(),
            coeff: (*c).into(),
        }))
    }

    /// Two summed decays' coefficients `a + b`, `a b` (by hand): the swap
    /// keeps both, `a -> -a` and `(a, b) -> (-b, -a)` do not (`a b` and
    /// `a + b` change sign); a zero `(b*, a*)` gives the swap, a zero that
    /// is no signed permutation of `star` none.
    #[test]
    fn maps_kept_by_the_coefficients() {
        let one = poly(&[([0, 0], 1)]);
        let fns = vec![
            (poly(&[([1, 0], 1), ([0, 1], 1)]), one.clone()),
            (poly(&[([1, 1], 1)]), one),
        ];
        assert!(keeps(&fns, &[(1, 1), (0, 1)]));
        assert!(!keeps(&fns, &[(0, -1), (1, 1)]));
        assert!(!keeps(&fns, &[(1, -1), (0, -1)]));
        let q = super::super::io_count::P0;
        let star = vec![5, 11];
        let maps = param_maps(&fns, &[star.clone(), vec![11, 5]], &star, q);
        assert_eq!(maps, vec![vec![(1, 1), (0, 1)]]);
        assert!(param_maps(&fns, &[vec![6, 10]], &star, q).is_empty());
        // A signed permutation that is a zero but keeps no coefficient is
        // not reported (the exact check, not the zero, decides).
        assert!(param_maps(&fns, &[vec![q - 5, 11]], &star, q).is_empty());
    }

    /// Rates `a` and `a + b` (systems/global/shifted_rates.sys, by hand):
    /// the coefficients `2 a + b` and `a (a + b)` keep `(a, b) -> (a + b,
    /// -b)`, reconstructed from the count's other solution and checked
    /// exactly; the same map does not keep two decays' `a + b`.
    #[test]
    fn a_rational_map_reconstructed_and_checked() {
        let one = poly(&[([0, 0], 1)]);
        let fns = vec![
            (poly(&[([1, 0], 2), ([0, 1], 1)]), one.clone()),
            (poly(&[([2, 0], 1), ([1, 1], 1)]), one.clone()),
        ];
        let map = rational_map(&fns, 2, &GlobalOptions::default(), 7)
            .unwrap()
            .expect("the other solution is rational");
        let names = ["a", "b"];
        let shown: Vec<String> = map.iter().map(|r| r.display(&names).to_string()).collect();
        assert_eq!(shown, ["a + b", "-b"]);
        assert!(!is_identity(&map[0], 0) && !is_identity(&map[1], 1));
        assert!(keeps_map(&fns, &map));
        let decays = vec![
            (poly(&[([1, 0], 1), ([0, 1], 1)]), one.clone()),
            (poly(&[([1, 1], 1)]), one),
        ];
        assert!(!keeps_map(&decays, &map));
    }
}
