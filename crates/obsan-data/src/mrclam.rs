//! The UTIAS Multi-Robot Cooperative Localization and Mapping data set
//! (Leung, Halpern, Barfoot, Liu, IJRR 2011) in obsan's data format, for
//! `systems/mrclam.sys`: a unicycle driven by the commanded (v, omega)
//! observing known landmarks by range and bearing.
//!
//! Dead reckoning over a 30-minute log diverges, so the log is cut into
//! windows, each a trajectory with its own initial state (fitted from its
//! own measurements); the params (odometry and sensor errors) are shared.
//! Text in, dataset out: no file I/O here.

use crate::angle::wrap;
use crate::data::{Dataset, DatasetMeta, Series, Trajectory};
use crate::error::{DataError, DataErrorKind as K};
use std::collections::BTreeMap;

/// One robot's files, as text, with the names used in messages.
pub struct MrclamText<'a> {
    pub odometry: (&'a str, &'a str),
    pub measurements: (&'a str, &'a str),
    pub landmarks: (&'a str, &'a str),
    /// Ground truth (t, x, y, theta): kept apart, for the comparison only.
    pub groundtruth: Option<(&'a str, &'a str)>,
}

/// Ground truth of one window, for checking estimates afterwards (no
/// estimator reads it): distance travelled and heading change by the Vicon
/// poses and by the commanded odometry.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WindowTruth {
    pub name: String,
    pub truth_distance: f64,
    pub commanded_distance: f64,
    pub truth_turn: f64,
    pub commanded_turn: f64,
    /// Pose at the window's start.
    pub start: [f64; 3],
}

fn rows<'a>(
    text: &'a str,
    file: &'a str,
    ncols: usize,
) -> impl Iterator<Item = Result<(usize, Vec<f64>), DataError>> + 'a {
    text.lines().enumerate().filter_map(move |(i, l)| {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            return None;
        }
        let v: Result<Vec<f64>, DataError> = l
            .split_whitespace()
            .enumerate()
            .map(|(c, x)| {
                x.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        DataError::new(
                            file,
                            Some(i + 1),
                            Some(format!("{}", c + 1)),
                            K::NotFinite(x.to_string()),
                        )
                    })
            })
            .collect();
        Some(v.and_then(|v| {
            if v.len() < ncols {
                Err(DataError {
                    file: file.into(),
                    row: Some(i + 1),
                    column: None,
                    kind: K::ColumnCount {
                        expected: ncols,
                        found: v.len(),
                    },
                })
            } else {
                Ok((i + 1, v))
            }
        }))
    })
}

/// The ground-truth rows with start <= t <= end, in file order.
fn in_window(
    gt: &[(f64, f64, f64, f64)],
    sorted: bool,
    start: f64,
    end: f64,
) -> Box<dyn Iterator<Item = &(f64, f64, f64, f64)> + '_> {
    if sorted {
        let lo = gt.partition_point(|g| g.0 < start);
        let hi = gt.partition_point(|g| g.0 <= end);
        Box::new(gt[lo..hi].iter())
    } else {
        Box::new(gt.iter().filter(move |g| g.0 >= start && g.0 <= end))
    }
}

/// Landmarks (barcode, x, y) of `Landmark_Groundtruth.dat`.
pub fn landmarks(text: &str, file: &str) -> Result<Vec<(u32, f64, f64)>, DataError> {
    rows(text, file, 3)
        .map(|r| r.map(|(_, v)| (v[0] as u32, v[1], v[2])))
        .collect()
}

/// Vicon poses as outputs (`px`, `py`, `pth`) are sampled this often.
pub const POSE_INTERVAL: f64 = 0.5;

/// What a window's outputs are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MrclamOutputs {
    /// The landmark ranges and bearings (`systems/mrclam.sys`).
    Landmarks,
    /// The Vicon poses every [`POSE_INTERVAL`] s (`systems/mrclam-pose.sys`):
    /// the ground truth's own answer to the same questions, for checking
    /// what the landmark data give. Same windows as `Landmarks`.
    ViconPoses,
}

/// The most windows a log may be cut into.
const MAX_WINDOWS: f64 = 1e6;

/// A ground-truth row (t, x, y, theta).
type Pose = (f64, f64, f64, f64);

/// One robot's log, read and checked: the windows are cut from it.
struct Log {
    /// Landmarks (barcode, x, y).
    lms: Vec<(u32, f64, f64)>,
    /// Odometry (t, v, omega), in time order (checked).
    odo: Vec<(f64, f64, f64)>,
    /// Landmark observations (t, barcode, range, bearing), sorted by time;
    /// other robots' barcodes dropped.
    meas: Vec<(f64, u32, f64, f64)>,
    gt: Vec<Pose>,
    /// Whether `gt` is in time order (as shipped): then cut by bisection.
    gt_sorted: bool,
    /// The output columns: `r<barcode>` for each landmark, then `b<barcode>`.
    cols: Vec<String>,
}

fn no_rows(file: &str, kind: K) -> DataError {
    DataError {
        file: file.into(),
        row: None,
        column: None,
        kind,
    }
}

/// The odometry rows (t, v, omega); time must not run backwards.
fn read_odometry(text: &str, file: &str) -> Result<Vec<(f64, f64, f64)>, DataError> {
    let mut odo: Vec<(f64, f64, f64)> = Vec::new();
    for r in rows(text, file, 3) {
        let (line, v) = r?;
        if let Some(last) = odo.last() {
            if v[0] < last.0 {
                return Err(DataError {
                    file: file.into(),
                    row: Some(line),
                    column: Some("1".into()),
                    kind: K::LogTimeBackwards {
                        t: v[0],
                        prev: last.0,
                    },
                });
            }
        }
        odo.push((v[0], v[1], v[2]));
    }
    if odo.len() < 2 {
        return Err(no_rows(file, K::TooFewOdometryRows));
    }
    Ok(odo)
}

/// The observations of the given landmarks, sorted by time.
fn read_measurements(
    text: &str,
    file: &str,
    lms: &[(u32, f64, f64)],
) -> Result<Vec<(f64, u32, f64, f64)>, DataError> {
    let mut meas: Vec<(f64, u32, f64, f64)> = Vec::new();
    for r in rows(text, file, 4) {
        let (_, v) = r?;
        let code = v[1] as u32;
        // Other robots' barcodes are not landmarks: skipped.
        if lms.iter().any(|l| l.0 == code) {
            meas.push((v[0], code, v[2], v[3]));
        }
    }
    meas.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(meas)
}

impl Log {
    fn read(t: &MrclamText) -> Result<Log, DataError> {
        let lms = landmarks(t.landmarks.0, t.landmarks.1)?;
        if lms.is_empty() {
            return Err(no_rows(t.landmarks.1, K::NoLandmarks));
        }
        let odo = read_odometry(t.odometry.0, t.odometry.1)?;
        let meas = read_measurements(t.measurements.0, t.measurements.1, &lms)?;
        let gt: Vec<Pose> = match &t.groundtruth {
            Some((text, file)) => rows(text, file, 4)
                .map(|r| r.map(|(_, v)| (v[0], v[1], v[2], v[3])))
                .collect::<Result<_, _>>()?,
            None => vec![],
        };
        // Ground truth in time order (as shipped) is cut by bisection too;
        // otherwise each window scans it, in file order, as before.
        let gt_sorted = gt.windows(2).all(|w| w[0].0 <= w[1].0);
        let cols = (lms.iter().map(|(code, _, _)| format!("r{code}")))
            .chain(lms.iter().map(|(code, _, _)| format!("b{code}")))
            .collect();
        Ok(Log {
            lms,
            odo,
            meas,
            gt,
            gt_sorted,
            cols,
        })
    }

    /// The ground-truth rows with start <= t <= end, in file order.
    fn poses(&self, start: f64, end: f64) -> Box<dyn Iterator<Item = &Pose> + '_> {
        in_window(&self.gt, self.gt_sorted, start, end)
    }

    /// The window [a, b) as the trajectory `name`, or `None` when it has
    /// fewer than two odometry rows, fewer than `min_measurements`
    /// observations, or (for Vicon outputs) fewer than two poses.
    fn window(
        &self,
        name: String,
        (a, b): (f64, f64),
        min_measurements: usize,
        what: MrclamOutputs,
    ) -> Option<Trajectory> {
        let mut inputs = Series::new(vec!["v".into(), "omega".into()]);
        // The logs are in time order (odometry checked, measurements
        // sorted): a window is a slice, found by bisection, so the import
        // is linear in the log's size, not windows x rows.
        let odo = &self.odo;
        let (lo, hi) = (
            odo.partition_point(|o| o.0 < a),
            odo.partition_point(|o| o.0 < b),
        );
        for &(t, v, w) in &odo[lo..hi] {
            inputs.push(t, &[Some(v), Some(w)]);
        }
        if inputs.len() < 2 {
            return None;
        }
        let start = inputs.t()[0];
        let end = inputs.t()[inputs.len() - 1];
        let (outputs, n_meas) = self.observations(start, end);
        if n_meas < min_measurements {
            return None;
        }
        let outputs = match what {
            MrclamOutputs::Landmarks => outputs,
            MrclamOutputs::ViconPoses => {
                let mut poses = Series::new(vec!["px".into(), "py".into(), "pth".into()]);
                let mut last = f64::NEG_INFINITY;
                for g in self.poses(start, end) {
                    if g.0 >= last + POSE_INTERVAL - 1e-9 {
                        poses.push(g.0, &[Some(g.1), Some(g.2), Some(g.3)]);
                        last = g.0;
                    }
                }
                if poses.len() < 2 {
                    return None;
                }
                poses
            }
        };
        let mut meta = BTreeMap::new();
        for (code, x, y) in &self.lms {
            meta.insert(format!("lx{code}"), *x);
            meta.insert(format!("ly{code}"), *y);
        }
        Some(Trajectory {
            name,
            inputs,
            outputs,
            meta,
        })
    }

    /// The landmark observations with start <= t <= end, one row each, and
    /// their number.
    fn observations(&self, start: f64, end: f64) -> (Series, usize) {
        let nl = self.lms.len();
        let mut outputs = Series::new(self.cols.clone());
        let mut n_meas = 0;
        let meas = &self.meas;
        let (lo, hi) = (
            meas.partition_point(|m| m.0 < start),
            meas.partition_point(|m| m.0 <= end),
        );
        for &(t, code, r, brg) in &meas[lo..hi] {
            // Only landmarks' codes were kept in `meas`.
            let Some(i) = self.lms.iter().position(|l| l.0 == code) else {
                continue;
            };
            let mut row = vec![None; 2 * nl];
            row[i] = Some(r);
            row[nl + i] = Some(brg);
            // Same time twice is allowed (two landmarks at once).
            outputs.push(t, &row);
            n_meas += 1;
        }
        (outputs, n_meas)
    }

    /// A window's ground truth beside its commanded odometry, `None`
    /// without ground truth or with fewer than two poses in it.
    fn truth(&self, traj: &Trajectory) -> Option<WindowTruth> {
        if self.gt.is_empty() {
            return None;
        }
        let inputs = &traj.inputs;
        let start = inputs.t()[0];
        let end = inputs.t()[inputs.len() - 1];
        // Vicon poses every 0.5 s: summing 100 Hz jitter would inflate the distance.
        let mut seg: Vec<&Pose> = Vec::new();
        for g in self.poses(start, end) {
            if seg.last().is_none_or(|l| g.0 >= l.0 + 0.5) {
                seg.push(g);
            }
        }
        if seg.len() < 2 {
            return None;
        }
        let dist: f64 = seg
            .windows(2)
            .map(|w| ((w[1].1 - w[0].1).powi(2) + (w[1].2 - w[0].2).powi(2)).sqrt())
            .sum();
        let turn: f64 = seg.windows(2).map(|w| wrap(w[1].3 - w[0].3)).sum();
        let (mut cd, mut ct) = (0.0, 0.0);
        for i in 0..inputs.len() {
            let dt = if i + 1 < inputs.len() {
                inputs.t()[i + 1] - inputs.t()[i]
            } else {
                end - inputs.t()[i]
            };
            cd += inputs.values()[0][i].unwrap_or(0.0).abs() * dt;
            ct += inputs.values()[1][i].unwrap_or(0.0) * dt;
        }
        Some(WindowTruth {
            name: traj.name.clone(),
            truth_distance: dist,
            commanded_distance: cd,
            truth_turn: turn,
            commanded_turn: ct,
            start: [seg[0].1, seg[0].2, seg[0].3],
        })
    }
}

/// Convert one robot's log into windows of `window` seconds (a window
/// needs at least `min_measurements` landmark observations, else it is
/// skipped). Output columns `r<barcode>`, `b<barcode>`; the landmark
/// positions are each window's constants `lx<barcode>`, `ly<barcode>`.
pub fn convert(
    t: &MrclamText,
    window: f64,
    min_measurements: usize,
    what: MrclamOutputs,
) -> Result<(Dataset, Vec<WindowTruth>), DataError> {
    if window.is_nan() || window <= 0.0 {
        return Err(no_rows("--window", K::BadWindow));
    }
    let log = Log::read(t)?;
    let (t0, t1) = (log.odo[0].0, log.odo[log.odo.len() - 1].0);
    // The window loop runs once per window: bound it (a tiny --window would
    // otherwise spin for hours over empty windows).
    if (t1 - t0) / window > MAX_WINDOWS {
        return Err(no_rows(
            "--window",
            K::TooManyWindows {
                window,
                span: t1 - t0,
                max: MAX_WINDOWS,
            },
        ));
    }
    let mut trajectories = Vec::new();
    let mut truths = Vec::new();
    let mut k = 0usize;
    loop {
        let (a, b) = (t0 + k as f64 * window, t0 + (k + 1) as f64 * window);
        if a >= t1 {
            break;
        }
        k += 1;
        let name = format!("w{:03}", k - 1);
        let Some(traj) = log.window(name, (a, b.min(t1)), min_measurements, what) else {
            continue;
        };
        truths.extend(log.truth(&traj));
        trajectories.push(traj);
    }
    if what == MrclamOutputs::ViconPoses && log.gt.is_empty() {
        return Err(no_rows(t.odometry.1, K::NeedsGroundTruth));
    }
    if trajectories.is_empty() {
        return Err(no_rows(
            t.measurements.1,
            K::NoWindow {
                window,
                min_measurements,
            },
        ));
    }
    let meta = DatasetMeta {
        model: Some(match what {
            MrclamOutputs::Landmarks => "systems/mrclam.sys".into(),
            MrclamOutputs::ViconPoses => "systems/mrclam-pose.sys".into(),
        }),
        ..DatasetMeta::default()
    };
    Ok((Dataset { meta, trajectories }, truths))
}

/// `systems/mrclam.sys`-style model text for the given landmark barcodes:
/// what the shipped file holds for the data set's 15 landmarks.
pub fn model_text(codes: &[u32]) -> String {
    let mut s = String::from(
        "# A unicycle driven by its commanded speed v and turn rate omega (MRCLAM odometry),\n\
         # observing known landmarks by range r<code> and bearing b<code> (Leung et al., IJRR 2011).\n\
         # Landmark positions are constants given per trajectory (meta.json, from `obsan import mrclam`).\n\
         system mrclam\n\
         description Unicycle with commanded (v, omega) observing known landmarks by range and bearing.\n\
         state x, y, th\n\
         input v, omega\n",
    );
    for c in codes {
        s.push_str(&format!("const lx{c}, ly{c}\n"));
    }
    s.push_str("\nx' = v*cos(th)\ny' = v*sin(th)\nth' = omega\n\n");
    for c in codes {
        s.push_str(&format!(
            "output r{c} = sqrt((lx{c} - x)^2 + (ly{c} - y)^2)\n"
        ));
    }
    for c in codes {
        s.push_str(&format!("output b{c} = atan2(ly{c} - y, lx{c} - x) - th\n"));
    }
    s
}
