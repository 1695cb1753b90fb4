//! `obsan diagnose --report DIR`: the report folder, laid out as a reader of
//! a paper wants it: the verdict, the estimates with their sds, the residuals
//! of each output pooled over all trajectories before and after the named
//! effects (by time, and against the output's own value and each measured
//! input, where a missing effect shows as structure), the candidates' scores,
//! then the fitted series and the whole console text.

use obsan_diagnose::{CandidateResult, Diagnosis, ModelFit};
use obsan_plot::{bars_with_legend, chart, figure_files, Series, Style, COLORS, GREY, PALE};
use std::fmt::Write;
use std::path::PathBuf;

/// Points drawn per series of a pooled chart: beyond it every k-th point
/// is drawn (the binned means use all of them), so a robot's log of 10^5
/// samples stays a readable figure of bounded size.
const MAX_DRAWN: usize = 6000;
/// Bins of the binned-mean line (equal width over the abscissa); a bin
/// with fewer than [`MIN_PER_BIN`] points has no mean drawn.
const BINS: usize = 24;
const MIN_PER_BIN: usize = 3;
/// Fitted-output charts: the series with the most samples, at most this many.
const MAX_FIT_CHARTS: usize = 8;
/// Measured inputs against which residuals are drawn, at most.
const MAX_INPUT_CHARTS: usize = 4;

/// The value ± its sd, with as many digits as the sd warrants.
fn pm(v: f64, s: f64) -> String {
    if !(s.is_finite() && s > 0.0) {
        return format!("{v:.6}");
    }
    let digits = ((-s.log10()).floor() as i32 + 2).clamp(1, 12) as usize;
    format!("{v:.digits$} ± {s:.digits$}")
}

/// Every k-th point so that at most [`MAX_DRAWN`] remain.
fn thin(xy: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    let k = xy.len().div_ceil(MAX_DRAWN).max(1);
    xy.into_iter().step_by(k).collect()
}

/// Mean of `y` in equal-width bins of `x`, as a line (bin centres).
fn binned_mean(xy: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let finite: Vec<&(f64, f64)> = xy
        .iter()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    let (lo, hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.0), a.1.max(p.0))
        });
    if finite.is_empty() || hi <= lo {
        return Vec::new();
    }
    let width = (hi - lo) / BINS as f64;
    let mut sum = [0.0; BINS];
    let mut cnt = [0usize; BINS];
    for p in finite {
        let k = (((p.0 - lo) / width) as usize).min(BINS - 1);
        sum[k] += p.1;
        cnt[k] += 1;
    }
    (0..BINS)
        .filter(|&k| cnt[k] >= MIN_PER_BIN)
        .map(|k| (lo + (k as f64 + 0.5) * width, sum[k] / cnt[k] as f64))
        .collect()
}

/// One pooled chart of an output's residuals (residual / sigma) against
/// `x` of each sample, before and after the named effects.
fn pooled_chart(
    title: &str,
    xlabel: &str,
    fits: &[(&str, &ModelFit)],
    output: &str,
    x: &dyn Fn(&obsan_diagnose::ResidualSeries, usize) -> Option<f64>,
) -> obsan_plot::Figure {
    let colors = [(PALE, GREY), (COLORS[0], COLORS[1])];
    let mut pts: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut lines: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for (name, f) in fits {
        let xy: Vec<(f64, f64)> = f
            .series
            .iter()
            .filter(|s| s.output == output)
            .flat_map(|s| (0..s.e.len()).filter_map(move |i| x(s, i).map(|xv| (xv, s.e[i]))))
            .collect();
        lines.push((format!("{name}, mean"), binned_mean(&xy)));
        pts.push((name.to_string(), thin(xy)));
    }
    let mut series = Vec::new();
    for (k, (name, xy)) in pts.iter().enumerate() {
        series.push(Series {
            name,
            color: colors[k % 2].0,
            style: Style::Points,
            xy: xy.clone(),
        });
    }
    for (k, (name, xy)) in lines.iter().enumerate() {
        series.push(Series {
            name,
            color: colors[k % 2].1,
            style: Style::Line,
            xy: xy.clone(),
        });
    }
    chart(title, xlabel, "residual / sigma", &series)
}

/// The fits to compare: the nominal, and the final one when effects were named.
fn fits(d: &Diagnosis) -> Vec<(&'static str, &ModelFit)> {
    let mut v = vec![("nominal", &d.nominal)];
    if !d.named.is_empty() {
        v.push(("with effects", &d.final_fit));
    }
    v
}

fn outputs(d: &Diagnosis) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for s in d.nominal.series.iter() {
        if !v.contains(&s.output) {
            v.push(s.output.clone());
        }
    }
    v
}

/// Residual figures per output; returns the markdown that shows them.
fn residual_figures(d: &Diagnosis, files: &mut Vec<(PathBuf, Vec<u8>)>) -> String {
    let mut md = String::new();
    let fits = fits(d);
    for out in outputs(d) {
        let first = d.nominal.series.iter().find(|s| s.output == out);
        let angular = first.is_some_and(|s| s.angular);
        let unit = if angular {
            "rad"
        } else {
            "units of outputs.csv"
        };
        let _ = writeln!(md, "### {out}\n");
        let stem = format!("residuals_{out}");
        files.extend(figure_files(
            &stem,
            &pooled_chart(
                &format!("{out}: residuals of all trajectories, by time"),
                "time (s)",
                &fits,
                &out,
                &|s, i| Some(s.t[i]),
            ),
        ));
        let _ = writeln!(md, "![{stem}]({stem}.png)\n");
        let stem = format!("residuals_{out}_vs_{out}");
        files.extend(figure_files(
            &stem,
            &pooled_chart(
                &format!("{out}: residuals against the predicted {out}"),
                &format!("predicted {out} ({unit})"),
                &fits,
                &out,
                &|s, i| {
                    let y = s.predicted[i];
                    Some(if s.angular { obsan_data::wrap(y) } else { y })
                },
            ),
        ));
        let _ = writeln!(md, "![{stem}]({stem}.png)\n");
        let inputs: Vec<String> = first
            .map(|s| s.inputs.iter().map(|u| u.0.clone()).collect())
            .unwrap_or_default();
        for u in inputs.iter().take(MAX_INPUT_CHARTS) {
            let stem = format!("residuals_{out}_vs_{u}");
            files.extend(figure_files(
                &stem,
                &pooled_chart(
                    &format!("{out}: residuals against the measured {u}"),
                    &format!("{u} (units of inputs.csv)"),
                    &fits,
                    &out,
                    &|s, i| {
                        s.inputs
                            .iter()
                            .find(|x| &x.0 == u)
                            .and_then(|x| x.1.get(i).copied())
                    },
                ),
            ));
            let _ = writeln!(md, "![{stem}]({stem}.png)\n");
        }
    }
    md
}

/// The markdown tables: estimates, and residual RMS before and after.
fn tables(d: &Diagnosis, u: &crate::diagnose_units::Units) -> String {
    let mut md = String::new();
    let after = !d.named.is_empty();
    let _ = writeln!(md, "## Estimates\n");
    let _ = writeln!(
        md,
        "| param | nominal model | {}robust sd | unit |",
        if after { "with named effects | " } else { "" }
    );
    let _ = writeln!(md, "|---|---|{}---|---|", if after { "---|" } else { "" });
    let f = if after { &d.final_fit } else { &d.nominal };
    for (k, (name, v, sd)) in f.params.iter().enumerate() {
        let nominal = d
            .nominal
            .param(name)
            .map_or("(not in the model)".to_string(), |(v, s)| pm(v, s));
        let robust = f
            .params_robust_sd
            .get(k)
            .filter(|x| x.is_finite())
            .map_or("-".to_string(), |x| format!("{x:.3e}"));
        let unit = u.label(name);
        if after {
            let _ = writeln!(
                md,
                "| {name} | {nominal} | {} | {robust} | {unit} |",
                pm(*v, *sd)
            );
        } else {
            let _ = writeln!(md, "| {name} | {nominal} | {robust} | {unit} |");
        }
    }
    let _ = writeln!(
        md,
        "\nValues ± the model's sd; the robust sd treats trajectories as clusters (none with one \
         trajectory). Units: datasets are in SI units with angles in rad \
         (docs/data-format.md); an effect's param takes the unit of where it enters (a bias its \
         output's, a scale none: 1, a time constant s), `unit NAME = UNIT` in the effects file \
         wins, and \"-\" is a unit nobody declared and none could be derived \
         (docs/diagnose.md, Units).\n"
    );
    let _ = writeln!(md, "## Residual RMS per output\n");
    let _ = writeln!(
        md,
        "| output | nominal model |{}\n|---|---|{}",
        if after {
            " with named effects | change |"
        } else {
            ""
        },
        if after { "---|---|" } else { "" }
    );
    for (o, r0) in &d.nominal.rms {
        if after {
            let r1 = d
                .final_fit
                .rms
                .iter()
                .find(|x| &x.0 == o)
                .map_or(f64::NAN, |x| x.1);
            let change = 100.0 * (r1 - r0) / r0;
            let _ = writeln!(md, "| {o} | {r0:.4e} | {r1:.4e} | {change:+.1}% |");
        } else {
            let _ = writeln!(md, "| {o} | {r0:.4e} |");
        }
    }
    let _ = writeln!(md, "\nIn the output's units (rad for angles).\n");
    md
}

/// A candidate whose fit did not run to an estimate: not drawn as a score.
fn failed(c: &CandidateResult) -> bool {
    c.error.is_some() || !c.lr.is_finite()
}

/// The first round's scores, with a legend and the critical line labelled.
fn candidate_figure(d: &Diagnosis, files: &mut Vec<(PathBuf, Vec<u8>)>) -> String {
    let Some(r) = d.rounds.first() else {
        return String::new();
    };
    let shown: Vec<&CandidateResult> = r.iter().filter(|c| !c.screened_out && !failed(c)).collect();
    let items: Vec<(String, f64, obsan_plot::Rgb)> = shown
        .iter()
        .map(|c| {
            // A hidden effect has no score: it is drawn as "-", not as 0.
            if !c.identifiable {
                (format!("{} (hidden)", c.effect), f64::NAN, PALE)
            } else if c.significant {
                (c.effect.clone(), c.lr, COLORS[1])
            } else if c.suggested {
                (c.effect.clone(), c.lr, COLORS[3])
            } else {
                (c.effect.clone(), c.lr, COLORS[0])
            }
        })
        .collect();
    let critical = format!("critical {:.2}", d.lr_critical);
    files.extend(figure_files(
        "candidates",
        &bars_with_legend(
            "candidate effects, round 1: likelihood-ratio statistic against the nominal model",
            "LR statistic (2 x log-likelihood gain; unitless)",
            &items,
            Some((d.lr_critical, &critical)),
            &[
                (COLORS[1], "significant"),
                (
                    COLORS[3],
                    "suggested: LR above the line, estimate not established",
                ),
                (
                    COLORS[0],
                    "not significant (below the line, or vetoed: see the text)",
                ),
                (PALE, "hidden: absorbed by the model's params (no score)"),
            ],
        ),
    ));
    let mut md = String::from("## Candidate scores\n\n![candidates](candidates.png)\n\n");
    let _ = writeln!(
        md,
        "The dashed line is the effects file's critical value ({:.2}); generated candidates \
         must clear {:.2}.",
        d.lr_critical, d.lr_critical_generated
    );
    let skipped: Vec<String> = r
        .iter()
        .filter(|c| failed(c))
        .map(|c| {
            format!(
                "{} ({})",
                c.effect,
                c.error.as_deref().unwrap_or("no estimate")
            )
        })
        .collect();
    let screened = r.iter().filter(|c| c.screened_out).count();
    if !skipped.is_empty() {
        let _ = writeln!(md, "Not drawn, their fits failed: {}.", skipped.join("; "));
    }
    if screened > 0 {
        let _ = writeln!(
            md,
            "Not drawn: {screened} generated candidates screened out before fitting (score below {:.2}).",
            d.screen_threshold
        );
    }
    md.push('\n');
    md
}

/// Measured against fitted for the longest series.
fn fit_figures(d: &Diagnosis, files: &mut Vec<(PathBuf, Vec<u8>)>) -> String {
    let mut order: Vec<usize> = (0..d.nominal.series.len()).collect();
    order.sort_by_key(|&k| std::cmp::Reverse(d.nominal.series[k].t.len()));
    let mut md = format!(
        "## Fitted outputs\n\nThe {} series with the most samples, of {} (trajectory, output):\n\n",
        order.len().min(MAX_FIT_CHARTS),
        order.len()
    );
    for &k in order.iter().take(MAX_FIT_CHARTS) {
        let (sb, sa) = (&d.nominal.series[k], &d.final_fit.series.get(k));
        let sigma = d
            .sigma
            .iter()
            .find(|x| x.0 == sb.output)
            .map_or(1.0, |x| x.1);
        let angle = |y: f64| if sb.angular { obsan_data::wrap(y) } else { y };
        let line = |xy: Vec<(f64, f64)>| {
            if sb.angular {
                obsan_plot::wrapped_angles(&xy)
            } else {
                xy
            }
        };
        let curve = |s: &obsan_diagnose::ResidualSeries| {
            line(
                s.t.iter()
                    .copied()
                    .zip(s.predicted.iter().map(|y| angle(*y)))
                    .collect(),
            )
        };
        let measured: Vec<(f64, f64)> =
            sb.t.iter()
                .zip(sb.predicted.iter().zip(&sb.e))
                .map(|(t, (y, e))| (*t, angle(y + e * sigma)))
                .collect();
        let mut series = vec![
            Series {
                name: "measured",
                color: GREY,
                style: Style::Points,
                xy: thin(measured),
            },
            Series {
                name: "nominal",
                color: COLORS[0],
                style: Style::Line,
                xy: curve(sb),
            },
        ];
        if let (Some(sa), false) = (sa, d.named.is_empty()) {
            series.push(Series {
                name: "with named effects",
                color: COLORS[1],
                style: Style::Line,
                xy: curve(sa),
            });
        }
        let stem = format!("fit_{k}_{}", sb.output);
        let ylabel = if sb.angular {
            format!("{} (rad)", sb.output)
        } else {
            format!("{} (units of outputs.csv)", sb.output)
        };
        files.extend(figure_files(
            &stem,
            &chart(
                &format!(
                    "{} on {} ({} samples)",
                    sb.output,
                    sb.trajectory,
                    sb.t.len()
                ),
                "time (s)",
                &ylabel,
                &series,
            ),
        ));
        let _ = writeln!(md, "![{stem}]({stem}.png)\n");
    }
    md
}

/// Every file of the report folder.
pub(crate) fn report_files(
    d: &Diagnosis,
    text: &str,
    u: &crate::diagnose_units::Units,
) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = vec![
        (
            PathBuf::from("extended.sys"),
            d.extended_sys.clone().into_bytes(),
        ),
        (
            PathBuf::from("diagnosis.json"),
            serde_json::to_string_pretty(&crate::json::diagnose(d, u))
                .unwrap_or_default()
                .into_bytes(),
        ),
    ];
    let mut md = String::new();
    let _ = writeln!(md, "# obsan diagnose: {}\n", d.model);
    // The verdict paragraph leads, as in the console text.
    let verdict: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("verdict:"))
        .take_while(|l| !l.trim().is_empty())
        .collect();
    let _ = writeln!(md, "{}\n", verdict.join("\n"));
    md.push_str(&tables(d, u));
    let _ =
        writeln!(
        md,
        "## Residuals per output\n\nEvery trajectory pooled; residual / sigma, the nominal model \
         in grey{}; lines are means over {BINS} equal bins of the abscissa. A missing effect shows \
         as structure in these lines (a trend in time, a curve against the output or an input).\n",
        if d.named.is_empty() { "" } else { ", with the named effects in colour" }
    );
    md.push_str(&residual_figures(d, &mut files));
    md.push_str(&candidate_figure(d, &mut files));
    md.push_str(&fit_figures(d, &mut files));
    let _ = writeln!(md, "## Extended model\n\n`extended.sys` (the nominal model with the named effects; `obsan rank extended.sys` and `obsan diagnose --model extended.sys` read it):\n\n```\n{}```\n", d.extended_sys);
    let _ = writeln!(md, "## The whole console text\n\n```\n{text}```\n");
    let _ = writeln!(
        md,
        "Every chart is also written as SVG (same name, `.svg`)."
    );
    files.push((PathBuf::from("report.md"), md.into_bytes()));
    files
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binned_means_of_a_line_lie_on_it_and_thin_keeps_a_bounded_subset() {
        // y = 2x + 1 over [0, 1]: each bin's mean is the line at the mean of
        // its x, which for evenly spread points is the bin's centre.
        let xy: Vec<(f64, f64)> = (0..=2400)
            .map(|i| i as f64 / 2400.0)
            .map(|x| (x, 2.0 * x + 1.0))
            .collect();
        let m = binned_mean(&xy);
        assert_eq!(m.len(), BINS);
        for (x, y) in m {
            assert!((y - (2.0 * x + 1.0)).abs() < 2.0 / 2400.0, "{x} {y}");
        }
        let many: Vec<(f64, f64)> = (0..3 * MAX_DRAWN + 1).map(|i| (i as f64, 0.0)).collect();
        let t = thin(many);
        assert!(
            t.len() <= MAX_DRAWN && t.len() >= MAX_DRAWN / 2,
            "{}",
            t.len()
        );
        assert!(binned_mean(&[(1.0, 1.0)]).is_empty());
    }
}
