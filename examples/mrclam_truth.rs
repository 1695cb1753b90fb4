//! The ground-truth figures of docs/diagnose.md ("Against the ground truth"),
//! computed from the raw MRCLAM files: what the Vicon poses say about the
//! odometry and the range sensor, independently of obsan's fits; and the
//! checks of the cascade `--generated` names (docs/diagnose.md, generated candidates): the bearings against the Vicon pose, the turn rate by speed,
//! the heading drift of the commanded odometry, and the bearing scale that
//! drift alone produces in a deterministic fit of a window.
//!
//! ```sh
//! cargo run --release --example mrclam_truth -- ../shared/data/mrclam
//! ```

use obsan_data::{mrclam_convert, mrclam_landmarks, MrclamOutputs, MrclamText};
use std::error::Error;

#[path = "support/ols.rs"]
mod ols;
use ols::{demean, ols, Ols};

type Rows = Vec<Vec<f64>>;

fn read_rows(path: &str) -> Result<Rows, Box<dyn Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {path}: {e}"))?;
    let mut out = Vec::new();
    for (i, l) in text.lines().enumerate() {
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let row: Result<Vec<f64>, _> = l.split_whitespace().map(str::parse::<f64>).collect();
        out.push(row.map_err(|e| format!("{path}:{}: {e}", i + 1))?);
    }
    Ok(out)
}

fn wrap(a: f64) -> f64 {
    a.sin().atan2(a.cos())
}

/// Least squares y = a x + b: (a, se(a), b, se(b)).
fn line(x: &[f64], y: &[f64]) -> (f64, f64, f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    let a = x
        .iter()
        .zip(y)
        .map(|(u, v)| (u - mx) * (v - my))
        .sum::<f64>()
        / sxx;
    let b = my - a * mx;
    let rss: f64 = x.iter().zip(y).map(|(u, v)| (v - b - a * u).powi(2)).sum();
    let s = (rss / (n - 2.0)).sqrt();
    (a, s / sxx.sqrt(), b, s * (1.0 / n + mx * mx / sxx).sqrt())
}

fn robot(dir: &str, r: u32) -> Result<(), Box<dyn Error>> {
    let file = |f: &str| format!("{dir}/robot{r}_{f}.txt");
    let text = |p: &str| std::fs::read_to_string(p).map_err(|e| format!("cannot read {p}: {e}"));
    let (odo_t, meas_t) = (text(&file("Odometry"))?, text(&file("Measurement"))?);
    let (gt_t, lm_path) = (
        text(&file("Groundtruth"))?,
        format!("{dir}/Landmark_Groundtruth.dat"),
    );
    let lm_t = text(&lm_path)?;
    let src = MrclamText {
        odometry: (&odo_t, "odometry"),
        measurements: (&meas_t, "measurements"),
        landmarks: (&lm_t, &lm_path),
        groundtruth: Some((&gt_t, "groundtruth")),
    };
    // 1. Window sums, as `obsan import mrclam` writes them to truth.json.
    let (ds, truth) = mrclam_convert(&src, 60.0, 30, MrclamOutputs::Landmarks)?;
    let dist: f64 = truth.iter().map(|w| w.truth_distance).sum::<f64>()
        / truth.iter().map(|w| w.commanded_distance).sum::<f64>();
    let ct: Vec<f64> = truth.iter().map(|w| w.commanded_turn).collect();
    let tt: Vec<f64> = truth.iter().map(|w| w.truth_turn).collect();
    let (a, sa, b, sb) = line(&ct, &tt);
    println!(
        "robot {r}: {} windows; distance truth/commanded {dist:.3}; turn truth = a commanded + b: a = {a:.3} ± {sa:.3}, b = {:.4} ± {:.4} rad/s",
        truth.len(),
        b / 60.0,
        sb / 60.0
    );
    // 2. Steady commands (unchanged 1 s before and after): Vicon motion
    //    over 0.5 s against the command.
    let gt = read_rows(&file("Groundtruth"))?;
    let od = read_rows(&file("Odometry"))?;
    let gts: Vec<f64> = gt.iter().map(|g| g[0]).collect();
    let (mut speed, mut turn) = (Vec::new(), Vec::new());
    for i in (50..od.len().saturating_sub(50)).step_by(10) {
        let (t, v, w) = (od[i][0], od[i][1], od[i][2]);
        if (i - 50..i + 50).any(|j| od[j][1] != v || od[j][2] != w) {
            continue;
        }
        let ga = gts.partition_point(|&x| x < t - 0.25);
        let gb = gts.partition_point(|&x| x < t + 0.25);
        if gb >= gt.len() || gt[gb][0] - gt[ga][0] < 0.4 {
            continue;
        }
        let dt = gt[gb][0] - gt[ga][0];
        if w.abs() > 0.1 {
            turn.push(wrap(gt[gb][3] - gt[ga][3]) / dt / w);
        }
        if v.abs() > 0.02 {
            let h = gt[ga][3] + 0.5 * wrap(gt[gb][3] - gt[ga][3]);
            let fwd = (gt[gb][1] - gt[ga][1]) * h.cos() + (gt[gb][2] - gt[ga][2]) * h.sin();
            speed.push(fwd / dt / v);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "  steady command: speed ratio {:.3} ({} samples), turn ratio {:.3} ({} samples)",
        median(&mut speed),
        speed.len(),
        median(&mut turn),
        turn.len()
    );
    // The lag of the best correlation between the commanded speed and the
    // Vicon forward speed (centred 0.1 s differences), on a 0.05 s grid.
    let vicon_speed: Vec<f64> = (0..od.len())
        .map(|i| {
            let t = od[i][0];
            let ga = gts.partition_point(|&x| x < t - 0.05).min(gt.len() - 1);
            let gb = gts.partition_point(|&x| x < t + 0.05).min(gt.len() - 1);
            let dt = gt[gb][0] - gt[ga][0];
            if dt <= 0.0 {
                return 0.0;
            }
            let h = gt[ga][3];
            ((gt[gb][1] - gt[ga][1]) * h.cos() + (gt[gb][2] - gt[ga][2]) * h.sin()) / dt
        })
        .collect();
    let corr = |lag: usize| {
        let (x, y): (Vec<f64>, Vec<f64>) = (0..od.len() - lag)
            .map(|i| (od[i][1], vicon_speed[i + lag]))
            .unzip();
        let n = x.len() as f64;
        let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
        let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
        let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
        sxy / (sxx * syy).sqrt()
    };
    // Odometry rows are 0.02 s apart: lags of 0, 0.05, ..., 0.5 s.
    let best = (0..=10)
        .map(|k| (k as f64 * 0.05, corr((k as f64 * 2.5).round() as usize)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((f64::NAN, f64::NAN));
    println!(
        "  commanded v to Vicon speed: best correlation {:.3} at a lag of {:.2} s",
        best.1, best.0
    );
    // 2b. Forward speed against the turn rate: 1 s blocks of
    //    commands, the Vicon forward distance over the same second 0.25 s
    //    later (the lag above), binned by the block's mean |omega|; and the
    //    least-squares c of v_true = v (1 + c |omega|) over the blocks.
    let (mut bins, mut sxx, mut sxy) = ([(0.0f64, 0.0f64, 0usize); 6], 0.0, 0.0);
    for b in (0..od.len().saturating_sub(63)).step_by(50) {
        let (t0, t1) = (od[b][0], od[b + 50][0]);
        let rows = &od[b..b + 50];
        let dc: f64 = rows.iter().map(|r| r[1] * 0.02).sum();
        let aw = rows.iter().map(|r| r[2].abs()).sum::<f64>() / 50.0;
        let ga = gts.partition_point(|&x| x < t0 + 0.25);
        let gb = gts.partition_point(|&x| x < t1 + 0.25);
        if dc < 0.02 || gb >= gt.len() || ga == 0 {
            continue;
        }
        let dv: f64 = (ga..gb)
            .map(|j| {
                let h = gt[j - 1][3];
                (gt[j][1] - gt[j - 1][1]) * h.cos() + (gt[j][2] - gt[j - 1][2]) * h.sin()
            })
            .sum();
        let k = ((aw / 0.1) as usize).min(5);
        bins[k].0 += dv;
        bins[k].1 += dc;
        bins[k].2 += 1;
        sxx += (dc * aw).powi(2);
        sxy += dc * aw * (dv - dc);
    }
    let text: Vec<String> = bins
        .iter()
        .enumerate()
        .filter(|(_, b)| b.2 > 0)
        .map(|(k, b)| {
            let hi = if k == 5 {
                "+".into()
            } else {
                format!("-{:.1}", 0.1 * (k + 1) as f64)
            };
            format!(
                "|omega| {:.1}{hi}: {:.3} ({})",
                0.1 * k as f64,
                b.0 / b.1,
                b.2
            )
        })
        .collect();
    println!(
        "  Vicon / commanded distance per 1 s block by mean |omega| (rad/s): {}",
        text.join(", ")
    );
    println!(
        "  v_true = v (1 + c |omega|) over the blocks: c = {:.3} s/rad",
        sxy / sxx
    );
    // 3. Ranges against the Vicon geometry (pose at the measurement time,
    //    surveyed landmark): ratios beyond 20% of the median dropped.
    let lms = mrclam_landmarks(&lm_t, &lm_path)?;
    let (mut rt, mut rm) = (Vec::new(), Vec::new());
    for m in read_rows(&file("Measurement"))? {
        let Some(l) = lms.iter().find(|l| l.0 == m[1] as u32) else {
            continue;
        };
        let i = gts.partition_point(|&x| x < m[0]);
        if i == 0 || i >= gt.len() {
            continue;
        }
        rt.push((l.1 - gt[i][1]).hypot(l.2 - gt[i][2]));
        rm.push(m[2]);
    }
    let mut ratios: Vec<f64> = rm.iter().zip(&rt).map(|(m, t)| m / t).collect();
    let med = median(&mut ratios);
    let keep: Vec<(f64, f64)> = rt
        .iter()
        .zip(&rm)
        .filter(|(t, m)| (*m / *t - med).abs() < 0.2)
        .map(|(t, m)| (*t, *m))
        .collect();
    let through0 =
        keep.iter().map(|(t, m)| t * m).sum::<f64>() / keep.iter().map(|(t, _)| t * t).sum::<f64>();
    let (xs, ys): (Vec<f64>, Vec<f64>) = keep.iter().copied().unzip();
    let (slope, _, icpt, _) = line(&xs, &ys);
    println!(
        "  ranges: {} measurements; r_meas / r_true {through0:.4} (through 0), affine slope {slope:.4}, offset {icpt:.3} m",
        rt.len()
    );
    // 4-7. The checks of the generated cascade, on the importer's windows.
    let windows: Vec<(f64, f64)> = ds
        .trajectories
        .iter()
        .map(|w| (w.inputs.t()[0], w.inputs.t()[w.inputs.len() - 1]))
        .collect();
    let (track, spikes) = Track::new(&gt);
    println!(
        "  Vicon heading spikes dropped: {spikes} of {} samples",
        gt.len()
    );
    let cum = Integral::new(&od, |_, w| w);
    let cum_v = Integral::new(&od, |v, w| w * v.abs());
    let bs = bearings(&track, &read_rows(&file("Measurement"))?, &lms, &windows);
    turn_by_speed(&track, &od, &windows);
    for sub in [60.0, 20.0, 10.0] {
        turn_by_window_fit(&track, &cum, &cum_v, &windows, sub);
    }
    heading_drift(&track, &cum, &windows, (a, b / 60.0));
    for sub in [60.0, 20.0, 10.0] {
        drift_as_scale(&bs, &track, &cum, &windows, sub);
    }
    pairwise_scale(&bs);
    Ok(())
}

// ---------------------------------------------------------------------------
// Vicon checks of the generated cascade: the bearings, the turn
// rate by speed, the heading drift, and what that drift does to a bearing
// scale fitted deterministically per window.

/// The Vicon lag of the commanded inputs (the best correlation above, and
/// the 0.25 s of the speed blocks).
const LAG: f64 = 0.25;
/// Bearing residuals beyond this (rad, about 10 sd) are misread barcodes.
const OUTLIER: f64 = 0.2;

/// The Vicon track with its heading unwrapped, interpolated linearly.
struct Track {
    t: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
    th: Vec<f64>,
}

impl Track {
    /// The Vicon headings have single-sample spikes near ±pi (3.133, 2.743,
    /// -3.138 in 0.04 s): a sample that turned faster than 3 rad/s since the
    /// last kept one is dropped (after 0.5 s of such the track resyncs).
    fn new(gt: &Rows) -> (Track, usize) {
        let mut k = Track {
            t: vec![],
            x: vec![],
            y: vec![],
            th: vec![],
        };
        let (mut dropped, mut last) = (0, 0.0);
        for g in gt {
            if let Some(&t) = k.t.last() {
                let d = wrap(g[3] - last);
                if d.abs() > 0.05 + 3.0 * (g[0] - t) && g[0] - t < 0.5 {
                    dropped += 1;
                    continue;
                }
                k.th.push(k.th[k.th.len() - 1] + d);
            } else {
                k.th.push(g[3]);
            }
            last = g[3];
            k.t.push(g[0]);
            k.x.push(g[1]);
            k.y.push(g[2]);
        }
        (k, dropped)
    }
    /// (x, y, unwrapped heading) at t, inside the track only.
    fn at(&self, t: f64) -> Option<[f64; 3]> {
        let i = self.t.partition_point(|&s| s < t);
        if i == 0 || i >= self.t.len() {
            return None;
        }
        let s = (t - self.t[i - 1]) / (self.t[i] - self.t[i - 1]);
        let l = |v: &[f64]| v[i - 1] + s * (v[i] - v[i - 1]);
        Some([l(&self.x), l(&self.y), l(&self.th)])
    }
}

/// The commanded turn integrated over the odometry log (omega held over
/// each 0.02 s row), interpolated.
struct Integral {
    t: Vec<f64>,
    c: Vec<f64>,
}

impl Integral {
    /// The integral of `f(v, omega)` (omega itself: the commanded turn).
    fn new(od: &Rows, f: impl Fn(f64, f64) -> f64) -> Integral {
        let mut c = vec![0.0];
        for w in od.windows(2) {
            c.push(c[c.len() - 1] + f(w[0][1], w[0][2]) * (w[1][0] - w[0][0]));
        }
        Integral {
            t: od.iter().map(|o| o[0]).collect(),
            c,
        }
    }
    fn at(&self, t: f64) -> f64 {
        let i = self
            .t
            .partition_point(|&s| s < t)
            .clamp(1, self.t.len() - 1);
        let s = ((t - self.t[i - 1]) / (self.t[i] - self.t[i - 1])).clamp(0.0, 1.0);
        self.c[i - 1] + s * (self.c[i] - self.c[i - 1])
    }
}

/// One landmark measurement with its Vicon geometry.
struct Bearing {
    t: f64,
    /// Window index.
    w: usize,
    meas: f64,
    /// Predicted by the Vicon pose and the surveyed landmark.
    truth: f64,
    /// Landmark in the robot frame (forward, left), from the Vicon pose.
    range: f64,
    /// Vicon turn rate at t (0.1 s centred difference).
    rate: f64,
    /// Bearing of the landmark from the Vicon position (world frame).
    world: f64,
}

fn fmt_fit(name: &str, f: &Ols, j: usize, scale: f64, unit: &str) -> String {
    format!(
        "{name} = {:.4} ± {:.4} [{:.4}]{unit}",
        f.beta[j] * scale,
        f.se[j] * scale,
        f.cr(j) * scale
    )
}

/// Check 4 (bearings): measured = (1 + kb) true + b0 against the Vicon pose.
fn bearings(
    track: &Track,
    meas: &Rows,
    lms: &[(u32, f64, f64)],
    windows: &[(f64, f64)],
) -> Vec<Bearing> {
    let (mut out, mut n_all, mut n_out) = (Vec::new(), 0usize, 0usize);
    for m in meas {
        let Some(l) = lms.iter().find(|l| l.0 == m[1] as u32) else {
            continue;
        };
        let w = windows.partition_point(|s| s.1 < m[0]);
        if w >= windows.len() || m[0] < windows[w].0 {
            continue;
        }
        let (Some(p), Some(p0), Some(p1)) =
            (track.at(m[0]), track.at(m[0] - 0.05), track.at(m[0] + 0.05))
        else {
            continue;
        };
        let world = (l.2 - p[1]).atan2(l.1 - p[0]);
        let truth = wrap(world - p[2]);
        n_all += 1;
        if wrap(m[3] - truth).abs() > OUTLIER {
            n_out += 1;
            continue;
        }
        out.push(Bearing {
            t: m[0],
            w,
            meas: truth + wrap(m[3] - truth),
            truth,
            range: (l.1 - p[0]).hypot(l.2 - p[1]),
            rate: (p1[2] - p0[2]) / 0.1,
            world,
        });
    }
    let g: Vec<usize> = out.iter().map(|b| b.w).collect();
    let y: Vec<f64> = out.iter().map(|b| b.meas - b.truth).collect();
    let x: Vec<Vec<f64>> = out.iter().map(|b| vec![b.truth, 1.0]).collect();
    let meas_y: Vec<f64> = out.iter().map(|b| b.meas).collect();
    println!(
        "  bearings: {} in windows, {} dropped (|measured - Vicon| > {OUTLIER} rad: misread barcodes)",
        n_all, n_out
    );
    if let (Some(f), Some(s)) = (ols(&x, &y, &g), ols(&x, &meas_y, &g)) {
        let rms = (y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64).sqrt();
        println!(
            "    frame check: measured = {:.4} x Vicon bearing + {:.4} rad (a sign error would give -1); residual RMS {rms:.4} rad",
            s.beta[0], s.beta[1]
        );
        println!(
            "    measured = (1 + kb) true + b0: {}, {} (± iid se [cluster-robust se, by window])",
            fmt_fit("kb", &f, 0, 1.0, ""),
            fmt_fit("b0", &f, 1, 1.0, " rad")
        );
    }
    // Per-window fits: the spread of the windows' own scales.
    let mut per = Vec::new();
    for w in 0..windows.len() {
        let (xs, ys): (Vec<f64>, Vec<f64>) = out
            .iter()
            .filter(|b| b.w == w)
            .map(|b| (b.truth, b.meas - b.truth))
            .unzip();
        if xs.len() >= 10 {
            per.push(line(&xs, &ys).0);
        }
    }
    let nw = per.len() as f64;
    let mean = per.iter().sum::<f64>() / nw;
    let sd = (per.iter().map(|k| (k - mean).powi(2)).sum::<f64>() / (nw - 1.0)).sqrt();
    println!(
        "    per-window kb: mean {mean:.4} ± {:.4} (sd {sd:.4} / sqrt {})",
        sd / nw.sqrt(),
        per.len()
    );
    // A camera ahead of the Vicon centre by a (m) changes the bearing by
    // a sin(b) / r; a camera latency d (s) by d x turn rate.
    let xe: Vec<Vec<f64>> = out
        .iter()
        .map(|b| vec![b.truth, 1.0, b.truth.sin() / b.range, b.rate])
        .collect();
    if let Some(f) = ols(&xe, &y, &g) {
        println!(
            "    with a camera offset and latency: {}, {}, {}, {}",
            fmt_fit("kb", &f, 0, 1.0, ""),
            fmt_fit("b0", &f, 1, 1.0, " rad"),
            fmt_fit("forward offset", &f, 2, 1.0, " m"),
            fmt_fit("latency", &f, 3, 1.0, " s")
        );
    }
    // By |true bearing|: the scale within each bin, b0 removed. The same in
    // every bin is a scale; a trend is a distortion.
    let b0 = ols(&x, &y, &g).map_or(0.0, |f| f.beta[1]);
    let mut cells = Vec::new();
    for k in 0..6 {
        let (lo, hi) = (
            0.1 * k as f64,
            if k == 5 { 9.0 } else { 0.1 * (k + 1) as f64 },
        );
        let rows: Vec<&Bearing> = out
            .iter()
            .filter(|b| b.truth.abs() >= lo && b.truth.abs() < hi)
            .collect();
        let xb: Vec<Vec<f64>> = rows.iter().map(|b| vec![b.truth]).collect();
        let yb: Vec<f64> = rows.iter().map(|b| b.meas - b.truth - b0).collect();
        let gb: Vec<usize> = rows.iter().map(|b| b.w).collect();
        let mres = yb
            .iter()
            .zip(&rows)
            .map(|(e, b)| e * b.truth.signum())
            .sum::<f64>()
            / rows.len().max(1) as f64;
        if let Some(f) = ols(&xb, &yb, &gb).filter(|_| rows.len() >= 20) {
            let hi = if k == 5 {
                "+".into()
            } else {
                format!("-{hi:.1}")
            };
            cells.push(format!(
                "{lo:.1}{hi}: kb {:.3} [{:.3}], mean signed residual {:.4} rad ({})",
                f.beta[0],
                f.cr(0),
                mres,
                rows.len()
            ));
        }
    }
    println!("    by |true bearing| (rad): {}", cells.join("; "));
    out
}

/// Check 5 (turn rate by speed): 1 s blocks of commands against the Vicon
/// heading change over the same second `LAG` later, by the block's mean |v|.
fn turn_by_speed(track: &Track, od: &Rows, windows: &[(f64, f64)]) {
    let (mut x, mut xv, mut y, mut g) = (vec![], vec![], vec![], vec![]);
    let (mut speed, mut turn) = (vec![], vec![]);
    for b in (0..od.len().saturating_sub(63)).step_by(50) {
        let (t0, t1) = (od[b][0], od[b + 50][0]);
        let w = windows.partition_point(|s| s.1 < t0);
        if w >= windows.len() || t0 < windows[w].0 {
            continue;
        }
        let rows = &od[b..b + 50];
        let dc: f64 = rows.iter().map(|r| r[2] * 0.02).sum();
        let av = rows.iter().map(|r| r[1].abs()).sum::<f64>() / 50.0;
        let (Some(pa), Some(pb)) = (track.at(t0 + LAG), track.at(t1 + LAG)) else {
            continue;
        };
        if dc.abs() < 0.01 {
            continue;
        }
        x.push(vec![dc]);
        xv.push(vec![dc, dc * av]);
        y.push(pb[2] - pa[2]);
        g.push(w);
        speed.push(av);
        turn.push(rows.iter().map(|r| r[2].abs()).sum::<f64>() / 50.0);
    }
    // Bins of width `step` of a block key; the last one open.
    let bins = |key: &[f64], step: f64, what: &str| {
        let mut cells = Vec::new();
        for k in 0..5 {
            let lo = step * k as f64;
            let hi = if k == 4 { 9.0 } else { lo + step };
            let idx: Vec<usize> = (0..y.len())
                .filter(|&i| key[i] >= lo && key[i] < hi)
                .collect();
            let xb: Vec<Vec<f64>> = idx.iter().map(|&i| x[i].clone()).collect();
            let yb: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
            let gb: Vec<usize> = idx.iter().map(|&i| g[i]).collect();
            if let Some(f) = ols(&xb, &yb, &gb).filter(|_| idx.len() >= 10) {
                let hi = if k == 4 {
                    "+".into()
                } else {
                    format!("-{hi:.2}")
                };
                let n = idx.len();
                cells.push(format!(
                    "{lo:.2}{hi}: {:.3} [{:.3}] ({n})",
                    f.beta[0],
                    f.cr(0)
                ));
            }
        }
        println!(
            "  Vicon / commanded turn per 1 s block by mean {what}, [cluster-robust se]: {}",
            cells.join(", ")
        );
    };
    bins(&speed, 0.02, "|v| (m/s)");
    bins(&turn, 0.1, "|omega| (rad/s)");
    if let (Some(a), Some(f)) = (ols(&x, &y, &g), ols(&xv, &y, &g)) {
        // omega_true = omega (p + q |v|), p = 1 + a, c = q / p (delta method).
        let (p, q) = (f.beta[0], f.beta[1]);
        let c = q / p;
        let (dp, dq) = (-q / (p * p), 1.0 / p);
        let var =
            |v: &Vec<Vec<f64>>| dp * dp * v[0][0] + 2.0 * dp * dq * v[0][1] + dq * dq * v[1][1];
        println!(
            "    omega_true = omega (1 + a): a = {:.3} ± {:.3} [{:.3}]; omega (1 + a)(1 + c |v|): a = {:.3} [{:.3}], c = {:.2} [{:.2}] s/m ({} blocks)",
            a.beta[0] - 1.0,
            a.se[0],
            a.cr(0),
            p - 1.0,
            f.cr(0),
            c,
            var(&f.vcr).sqrt(),
            y.len()
        );
    }
}

/// Check 6 (heading drift): per window, the commanded turn integrated from
/// the Vicon heading at the start (inputs `LAG` late) against the Vicon
/// heading, raw and with a turn scale and bias (a, b) applied.
fn heading_drift(track: &Track, cum: &Integral, windows: &[(f64, f64)], ab: (f64, f64)) {
    let taus = [5.0, 10.0, 20.0, 30.0, 45.0, 59.0];
    for (label, (a, b)) in [("raw", (1.0, 0.0)), ("with a, b", ab)] {
        let mut rms = Vec::new();
        let mut last = Vec::new();
        for &tau in &taus {
            let errs: Vec<f64> = windows
                .iter()
                .filter(|w| w.1 - w.0 >= tau)
                .filter_map(|w| {
                    let (p0, p1) = (track.at(w.0 + LAG)?, track.at(w.0 + LAG + tau)?);
                    let odo = a * (cum.at(w.0 + tau) - cum.at(w.0)) + b * tau;
                    Some(wrap(odo - (p1[2] - p0[2])))
                })
                .collect();
            rms.push((errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt());
            last = errs;
        }
        // log RMS against log tau from 10 s on: 0.5 for a random walk, 1 for a trend.
        let lx: Vec<f64> = taus[1..].iter().map(|t| t.ln()).collect();
        let ly: Vec<f64> = rms[1..].iter().map(|r| r.ln()).collect();
        let slope = line(&lx, &ly).0;
        let mean = last.iter().sum::<f64>() / last.len() as f64;
        let cells: Vec<String> = taus
            .iter()
            .zip(&rms)
            .map(|(t, r)| format!("{t:.0} s {r:.3}"))
            .collect();
        println!(
            "  heading drift ({label}): RMS over windows (rad) {}; log-log slope 10-59 s {slope:.2}; mean at 59 s {mean:+.3}",
            cells.join(", ")
        );
    }
}

/// Check 7: the bearings fitted per window with the odometry heading (the
/// commanded turn integrated from the Vicon start, `LAG` late) and the Vicon
/// positions, each window's initial heading free: the bearing scale the
/// drift alone would produce (synthetic: measured := Vicon bearing) and the
/// one the real bearings give, against the Vicon heading's.
fn drift_as_scale(bs: &[Bearing], track: &Track, cum: &Integral, windows: &[(f64, f64)], sub: f64) {
    // Each window cut into pieces of `sub` s, each piece its own initial
    // heading; clusters stay the windows.
    let start = |b: &Bearing| {
        let a = windows[b.w].0;
        a + ((b.t - a) / sub).floor() * sub
    };
    let g: Vec<usize> = bs.iter().map(|b| b.w).collect();
    let gs: Vec<usize> = bs
        .iter()
        .map(|b| b.w * 1000 + ((b.t - windows[b.w].0) / sub) as usize)
        .collect();
    let odo: Vec<f64> = bs
        .iter()
        .map(|b| {
            let a = start(b);
            let th0 = track.at(a + LAG).map_or(0.0, |p| p[2]);
            th0 + cum.at(b.t - LAG) - cum.at(a)
        })
        .collect();
    // Bearing predicted with the odometry heading.
    let pred: Vec<f64> = bs
        .iter()
        .zip(&odo)
        .map(|(b, o)| wrap(b.world - o))
        .collect();
    let since: Vec<(f64, f64)> = bs
        .iter()
        .map(|b| {
            let w = start(b);
            (cum.at(b.t - LAG) - cum.at(w), b.t - w)
        })
        .collect();
    let fit = |target: &dyn Fn(&Bearing) -> f64, heading: bool, turn: bool| {
        let mut x: Vec<Vec<f64>> = bs
            .iter()
            .zip(&pred)
            .zip(&since)
            .map(|((b, p), s)| {
                let mut r = vec![if heading { *p } else { b.truth }];
                if turn {
                    r.extend([s.0, s.1]);
                }
                r
            })
            .collect();
        let mut y: Vec<f64> = bs
            .iter()
            .zip(&pred)
            .map(|(b, p)| target(b) - if heading { *p } else { b.truth })
            .collect();
        demean(&mut x, &mut y, &gs);
        ols(&x, &y, &g)
    };
    let measured = |b: &Bearing| b.meas;
    let synthetic = |b: &Bearing| b.truth;
    let show = |name: &str, f: Option<Ols>| match f {
        Some(f) => format!("{name} {:.4} [{:.4}]", f.beta[0], f.cr(0)),
        None => format!("{name} singular"),
    };
    // The errors-in-variables prediction: a heading error d (free constant
    // per window) in the regressor shrinks the slope by var d / (var b + var d).
    let mut d: Vec<Vec<f64>> = bs.iter().map(|b| vec![b.truth]).collect();
    let mut e: Vec<f64> = bs.iter().zip(&pred).map(|(b, p)| b.truth - p).collect();
    demean(&mut d, &mut e, &gs);
    let (vb, vd) = (
        d.iter().map(|r| r[0] * r[0]).sum::<f64>() / d.len() as f64,
        e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64,
    );
    if sub < 60.0 {
        println!(
            "    pieces of {sub:.0} s: {}, {}",
            show(
                "synthetic, turn scale and bias free",
                fit(&synthetic, true, true)
            ),
            show("measured", fit(&measured, true, true)),
        );
        return;
    }
    println!(
        "  bearing scale per window (initial heading free) with the odometry heading: {}, {}; with a turn scale and bias free too: {}, {}; with the Vicon heading: {}",
        show("synthetic (no camera error)", fit(&synthetic, true, false)),
        show("measured", fit(&measured, true, false)),
        show("synthetic", fit(&synthetic, true, true)),
        show("measured", fit(&measured, true, true)),
        show("measured", fit(&measured, false, false)),
    );
    println!(
        "    within-window heading error RMS {:.3} rad, bearing sd {:.3} rad: errors-in-variables kb = -{:.4}",
        vd.sqrt(),
        vb.sqrt(),
        vd / (vb + vd)
    );
}

/// Check 5b: the same coupling from a deterministic fit of each window's
/// Vicon heading, as a pose fit does it: th(t) - th(t0) = p C(t) + q D(t) +
/// bw (t - t0) + const, C the commanded turn, D the integral of omega |v|
/// (inputs `LAG` late), every 0.5 s; c = q / p. The drift of the commanded
/// heading is the residual here, not white noise.
fn turn_by_window_fit(track: &Track, cum: &Integral, cum_v: &Integral, w: &[(f64, f64)], sub: f64) {
    let (mut x, mut y, mut g, mut gs) = (vec![], vec![], vec![], vec![]);
    for (k, &(a0, b)) in w.iter().enumerate() {
        // Pieces of `sub` s, each with its own initial heading.
        for piece in 0..((b - a0) / sub).ceil() as usize {
            let a = a0 + piece as f64 * sub;
            let Some(p0) = track.at(a + LAG) else {
                continue;
            };
            let mut t = a;
            while t <= b && t < a + sub {
                if let Some(p) = track.at(t + LAG) {
                    x.push(vec![
                        cum.at(t) - cum.at(a),
                        cum_v.at(t) - cum_v.at(a),
                        t - a,
                    ]);
                    y.push(p[2] - p0[2]);
                    g.push(k);
                    gs.push(k * 1000 + piece);
                }
                t += 0.5;
            }
        }
    }
    let mut xs: Vec<Vec<f64>> = x.iter().map(|r| vec![r[0], r[1]]).collect();
    let mut ys = y.clone();
    demean(&mut x, &mut y, &gs);
    demean(&mut xs, &mut ys, &gs);
    for (label, f) in [
        ("with a turn bias", ols(&x, &y, &g)),
        ("without", ols(&xs, &ys, &g)),
    ] {
        let Some(f) = f else { continue };
        let (p, q) = (f.beta[0], f.beta[1]);
        let (dp, dq) = (-q / (p * p), 1.0 / p);
        let v = &f.vcr;
        let sc = (dp * dp * v[0][0] + 2.0 * dp * dq * v[0][1] + dq * dq * v[1][1]).sqrt();
        println!(
            "    window fit of the Vicon heading, pieces of {sub:.0} s ({label}): a = {:.3} [{:.3}], c = {:.2} [{:.2}] s/m",
            p - 1.0,
            f.cr(0),
            q / p,
            sc
        );
    }
}

/// Check 8: a bearing scale read from pairs of landmarks seen at the same
/// time: their difference is free of the heading (and of its drift).
fn pairwise_scale(bs: &[Bearing]) {
    let (mut x, mut y, mut g) = (vec![], vec![], vec![]);
    for (i, a) in bs.iter().enumerate() {
        for b in bs[i + 1..].iter().take_while(|b| b.t - a.t < 0.01) {
            let d = wrap(a.truth - b.truth);
            x.push(vec![d]);
            y.push(wrap(a.meas - b.meas) - d);
            g.push(a.w);
        }
    }
    match ols(&x, &y, &g).filter(|_| x.len() >= 20) {
        Some(f) => println!(
            "  bearing scale from {} simultaneous pairs (heading-free): {}",
            x.len(),
            fmt_fit("kb", &f, 0, 1.0, "")
        ),
        None => println!(
            "  bearing scale from simultaneous pairs: {} pairs, too few",
            x.len()
        ),
    }
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/data/mrclam".into());
    for r in 1..=3 {
        robot(&dir, r)?;
    }
    Ok(())
}
