//! The physical range of a generated param: a fitted value outside it is a
//! failed fit (a local optimum, a stand-in for something else), never a
//! finding, as a lag longer than the trajectory is not.

use obsan_data::Dataset;

/// Prefix of the session clocks of the drift family: an input declared
/// without a definition whose name starts with this, absent from the data,
/// is filled by [`crate::prepare`] with the time since the dataset's first
/// input row, in s (one clock over every trajectory: wear accumulates over
/// the session, not per trajectory).
pub(crate) const SESSION_CLOCK: &str = "session_t";

/// How a limit reads the columns it names (outputs, or measured inputs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Reading {
    /// The value is multiplied by the largest measured |y|.
    MaxAbs,
    /// The value is divided by the spread (max - min) of the measured y.
    Spread,
}

/// `|param| x (session span, if per_second) x (the columns' reading) <=
/// bound`, the product being what `what` says in words.
#[derive(Clone, Debug)]
pub(crate) struct Limit {
    pub(crate) param: String,
    pub(crate) bound: f64,
    pub(crate) per_second: bool,
    /// Outputs, or measured inputs, of the data read as `Reading` says.
    pub(crate) columns: Option<(Vec<String>, Reading)>,
    pub(crate) what: String,
}

impl Limit {
    /// The reason `estimates` (name, value, sd) break the limit on `data`,
    /// or `None`. A param not among them breaks nothing.
    pub(crate) fn violated(
        &self,
        estimates: &[(String, f64, f64)],
        data: &Dataset,
    ) -> Option<String> {
        let v = estimates.iter().find(|e| e.0 == self.param)?.1;
        let mut x = v.abs();
        if self.per_second {
            x *= session(data).1;
        }
        if let Some((ys, r)) = &self.columns {
            let (max_abs, spread) = readings(data, ys);
            x = match r {
                Reading::MaxAbs => x * max_abs,
                Reading::Spread if spread > 0.0 => x / spread,
                Reading::Spread => f64::INFINITY,
            };
        }
        (x.is_nan() || x > self.bound).then(|| {
            format!(
                "{} = {v:.3e}: {} would be {x:.3}, beyond the physical range {}: a failed fit, not a finding",
                self.param, self.what, self.bound
            )
        })
    }
}

/// The session's first input time and its span (last input time less
/// first, over every trajectory), in the data's time unit.
pub(crate) fn session(data: &Dataset) -> (f64, f64) {
    let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
    for tr in &data.trajectories {
        let t = tr.inputs.t();
        if let (Some(f), Some(l)) = (t.first(), t.last()) {
            a = a.min(*f);
            b = b.max(*l);
        }
    }
    if a.is_finite() && b.is_finite() {
        (a, b - a)
    } else {
        (0.0, 0.0)
    }
}

/// The largest |y| and the spread of the measured values of `ys`, each an
/// output or else a measured input.
fn readings(data: &Dataset, ys: &[String]) -> (f64, f64) {
    let (mut lo, mut hi, mut m) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for tr in &data.trajectories {
        for y in ys {
            let col = tr.outputs.column(y).or_else(|| tr.inputs.column(y));
            for v in col.unwrap_or(&[]).iter().flatten() {
                lo = lo.min(*v);
                hi = hi.max(*v);
                m = m.max(v.abs());
            }
        }
    }
    (m, if hi >= lo { hi - lo } else { 0.0 })
}
