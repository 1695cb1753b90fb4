//! Symmetries by reconstruction (docs/reconstruction.md).
//!
//! Black box: at a point of F_p (p = 2^61 - 1, the engine's prime) the
//! gradients of the basis Lie derivatives come from Taylor jets (nothing is
//! expanded), and the null vector of free column j is normalised by
//! `v[j] = 1`, `v[other free] = 0`, the pivot entries solved from the pivot
//! minor. Each entry is then a well-defined rational function of the point's
//! coordinates (Cramer's rule), which `obsan_recon` reconstructs. A point
//! where the pivot minor vanishes (or a denominator of the system) is bad.
//! Trig systems are read in the tangent half-angle view: an angle pair is one
//! coordinate t with sin = 2t/(1+t^2), cos = (1-t^2)/(1+t^2), and the result
//! is mapped back to sin/cos.
//!
//! The reconstruction uses one prime, so its output is only a candidate;
//! [`certify_symmetries`] proves it with high probability, independently of
//! how it was found, on the expression graph modulo fresh random primes (so
//! that the reconstruction's prime cannot hide an error in a coefficient).

use crate::rank::{lie_jets, AnalysisError, LieWord, RankReport};
use obsan_expr::{
    evaluate::degree_bounds, lie::height_bounds, lie::Coord, Fp, FpEchelon, FpField, Id, Mono,
    Poly, RatFun, SplitMix, P,
};
use obsan_model::NormalForm;
use obsan_recon::{reconstruct_vec, Options, ReconError};
use std::collections::HashSet;
use std::time::Instant;

/// How a symmetry basis was certified at random points.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomCheck {
    /// Independent random points at which every identity held.
    pub points: u32,
    /// Identities per point: vectors times gradient rows.
    pub identities: usize,
    /// Largest numerator degree bound of an identity (Schwartz–Zippel).
    pub degree: u64,
    /// Fresh random 62-bit primes; `points` is spread evenly over them.
    pub primes: u32,
    /// Bound on log2 of the content of an identity's integer numerator
    /// (a prime dividing it sees the identity as zero everywhere).
    pub content_bits: u64,
    /// Probability that a wrong basis passes every check.
    pub error_bound: f64,
}

/// Why the reconstruction route did not give a basis.
#[derive(Debug)]
pub(crate) enum ReconFail {
    /// Not applicable (a square root): the exact route decides.
    Unsupported,
    /// A real error (deadline, budget), for the user.
    Error(AnalysisError),
}

/// Solve `M_piv X = -M_free` mod P for the rows of `m` (r x n); per free
/// column, the pivot entries of its null vector; `None` if the pivot minor
/// is singular.
fn solve_free(m: &[Vec<Fp>], piv: &[usize], free: &[usize]) -> Option<Vec<Vec<Fp>>> {
    let r = piv.len();
    if m.len() != r {
        return None;
    }
    let a = m.iter().map(|row| {
        piv.iter()
            .map(|&c| row[c])
            .chain(free.iter().map(|&c| -row[c]))
            .collect()
    });
    let x = FpEchelon::of_rows(FpField, a).solve(r)?;
    // Row i of X holds pivot entry i of every free column's vector.
    Some(
        (0..free.len())
            .map(|j| x.iter().map(|xi| xi[j]).collect())
            .collect(),
    )
}

/// The roots whose leaves a point must give values to: outputs and fields.
fn system_roots(nf: &NormalForm, report: &RankReport) -> Vec<Id> {
    let mut roots: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    for f in &report.fields.vectors {
        roots.extend(f.iter().copied());
    }
    roots
}

/// The basis of symmetries for the free columns `free`, by reconstruction;
/// vectors in sin/cos form, not yet normalised for printing or certified.
pub(crate) fn reconstruct_basis(
    nf: &mut NormalForm,
    report: &RankReport,
    free: &[usize],
    deadline: Option<Instant>,
) -> Result<Vec<Vec<RatFun>>, ReconFail> {
    let n = report.n;
    let r = report.rank;
    let piv: Vec<usize> = (0..n).filter(|j| !free.contains(j)).collect();
    let roots = system_roots(nf, report);
    let coords = nf
        .ctx
        .free_coords(&roots, &[])
        .ok_or(ReconFail::Unsupported)?;
    let jets = lie_jets(nf, &report.fields);
    let ctx = &nf.ctx;
    let basis = &report.basis;
    let k = free.len();
    // One jet per maximal basis word gives the rows of all its prefixes.
    let is_prefix = |a: &LieWord, b: &LieWord| {
        a.output == b.output && a.fields.len() <= b.fields.len() && b.fields.starts_with(&a.fields)
    };
    let mut tops: Vec<LieWord> = Vec::new();
    for w in basis {
        if !basis
            .iter()
            .any(|b| b.fields.len() > w.fields.len() && is_prefix(w, b))
            && !tops.contains(w)
        {
            tops.push(w.clone());
        }
    }
    let place: Vec<(usize, usize)> = basis
        .iter()
        .map(|w| {
            let t = tops.iter().position(|t| is_prefix(w, t)).unwrap_or(0);
            (t, w.fields.len())
        })
        .collect();
    const CANCELLED: &str = "interrupted";
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, String> {
        if p != P {
            return Err(format!("internal: the black box works modulo {P} only"));
        }
        // The caller's interrupt (Ctrl-C from Python): the error ends the run
        // and is mapped to `Cancelled` below.
        if obsan_expr::cancel_requested() {
            return Err(CANCELLED.to_string());
        }
        let vals: Vec<Fp> = x.iter().map(|&v| Fp::new(v)).collect();
        let Ok(pt) = ctx.fp_point_at(&coords, &vals) else {
            return Ok(None);
        };
        let mut rows = Vec::with_capacity(tops.len());
        for t in &tops {
            match jets.prefix_rows(t.output, &t.fields, &pt) {
                Ok(rs) => rows.push(rs),
                Err(_) => return Ok(None),
            }
        }
        let m: Vec<Vec<Fp>> = place
            .iter()
            .map(|&(t, len)| rows[t][len].gradient.clone())
            .collect();
        Ok(solve_free(&m, &piv, free).map(|xs| xs.into_iter().flatten().map(|f| f.0).collect()))
    };
    // One agreeing value ends an interpolation early (the library's default
    // is 2): a premature stop has probability about deg/p, and would give a
    // wrong candidate, which the certificate below rejects; every black-box
    // point is a jet, so the saved points are most of the run.
    let opts = Options {
        primes: Some(vec![P]),
        agree: 1,
        deadline,
        seed: report.seed ^ 0x5ec0_4ec0,
        ..Options::default()
    };
    let rec = match reconstruct_vec(coords.len(), k * r, &mut bb, &opts) {
        Ok(x) => x,
        Err(_) if obsan_expr::cancel_requested() => {
            return Err(ReconFail::Error(AnalysisError::Cancelled))
        }
        Err(e @ ReconError::Budget { .. }) => {
            return Err(ReconFail::Error(AnalysisError::Timeout(format!(
                "reconstructing the symmetries: {e}"
            ))))
        }
        Err(e) => {
            return Err(ReconFail::Error(AnalysisError::Invalid(format!(
                "reconstructing the symmetries: {e}"
            ))))
        }
    };
    let th = nf.ctx.tan_half();
    let angles = coords.iter().any(|c| matches!(c, Coord::Angle { .. }));
    let to_poly = |p: &obsan_recon::Poly| {
        Poly::from_terms(p.terms().iter().map(|t| {
            let mono = Mono::from_pairs(
                t.exps
                    .iter()
                    .zip(&coords)
                    .filter(|(&e, _)| e > 0)
                    .map(|(&e, c)| (c.var(), e)),
            );
            (mono, t.coeff.clone())
        }))
    };
    let mut vectors = Vec::with_capacity(k);
    for (j, &fc) in free.iter().enumerate() {
        let mut v = vec![RatFun::zero(); n];
        v[fc] = RatFun::one();
        for (i, &pc) in piv.iter().enumerate() {
            let f = &rec.functions[j * r + i];
            let num = RatFun::from_poly(to_poly(f.num()));
            let den = RatFun::from_poly(to_poly(f.den()));
            let Some(inv) = nf.ctx.rf_inv(&den) else {
                return Err(ReconFail::Error(AnalysisError::Invalid(
                    "internal: a reconstructed denominator is zero".into(),
                )));
            };
            let e = nf.ctx.rf_mul(&num, &inv);
            v[pc] = if angles {
                nf.ctx.from_tan_half(&th, &e)
            } else {
                e
            };
        }
        vectors.push(v);
    }
    Ok(vectors)
}

/// The words whose gradients a symmetry basis must annihilate for the
/// closure argument of the exact route (`symmetry.rs`): every output (level 0, so that
/// outputs the rank test set aside are covered too), every basis word and
/// every one-step extension of one (structurally zero ones left out).
fn closure_words(nf: &NormalForm, report: &RankReport) -> Vec<LieWord> {
    let jets = lie_jets(nf, &report.fields);
    let mut seen: HashSet<(usize, Vec<usize>)> = HashSet::new();
    let mut out = Vec::new();
    let mut push = |w: LieWord| {
        if jets.support(w.output, &w.fields).is_some() && seen.insert((w.output, w.fields.clone()))
        {
            out.push(w);
        }
    };
    for i in 0..nf.outputs.len() {
        push(LieWord {
            output: i,
            fields: vec![],
        });
    }
    for w in &report.basis {
        push(w.clone());
        for f in 0..report.fields.vectors.len() {
            let mut w2 = w.clone();
            w2.fields.push(f);
            push(w2);
        }
    }
    out
}

/// Fresh primes and points per prime of the certificate. Three primes: the
/// chance that a random prime divides the content of a false identity is
/// about `bits / 2^61` (see [`certify_symmetries`]), so it enters the bound
/// to the power of the number of primes.
pub const CHECK_PRIMES: u32 = 3;
pub const CHECK_POINTS: u32 = 2;

/// A lower bound on the number of primes in `(2^61, 2^62)`: by Rosser and
/// Schoenfeld (1962), `x / ln x < pi(x) < 1.25506 x / ln x` for x >= 17, so
/// `pi(2^62) - pi(2^61) > (2^61 / ln 2) (2/62 - 1.25506/61) > 2^61 / 60`.
const PRIMES_IN_RANGE: f64 = (1u64 << 61) as f64 / 60.0;

/// The probability that a wrong basis passes every check (the module docs
/// of [`certify_symmetries`]): `K (rho + beta^points)^primes`, with
/// `beta = D / (2^61 - B)` the Schwartz–Zippel bound of one point and
/// `rho = floor(bits / 61) / PRIMES_IN_RANGE` the chance that a uniformly
/// random prime of `(2^61, 2^62)` divides a content of at most `2^bits`.
fn error_bound(identities: usize, degree: u64, poles: u64, bits: f64) -> f64 {
    let q_min = (1u64 << 61) as f64;
    let beta = (degree as f64 / (q_min - poles as f64).max(1.0)).min(1.0);
    let rho = ((bits / 61.0).floor() / PRIMES_IN_RANGE).min(1.0);
    let per_prime = (rho + beta.powi(CHECK_POINTS as i32)).min(1.0);
    (identities as f64 * per_prime.powi(CHECK_PRIMES as i32)).min(1.0)
}

/// A random prime in `(2^61, 2^62)`, never the engine's 2^61 - 1.
fn random_prime(rng: &mut SplitMix) -> u64 {
    loop {
        let c = (rng.next_u64() >> 2) | (1 << 61) | 1;
        if obsan_recon::is_prime(c) {
            return c;
        }
    }
}

/// Certifies a symmetry basis: each vector annihilates the gradients of the
/// outputs, of the basis Lie derivatives and of their one-step Lie
/// derivatives along every field, evaluated on the expression graph at
/// [`CHECK_POINTS`] random points modulo each of [`CHECK_PRIMES`] random
/// 62-bit primes (fresh: the reconstruction works modulo 2^61 - 1 only).
/// With the rank r of the basis rows (proved by the rank test's non-zero
/// minor) and n - r vectors independent by construction (each has a unit
/// entry on its own free column and zeros on the others, up to a non-zero
/// scalar factor), passing all identities proves the basis (symmetry.rs's
/// closure argument). A false identity is a non-zero rational function over
/// Q whose numerator has degree at most D; modulo a prime q not dividing its
/// content it vanishes at a random point with probability at most
/// D / (q - B) given that the point avoids the poles (degree at most B), so a
/// false identity passes the points of one prime with probability at most
/// `beta^points`, `beta = D / (2^61 - B)`. Modulo a prime dividing the
/// content of its integer numerator P it vanishes identically; that content
/// is at most `||P||_1 <= 2^bits` (`height_bounds`), so it has at most
/// `floor(bits / 61)` prime factors above 2^61, and a uniformly random prime
/// of `(2^61, 2^62)` (there are more than 2^61/60) divides it with
/// probability at most `rho = floor(bits / 61) * 60 / 2^61`. The primes are
/// independent, so a wrong basis passes with probability at most
/// `K (rho + beta^points)^primes` for K identities (a union bound).
///
/// `Ok(None)` if some identity fails (the basis is wrong);
/// `Err` for the deadline, or when no point avoids the poles.
pub fn certify_symmetries(
    nf: &mut NormalForm,
    report: &RankReport,
    vectors: &[Vec<RatFun>],
    deadline: Option<Instant>,
) -> Result<Option<RandomCheck>, AnalysisError> {
    let n = report.n;
    let words = closure_words(nf, report);
    let lies = report.words_on_graph(nf, &words)?;
    let vars = nf.state_vars.clone();
    let comps: Vec<Vec<Id>> = vectors
        .iter()
        .map(|v| v.iter().map(|e| nf.ctx.from_canonical(e)).collect())
        .collect();
    let flat: Vec<Id> = comps.iter().flatten().copied().collect();
    let mut all = lies.clone();
    all.extend(&flat);
    let coords = nf.ctx.free_coords(&all, &[]).ok_or_else(|| {
        AnalysisError::Invalid("internal: certification needs no square root".into())
    })?;
    // Degrees as rational functions of the coordinates: a gradient entry of
    // A/B (degrees a, b) is (A'B - AB')/B^2, times (1 + t^2)/2 for an angle
    // coordinate: degrees at most (a + b + 2, 2b).
    let gdeg: Vec<(u64, u64)> = degree_bounds(&nf.ctx, &lies)
        .into_iter()
        .map(|(a, b)| (a.saturating_add(b).saturating_add(2), b.saturating_mul(2)))
        .collect();
    let vdeg: Vec<Vec<(u64, u64)>> = comps.iter().map(|c| degree_bounds(&nf.ctx, c)).collect();
    let mut degree = 0u64;
    let mut poles = 0u64;
    for vd in &vdeg {
        for gd in &gdeg {
            // One denominator per gradient row (B^2), one per vector entry.
            let den = vd.iter().map(|d| d.1).fold(gd.1, u64::saturating_add);
            let top = vd
                .iter()
                .map(|d| d.0)
                .max()
                .unwrap_or(0)
                .saturating_add(gd.0);
            degree = degree.max(den.saturating_add(top));
            poles = poles.max(den);
        }
    }
    // Content: an identity's numerator is sum_i N_i prod_{j != i} M_j G_i for
    // vector entries N_i / M_i and gradient entries G_i / (2 B^2) of a row
    // A / B; ||G_i||_1 <= (a + b) ||A||_1 ||B||_1 times 2 for the half-angle
    // factor (1 + t^2)/2 (L1 norms are submultiplicative, a derivative
    // multiplies a coefficient by at most the degree).
    let rdeg = degree_bounds(&nf.ctx, &lies);
    let ghts: Vec<f64> = height_bounds(&nf.ctx, &lies)
        .into_iter()
        .zip(&rdeg)
        .map(|((ha, hb), &(a, b))| ha + hb + ((a.saturating_add(b)).max(1) as f64).log2() + 1.0)
        .collect();
    let mut bits = 0f64;
    for c in &comps {
        let vh = height_bounds(&nf.ctx, c);
        let dens: f64 = vh.iter().map(|h| h.1).sum();
        let top = vh.iter().map(|h| h.0).fold(0.0, f64::max);
        let g = ghts.iter().copied().fold(0.0, f64::max);
        bits = bits.max(top + dens + g + (n.max(1) as f64).log2());
    }
    let grads = &lies;
    let identities = vectors.len() * grads.len();
    let mut rng = SplitMix(report.seed ^ 0xce27_1f1e);
    let mut bad = 0;
    for pi in 0..CHECK_PRIMES {
        let q = random_prime(&mut rng);
        let mut done = 0;
        while done < CHECK_POINTS {
            if obsan_expr::cancel_requested() {
                return Err(AnalysisError::Cancelled);
            }
            if deadline.is_some_and(|d| Instant::now() > d) {
                return Err(AnalysisError::Timeout(format!(
                    "certifying the symmetries: {} of {} points checked",
                    pi * CHECK_POINTS + done,
                    CHECK_PRIMES * CHECK_POINTS
                )));
            }
            let vals: Vec<u64> = coords.iter().map(|_| rng.next_u64() % q).collect();
            let x = nf.ctx.mod_point_at(&coords, &vals, q).and_then(|leaves| {
                let g = nf.ctx.grad_mod_prime(&lies, &leaves, &vars, q)?;
                let v = nf.ctx.eval_mod_prime(&flat, &leaves, q)?;
                Ok((g, v))
            });
            let Ok((gx, vx)) = x else {
                bad += 1;
                if bad > 64 {
                    return Err(AnalysisError::NoPoint);
                }
                continue;
            };
            for vi in 0..vectors.len() {
                let v = &vx[vi * n..(vi + 1) * n];
                for g in &gx {
                    let acc = v
                        .iter()
                        .zip(g)
                        .fold(0u128, |a, (&s, &t)| (a + s as u128 * t as u128) % q as u128);
                    if acc != 0 {
                        return Ok(None);
                    }
                }
            }
            done += 1;
        }
    }
    Ok(Some(RandomCheck {
        primes: CHECK_PRIMES,
        points: CHECK_PRIMES * CHECK_POINTS,
        identities,
        degree,
        content_bits: if bits.is_finite() {
            bits.ceil() as u64
        } else {
            u64::MAX
        },
        error_bound: error_bound(identities, degree, poles, bits),
    }))
}
