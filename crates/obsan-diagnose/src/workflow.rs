//! The discrepancy workflow: fit the nominal model, test the residuals, try
//! every candidate effect that the data can reveal, name the significant
//! ones greedily. [`diagnose`] runs named steps, each handing its result to
//! the next and none reaching back:
//!
//! 1. [`output_levels`] and [`nominal_fit`]: the noise levels and the nominal
//!    fit under them ([`Levels`]);
//! 2. [`Limits::new`]: the candidates' critical values (file and generated);
//! 3. [`input_checks`]: the effects file's input relations, tested on the inputs;
//! 4. [`Rounds`]: the greedy search, one round a method ([`Rounds::round`]);
//! 5. [`settle`]: rivals, refined estimates, correlations and words of what
//!    was named, from the final fit;
//! 6. [`extended_model`] and [`name_relations`]: the extended model's text;
//!    then the [`Diagnosis`] is assembled.

use crate::candidate::{candidate, rank_only, Fitted, Noise};
use crate::combine::{of_named, of_suggested, At};
use crate::compete::{against_named, file_rival, fit_together};
use crate::error::DiagnoseError;
use crate::generate::{generate, levels, Generation, ORIGIN_GENERATED};
use crate::identify::input_class;
use crate::model_fit::{
    class_inputs, estimate_levels, first_fit, fit_model, given_levels, input_noise, output_levels,
    prepare, ModelFit, Start,
};
use crate::options::{DiagnoseOptions, InputNoise, AUTO_ESTIMATE_BELOW};
use crate::relation::{input_check, InputCheck};
use crate::relevel::{weak_under_final, After, Levels};
use crate::report::{CandidateResult, Competing, Diagnosis, Named, Refit, Rival, ORIGIN_FILE};
use crate::screen::{file_stand_in, score, Outcome, Scored, SCREEN_SAFETY};
use crate::settle::{extended_model, mark_stand_ins, name_relations, rivals, settle};
use crate::start::own_start;
use crate::stats::{chi2_critical, normal_critical};
use obsan_data::Dataset;
use obsan_model::{Effect, EffectLibrary, System};
use std::collections::HashMap;

/// Run the workflow. `progress` is told what is being done.
pub fn diagnose(
    sys: &System,
    lib: Option<&EffectLibrary>,
    data: &Dataset,
    start: &Start,
    o: &DiagnoseOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Diagnosis, DiagnoseError> {
    if let Some(l) = lib {
        crate::identify::check_effect_sizes(l)?;
    }
    let outputs: Vec<String> = sys.output_names().iter().map(|s| s.to_string()).collect();
    let sigma = given_levels(&outputs, data, o);
    let prepared = prepare(sys, data)?;
    progress("fitting the nominal model");
    let own = || own_start(sys, data, start);
    let (levels, nominal) = crate::phase::time("levels, nominal fit", || {
        let (sigma, sigma_estimated) = output_levels(sys, &prepared, start, sigma, (o, &own))?;
        nominal_fit(
            sys,
            data,
            &prepared,
            start,
            sigma,
            sigma_estimated,
            o,
            progress,
        )
    })?;

    let effects: Vec<&Effect> = lib.map(|l| l.effects.iter().collect()).unwrap_or_default();
    let file_effects: Vec<&Effect> = effects
        .iter()
        .copied()
        .filter(|e| !e.is_input_side())
        .collect();
    // Candidates generated from the model's structure join the file's,
    // each side with its own share of alpha (generate.rs, `levels`).
    let gen = if o.generate {
        generate(sys, &file_effects)
    } else {
        Generation::default()
    };
    let limits = Limits::new(o.alpha, file_effects.len(), &gen);
    let candidates: Vec<&Effect> = file_effects
        .into_iter()
        .chain(gen.candidates.iter().map(|g| &g.effect))
        .collect();
    let input_checks = input_checks(
        sys,
        data,
        &effects,
        (&levels.noise, levels.estimate),
        limits.a_user,
    );

    let all_candidates = candidates.clone();
    let mut rounds = Rounds::new(
        sys,
        lib,
        data,
        &gen,
        &limits,
        candidates,
        nominal.clone(),
        levels,
        o,
    );
    for round in 0..o.max_rounds {
        if !rounds.round(round, progress)? {
            break;
        }
    }
    let Rounds {
        current_sys,
        current,
        mut named,
        rounds,
        hidden,
        class_text,
        levels,
        refits,
        nominal_refit,
        competing,
        with_named,
        relevels,
        ..
    } = rounds;
    // What the last round found above its critical value but not by its
    // Wald z: suggested, not established (docs/diagnose.md, "Never confidently wrong").
    let suggested: Vec<CandidateResult> = rounds
        .last()
        .map(|r| r.iter().filter(|c| c.suggested).cloned().collect())
        .unwrap_or_default();
    let start_text = match &levels.start_replaced {
        Some(why) => format!("{}; {why}", start.2),
        None => start.2.clone(),
    };

    crate::phase::time("settle", || settle(&mut named, &rounds, &current, &gen));
    if relevels.iter().any(|r| r.replaced) {
        let crit = |n: &str| limits.named(n, &gen, data.trajectories.len());
        let lv = (&levels.sigma[..], &levels.noise[..]);
        crate::phase::time("final-levels refits", || {
            weak_under_final(
                sys,
                &mut named,
                &all_candidates,
                &current,
                data,
                lv,
                &crit,
                o,
            )
        });
    }
    crate::phase::time("stand-ins", || {
        mark_stand_ins(&mut named, &all_candidates, &current, &levels.sigma)
    });
    // Pairs fixed only in combination (item 7 of the never-confidently-
    // wrong rules): among the named effects, and among the suggested ones
    // fitted together.
    let crit = |origin: &str| limits.of(origin);
    let at = At {
        sys: &current_sys,
        data,
        fit: &current,
        sigma: &levels.sigma,
        noise: &levels.noise,
        o,
    };
    progress("combinations of correlated effects");
    let mut combinations = crate::phase::time("combinations", || -> Result<_, DiagnoseError> {
        let mut c = of_named(&named, &at, &crit)?;
        c.extend(of_suggested(&suggested, &all_candidates, &at, &crit));
        Ok(c)
    })?;
    combinations.extend(with_named);
    let mut extended_sys = extended_model(&named, &current_sys);
    name_relations(&mut named, &mut extended_sys, &input_checks, &effects);
    let screen_threshold = match o.screen && levels.noise.is_empty() {
        true => limits.screen_threshold,
        false => f64::INFINITY,
    };
    crate::phase::report();
    Ok(Diagnosis {
        model: sys.name.clone(),
        start: start_text,
        sigma: outputs.into_iter().zip(levels.sigma).collect(),
        sigma_estimated: levels.sigma_estimated,
        input_noise_source: if levels.noise.is_empty() {
            "none"
        } else if levels.estimate {
            "estimated"
        } else {
            "stated"
        }
        .into(),
        input_noise: levels.noise,
        input_noise_lr: levels.noise_lr,
        input_class: class_text,
        nominal_converged: !refits.iter().any(|r| r.round == 1),
        nominal: nominal_refit.unwrap_or(nominal),
        refits,
        rounds,
        named,
        suggested,
        combinations,
        competing,
        input_checks,
        final_fit: current,
        hidden,
        extended_sys,
        lr_critical: limits.crit,
        lr_critical_generated: limits.crit_gen,
        generated_dropped: gen.dropped,
        screen_threshold,
        relevels,
    })
}

/// The nominal fit under the input noise the options choose: stated, or
/// estimated by restricted ML (twice: the levels at the white-noise fit, the
/// refit under them, the levels again).
#[allow(clippy::too_many_arguments)]
fn nominal_fit(
    sys: &System,
    data: &Dataset,
    prepared: &Dataset,
    start: &Start,
    sigma: Vec<f64>,
    sigma_estimated: bool,
    o: &DiagnoseOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<(Levels, ModelFit), DiagnoseError> {
    let stated = input_noise(sys, data);
    let estimate = match o.input_noise {
        InputNoise::Estimate => true,
        InputNoise::Auto => stated.is_empty() && data.trajectories.len() < AUTO_ESTIMATE_BELOW,
        InputNoise::Stated | InputNoise::None => false,
    };
    let noise = match o.input_noise {
        InputNoise::Stated | InputNoise::Auto => stated,
        InputNoise::Estimate | InputNoise::None => vec![],
    };
    let own = || own_start(sys, data, start);
    let (nominal, replaced) = first_fit(sys, prepared, start, (&sigma, &noise), o, &own)?;
    let outputs: Vec<String> = sys.output_names().iter().map(|s| s.to_string()).collect();
    let estimated_outputs = given_levels(&outputs, data, o);
    let mut levels = Levels {
        sigma,
        sigma_estimated,
        estimated_outputs: estimated_outputs.iter().map(|s| s.is_nan()).collect(),
        groups: crate::relevel::sensor_groups(sys),
        noise,
        estimate,
        noise_lr: Vec::new(),
        white_sigma: None,
        white_fit: None,
        start_replaced: replaced,
    };
    if !estimate {
        return Ok((levels, nominal));
    }
    progress("estimating the noise levels");
    let est = (|| -> Result<_, DiagnoseError> {
        let (mut s2, mut c2, mut lr, mut nom) =
            (levels.sigma.clone(), vec![], 0.0, nominal.clone());
        for _ in 0..2 {
            let (s, c, l) = estimate_levels(sys, prepared, &nom, &s2, sigma_estimated, o)?;
            let pv: Vec<f64> = nom.params.iter().map(|p| p.1).collect();
            let states = nom.initial_states.clone();
            nom = fit_model(sys, prepared, &pv, &states, &s, &c, o)?;
            (s2, c2, lr) = (s, c, l);
        }
        Ok((s2, c2, lr, nom))
    })();
    // `auto` keeps the estimate only where white noise is rejected
    // (chi-square 1 at alpha): noiseless inputs keep ordinary least
    // squares, and with it the effects whose fast states the
    // linearised noise model cannot carry (a lag, tests/lag.rs).
    let forced = o.input_noise == InputNoise::Estimate;
    match est {
        Ok((s, c, lr, nom)) if forced || lr > normal_critical(o.alpha).powi(2) => {
            let white_sigma = std::mem::replace(&mut levels.sigma, s);
            levels.noise = c;
            levels.noise_lr.push(lr);
            if !forced {
                // The white-noise levels and the nominal fit under them.
                (levels.white_sigma, levels.white_fit) = (Some(white_sigma), Some(nominal));
            }
            Ok((levels, nom))
        }
        Err(e) if forced => Err(e),
        _ => {
            levels.estimate = false;
            Ok((levels, nominal))
        }
    }
}

/// Per-round significance: the file's and the generated candidates' shares
/// of alpha and their critical values, and the score screen's threshold.
struct Limits {
    a_user: f64,
    a_gen: f64,
    crit: f64,
    /// Infinite when none are generated.
    crit_gen: f64,
    screen_threshold: f64,
}

impl Limits {
    fn new(alpha: f64, n_file: usize, gen: &Generation) -> Limits {
        let (a_user, a_gen) = levels(alpha, n_file, gen.candidates.len());
        let crit = normal_critical(a_user).powi(2);
        let crit_gen = if gen.candidates.is_empty() {
            f64::INFINITY
        } else {
            normal_critical(a_gen).powi(2)
        };
        Limits {
            a_user,
            a_gen,
            crit,
            crit_gen,
            screen_threshold: crit.min(crit_gen) / SCREEN_SAFETY,
        }
    }

    /// The one-degree critical value of an effect of this origin.
    fn of(&self, origin: &str) -> f64 {
        if origin == ORIGIN_GENERATED {
            self.crit_gen
        } else {
            self.crit
        }
    }

    /// The critical value of a named or candidate effect: a generated one
    /// with more than one param or states of its own has a degree of
    /// freedom per param and per free initial value (`k` trajectories).
    fn named(&self, name: &str, gen: &Generation, k: usize) -> f64 {
        match gen.candidates.iter().find(|g| g.effect.name == name) {
            Some(g) if !g.effect.states.is_empty() || g.effect.params.len() > 1 => {
                let df = g.effect.params.len() + g.effect.states.len() * k;
                chi2_critical(self.a_gen, df as f64)
            }
            Some(_) => self.crit_gen,
            None => self.crit,
        }
    }
}

/// The effects file's input relations, each tested on the measured inputs.
/// Weighed by the encoder noise the fit uses (stated or estimated), else by
/// dataset.json's even under `--input-noise none` (the fit may ignore it;
/// the inputs' own test should not), else by one intensity estimated from
/// the relation's scatter.
fn input_checks(
    sys: &System,
    data: &Dataset,
    effects: &[&Effect],
    (noise, estimated): (&[(String, f64)], bool),
    alpha: f64,
) -> Vec<InputCheck> {
    let (relation_noise, source) = match (noise.is_empty(), estimated) {
        (true, _) => (input_noise(sys, data), "stated in dataset.json"),
        (false, true) => (noise.to_vec(), "estimated with the fit"),
        (false, false) => (noise.to_vec(), "stated in dataset.json"),
    };
    effects
        .iter()
        .filter(|e| e.is_input_side())
        .map(|e| input_check(e, data, (&relation_noise, source), alpha))
        .collect()
}

/// The greedy search's state: the current model and its fit, what has been
/// named and every round's results. [`Rounds::round`] runs one round.
struct Rounds<'a> {
    lib: Option<&'a EffectLibrary>,
    data: &'a Dataset,
    gen: &'a Generation,
    limits: &'a Limits,
    o: &'a DiagnoseOptions,
    /// The model-side candidates: the file's, then the generated ones.
    candidates: Vec<&'a Effect>,
    /// The measured (not derived) inputs, for the file's score stand-ins.
    measured: Vec<String>,
    /// Trajectories stacked in the rank test.
    which: Vec<usize>,
    levels: Levels,
    current_sys: System,
    current: ModelFit,
    named: Vec<Named>,
    rounds: Vec<Vec<CandidateResult>>,
    /// Effects the data cannot reveal (the first round's rank tests).
    hidden: Vec<CandidateResult>,
    class_text: String,
    /// Refits of the current model that a candidate's point showed had
    /// stopped short, and the nominal fit's refit (the first round's).
    refits: Vec<Refit>,
    nominal_refit: Option<ModelFit>,
    /// Each candidate's last estimate of its new params: the next round's
    /// fit starts there (the same optimum, fewer iterations; on MRCLAM
    /// robot 1 the named list and its printed estimates are unchanged).
    warm: HashMap<String, Vec<f64>>,
    /// Generated winners fitted together with a competing file candidate.
    competing: Vec<Competing>,
    /// A later round's winner fixed only in combination with a named effect.
    with_named: Vec<crate::correlation::Combination>,
    /// The levels after each naming.
    relevels: Vec<crate::report::Relevel>,
}

impl<'a> Rounds<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        sys: &System,
        lib: Option<&'a EffectLibrary>,
        data: &'a Dataset,
        gen: &'a Generation,
        limits: &'a Limits,
        candidates: Vec<&'a Effect>,
        nominal: ModelFit,
        levels: Levels,
        o: &'a DiagnoseOptions,
    ) -> Rounds<'a> {
        Rounds {
            lib,
            data,
            gen,
            limits,
            o,
            candidates,
            measured: sys
                .decls_of(obsan_model::Kind::Input)
                .filter(|d| d.derived.is_none())
                .map(|d| d.name.clone())
                .collect(),
            which: (0..data.trajectories.len().min(o.rank_trajectories)).collect(),
            levels,
            current_sys: sys.clone(),
            current: nominal,
            named: Vec::new(),
            rounds: Vec::new(),
            hidden: Vec::new(),
            class_text: String::new(),
            refits: Vec::new(),
            nominal_refit: None,
            warm: HashMap::new(),
            competing: Vec::new(),
            with_named: Vec::new(),
            relevels: Vec::new(),
        }
    }

    /// One round: weigh every remaining candidate, name the most significant
    /// one and move the model to it. `false`: the search is over.
    fn round(
        &mut self,
        round: usize,
        progress: &(dyn Fn(&str) + Sync),
    ) -> Result<bool, DiagnoseError> {
        let remaining: Vec<&'a Effect> = self
            .candidates
            .iter()
            .copied()
            .filter(|e| !self.named.iter().any(|n| n.effect == e.name))
            .collect();
        if remaining.is_empty() {
            return Ok(false);
        }
        progress(&format!(
            "round {}: {} candidate effects",
            round + 1,
            remaining.len()
        ));
        // The current model's derived inputs, once for the round: every
        // candidate's extension computes only its own (prepare skips the
        // columns present; on MRCLAM they were 9 % of the run once the
        // couplings were named).
        let round_data = prepare(&self.current_sys, self.data)?;
        let mut results =
            crate::phase::time("weigh", || self.weigh(round, &remaining, &round_data));
        // An LR is only meaningful against a converged fit:
        // where a candidate's point, its params at 0, fits better than the
        // current fit, the current fit had stopped short; it is refitted and
        // the round weighed again.
        for _ in 0..MAX_REFITS {
            let Some((fit, from)) =
                crate::phase::time("refit check", || self.refit(&results, &round_data))
            else {
                break;
            };
            self.refits.push(Refit {
                round: round + 1,
                from,
                m2ll_before: self.current.m2ll(),
                m2ll_after: fit.m2ll(),
            });
            if round == 0 {
                self.nominal_refit = Some(fit.clone());
            }
            self.current = fit;
            results = crate::phase::time("weigh again after refit", || {
                self.weigh(round, &remaining, &round_data)
            });
        }
        if round == 0 {
            crate::phase::time("first-round ranks", || {
                self.first_round(&remaining, &round_data, &mut results)
            })?;
        }
        let best = results
            .iter()
            .filter(|r| r.0.significant)
            .max_by(|a, b| a.0.lr.total_cmp(&b.0.lr))
            .map(|r| (r.0.clone(), r.1.clone()));
        let rivals = best
            .as_ref()
            .map(|(b, _)| rivals(&results, b))
            .unwrap_or_default();
        let file_rival = best
            .as_ref()
            .and_then(|(b, _)| file_rival(b, &results, &self.current));
        self.remember_estimates(&results);
        self.rounds.push(results.into_iter().map(|r| r.0).collect());
        let Some((mut res, Some(mut fitted))) = best else {
            return Ok(false);
        };
        // `best` is one of the candidates.
        let find = |n: &str| self.candidates.iter().copied().find(|e| e.name == n);
        let Some(mut eff) = find(&res.effect) else {
            return Ok(false);
        };
        // A generated winner and a competing file candidate: fitted
        // together, one is named only if it alone stays established.
        if let Some((fe, fres, ffit)) = file_rival.and_then(|(r, f)| Some((find(&r.effect)?, r, f)))
        {
            let lv = &self.levels;
            let levels = match (fitted.white_won, lv.white_sigma.as_deref()) {
                (true, Some(w)) => (w, &[][..]),
                _ => (&lv.sigma[..], &lv.noise[..]),
            };
            let at = (&self.current_sys, &self.current, &round_data);
            let crit = [self.limits.crit_gen, self.limits.crit];
            let together = crate::phase::time("generated vs file", || {
                fit_together(
                    at,
                    (&res, eff),
                    (&fres, fe),
                    levels,
                    crit,
                    round + 1,
                    self.o,
                )
            });
            if let Ok(c) = together {
                let who = c.established.clone().or_else(|| c.named_form.clone());
                self.competing.push(c);
                match who {
                    None => return Ok(false),
                    Some(n) if n == fres.effect => (res, fitted, eff) = (fres, ffit, fe),
                    Some(_) => {}
                }
            }
        }
        // A winner fixed only in combination with an effect already named
        // is not named: the pair's combination is reported instead.
        if round > 0 {
            let lv = &self.levels;
            let (sigma, noise) = match (fitted.white_won, lv.white_sigma.as_deref()) {
                (true, Some(w)) => (w, &[][..]),
                _ => (&lv.sigma[..], &lv.noise[..]),
            };
            let at = At {
                sys: &fitted.sys,
                data: self.data,
                fit: &fitted.fit,
                sigma,
                noise,
                o: self.o,
            };
            let crit = |origin: &str| self.limits.of(origin);
            let against = crate::phase::time("against named", || {
                against_named(&at, &res, &self.named, &crit)
            });
            if let Some(c) = against? {
                self.with_named.push(c);
                return Ok(false);
            }
        }
        self.name(eff, &res, &fitted, rivals);
        let white = fitted.white.clone();
        let white_won = fitted.white_won;
        self.current_sys = fitted.sys;
        self.current = fitted.fit;
        let mut after = After {
            sys: &self.current_sys,
            data: self.data,
            current: &mut self.current,
            levels: &mut self.levels,
            o: self.o,
        };
        let r = crate::phase::time("re-estimate levels", || {
            after.relevel((round + 1, &res.effect), (white, white_won), progress)
        })?;
        self.relevels.push(r);
        Ok(true)
    }

    /// Every remaining candidate scored and, unless screened out, fitted.
    fn weigh(
        &self,
        round: usize,
        remaining: &[&'a Effect],
        data: &Dataset,
    ) -> Vec<Outcome<Fitted>> {
        let (o, lim, lv) = (self.o, self.limits, &self.levels);
        // The caller's cancel flag is thread-local: hand it to the workers.
        let cancel = obsan_expr::cancel_flag();
        // The score weighs residuals as ordinary least squares; it is
        // computed with the screen off too (to compare it with the LR).
        // The file's candidates are scored too once a round has been fitted
        // in full (the first round's rank tests give the hidden effects);
        // one threshold for both sides, the lower critical value's.
        let scoring = lv.noise.is_empty();
        let screen_at = (o.screen && scoring).then_some(lim.screen_threshold);
        let gen_of_name = |n: &str| self.gen.candidates.iter().find(|g| g.effect.name == n);
        let gen_of = |e: &Effect| gen_of_name(&e.name);
        let scorer = |e: &Effect| {
            if !scoring {
                return None;
            }
            let own;
            let se = match gen_of(e) {
                Some(g) => g.screen.as_ref()?,
                // In the first round only with generation, where the
                // candidates are many; their rank tests are run below.
                None if round > 0 || o.generate => {
                    own = file_stand_in(e, &self.measured)?;
                    &own
                }
                None => return None,
            };
            // The heading-free check is predicted at the candidate's limit.
            let c = if gen_of(e).is_some() {
                lim.crit_gen
            } else {
                lim.crit
            };
            obsan_expr::with_cancel(cancel.clone(), || {
                score(
                    &self.current_sys,
                    &self.current,
                    se,
                    data,
                    &lv.sigma,
                    (o.max_step, Some(c)),
                )
                .ok()
            })
        };
        let fit = |e: &Effect, scored: Option<&Scored>| {
            let g = gen_of(e);
            // A generated candidate must also clear the critical value in
            // cluster-robust sds; one that adds states is tested with a
            // degree of freedom per free initial value (K per state).
            let c = lim.named(&e.name, self.gen, data.trajectories.len());
            let origin = match g {
                Some(_) => ORIGIN_GENERATED,
                None => self.lib.map_or("effects", |l| l.origin.as_str()),
            };
            // Every candidate's Wald z at its side's one-degree critical
            // value: the same rule for file and generated candidates.
            let wald = Some(if g.is_some() { lim.crit_gen } else { lim.crit }.sqrt());
            let (mut r, mut x) = obsan_expr::with_cancel(cancel.clone(), || {
                let levels = Noise {
                    sigma: &lv.sigma,
                    noise: &lv.noise,
                    // A drift is weighed at the estimated input noise
                    // only (generate/families.rs, `drifts`).
                    white: lv
                        .white_sigma
                        .as_deref()
                        .zip(lv.white_fit.as_ref())
                        .filter(|_| !g.is_some_and(|g| g.estimated_noise_only)),
                    profile: lv.sigma_estimated,
                };
                candidate(
                    &self.current_sys,
                    &self.current,
                    e,
                    data,
                    &self.which,
                    levels,
                    (c, wald),
                    o,
                    origin,
                    self.warm.get(&e.name).map(Vec::as_slice),
                )
            });
            // A generated param outside its physical range: a failed fit.
            let fitted = g.filter(|_| x.is_some());
            if let Some(why) = fitted.and_then(|g| g.implausible(&r.estimates, data)) {
                (r.error, r.significant, r.suggested, x) = (Some(why), false, false, None);
            }
            r.score = scored.map(|s| s.score);
            // Beside the check, the z its prediction gave.
            let pz = scored.and_then(|s| s.check.as_ref()).map(|c| c.predicted_z);
            if let (Some(c), Some(z)) = (r.common_mode.as_mut(), pz) {
                c.predicted_z = z;
            }
            (r, x)
        };
        let is_file = |e: &Effect| gen_of(e).is_none();
        let mut results = crate::screen::round(remaining, scorer, fit, screen_at, is_file);
        for r in results.iter_mut().filter(|r| r.0.screened_out) {
            if gen_of_name(&r.0.effect).is_none() {
                r.0.origin = ORIGIN_FILE.into();
            }
        }
        results
    }

    /// The first round also gives every file candidate's rank (the screened
    /// ones are rank-tested alone, no fit) for the "cannot reveal" report,
    /// and the data's input class.
    fn first_round(
        &mut self,
        remaining: &[&'a Effect],
        data: &Dataset,
        results: &mut [Outcome<Fitted>],
    ) -> Result<(), DiagnoseError> {
        use rayon::prelude::*;
        let cancel = obsan_expr::cancel_flag();
        let origin = self.lib.map_or("effects", |l| l.origin.as_str());
        let (sys, fit, which) = (&self.current_sys, &self.current, &self.which);
        results
            .par_iter_mut()
            .filter(|r| r.0.screened_out && r.0.origin == ORIGIN_FILE)
            .for_each(|r| {
                if let Some(e) = remaining.iter().find(|e| e.name == r.0.effect) {
                    obsan_expr::with_cancel(cancel.clone(), || {
                        rank_only(sys, fit, e, data, which, origin, &mut r.0)
                    });
                }
            });
        if let Ok(ext) = self.current_sys.extend(&[], "") {
            let prepared = prepare(&ext, data)?;
            let (ins, der) = class_inputs(&ext);
            if let Ok(c) = input_class(&ins, &der, &prepared) {
                self.class_text = c.describe();
            }
        }
        self.hidden = results
            .iter()
            .filter(|r| !r.0.identifiable && r.0.error.is_none() && !r.0.screened_out)
            .map(|r| r.0.clone())
            .collect();
        Ok(())
    }

    /// The current model refitted from the points of the round's best
    /// candidates (by LR, above the lower critical value), each with its new
    /// params at 0 (the current model's params and states read from the
    /// candidate's fit by name): the best such fit when it lowers `-2 log L`
    /// by more than [`REFIT_GAIN`], with the candidate it came from.
    fn refit(&self, results: &[Outcome<Fitted>], data: &Dataset) -> Option<(ModelFit, String)> {
        use rayon::prelude::*;
        let (lv, o) = (&self.levels, self.o);
        let floor = self.limits.crit.min(self.limits.crit_gen);
        let mut from: Vec<(&CandidateResult, &Fitted)> = results
            .iter()
            .filter_map(|r| Some((&r.0, r.1.as_ref()?)))
            .filter(|(r, _)| r.error.is_none() && r.lr > floor)
            .collect();
        from.sort_by(|a, b| b.0.lr.total_cmp(&a.0.lr));
        from.truncate(REFIT_FROM);
        let names = |sys: &System| -> Vec<String> {
            sys.decls_of(obsan_model::Kind::State)
                .map(|d| d.name.clone())
                .collect()
        };
        let (states, cur) = (names(&self.current_sys), &self.current);
        let cancel = obsan_expr::cancel_flag();
        let best = from
            .par_iter()
            .filter_map(|(r, f)| {
                let pv: Vec<f64> = cur
                    .params
                    .iter()
                    .map(|p| f.fit.param(&p.0).map_or(p.1, |x| x.0))
                    .collect();
                let ext_states = names(&f.sys);
                let sv: Vec<Vec<f64>> = cur
                    .initial_states
                    .iter()
                    .zip(&f.fit.initial_states)
                    .map(|(c, e)| {
                        states
                            .iter()
                            .zip(c)
                            .map(|(n, v)| {
                                ext_states
                                    .iter()
                                    .position(|x| x == n)
                                    .and_then(|i| e.get(i).copied())
                                    .unwrap_or(*v)
                            })
                            .collect()
                    })
                    .collect();
                obsan_expr::with_cancel(cancel.clone(), || {
                    fit_model(&self.current_sys, data, &pv, &sv, &lv.sigma, &lv.noise, o).ok()
                })
                .map(|fit| (fit, r.effect.clone()))
            })
            .min_by(|a, b| a.0.m2ll().total_cmp(&b.0.m2ll()))?;
        (best.0.m2ll() < cur.m2ll() - REFIT_GAIN).then_some(best)
    }

    /// Each fitted candidate's estimates, to start its next fit from.
    fn remember_estimates(&mut self, results: &[Outcome<Fitted>]) {
        for r in results
            .iter()
            .filter(|r| r.1.is_some() && r.0.error.is_none())
        {
            let v: Vec<f64> = r.0.estimates.iter().map(|e| e.1).collect();
            if v.len() == r.0.params.len() && v.iter().all(|x| x.is_finite()) {
                self.warm.insert(r.0.effect.clone(), v);
            }
        }
    }

    /// The round's winner joins the named effects.
    fn name(&mut self, eff: &Effect, res: &CandidateResult, fitted: &Fitted, rivals: Vec<Rival>) {
        let (description, origin) = match self
            .gen
            .candidates
            .iter()
            .find(|g| g.effect.name == eff.name)
        {
            Some(g) => (
                g.words(res.estimates.first().map_or(0.0, |x| x.1)),
                ORIGIN_GENERATED,
            ),
            None => (eff.description.clone(), ORIGIN_FILE),
        };
        self.named.push(Named {
            effect: res.effect.clone(),
            description,
            origin: origin.into(),
            estimates: res.estimates.clone(),
            robust_sd: res.robust_sd.clone(),
            rms_before: self.current.rms.clone(),
            rms_after: fitted.fit.rms.clone(),
            lr: res.lr,
            p_value: res.p_value,
            rivals,
            ..Named::default()
        });
    }
}

/// Refits of the current model per round, at most (each weighs the round
/// again).
const MAX_REFITS: usize = 2;
/// The round's candidates (best LR first) whose points restart the current
/// fit.
const REFIT_FROM: usize = 2;
/// A restart that lowers `-2 log L` by more than this replaces the current
/// fit: below it no likelihood ratio moves by a unit (critical values are
/// near 10), above it the comparison was with a fit that had stopped short.
const REFIT_GAIN: f64 = 1.0;
