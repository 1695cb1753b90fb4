//! The ground-truth figures of docs/diagnose.md ("Against the ground truth"),
//! computed from the raw MRCLAM files: what the Vicon poses say about the
//! odometry and the range sensor, independently of obsan's fits.
//!
//! ```sh
//! cargo run --release --example mrclam_truth -- ../shared/data/mrclam
//! ```

use obsan_data::{mrclam_convert, mrclam_landmarks, MrclamOutputs, MrclamText};
use std::error::Error;

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
    let (_, truth) = mrclam_convert(&src, 60.0, 30, MrclamOutputs::Landmarks)?;
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
    // 2b. Forward speed against the turn rate (issue 18.6): 1 s blocks of
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
    Ok(())
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
