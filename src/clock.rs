//! Explicit time `t` in what the commands print, and the refusal of the
//! commands that do not handle it yet (docs/sys-format.md, "Explicit time").
//!
//! A model whose fields or outputs use `t` is analysed with a clock: the
//! state `t` with `t' = 1` and the known output `t` (the normal form appends
//! both, the output first so that its row `dt` opens every basis). A verdict
//! is then about the user's states along a trajectory on which time is known;
//! the clock is the analysis' coordinate, never reported as a state: it is
//! left out of the state lists, and its row out of the ranks and bases.

use crate::Failure;
use obsan_analysis::{
    unknown_inputs::UnknownInputReport, unknown_inputs::UnknownInputSymmetries, Certificate,
    LieWord, RankReport, SymmetryKind, SymmetryReport,
};
use obsan_model::{NormalForm, System};
use std::cell::Cell;

thread_local! {
    /// The command being run, as the user typed it (set by `dispatch`), for
    /// located refusals that name it.
    static COMMAND: Cell<&'static str> = const { Cell::new("") };
}

/// The commands that handle explicit time.
const HANDLED: [&str; 6] = ["show", "rank", "symmetries", "simulate", "modes", "verify"];

/// Note the command being run on this thread (see [`refuse_time`]).
pub fn set_command(name: &'static str) {
    COMMAND.with(|c| c.set(name));
}

/// A located refusal (at the first `t`, exit code 2) when the system uses
/// explicit time and the command being run does not handle it.
pub fn refuse_time(sys: &System) -> Result<(), Failure> {
    let command = COMMAND.with(Cell::get);
    if HANDLED.contains(&command) {
        return Ok(());
    }
    let what = if command.is_empty() {
        "this command".to_string()
    } else {
        format!("`obsan {command}`")
    };
    match sys.time_refusal(&what) {
        Some(e) => Err(Failure(e.to_string())),
        None => Ok(()),
    }
}

/// The commands that handle outputs reading known inputs (the normal form
/// measures those inputs: docs/sys-format.md, "Outputs that read inputs").
/// `modes` and `verify` refuse: their reduced systems and decomposition files
/// would carry the measured coordinates as modes, not yet specified.
/// `simulate` evaluates `h(x, u(t))` (`sim_drive.rs`).
const HANDLED_MEASURED: [&str; 5] = ["show", "rank", "symmetries", "global", "simulate"];

/// A located refusal (at the first input an output reads, exit code 2) when
/// the command being run does not handle outputs that read known inputs.
pub fn refuse_measured(sys: &System) -> Result<(), Failure> {
    let command = COMMAND.with(Cell::get);
    if HANDLED_MEASURED.contains(&command) {
        return Ok(());
    }
    let what = if command.is_empty() {
        "this command".to_string()
    } else {
        format!("`obsan {command}`")
    };
    match sys.input_output_refusal(&what) {
        Some(e) => Err(Failure(format!(
            "{e}\n(`obsan rank`, `symmetries`, `global`, `show` and `simulate MODEL.sys` handle them)"
        ))),
        None => Ok(()),
    }
}

/// The line saying which known inputs the outputs read and what the
/// analysis assumes of them; `None` when no output reads one.
pub fn measured_note(nf: &NormalForm) -> Option<String> {
    let m = &nf.measured_inputs;
    if m.is_empty() {
        return None;
    }
    let d: Vec<String> = m
        .iter()
        .map(|u| format!("{u}{}", obsan_model::DERIVATIVE_MARK))
        .collect();
    Some(format!(
        "outputs read the known input{} {}: measured, with {} known too (each input a coordinate \
         known from its own output, its derivative a known input; verdicts about the other variables)",
        if m.len() == 1 { "" } else { "s" },
        m.join(", "),
        d.join(", ")
    ))
}

/// The analysis' own coordinates in a normal form: the clock and the known
/// inputs that outputs read (measured coordinates, obsan-model's
/// `measured.rs`): each a dynamic state with an output of its own name whose
/// order-0 row opens the basis. Their state indices (ascending) and outputs.
#[derive(Clone, Debug)]
pub struct Clock {
    pub states: Vec<usize>,
    pub outputs: Vec<usize>,
}

impl Clock {
    pub fn of(nf: &NormalForm) -> Option<Clock> {
        let mut names: Vec<&str> = nf.measured_inputs.iter().map(String::as_str).collect();
        if nf.clock().is_some() {
            names.push(obsan_model::TIME);
        }
        let mut states = Vec::new();
        let mut outputs = Vec::new();
        for n in names {
            let k = nf.state[..nf.n_dynamic].iter().position(|s| s == n)?;
            states.push(k);
            outputs.push(nf.outputs.iter().position(|o| o.0 == n)?);
        }
        states.sort_unstable();
        (!states.is_empty()).then_some(Clock { states, outputs })
    }

    /// `v` (one entry per analysed variable) without the hidden entries.
    pub fn drop<T: Clone>(&self, v: &[T]) -> Vec<T> {
        v.iter()
            .enumerate()
            .filter(|(i, _)| !self.states.contains(i))
            .map(|(_, x)| x.clone())
            .collect()
    }

    /// Index `j` of a kept variable in the list without the hidden ones.
    fn shift(&self, j: usize) -> usize {
        j - self.states.iter().filter(|&&k| k < j).count()
    }

    /// A hidden coordinate's own row: its output at order 0.
    fn is_row(&self, w: &LieWord) -> bool {
        self.outputs.contains(&w.output) && w.order() == 0
    }

    /// What both reports hold alike: the hidden rows out of the basis (and
    /// the rank), their states out of `n` and of the per-variable verdicts.
    /// The rows dropped.
    fn hide<T: Clone>(
        &self,
        basis: &mut Vec<LieWord>,
        rank: &mut usize,
        n: &mut usize,
        observable: &mut Vec<T>,
    ) -> usize {
        let before = basis.len();
        basis.retain(|w| !self.is_row(w));
        let dropped = before - basis.len();
        *rank -= dropped.min(*rank);
        *n -= self.states.len();
        *observable = self.drop(observable);
        dropped
    }
}

/// A known-input rank report about the user's states. The clock's row `dt`
/// is in the codistribution (it opens the basis), so the rank over the user's
/// states is one less: each other row minus its `t` component along `dt`.
pub fn hide_in_rank(nf: &NormalForm, r: &mut RankReport) {
    let Some(c) = Clock::of(nf) else { return };
    c.hide(&mut r.basis, &mut r.rank, &mut r.n, &mut r.observable);
    r.pivots.retain(|p| !c.states.contains(p));
    for p in r.pivots.iter_mut() {
        *p = c.shift(*p);
    }
}

/// The same for the report with unknown inputs (both routes, every order:
/// `dt` is in the span from order 0 on).
pub fn hide_in_unknown_input(nf: &NormalForm, r: &mut UnknownInputReport) {
    let Some(c) = Clock::of(nf) else { return };
    let dropped = c.hide(&mut r.basis, &mut r.rank, &mut r.n, &mut r.observable);
    for s in r.steps.iter_mut() {
        s.rank -= dropped.min(s.rank);
        s.state_rank -= dropped.min(s.state_rank);
    }
    let m = &mut r.martinelli;
    let h = c.states.len();
    m.rank = m.rank.saturating_sub(h);
    m.n = m.n.saturating_sub(h);
    m.dimension = m.dimension.saturating_sub(h);
    m.codistribution_rank = m.codistribution_rank.saturating_sub(h);
    m.observable = c.drop(&m.observable);
}

/// A copy of `nf` for printing, whose state is the user's (the clock left
/// out); `None` without a clock. Its fields keep the clock's entries: use it
/// for names, not for computing.
pub fn user_view(nf: &NormalForm) -> Option<NormalForm> {
    let c = Clock::of(nf)?;
    let mut v = nf.clone();
    v.state = c.drop(&nf.state);
    v.state_vars = c.drop(&nf.state_vars);
    v.n_dynamic -= c.states.len();
    Some(v)
}

/// A known-input symmetry report about the user's states: the clock's
/// component of every vector is zero (each symmetry leaves the output `t`
/// invariant), so it is dropped; the ranks as in [`hide_in_rank`].
pub fn hide_in_symmetries(nf: &NormalForm, r: &mut RankReport, s: &mut SymmetryReport) {
    let Some(c) = Clock::of(nf) else { return };
    hide_in_rank(nf, r);
    s.n -= c.states.len();
    s.rank = s.rank.saturating_sub(c.states.len());
    for v in s.vectors.iter_mut() {
        *v = c.drop(v);
    }
    let shift = |j: usize| c.shift(j);
    s.free = s.free.iter().map(|&j| shift(j)).collect();
    if let Certificate::Invariance(kinds) = &mut s.certificate {
        for k in kinds.iter_mut() {
            if let SymmetryKind::Free(j) = k {
                *j = shift(*j);
            }
        }
    }
}

/// The same for a symmetry report with unknown inputs.
pub fn hide_in_unknown_input_symmetries(nf: &NormalForm, s: &mut UnknownInputSymmetries) {
    let Some(c) = Clock::of(nf) else { return };
    hide_in_unknown_input(nf, &mut s.report);
    for v in s.vectors.iter_mut() {
        *v = c.drop(v);
    }
    s.free = s.free.iter().map(|&j| c.shift(j)).collect();
}
