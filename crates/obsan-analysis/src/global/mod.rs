//! Global identifiability: how many values of each parameter and initial
//! state give the output of a generic one, and the discrete symmetries that
//! map one to another (docs/engine.md, "Global identifiability").
//!
//! SIAN's route (Hong, Ovchinnikov, Pogudin, Yap, Bioinformatics 2019): the
//! output's Taylor coefficients `y^(j)(0)` are polynomials in the parameters,
//! the initial state and the higher derivatives `x^(k)(0)` (new unknowns tied
//! by `x^(k+1) = D^k f`), the inputs' coefficients random. At a random point
//! the coefficients are numbers; the zeros of the system over the algebraic
//! closure of F_p are the (params, initial states) with the same output jet,
//! and a Gröbner basis over F_p (obsan-groebner) counts the values each
//! variable takes on them. Denominators are cleared by `z * den = 1`, with
//! `z' = -z^2 den'` so the system stays polynomial.

use crate::rank::AnalysisError;
use obsan_model::NormalForm;

mod count;
mod io;
mod io_check;
mod io_choice;
mod io_count;
mod io_elim;
mod io_part;
mod io_pres;
mod io_report;
mod io_series;
mod lie;
mod maps;
mod model;
mod outputs;
mod run;
mod sian;
mod trig;
mod types;
mod weights;

use count::{count_once, error_bounds};
pub use io_count::IoSize;
use maps::{find_maps, group_order, map_signs};
use model::zmodel;
pub use outputs::OutputForm;
use run::Run;
use types::err;
pub use types::{
    DiscreteMap, GlobalOptions, GlobalReport, GlobalVariable, Identifiability, Route, StatesAfterIo,
};

/// Global identifiability of every parameter and initial state (SIAN's
/// route; the certificate and the bounds are in docs/engine.md): two
/// independent runs (different primes and random points) must agree. With
/// [`Route::Auto`], a Taylor system past a budget falls back on the
/// input-output relations (io_report.rs), which count the parameters only.
pub fn global_identifiability(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
) -> Result<GlobalReport, AnalysisError> {
    if opts.multi_experiment {
        // Several experiments share the parameters, not the initial states:
        // the io relations' coefficients count them (io_count.rs), and
        // elimination is asked for as by `--route io`.
        return match opts.route {
            Route::Auto | Route::InputOutput => io_report::io_route(nf, opts, None, true, io_report::MAX_ANSATZ),
            _ => Err(err(
                "global: --multi-experiment counts by the input-output relations (--route io or auto)",
            )),
        };
    }
    match opts.route {
        Route::Taylor => taylor_route(nf, opts, false, true, &[], &mut Prolonged::default()),
        Route::Lie => taylor_route(nf, opts, true, false, &[], &mut Prolonged::default()),
        Route::InputOutput => io_report::io_route(nf, opts, None, true, io_report::MAX_ANSATZ),
        Route::Auto => {
            let r = auto_route(nf, opts)?;
            Ok(maps_from_relations(nf, opts, r))
        }
    }
}

/// Under `--route auto`, an answer whose maps do not reach every solution
/// (the Taylor route's search is of signed permutations, with a budget):
/// the input-output relations' maps of the parameters (io_check.rs: signed
/// permutations, or a rational map between two solutions), sought under
/// the cheap io attempt's bounds, replace them when they generate a larger
/// group and the relations give every parameter the same verdict. The
/// answer stands whatever that attempt does (SI.jl's Treatment, Covid3,
/// SEIR1, Biohydrogenation: each count of 2 now with its map).
fn maps_from_relations(nf: &mut NormalForm, opts: &GlobalOptions, r: GlobalReport) -> GlobalReport {
    let unexplained = r.solutions.is_some_and(|k| k > r.group_order);
    if r.route == Route::InputOutput || r.solutions_at_most || !unexplained {
        return r;
    }
    let cheap = GlobalOptions {
        max_work: opts.max_work.min(io_choice::QUICK_WORK),
        max_io_work: opts.max_io_work.min(io_choice::QUICK_IO_WORK),
        ..opts.clone()
    };
    let Ok(io) = io_report::io_route(nf, &cheap, None, false, io_report::MAX_ANSATZ) else {
        return r;
    };
    let same = io.variables.iter().all(|v| {
        r.variables
            .iter()
            .any(|w| w.param && w.name == v.name && w.verdict == v.verdict)
    });
    if !same || io.group_order <= r.group_order {
        return r;
    }
    GlobalReport {
        maps: io.maps,
        group_order: io.group_order,
        ..r
    }
}

/// `--route auto` (issue 36): the Taylor route first under a small bound on
/// its Gröbner basis's work ([`io_choice::QUICK_WORK`]); past it, the
/// input-output route with its kernels bounded ([`io_choice::QUICK_IO_WORK`],
/// no elimination past the ansatz); when
/// that one does not answer, the Taylor route under a larger bound
/// ([`io_choice::FIRST_WORK`]), then the input-output route on the full
/// ansatz. When an io attempt answers, the initial states by the Taylor
/// route with the params it found global fixed (`states_after_io`, under
/// [`io_choice::EARLY_WORK`]); only when no io attempt answers, the Taylor
/// route again without the bound, then the Lie route (lie.rs: no Taylor
/// unknowns, initial states counted too, every input's question). Before
/// the Lie route, for a model without inputs whose relation is past the
/// dense ansatz's cap, the input-output route once more with that relation
/// found by elimination (io_elim.rs, as `--route io` does), its Gröbner
/// bases and kernels under work bounds ([`io_choice::ELIM_WORK`],
/// [`io_choice::ELIM_IO_WORK`]). Every step is deterministic (work and
/// sizes, never time), so the same seed takes the same route.
fn auto_route(nf: &mut NormalForm, opts: &GlobalOptions) -> Result<GlobalReport, AnalysisError> {
    let bounded = |work: u64| GlobalOptions {
        max_work: opts.max_work.min(work),
        ..opts.clone()
    };
    // The Taylor attempts' prolonged systems, kept from one to the next;
    // the io attempts between them have the memory budget less what those
    // hold. Kept only after an attempt the work bound stopped (past the
    // memory budget no later attempt goes further) and while they hold at
    // most a quarter of the budget (QY's held all of it, and the io
    // attempt had none left).
    let mut kept = Prolonged::default();
    let settle = |kept: &mut Prolonged, why: &str| {
        if !io_choice::stopped_early(why) || kept.held_bytes() > opts.max_bytes / 4 {
            *kept = Prolonged::default();
        }
    };
    let beside = |kept: &Prolonged, o: &GlobalOptions| GlobalOptions {
        max_bytes: o.max_bytes.saturating_sub(kept.held_bytes()),
        ..o.clone()
    };
    let quick = bounded(io_choice::QUICK_WORK);
    let why = match taylor_route(nf, &quick, false, true, &[], &mut kept) {
        Err(AnalysisError::Invalid(why))
            if io_choice::stopped_early(&why) && quick.max_work < opts.max_work =>
        {
            let reason = io_choice::early_reason(&why, quick.max_work);
            settle(&mut kept, &why);
            let cheap = GlobalOptions {
                max_io_work: opts.max_io_work.min(io_choice::QUICK_IO_WORK),
                ..beside(&kept, &quick)
            };
            match io_report::io_route(nf, &cheap, Some(reason), false, io_report::MAX_ANSATZ) {
                Ok(r) => {
                    drop(kept);
                    return states_after_io(nf, opts, r, true);
                }
                Err(AnalysisError::Timeout(e)) => return Err(AnalysisError::Timeout(e)),
                // Larger relations, or none: the Taylor route goes on.
                Err(_) => {}
            }
            match taylor_route(
                nf,
                &bounded(io_choice::FIRST_WORK),
                false,
                true,
                &[],
                &mut kept,
            ) {
                Err(AnalysisError::Invalid(why)) if io_report::falls_back(&why) => why,
                r => return r,
            }
        }
        // Past the memory budget: a larger work bound stops at the same place.
        Err(AnalysisError::Invalid(why)) if io_report::falls_back(&why) => why,
        r => return r,
    };
    settle(&mut kept, &why);
    let first = bounded(io_choice::FIRST_WORK);
    let stopped = io_choice::stopped_early(&why) && first.max_work < opts.max_work;
    let reason = if stopped {
        io_choice::early_reason(&why, first.max_work)
    } else {
        why.clone()
    };
    let io_err = match io_report::io_route(
        nf,
        &beside(&kept, opts),
        Some(reason.clone()),
        false,
        io_report::MAX_ANSATZ,
    ) {
        Ok(r) => {
            drop(kept);
            return states_after_io(nf, opts, r, stopped);
        }
        Err(e) => e,
    };
    // A relation past the ansatz, found by elimination as `--route io`
    // does (io_elim.rs; models without inputs), under deterministic bounds
    // ([`io_choice::ELIM_WORK`], [`io_choice::ELIM_IO_WORK`]): before the
    // unbounded Taylor attempt, which answers no such model of the SI.jl
    // suite and took SIWR_orig 10 s to pass the memory budget, and before
    // the Lie route, whose exact derivatives fill the expression budget the
    // elimination's model needs (EAIHRD after them: "expression too large").
    let past_ansatz = nf.input_vars.is_empty()
        && !matches!(io_err, AnalysisError::Timeout(_))
        && io_err.to_string().contains(io_report::PAST_ANSATZ);
    let mut elim_err = None;
    if past_ansatz {
        let elim = GlobalOptions {
            max_work: opts.max_work.min(io_choice::ELIM_WORK),
            max_io_work: opts.max_io_work.min(io_choice::ELIM_IO_WORK),
            ..beside(&kept, opts)
        };
        let why = format!("{reason}; the input-output route: {io_err}");
        // One output, whose relation the attempt above found past the
        // dense ansatz: the elimination straight away (a cap of 0), not the
        // same ansatz's kernels again first (SIWR_orig: 0.17 s of 2.8 s).
        let cap = if nf.outputs.len() == 1 {
            0
        } else {
            io_report::MAX_ANSATZ
        };
        match io_report::io_route(nf, &elim, Some(why), true, cap) {
            Ok(r) => {
                drop(kept);
                return states_after_io(nf, opts, r, stopped);
            }
            Err(e @ AnalysisError::Timeout(_)) => return Err(e),
            Err(e) => elim_err = Some(e),
        }
    }
    // The unbounded Taylor attempt (the deadline passed: no time for it).
    let why = if stopped && !matches!(io_err, AnalysisError::Timeout(_)) {
        // One run at a time: a system past the early bound is large, and
        // most such pass half the memory budget (taylor_runs), where a
        // parallel attempt would only add its time to the refusal
        // (EAIHRD: 11.8 s -> 20.5 s); JAK_STAT, the one SI.jl model this
        // attempt answers, holds 43 MB.
        match taylor_route(nf, opts, false, false, &[], &mut kept) {
            Err(AnalysisError::Invalid(why)) if io_report::falls_back(&why) => why,
            r => return r,
        }
    } else {
        reason
    };
    // No Taylor attempt follows: what it kept goes.
    drop(kept);
    let mut why = format!("{why}; the input-output route: {io_err}");
    if let Some(e) = elim_err {
        why = format!("{why}; the input-output route by elimination: {e}");
    }
    match taylor_route(nf, opts, true, false, &[], &mut Prolonged::default()) {
        Ok(mut r) => {
            r.fallback = Some(why);
            Ok(r)
        }
        Err(e) => Err(err(format!("{why}; the Lie route: {e}"))),
    }
}

/// The initial states after the input-output route (`--route auto`): the
/// Taylor route on the model whose globally identifiable params (by the
/// relations) are known constants, given random values at the point as
/// every constant. Why no solution is lost: on a generic fibre such a param
/// takes one value, the point's, so the fibre lies in the slice where it
/// equals it; the Taylor system of the smaller model at the same point is
/// that slice. Its orders are that model's own (docs/engine.md, "Taylor
/// orders", applied to it), lower than the whole model's (SI.jl's Goodwin:
/// 28 unknowns instead of 43, answered in milliseconds where the whole
/// system's basis needs 9.3e9 multiply-adds). The other params' counts must
/// agree with the relations' (two routes, two independent computations);
/// a disagreement is an error, never an answer. When the attempt does not
/// answer within [`io_choice::EARLY_WORK`] (or `stopped` is false and
/// nothing is fixed: the same system already failed), the io route's answer
/// stands, saying why the states were not counted.
fn states_after_io(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
    io: GlobalReport,
    stopped: bool,
) -> Result<GlobalReport, AnalysisError> {
    let fixed: Vec<bool> = io
        .variables
        .iter()
        .map(|v| v.verdict == Identifiability::Global)
        .collect();
    let names: Vec<String> = io
        .variables
        .iter()
        .filter(|v| v.verdict == Identifiability::Global)
        .map(|v| v.name.clone())
        .collect();
    let mut io = io;
    let skipped = |mut io: GlobalReport, why: String| {
        io.states_after_io = Some(StatesAfterIo {
            fixed: names.clone(),
            counted: false,
            output_orders: Vec::new(),
            unknowns: 0,
            equations: 0,
            error_bound: 1.0,
            why_not: Some(why),
        });
        Ok(io)
    };
    if !stopped && names.is_empty() {
        return skipped(
            io,
            "the Taylor system is the one that did not answer".into(),
        );
    }
    let states_opts = GlobalOptions {
        max_work: opts.max_work.min(io_choice::EARLY_WORK),
        ..opts.clone()
    };
    let t = match taylor_route(
        nf,
        &states_opts,
        false,
        true,
        &fixed,
        &mut Prolonged::default(),
    ) {
        Ok(t) => t,
        Err(e) => return skipped(io, e.to_string()),
    };
    // The params: the relations' verdicts and the Taylor count's agree.
    for (v, w) in io.variables.iter().zip(&t.variables) {
        if v.name != w.name || v.verdict != w.verdict {
            return Err(err(format!(
                "global: the input-output relations and the Taylor count of the initial states disagree on `{}` (a non-generic point); try another --seed",
                v.name
            )));
        }
    }
    io.states_after_io = Some(StatesAfterIo {
        fixed: names,
        counted: true,
        output_orders: t.output_orders,
        unknowns: t.unknowns,
        equations: t.equations,
        error_bound: t.error_bound,
        why_not: None,
    });
    // The params' verdicts agree; the states', the joint count and (when
    // it finds any) the maps are the Taylor count's (over params and
    // initial states). The
    // error bound stays the io route's (none): the states' count assumes
    // the params' verdicts.
    io.variables = t.variables;
    io.solutions = t.solutions;
    io.all_local = t.all_local;
    // The relations' maps of the parameters stay when they generate a
    // larger group than the Taylor count's maps over parameters and states
    // (whose search is bounded: Bilirubin's finds one swap, order 2, where
    // the relations give all six relabellings), else the Taylor count's.
    if t.group_order >= io.group_order {
        io.maps = t.maps;
        io.group_order = t.group_order;
    }
    Ok(io)
}

/// SIAN's route, or (`lie`) the Lie route (lie.rs): the same counts and
/// report on another polynomial system. The params marked in `fixed` (the
/// input-output route's global ones, `states_after_io`) are known constants
/// of the Taylor system, each reported as taking one value.
fn taylor_route(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
    lie: bool,
    parallel: bool,
    fixed: &[bool],
    kept: &mut Prolonged,
) -> Result<GlobalReport, AnalysisError> {
    let m = zmodel(nf)?;
    let primes = [obsan_recon::PRIMES[0], obsan_recon::PRIMES[1]];
    let kmax = opts.max_order + 2;
    let mut results = Vec::new();
    let any_fixed = fixed.iter().any(|&f| f);
    let fixed_model;
    let mt = if any_fixed {
        fixed_model = m.with_fixed_params(fixed);
        &fixed_model
    } else {
        &m
    };
    if lie {
        results = lie::lie_counts(&m, &mut nf.ctx, &primes, opts)?;
    }
    if !lie {
        results = taylor_runs(mt, &primes, kmax, opts, parallel, kept)?;
    }
    if any_fixed {
        // Back to every param (params then states, as the counts are
        // ordered): a fixed one takes its one value.
        let np_t = mt.param_vars.len();
        for r in results.iter_mut() {
            let mut rest = r.per_var[..np_t].iter();
            let mut per: Vec<Option<usize>> = (0..m.param_vars.len())
                .map(|i| {
                    if fixed.get(i).copied().unwrap_or(false) {
                        Some(1)
                    } else {
                        rest.next().copied().flatten()
                    }
                })
                .collect();
            per.extend_from_slice(&r.per_var[np_t..]);
            r.per_var = per;
        }
    }
    let (a, b) = (&results[0], &results[1]);
    if a.per_var != b.per_var || a.joint != b.joint || a.orders != b.orders {
        return Err(err(
            "global: two independent random points disagree on the counts (a non-generic point); try another --seed",
        ));
    }
    let nx = m.dyn_vars.len();
    let np = m.param_vars.len();
    // SIAN's degree bounds are of its Taylor system; the Lie route has none
    // derived (1: no bound), as the input-output route.
    let bounds = if lie {
        (0.0, 0.0, 1.0)
    } else {
        error_bounds(mt, &results, &primes)
    };
    // Names: params then states, as the counts are ordered.
    let names: Vec<(String, bool)> = nf.state[nx..]
        .iter()
        .map(|s| (s.clone(), true))
        .chain(nf.state[..nx].iter().map(|s| (s.clone(), false)))
        .collect();
    let variables: Vec<GlobalVariable> = names
        .iter()
        .zip(&a.per_var)
        .enumerate()
        .map(|(i, ((name, param), c))| GlobalVariable {
            name: name.clone(),
            param: *param,
            angle: m.angle[if i < np { nx + i } else { i - np }],
            verdict: match c {
                None => Identifiability::NotIdentifiable,
                Some(1) => Identifiability::Global,
                Some(k) => Identifiability::Local(*k),
            },
            at_most: false,
        })
        .collect();
    let all_local = a.per_var.iter().all(|c| c.is_some());
    let tangents = !m.angle_outputs.is_empty();
    // Multi-valued variables in model order (states then params).
    let mut multi = vec![false; nx + np];
    for (i, c) in a.per_var.iter().enumerate() {
        let idx = if i < np { nx + i } else { i - np };
        multi[idx] = matches!(c, Some(k) if *k > 1);
    }
    let maps = if multi.iter().any(|&x| x) {
        find_maps(&m, &multi, 200_000)
    } else {
        Vec::new()
    };
    let group = group_order(&maps, nx + np, 100_000);
    // With outputs read through an angle's tangent, each map is checked on
    // the angle itself (outputs.rs): the sign it gives each such output.
    let signs: Vec<Vec<Option<i8>>> = maps
        .iter()
        .map(|s| {
            if tangents {
                map_signs(&mut nf.ctx, &m.angle_outputs, &m.symbols, &m.angle, s)
            } else {
                Vec::new()
            }
        })
        .collect();
    // When the maps reach every solution (the orbit of the generic point is
    // the whole fibre of the tangents) and each map's sign on every angle
    // output is proven, the real fibre is the subgroup keeping every angle:
    // the kernel of `g -> (sign_j(g))_j` (signs multiply along compositions,
    // each being a constant), of order `group / 2^rank` with the rank of the
    // generators' sign vectors over F_2. All of it: the counts stand; only
    // the generic point: every variable is global; else the joint count is
    // the kernel's order and the per-variable counts stay upper bounds.
    // (More than 64 angle outputs: not settled, the bound stays.)
    let settled = a.joint == Some(group)
        && m.angle_outputs.len() <= 64
        && signs.iter().flatten().all(|x| x.is_some());
    let kernel = settled.then(|| group >> sign_rank(&signs));
    let exact = !tangents || kernel == Some(group);
    let all_global = tangents && kernel == Some(1);
    let all_names: Vec<&str> = nf.state.iter().map(|s| s.as_str()).collect();
    let maps_out = maps
        .iter()
        .zip(&signs)
        .map(|(s, sg)| DiscreteMap {
            images: s
                .iter()
                .enumerate()
                .filter(|(v, im)| *v != im.var || im.sign < 0 || im.exp < 0)
                .map(|(v, im)| im.named(all_names[v], &all_names))
                .collect(),
            keeps_angles: if sg.iter().all(|&x| x == Some(1)) {
                Some(true)
            } else if sg.contains(&Some(-1)) {
                Some(false)
            } else {
                None
            },
            params_only: false,
        })
        .collect();
    let variables: Vec<GlobalVariable> = variables
        .into_iter()
        .map(|mut v| {
            if all_global && matches!(v.verdict, Identifiability::Local(_)) {
                v.verdict = Identifiability::Global;
            }
            v.at_most = !exact && matches!(v.verdict, Identifiability::Local(_));
            v
        })
        .collect();
    Ok(GlobalReport {
        variables,
        solutions: if tangents {
            kernel.or(a.joint)
        } else {
            a.joint
        },
        all_local,
        maps: maps_out,
        group_order: group,
        solutions_at_most: kernel.is_none() && !exact && a.joint.is_some_and(|k| k > 1),
        output_forms: nf
            .outputs
            .iter()
            .zip(&m.forms)
            .map(|(o, f)| (o.0.clone(), f.clone()))
            .collect(),
        order: a.orders.iter().copied().max().unwrap_or(0),
        rank_order: a.rank_order,
        output_orders: nf
            .outputs
            .iter()
            .zip(&a.orders)
            .map(|(o, &k)| (o.0.clone(), k))
            .collect(),
        delta_local: bounds.0,
        log10_delta_global: bounds.1,
        error_bound: bounds.2,
        unknowns: a.unknowns,
        equations: a.equations,
        primes,
        route: if lie { Route::Lie } else { Route::Taylor },
        fallback: None,
        io_sizes: Vec::new(),
        multi_experiment: false,
        states_after_io: None,
    })
}

/// SIAN's two runs (one per prime, each at its own random point drawn from
/// `seed + run`), on two threads when `parallel` and the machine has two
/// cores (else one after the other, each with the whole budget). Each
/// thread holds at most half the memory budget, so the two together stay
/// within it; a run that passes its half is redone alone with the whole
/// budget. The answer is the sequential one: a budget only stops a run,
/// never changes what it computes, so a run that finished (or stopped for
/// another reason) under half the budget does the same under all of it.
fn taylor_runs(
    m: &model::ZModel,
    primes: &[u64; 2],
    kmax: usize,
    opts: &GlobalOptions,
    parallel: bool,
    kept: &mut Prolonged,
) -> Result<Vec<count::Counts>, AnalysisError> {
    if kept.key != Some((opts.seed, kmax)) {
        *kept = Prolonged {
            key: Some((opts.seed, kmax)),
            ..Prolonged::default()
        };
    }
    let one = |slot: &mut Option<Run>,
               r: usize,
               o: &GlobalOptions|
     -> Result<count::Counts, AnalysisError> {
        let mut run = match slot.take() {
            Some(run) => run,
            None => Run::new(m, primes[r], opts.seed.wrapping_add(r as u64), kmax)?,
        };
        run.rewind();
        run.max_bytes = o.max_bytes;
        let counts = count_once(&mut run, o);
        *slot = Some(run);
        counts
    };
    let [s0, s1] = &mut kept.runs;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (mut a, mut b) = if parallel && cores >= 2 {
        let half = GlobalOptions {
            max_bytes: opts.max_bytes / 2,
            ..opts.clone()
        };
        std::thread::scope(|s| {
            let second = s.spawn(|| one(s1, 1, &half));
            let a = one(s0, 0, &half);
            let b = second
                .join()
                .unwrap_or_else(|_| Err(err("global: the second run's thread panicked")));
            (Some(a), Some(b))
        })
    } else {
        (None, None)
    };
    let over = |r: &Option<Result<count::Counts, AnalysisError>>| match r {
        None => true,
        Some(Err(AnalysisError::Invalid(why))) => why.starts_with("too large"),
        Some(_) => false,
    };
    // A run on its own takes the whole memory budget: the other's kept
    // derivatives go first (one run held at a time, as before they were
    // kept).
    if over(&a) {
        *s1 = None;
        a = Some(one(s0, 0, opts));
    }
    let a = a.unwrap_or_else(|| Err(err("global: no first run")))?;
    if over(&b) {
        *s0 = None;
        b = Some(one(s1, 1, opts));
    }
    let b = b.unwrap_or_else(|| Err(err("global: no second run")))?;
    Ok(vec![a, b])
}

/// The Taylor runs' prolonged systems (their derivatives, functions of the
/// model, the seed and the prepared order alone) kept across `--route
/// auto`'s Taylor attempts on one model: each attempt rewinds a kept run
/// (`Run::rewind`), so it counts exactly as a fresh one would, without
/// deriving again (TranAlRadhawi derived its system in about 4 s per
/// attempt). Never shared between models (the initial states' attempt with
/// params fixed builds its own).
#[derive(Default)]
struct Prolonged {
    /// The seed and the prepared order the runs were made for.
    key: Option<(u64, usize)>,
    runs: [Option<Run>; 2],
}

impl Prolonged {
    fn held_bytes(&self) -> usize {
        self.runs.iter().flatten().map(Run::held_bytes).sum()
    }
}

/// Rank over F_2 of the maps' sign vectors (`-1` as 1), each map's signs on
/// the angle outputs (all proven, at most 64 outputs).
fn sign_rank(signs: &[Vec<Option<i8>>]) -> u32 {
    let mut rows: Vec<u64> = signs
        .iter()
        .map(|s| {
            s.iter()
                .enumerate()
                .filter(|(_, x)| **x == Some(-1))
                .fold(0u64, |acc, (j, _)| acc | (1u64 << j))
        })
        .collect();
    let mut rank = 0;
    for bit in 0..64 {
        let Some(p) = rows.iter().position(|r| r >> bit & 1 == 1) else {
            continue;
        };
        let pivot = rows.swap_remove(p);
        for r in rows.iter_mut() {
            if *r >> bit & 1 == 1 {
                *r ^= pivot;
            }
        }
        rank += 1;
    }
    rank
}

#[cfg(test)]
mod tests;
