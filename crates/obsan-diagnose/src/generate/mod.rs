//! Candidate effects nobody wrote: generated from the model's
//! structure alone, as `.eff` text, so the rank test, the fit and the
//! likelihood ratio treat them exactly as the user's effects.
//!
//! Per measured input `u`: a scale `(1 + k) u`, a bias `u + b`, a coupling
//! with every other measured input `w`, `u (1 + c |w|)`, a first-order lag
//! (time constant T), a delay. Per group of outputs of one form (the
//! outputs whose expressions agree once the known constants are blanked:
//! the 15 ranges of mrclam.sys are one group), a scale and a bias, and for
//! angle outputs (those built on `atan`/`atan2`) the harmonics `sin y`,
//! `cos y`, `sin 2y`, `cos 2y` (`basic.rs`). What real sensors and wheels
//! also do (`families.rs`): a slow drift in session time of an input's
//! scale or of an output group's bias, a quadratic in a non-angle output,
//! a periodic error in an input's integral (an out-of-round wheel), and an
//! output bias that depends on an angle state (a bearing bias with
//! heading), and, when the inputs are wheel speeds, each wheel slipping in
//! proportion to its own speed, `u (1 - s_u |u|)`; each with a physical range its fitted value must respect
//! (`limits.rs`). A candidate that extends the model exactly as a user
//! effect does (compared numerically, params matched in order,
//! `signature.rs`) is left out: the user's file is the first-class source.

mod basic;
mod families;
mod limits;
mod signature;
#[cfg(test)]
mod tests;

use obsan_model::{Effect, EffectLibrary, Kind, System};

#[cfg(test)]
use limits::Reading;
pub(crate) use limits::{session, Limit, SESSION_CLOCK};

/// [`crate::Named::origin`] and [`crate::CandidateResult::origin`] of a
/// generated candidate.
pub const ORIGIN_GENERATED: &str = "generated";

/// One generated candidate with the words that name it.
#[derive(Clone, Debug)]
pub struct Generated {
    pub effect: Effect,
    /// The patch in words, e.g. `v_eff = v (1 + c |omega|)`.
    pub formula: String,
    /// What a positive and a negative value of the new param mean, e.g.
    /// `v rises with |omega|`, `v falls with |omega|`.
    pub positive: String,
    pub negative: String,
    /// The effect whose score statistic at zero new params screens this
    /// candidate before its fit (`screen.rs`): the effect itself, or
    /// for a lag its limit as T -> 0, `u - T rate(u)` (a lag at T = 0 is
    /// singular, and its state is held at the first input: no transient).
    /// `None`: always fitted (an exact `delay`, whose sensitivity the
    /// screen does not take).
    pub screen: Option<Effect>,
    /// The physical ranges of its fitted params ([`Generated::implausible`]).
    pub(crate) limits: Vec<Limit>,
    /// Weighed only at the estimated input noise, never also at white
    /// input noise (where the workflow otherwise tries every candidate):
    /// an effect that the noise's random walk itself mimics (a drift).
    pub(crate) estimated_noise_only: bool,
}

impl Generated {
    /// The readable name at a fitted value of the new param: "v falls with
    /// |omega|: v_eff = v (1 + c |omega|)".
    pub fn words(&self, value: f64) -> String {
        let what = if value < 0.0 {
            &self.negative
        } else {
            &self.positive
        };
        format!("{what}: {}", self.formula)
    }

    /// Why the fitted `estimates` (name, value, sd) lie outside the
    /// candidate's physical range on `data` (a wheel whose radius would
    /// halve within the session, a quadratic term half the reading), or
    /// `None`: such a fit failed, it is no finding.
    pub(crate) fn implausible(
        &self,
        estimates: &[(String, f64, f64)],
        data: &obsan_data::Dataset,
    ) -> Option<String> {
        self.limits.iter().find_map(|l| l.violated(estimates, data))
    }
}

/// The generated candidates, and the ones left out with the reason.
#[derive(Clone, Debug, Default)]
pub struct Generation {
    pub candidates: Vec<Generated>,
    pub dropped: Vec<(String, String)>,
}

/// The effects file's share of the per-round false-alarm probability when
/// candidates are generated: half, whatever their number, so a file of 8
/// effects is tested at alpha / 16 per candidate against, on mrclam.sys,
/// alpha / 24 for each of the 12 generated ones.
pub const FILE_SHARE: f64 = 0.5;

/// Per-candidate significance levels (file, generated): a weighted
/// Bonferroni split of `alpha` over `n_file + n_generated` candidates, the
/// file's `FILE_SHARE` over its own, the rest over the generated ones. The
/// probability that a round names anything on data without an effect stays
/// below `alpha`; without generated candidates the file keeps all of it.
pub fn levels(alpha: f64, n_file: usize, n_generated: usize) -> (f64, f64) {
    match (n_file, n_generated) {
        (u, 0) => (alpha / u.max(1) as f64, alpha),
        (0, g) => (alpha, alpha / g as f64),
        (u, g) => (
            alpha * FILE_SHARE / u as f64,
            alpha * (1.0 - FILE_SHARE) / g as f64,
        ),
    }
}

/// One candidate before it is read: its `.eff` body and its words.
struct Draft {
    name: String,
    body: String,
    formula: String,
    positive: String,
    negative: String,
    /// The screen's stand-in (see [`Generated::screen`]): `None` the effect
    /// itself, `Some(None)` no screen, `Some(Some(body))` this body.
    screen: Option<Option<String>>,
    limits: Vec<Limit>,
    estimated_noise_only: bool,
}

impl Draft {
    /// A draft screened by itself, with no physical range.
    fn plain(name: String, body: String, formula: String, words: (String, String)) -> Draft {
        Draft {
            name,
            body,
            formula,
            positive: words.0,
            negative: words.1,
            screen: None,
            limits: Vec::new(),
            estimated_noise_only: false,
        }
    }
}

/// Fresh names: none of the model's, of the user's effects', or of those
/// already given out (a trailing `_` added until free).
struct Names {
    taken: Vec<String>,
}

impl Names {
    fn new(sys: &System, user: &[&Effect]) -> Names {
        let mut taken: Vec<String> = sys.decls.iter().map(|d| d.name.clone()).collect();
        taken.extend(sys.output_names().iter().map(|s| s.to_string()));
        for e in user {
            taken.push(e.name.clone());
            taken.extend(e.params.iter().cloned());
            taken.extend(e.states.iter().cloned());
            taken.extend(e.consts.iter().cloned());
            taken.extend(e.inputs.iter().map(|i| i.0.clone()));
        }
        Names { taken }
    }

    fn fresh(&mut self, base: &str) -> String {
        let mut n = base.to_string();
        while self.taken.contains(&n) {
            n.push('_');
        }
        self.taken.push(n.clone());
        n
    }
}

/// Candidates generated from `sys`'s structure, without those that
/// duplicate one of `user` (the effects file's model-side effects).
pub fn generate(sys: &System, user: &[&Effect]) -> Generation {
    let mut names = Names::new(sys, user);
    let inputs: Vec<String> = sys
        .decls_of(Kind::Input)
        .filter(|d| d.derived.is_none())
        .map(|d| d.name.clone())
        .collect();
    let groups = basic::output_groups(sys);
    let mut drafts = basic::input_drafts(&inputs, &mut names);
    drafts.extend(basic::output_drafts(&groups, &mut names));
    drafts.extend(families::drafts(sys, &inputs, &groups, &mut names));
    admit(sys, user, drafts)
}

/// Read each draft, keep the ones that extend `sys` and differ from every
/// effect of `user` and from every one kept before; the others are listed
/// with the reason.
fn admit(sys: &System, user: &[&Effect], drafts: Vec<Draft>) -> Generation {
    let mut out = Generation::default();
    let user_named: Vec<(&str, Option<Vec<f64>>)> = user
        .iter()
        .map(|e| (e.name.as_str(), signature::signature(sys, e)))
        .collect();
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for d in drafts {
        let text = format!(
            "effect {}\ndescription {} (generated)\n{}",
            d.name, d.formula, d.body
        );
        let lib = match EffectLibrary::parse(&text, ORIGIN_GENERATED) {
            Ok(l) => l,
            Err(e) => {
                out.dropped.push((d.name, e.to_string()));
                continue;
            }
        };
        let Some(effect) = lib.effects.into_iter().next() else {
            continue;
        };
        if let Err(e) = sys.extend(&[&effect], ORIGIN_GENERATED) {
            out.dropped.push((d.name, e.to_string()));
            continue;
        }
        let Some(sig) = signature::signature(sys, &effect) else {
            out.dropped.push((d.name, "cannot be evaluated".into()));
            continue;
        };
        if let Some((u, _)) = user_named
            .iter()
            .find(|(_, s)| s.as_ref().is_some_and(|s| signature::same(s, &sig)))
        {
            out.dropped
                .push((d.name, format!("the same as '{u}' of the effects file")));
            continue;
        }
        if kept.iter().any(|s| signature::same(s, &sig)) {
            out.dropped
                .push((d.name, "the same as another generated candidate".into()));
            continue;
        }
        let screen = match &d.screen {
            None => Some(effect.clone()),
            Some(None) => None,
            Some(Some(body)) => {
                let text = format!("effect {}\n{body}", d.name);
                match EffectLibrary::parse(&text, ORIGIN_GENERATED) {
                    Ok(l) => l.effects.into_iter().next(),
                    Err(_) => None,
                }
            }
        };
        kept.push(sig);
        out.candidates.push(Generated {
            effect,
            formula: d.formula,
            positive: d.positive,
            negative: d.negative,
            screen,
            limits: d.limits,
            estimated_noise_only: d.estimated_noise_only,
        });
    }
    out
}
