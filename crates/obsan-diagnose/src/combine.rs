//! Effects fixed only in combination: two params whose estimates correlate
//! at `|r| >=` [`CORRELATION_CAUTION`] are reported by the combination the
//! data fix ([`Combination`]: the smallest-variance direction of their
//! joint covariance, its estimate, model sd and cluster-robust sd).
//!
//! Two sources: pairs of named effects in the final fit, and pairs of the
//! last round's suggested candidates, fitted together once for this. The
//! second case is MRCLAM robot 1's Vicon poses: `turn_scale` and
//! `omega_with_abs_v` each clear the LR but not the Wald check (robust sds
//! 5 to 6 times the model's: the turn-rate error varies from window to
//! window), while from the landmarks both are named at r = -0.99. What
//! either side can compare with the other is the combination, not `kw`
//! alone (which, fitted without the coupling, is that combination).

use crate::correlation::{correlation, Combination, CORRELATION_CAUTION};
use crate::error::DiagnoseError;
use crate::model_fit::{fit_model, prepare, ModelFit};
use crate::options::DiagnoseOptions;
use crate::report::{CandidateResult, Named, ORIGIN_RELATION};
use crate::sandwich::robust_covariance;
use crate::start::extended_start;
use obsan_data::Dataset;
use obsan_model::{Effect, System};

/// The fit the combinations are read from and how it was weighed.
pub(crate) struct At<'a> {
    pub sys: &'a System,
    /// The dataset as given (each model's derived inputs are added here).
    pub data: &'a Dataset,
    pub fit: &'a ModelFit,
    pub sigma: &'a [f64],
    pub noise: &'a [(String, f64)],
    pub o: &'a DiagnoseOptions,
}

/// Suggested candidates fitted together in pairs, at most this many of
/// them (the best by LR): `n (n - 1) / 2` extra fits.
const MAX_PAIRED: usize = 4;

/// The combination of params `i` and `j` of fit `f` of `sys` (the data
/// prepared for it), owned by `effects`, when they correlate at the
/// caution or more; `crit` the critical value of the Wald z squared.
pub(crate) fn pair(
    at: &At,
    (sys, prepared, f): (&System, &Dataset, &ModelFit),
    (i, j): (usize, usize),
    effects: [String; 2],
    crit: f64,
) -> Option<Combination> {
    let r = correlation(&f.covariance, i, j).filter(|r| r.abs() >= CORRELATION_CAUTION)?;
    let levels = (at.sigma, !at.noise.is_empty(), at.o.max_step);
    // A prediction that fails here (it did not in the fit) leaves the
    // robust sd unknown, not the diagnosis failed.
    // Under input noise the sandwich here cannot whiten: the fitter's own
    // robust covariance (whitened scores) gives the pair's block.
    let own = || {
        let v = |a: usize, b: usize| f.params_robust_cov.get(a)?.get(b).copied();
        Some(vec![vec![v(i, i)?, v(i, j)?], vec![v(j, i)?, v(j, j)?]])
    };
    let rob = robust_covariance(sys, prepared, f, levels, &[i, j])
        .ok()
        .flatten()
        .or_else(own);
    let robust = match rob {
        Some(v) => [[v[0][0], v[0][1]], [v[1][0], v[1][1]]],
        None => [[f64::NAN; 2]; 2],
    };
    let infl = f.inflation().sqrt();
    let (a, b) = (&f.params[i], &f.params[j]);
    let mut c = Combination::new(
        [a.0.clone(), b.0.clone()],
        effects,
        ([a.1, b.1], [a.2 * infl, b.2 * infl], r),
        robust,
    );
    c.established = c.wald_z > crit.sqrt();
    Some(c)
}

/// Every pair of params of two named effects (the earlier one's first)
/// fixed only in combination in the final fit `at.fit` of `at.sys`.
/// `crit(origin)`: the LR critical value of an effect of that origin.
pub(crate) fn of_named(
    named: &[Named],
    at: &At,
    crit: &dyn Fn(&str) -> f64,
) -> Result<Vec<Combination>, DiagnoseError> {
    let index = |p: &str| at.fit.params.iter().position(|x| x.0 == p);
    let owned: Vec<(usize, &Named)> = named
        .iter()
        .filter(|n| n.origin != ORIGIN_RELATION)
        .flat_map(|n| {
            n.estimates
                .iter()
                .filter_map(move |e| Some((index(&e.0)?, n)))
        })
        .collect();
    let mut out = Vec::new();
    let mut prepared = None;
    for (a, (i, n)) in owned.iter().enumerate() {
        for (j, m) in owned.iter().skip(a + 1) {
            if n.effect == m.effect
                || correlation(&at.fit.covariance, *i, *j)
                    .is_none_or(|r| r.abs() < CORRELATION_CAUTION)
            {
                continue;
            }
            if prepared.is_none() {
                prepared = Some(prepare(at.sys, at.data)?);
            }
            let Some(p) = prepared.as_ref() else { continue };
            let c = crit(&n.origin).max(crit(&m.origin));
            let effects = [n.effect.clone(), m.effect.clone()];
            out.extend(pair(at, (at.sys, p, at.fit), (*i, *j), effects, c));
        }
    }
    Ok(out)
}

/// Pairs of the last round's suggested candidates (the best
/// [`MAX_PAIRED`] by LR, those without states of their own) fitted
/// together on `at.sys` (the final model): the combination of their
/// weakest params where they correlate at the caution or more. A pair
/// whose joint fit fails is left out.
pub(crate) fn of_suggested(
    suggested: &[CandidateResult],
    effects: &[&Effect],
    at: &At,
    crit: &dyn Fn(&str) -> f64,
) -> Vec<Combination> {
    let mut cands: Vec<(&CandidateResult, &Effect)> = suggested
        .iter()
        .filter_map(|c| Some((c, *effects.iter().find(|e| e.name == c.effect)?)))
        .filter(|(c, e)| e.states.is_empty() && !c.estimates.is_empty())
        .collect();
    cands.sort_by(|a, b| b.0.lr.total_cmp(&a.0.lr));
    cands.truncate(MAX_PAIRED);
    let mut out = Vec::new();
    for (a, (ca, ea)) in cands.iter().enumerate() {
        for (cb, eb) in cands.iter().skip(a + 1) {
            let c = crit(&ca.origin).max(crit(&cb.origin));
            if let Ok(Some(mut comb)) = jointly(at, (ca, ea), (cb, eb), c) {
                comb.named = false;
                out.push(comb);
            }
        }
    }
    out
}

/// Two candidates fitted together from the final fit and their own
/// estimates; the combination of each one's weakest param (by Wald z).
fn jointly(
    at: &At,
    (ca, ea): (&CandidateResult, &Effect),
    (cb, eb): (&CandidateResult, &Effect),
    crit: f64,
) -> Result<Option<Combination>, DiagnoseError> {
    let ext = at
        .sys
        .extend(&[ea, eb], crate::generate::ORIGIN_GENERATED)
        .map_err(|e| DiagnoseError::Extend(Box::new(e)))?;
    let prepared = prepare(&ext, at.data)?;
    let base: Vec<f64> = at.fit.params.iter().map(|p| p.1).collect();
    let (mut pv, sv) = extended_start(&ext, &base, &at.fit.initial_states, &prepared)?;
    let names: Vec<String> = ext
        .decls_of(obsan_model::Kind::Param)
        .map(|d| d.name.clone())
        .collect();
    for (p, v, _) in ca.estimates.iter().chain(&cb.estimates) {
        if let Some(k) = names.iter().position(|n| n == p) {
            if let Some(slot) = pv.get_mut(k).filter(|_| v.is_finite()) {
                *slot = *v;
            }
        }
    }
    let f = fit_model(&ext, &prepared, &pv, &sv, at.sigma, at.noise, at.o)?;
    let weakest = |c: &CandidateResult| {
        c.estimates
            .iter()
            .zip(c.robust_sd.iter().chain(std::iter::repeat(&f64::NAN)))
            .min_by(|x, y| {
                let z = |((_, v, s), r): &(&(String, f64, f64), &f64)| {
                    (v / if r.is_finite() { s.max(**r) } else { *s }).abs()
                };
                z(x).total_cmp(&z(y))
            })
            .map(|x| x.0 .0.clone())
    };
    let index = |p: Option<String>| f.params.iter().position(|x| Some(&x.0) == p.as_ref());
    let (Some(i), Some(j)) = (index(weakest(ca)), index(weakest(cb))) else {
        return Ok(None);
    };
    let effects = [ca.effect.clone(), cb.effect.clone()];
    Ok(pair(at, (&ext, &prepared, &f), (i, j), effects, crit))
}
