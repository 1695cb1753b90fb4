//! `obsan rank --along`: the windows' verdicts gathered into degenerate
//! stretches, each named by its inputs' relations and matched against the
//! exact symmetries of the model restricted to those inputs; and the rank of
//! the whole dataset (every trajectory's own start, shared params).

use crate::along::{numerical_rank, windows, AlongOptions, AlongTrajectory, AlongWindow, Wholes};
use crate::along_sym::{compare, input_span, Cache, InputSpan, SymmetryMatch};
use crate::rank::AnalysisError;
use obsan_model::NormalForm;

/// Consecutive degenerate windows of one trajectory with the same rank and
/// the same input relations.
#[derive(Clone, Debug)]
pub struct AlongStretch {
    pub trajectory: usize,
    pub t0: f64,
    pub t1: f64,
    /// Indices into [`AlongReport::windows`].
    pub windows: Vec<usize>,
    pub rank: usize,
    /// The first window's kernel (unit vectors, state order).
    pub kernel: Vec<Vec<f64>>,
    pub inputs: InputSpan,
    /// The first window's kernel against the restricted model's symmetries.
    pub symmetry: SymmetryMatch,
}

/// The whole dataset as one experiment: rows of every trajectory, columns
/// the shared params then each trajectory's own initial dynamic state.
#[derive(Clone, Debug)]
pub struct DatasetRank {
    /// Column names: params, then `x@trajectory`.
    pub columns: Vec<String>,
    pub singular_values: Vec<f64>,
    pub tolerance: f64,
    pub rank: usize,
    pub kernel: Vec<Vec<f64>>,
}

#[derive(Clone, Debug)]
pub struct AlongReport {
    pub n: usize,
    pub windows: Vec<AlongWindow>,
    /// Per window: the relations of its inputs.
    pub inputs: Vec<InputSpan>,
    pub stretches: Vec<AlongStretch>,
    pub dataset: DatasetRank,
}

/// Observability along every trajectory (module docs of `along.rs`).
pub fn along(
    nf: &mut NormalForm,
    trajs: &[AlongTrajectory],
    opts: &AlongOptions,
) -> Result<AlongReport, AnalysisError> {
    if !(opts.window > 0.0 && opts.window.is_finite()) {
        return Err(AnalysisError::Invalid(format!(
            "the window length must be a positive number of seconds, not {}",
            opts.window
        )));
    }
    let n = nf.state.len();
    let m = nf.inputs.len();
    let (wins, wholes) = windows(nf, trajs, opts)?;
    let spans: Vec<InputSpan> = wins.iter().map(|w| input_span(&w.input_rows, m)).collect();
    let mut cache = Cache::default();
    let mut stretches: Vec<AlongStretch> = Vec::new();
    for (i, w) in wins.iter().enumerate() {
        if w.rank == n {
            continue;
        }
        if let Some(s) = stretches.last_mut() {
            let prev = *s.windows.last().unwrap_or(&usize::MAX);
            if prev + 1 == i
                && s.trajectory == w.trajectory
                && s.rank == w.rank
                && spans[prev].basis == spans[i].basis
                && wins[prev].outputs_seen == w.outputs_seen
            {
                s.windows.push(i);
                s.t1 = w.t1;
                continue;
            }
        }
        let sym = cache.get(nf, &spans[i], &w.outputs_seen, opts.deadline)?;
        stretches.push(AlongStretch {
            trajectory: w.trajectory,
            t0: w.t0,
            t1: w.t1,
            windows: vec![i],
            rank: w.rank,
            kernel: w.kernel.clone(),
            inputs: spans[i].clone(),
            symmetry: compare(w, &trajs[w.trajectory].consts, sym),
        });
    }
    let dataset = dataset_rank(nf, trajs, &wholes);
    Ok(AlongReport {
        n,
        windows: wins,
        inputs: spans,
        stretches,
        dataset,
    })
}

/// Stack each trajectory's rows (sensitivity to its own start and the
/// params) into one matrix: params shared, initial states apart.
fn dataset_rank(nf: &NormalForm, trajs: &[AlongTrajectory], wholes: &Wholes) -> DatasetRank {
    let (n, nd) = (nf.state.len(), nf.n_dynamic);
    let np = n - nd;
    let mut columns: Vec<String> = nf.state[nd..].to_vec();
    for t in trajs {
        for s in &nf.state[..nd] {
            columns.push(format!("{s}@{}", t.name));
        }
    }
    let width = columns.len();
    let place = |which: usize| -> Vec<Vec<f64>> {
        let mut out = Vec::new();
        for (ti, w) in wholes.iter().enumerate() {
            for r in &w[which] {
                let mut row = vec![0.0; width];
                row[..np].copy_from_slice(&r[nd..]);
                row[np + ti * nd..np + (ti + 1) * nd].copy_from_slice(&r[..nd]);
                out.push(row);
            }
        }
        out
    };
    let (fine, coarse) = (place(0), place(1));
    let (s, tol, rank, v) = numerical_rank(&fine, &coarse, width);
    DatasetRank {
        columns,
        singular_values: s,
        tolerance: tol,
        rank,
        kernel: v[rank..].to_vec(),
    }
}
