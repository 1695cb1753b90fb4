//! The generating part chosen before the axis probes are complete
//! (io_count.rs `reconstruct`, `Part::Generating`).
//!
//! `normalisation` samples every axis line until all the relation's
//! quotients are interpolated, and the part is chosen after. The part's
//! quotients are the simplest: SIWR_orig's 67 of 770 are interpolated from
//! 49 axis samples, all of them from 83. So here the axes are sampled a
//! few at a time (`cap` samples per axis, one more each round) and, with
//! them, a random line; after each round the quotients whose interpolation
//! is done on every axis with a monomial denominator give their scaling,
//! their degrees and their Jacobian rows, and `select_ranked` is asked for
//! a part of full rank (every parameter) from what is known. The others'
//! sizes are lower bounds as far as the samples show.
//!
//! Why the answer cannot depend on it: a part whose Jacobian has rank
//! `np` generates a subfield of the whole coefficients' field with the
//! same transcendence degree (io_count.rs `generating_part`), whatever
//! the rest of the quotients turn out to be; a count above 1 over it sends
//! io_count_under to the whole. The sizes only choose which such part is
//! interpolated (a cost), and a part's quotients that are no polynomials
//! (a non-generic probe) are not recognised by the sparse interpolation,
//! which then falls back to the whole.

use super::io_count::{
    fraction_derivative, is_monomial, line_ends, line_point, quotient_index, select_ranked, Axes,
    Estimate, AGREE, MAX_AXIS_SAMPLES, P0,
};
use crate::rank::AnalysisError;
use obsan_recon::fp::{inv, mul, pow, Echelon, Zp};
use obsan_recon::{DegreeBounds, Univariate};

/// A part chosen early: the coefficient divided by, and per quotient of
/// the part its monomial scaling, per-axis degrees and total degree.
pub(super) struct Early {
    pub(super) j: usize,
    pub(super) part: Vec<usize>,
    pub(super) alpha: Vec<Vec<u32>>,
    pub(super) per: Vec<Vec<u32>>,
    pub(super) degrees: Vec<u32>,
}

/// Samples per axis of the first round (a quotient needs at least `1 +
/// AGREE`).
const FIRST_CAP: usize = 4;

/// What the probes show of one quotient.
enum Seen {
    /// Done on every axis with a monomial denominator: its scaling, its
    /// per-axis degrees and its Jacobian row at the base point.
    Ready(Vec<u32>, Vec<u32>, Vec<u64>),
    /// A denominator that is no monomial on some axis: never in a part.
    Rational,
    /// Per axis, a lower bound of its degree (exact where done).
    Pending(Vec<u32>),
}

/// The part, when the probes decide one before every quotient is known;
/// `None` when they do not (the whole's probes then take over, on the same
/// samples) or when the part would not be worth it.
pub(super) fn early_part(
    axes: &mut Axes<'_, '_>,
    np: usize,
    n: usize,
    seed: u64,
) -> Result<Option<Early>, AnalysisError> {
    let nq = n - 1;
    let mut line = RawLine::new(np, seed);
    // The coefficient divided by, once it is not the last; the axes the
    // next round samples.
    let mut fixed: Option<usize> = None;
    let mut targets = vec![true; np];
    // Coefficients some quotient by which has a denominator that is no
    // monomial: no monomials themselves (`normalisation`).
    let mut rejected: Vec<usize> = Vec::new();
    for cap in FIRST_CAP..=MAX_AXIS_SAMPLES {
        let j = match fixed {
            Some(j) => j,
            None => {
                for k in (0..np).filter(|&k| targets[k]) {
                    if !axes.advance(k, n - 1, cap)? {
                        return Ok(None);
                    }
                }
                match divisor(axes, np, n, &rejected) {
                    // Every quotient by the last probed and no candidate
                    // left: the whole's normalisation decides.
                    None if (0..np).all(|k| {
                        axes.probes(k, n - 1)
                            .is_some_and(|th| th.iter().all(Univariate::done))
                    }) =>
                    {
                        return Ok(None)
                    }
                    None => {
                        targets = vec![true; np];
                        continue;
                    }
                    Some(j) if j == n - 1 => j,
                    Some(j) => {
                        fixed = Some(j);
                        targets = vec![true; np];
                        j
                    }
                }
            }
        };
        if j != n - 1 {
            for k in (0..np).filter(|&k| targets[k]) {
                if !axes.advance(k, j, cap)? {
                    return Ok(None);
                }
            }
        }
        let seen: Vec<Seen> = (0..nq).map(|q| seen(axes, np, j, q)).collect();
        if j != n - 1 && seen.iter().any(|s| matches!(s, Seen::Rational)) {
            rejected.push(j);
            fixed = None;
            targets = vec![true; np];
            continue;
        }
        // Everything known: the whole's own choice (io_count.rs) decides.
        if seen.iter().all(|s| !matches!(s, Seen::Pending(_))) {
            return Ok(None);
        }
        let rows = seen.iter().filter_map(|s| match s {
            Seen::Ready(_, _, row) => Some(row.clone()),
            _ => None,
        });
        if obsan_recon::fp::rank(Zp(P0), rows) < np {
            targets = vec![true; np];
            continue;
        }
        if !line.sample_to(axes, cap)? {
            return Ok(None);
        }
        let est: Vec<Estimate> = (0..nq).map(|q| line.estimate(q, j, &seen[q])).collect();
        let jac: Vec<Vec<u64>> = seen
            .iter()
            .map(|s| match s {
                Seen::Ready(_, _, row) => row.clone(),
                _ => vec![0; np],
            })
            .collect();
        match select_ranked(&est, &jac, P0, np) {
            Some(Some(part)) => {
                let ready = |q: usize| match &seen[q] {
                    Seen::Ready(a, d, _) => (a.clone(), d.clone()),
                    _ => (vec![0; np], vec![0; np]),
                };
                let (alpha, per) = part.iter().map(|&q| ready(q)).unzip();
                let degrees = part.iter().map(|&q| line.degree(q).unwrap_or(0)).collect();
                return Ok(Some(Early {
                    j,
                    part,
                    alpha,
                    per,
                    degrees,
                }));
            }
            Some(None) => return Ok(None),
            None => targets = blocking(axes, j, &seen, &est, &jac, np),
        }
    }
    Ok(None)
}

/// The axes the next round samples: those where a quotient that keeps
/// `select_ranked` from deciding is not yet done. The blocking ones are
/// the pending quotients within the cap `select_ranked` sets (twice the
/// estimate of the ready quotient that completes the rank); when only the
/// line blocks (a ready quotient within the cap not done along it), no
/// axis; when none does (the whole's lower bound not yet far enough), all.
fn blocking(
    axes: &Axes<'_, '_>,
    j: usize,
    seen: &[Seen],
    est: &[Estimate],
    jac: &[Vec<u64>],
    np: usize,
) -> Vec<bool> {
    let mut order: Vec<usize> = (0..est.len())
        .filter(|&q| matches!(seen[q], Seen::Ready(..)))
        .collect();
    order.sort_by_key(|&q| (est[q].low(), q));
    let mut ech = Echelon::new(Zp(P0));
    let mut last = 0;
    for q in order {
        ech.insert(jac[q].clone());
        if ech.rank() == np {
            last = est[q].low();
            break;
        }
    }
    let cap = last.saturating_mul(2).max(8);
    let mut t = vec![false; np];
    let mut line_only = false;
    for (q, s) in seen.iter().enumerate() {
        if est[q].low() > cap {
            continue;
        }
        match s {
            Seen::Pending(_) => {
                for (k, tk) in t.iter_mut().enumerate() {
                    let done = axes
                        .probes(k, j)
                        .and_then(|th| th.get(q))
                        .is_some_and(Univariate::done);
                    *tk |= !done;
                }
            }
            Seen::Ready(..) => line_only |= matches!(est[q], Estimate::AtLeast(_)),
            Seen::Rational => {}
        }
    }
    if !t.contains(&true) && !line_only {
        t = vec![true; np];
    }
    t
}

/// The coefficient to divide by, as `normalisation` chooses it but from the
/// probes so far: the last while no quotient by it shows a denominator that
/// is no monomial; else the first whose quotient by the last is done on
/// every axis with a monomial numerator and not `rejected` (`None` while
/// there is none).
fn divisor(axes: &Axes<'_, '_>, np: usize, n: usize, rejected: &[usize]) -> Option<usize> {
    let fracs = |k: usize| axes.probes(k, n - 1).unwrap_or(&[]);
    let bad = (0..np).any(|k| {
        fracs(k)
            .iter()
            .any(|u| u.done() && !is_monomial(&u.rational().1))
    });
    if !bad {
        return Some(n - 1);
    }
    (0..n - 1).find(|&m| {
        !rejected.contains(&m)
            && (0..np).all(|k| {
                fracs(k)
                    .get(m)
                    .is_some_and(|u| u.done() && is_monomial(&u.rational().0))
            })
    })
}

/// What the probes by coefficient `j` show of quotient `q`.
fn seen(axes: &Axes<'_, '_>, np: usize, j: usize, q: usize) -> Seen {
    let ord = |v: &[u64]| v.iter().position(|&c| c != 0).unwrap_or(0) as i64;
    let deg = |v: &[u64]| v.iter().rposition(|&c| c != 0).unwrap_or(0) as i64;
    let (mut alpha, mut per, mut row) = (vec![0; np], vec![0; np], vec![0; np]);
    let mut pending = false;
    for k in 0..np {
        let Some(u) = axes.probes(k, j).and_then(|th| th.get(q)) else {
            pending = true;
            continue;
        };
        if !u.done() {
            pending = true;
            per[k] = u.len().saturating_sub(AGREE) as u32;
            continue;
        }
        let (num, den) = u.rational();
        if !is_monomial(&den) {
            return Seen::Rational;
        }
        let a = (ord(&den) - ord(&num)).max(0);
        alpha[k] = a as u32;
        per[k] = (deg(&num) + a - ord(&den)).max(0) as u32;
        match fraction_derivative(&num, &den, axes.base()[k], P0) {
            Some(d) => row[k] = d,
            None => return Seen::Rational,
        }
    }
    if pending {
        Seen::Pending(per)
    } else {
        Seen::Ready(alpha, per, row)
    }
}

/// The black box's raw vectors along one random line `a + t b`, `t = 1,
/// 2, ..` (the same points as io_count.rs `Line`), and per quotient ready
/// its scaled values' interpolation, fed as samples come.
struct RawLine {
    a: Vec<u64>,
    b: Vec<u64>,
    samples: Vec<(u64, Vec<u64>, Vec<u64>)>,
    t: u64,
    misses: usize,
    /// Per quotient: the divisor and the samples its interpolation took.
    th: Vec<Option<(usize, usize, Univariate)>>,
}

impl RawLine {
    fn new(np: usize, seed: u64) -> RawLine {
        let (a, b) = line_ends(np, seed);
        RawLine {
            a,
            b,
            samples: Vec::new(),
            t: 0,
            misses: 0,
            th: Vec::new(),
        }
    }

    /// Samples up to `cap`; false when they run out.
    fn sample_to(&mut self, axes: &mut Axes<'_, '_>, cap: usize) -> Result<bool, AnalysisError> {
        while self.samples.len() < cap {
            self.t += 1;
            if self.misses > 8 || self.t as usize > MAX_AXIS_SAMPLES {
                return Ok(false);
            }
            let pt = line_point(&self.a, &self.b, self.t);
            match axes.call(&pt)? {
                Some(v) => self.samples.push((self.t, pt, v)),
                None => self.misses += 1,
            }
        }
        Ok(true)
    }

    /// Quotient `q`'s size estimate: exact when it is ready and done
    /// along the line, else a lower bound.
    fn estimate(&mut self, q: usize, j: usize, s: &Seen) -> Estimate {
        let size = |per: &[u32], total: u32| {
            DegreeBounds {
                per_var: per.to_vec(),
                total: Some(total.max(per.iter().copied().max().unwrap_or(0))),
            }
            .monomials()
        };
        match s {
            Seen::Rational => Estimate::AtLeast(usize::MAX),
            Seen::Pending(per) => Estimate::AtLeast(size(per, 0)),
            Seen::Ready(alpha, per, _) => {
                let u = self.feed(q, j, alpha);
                if !u.done() {
                    return Estimate::AtLeast(size(per, u.len().saturating_sub(AGREE) as u32));
                }
                let (num, den) = u.rational();
                if den.iter().skip(1).any(|&c| c != 0) {
                    return Estimate::AtLeast(usize::MAX);
                }
                let d = num.iter().rposition(|&c| c != 0).unwrap_or(0) as u32;
                Estimate::Exact(size(per, d))
            }
        }
    }

    /// Quotient `q`'s interpolation along the line, scaled by `theta^alpha`
    /// after division by coefficient `j`, fed with every sample so far.
    fn feed(&mut self, q: usize, j: usize, alpha: &[u32]) -> &Univariate {
        if self.th.len() <= q {
            self.th.resize_with(q + 1, || None);
        }
        let slot = &mut self.th[q];
        if slot.as_ref().is_none_or(|(jj, _, _)| *jj != j) {
            *slot = Some((j, 0, Univariate::new(P0, AGREE)));
        }
        let Some((_, fed, u)) = slot else {
            unreachable!("set above")
        };
        let m = quotient_index(q, j);
        while *fed < self.samples.len() && !u.done() {
            let (t, pt, v) = &self.samples[*fed];
            *fed += 1;
            let Some(iv) = inv(v[j], P0) else {
                continue;
            };
            let y = alpha
                .iter()
                .zip(pt)
                .fold(mul(v[m], iv, P0), |acc, (&e, &x)| {
                    mul(acc, pow(x, u64::from(e), P0), P0)
                });
            u.add(*t, y);
        }
        u
    }

    /// Quotient `q`'s total degree, when done and a polynomial.
    fn degree(&self, q: usize) -> Option<u32> {
        let (_, _, u) = self.th.get(q)?.as_ref()?;
        let (num, den) = u.rational();
        (u.done() && den.len() == 1).then(|| num.len().saturating_sub(1) as u32)
    }
}
