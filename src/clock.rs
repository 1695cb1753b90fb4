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

/// Where the clock sits in a normal form: its state index and its output.
#[derive(Clone, Copy, Debug)]
pub struct Clock {
    pub state: usize,
    pub output: usize,
}

impl Clock {
    pub fn of(nf: &NormalForm) -> Option<Clock> {
        let state = nf.clock()?;
        let output = nf.outputs.iter().position(|o| o.0 == obsan_model::TIME)?;
        Some(Clock { state, output })
    }

    /// `v` (one entry per analysed variable) without the clock's entry.
    pub fn drop<T: Clone>(&self, v: &[T]) -> Vec<T> {
        v.iter()
            .enumerate()
            .filter(|(i, _)| *i != self.state)
            .map(|(_, x)| x.clone())
            .collect()
    }

    /// The clock's own row: its output at order 0.
    fn is_row(&self, w: &LieWord) -> bool {
        w.output == self.output && w.order() == 0
    }

    /// What both reports hold alike: the clock's row out of the basis (and
    /// the rank), its state out of `n` and of the per-variable verdicts.
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
        *n -= 1;
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
    r.pivots.retain(|&p| p != c.state);
    for p in r.pivots.iter_mut() {
        if *p > c.state {
            *p -= 1;
        }
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
    m.rank = m.rank.saturating_sub(1);
    m.n = m.n.saturating_sub(1);
    m.dimension = m.dimension.saturating_sub(1);
    m.codistribution_rank = m.codistribution_rank.saturating_sub(1);
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
    v.n_dynamic -= 1;
    Some(v)
}

/// A known-input symmetry report about the user's states: the clock's
/// component of every vector is zero (each symmetry leaves the output `t`
/// invariant), so it is dropped; the ranks as in [`hide_in_rank`].
pub fn hide_in_symmetries(nf: &NormalForm, r: &mut RankReport, s: &mut SymmetryReport) {
    let Some(c) = Clock::of(nf) else { return };
    hide_in_rank(nf, r);
    s.n -= 1;
    s.rank = s.rank.saturating_sub(1);
    for v in s.vectors.iter_mut() {
        *v = c.drop(v);
    }
    let shift = |j: usize| if j > c.state { j - 1 } else { j };
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
    s.free = s
        .free
        .iter()
        .map(|&j| if j > c.state { j - 1 } else { j })
        .collect();
}
