//! Charts drawn into a display list: axes, ticks, legend, series, bars.

use crate::{Anchor, Figure, Op, Rgb, Series, Style, BLACK, FRAME, LIGHT};

/// Round tick step for a span.
fn step(span: f64) -> f64 {
    let raw = span / 6.0;
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

fn fmt_tick(v: f64, step: f64) -> String {
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    let digits = (-(step.log10().floor())).max(0.0) as usize;
    format!("{v:.digits$}")
}

/// Stroke of a line series (px); a point's radius exceeds half of it by more
/// than a pixel, so a point under a line shows on both sides of it.
const LINE_WIDTH: f64 = 1.5;
const LINE_OPACITY: f64 = 0.8;
const POINT_RADIUS: f64 = 2.2;

/// Angles in (-pi, pi] for a line series: where consecutive values jump by
/// more than pi the curve wrapped, so the line is carried to the edge it
/// crossed (+pi or -pi, at the interpolated abscissa), the pen lifted
/// (a non-finite point) and put down at the opposite edge. A line chart then
/// shows the wrap as a reader draws it, with no vertical stroke across the
/// plot. Non-finite points pass through (they already lift the pen).
pub fn wrapped_angles(xy: &[(f64, f64)]) -> Vec<(f64, f64)> {
    use std::f64::consts::PI;
    let mut out = Vec::with_capacity(xy.len());
    let mut last: Option<(f64, f64)> = None;
    for &(x, y) in xy {
        if !(x.is_finite() && y.is_finite()) {
            out.push((x, y));
            last = None;
            continue;
        }
        if let Some((x0, y0)) = last {
            let jump = y - y0;
            if jump.abs() > PI {
                // The shorter way round: up through +pi or down through -pi.
                let d = if jump > 0.0 {
                    jump - 2.0 * PI
                } else {
                    jump + 2.0 * PI
                };
                let edge = if d > 0.0 { PI } else { -PI };
                let frac = if d != 0.0 {
                    ((edge - y0) / d).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                let xc = x0 + frac * (x - x0);
                out.push((xc, edge));
                out.push((f64::NAN, f64::NAN));
                out.push((xc, -edge));
            }
        }
        out.push((x, y));
        last = Some((x, y));
    }
    out
}

/// Series against shared axes, 760 x 360 px, legend on the right. Axis
/// labels should carry their unit, e.g. "time (s)", "beta (rad)".
pub fn chart(title: &str, xlabel: &str, ylabel: &str, series: &[Series]) -> Figure {
    let (w, h, l, r, t, b) = (760.0, 360.0, 70.0, 150.0, 30.0, 45.0);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in series
        .iter()
        .flat_map(|s| &s.xy)
        .filter(|p| p.0.is_finite() && p.1.is_finite())
    {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    if x1 - x0 < 1e-12 {
        x1 = x0 + 1.0;
    }
    if y1 - y0 < 1e-12 {
        y0 -= 0.5;
        y1 += 0.5;
    }
    let pad = 0.05 * (y1 - y0);
    (y0, y1) = (y0 - pad, y1 + pad);
    let sx = |x: f64| l + (x - x0) / (x1 - x0) * (w - l - r);
    let sy = |y: f64| t + (y1 - y) / (y1 - y0) * (h - t - b);
    let mut f = Figure::new(w, h);
    f.text((l + w - r) / 2.0, 18.0, title, 14.0, Anchor::Middle);
    let (xs, ys) = (step(x1 - x0), step(y1 - y0));
    let mut v = (x0 / xs).ceil() * xs;
    while v <= x1 + 1e-9 * xs {
        f.line((sx(v), t), (sx(v), h - b), LIGHT, 1.0, false);
        f.text(sx(v), h - b + 15.0, &fmt_tick(v, xs), 12.0, Anchor::Middle);
        v += xs;
    }
    let mut v = (y0 / ys).ceil() * ys;
    while v <= y1 + 1e-9 * ys {
        f.line((l, sy(v)), (w - r, sy(v)), LIGHT, 1.0, false);
        f.text(l - 5.0, sy(v) + 4.0, &fmt_tick(v, ys), 12.0, Anchor::End);
        v += ys;
    }
    f.ops.push(Op::Rect {
        x: l,
        y: t,
        w: w - l - r,
        h: h - t - b,
        fill: None,
        stroke: Some(FRAME),
    });
    f.text((l + w - r) / 2.0, h - 8.0, xlabel, 12.0, Anchor::Middle);
    f.ops.push(Op::Text {
        x: 15.0,
        y: (t + h - b) / 2.0,
        text: ylabel.to_string(),
        size: 12.0,
        anchor: Anchor::Middle,
        vertical: true,
    });
    // Points and stars first, lines over them: a fitted line is never buried
    // in a cloud of measurements, and the measurements stay visible under it
    // (points wider than the line, lines slightly transparent).
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let lines_last = series
        .iter()
        .filter(|s| s.style != Style::Line)
        .chain(series.iter().filter(|s| s.style == Style::Line));
    for se in lines_last {
        match se.style {
            Style::Line => {
                // A gap (non-finite point) lifts the pen.
                let mut run: Vec<(f64, f64)> = Vec::new();
                for p in se.xy.iter().chain(std::iter::once(&(f64::NAN, f64::NAN))) {
                    if finite(&p) {
                        run.push((sx(p.0), sy(p.1)));
                    } else if !run.is_empty() {
                        f.ops.push(Op::Path {
                            pts: std::mem::take(&mut run),
                            color: se.color,
                            width: LINE_WIDTH,
                            dashed: false,
                            opacity: LINE_OPACITY,
                        });
                    }
                }
            }
            Style::Points => {
                for p in se.xy.iter().filter(finite) {
                    f.ops.push(Op::Dot {
                        x: sx(p.0),
                        y: sy(p.1),
                        r: POINT_RADIUS,
                        color: se.color,
                    });
                }
            }
            Style::Stars => {
                for p in se.xy.iter().filter(finite) {
                    star(&mut f, sx(p.0), sy(p.1), 7.0, se.color);
                }
            }
        }
    }
    for (i, se) in series.iter().enumerate() {
        let ly = t + 15.0 + 18.0 * i as f64;
        match se.style {
            Style::Stars => star(&mut f, w - r + 16.0, ly - 4.0, 6.0, se.color),
            _ => f.ops.push(Op::Rect {
                x: w - r + 10.0,
                y: ly - 8.0,
                w: 12.0,
                h: 8.0,
                fill: Some(se.color),
                stroke: None,
            }),
        }
        f.text(w - r + 26.0, ly, se.name, 12.0, Anchor::Start);
    }
    f
}

/// A six-pointed asterisk of radius `r`.
fn star(f: &mut Figure, x: f64, y: f64, r: f64, color: Rgb) {
    for k in 0..3 {
        let a = std::f64::consts::PI * (0.5 + k as f64 / 3.0);
        let (s, c) = a.sin_cos();
        f.line(
            (x - r * c, y - r * s),
            (x + r * c, y + r * s),
            color,
            2.0,
            false,
        );
    }
}

/// Horizontal bars (label, value, colour), with an optional dashed
/// vertical reference line.
pub fn bars(
    title: &str,
    xlabel: &str,
    items: &[(String, f64, Rgb)],
    reference: Option<(f64, &str)>,
) -> Figure {
    bars_with_legend(title, xlabel, items, reference, &[])
}

/// [`bars`] with a scale under the bars (ticks and values, so lengths read
/// as numbers) and a legend of what each colour means, one a line below it.
pub fn bars_with_legend(
    title: &str,
    xlabel: &str,
    items: &[(String, f64, Rgb)],
    reference: Option<(f64, &str)>,
    legend: &[(Rgb, &str)],
) -> Figure {
    let n = items.len().max(1) as f64;
    // Room above the bars for the reference line's label when a legend
    // takes the bottom.
    let (w, l, r) = (760.0, 170.0, 80.0);
    let t = if legend.is_empty() { 30.0 } else { 46.0 };
    // Room for the scale's labels and one legend line per two entries.
    let b = 40.0
        + if legend.is_empty() {
            0.0
        } else {
            20.0 + 18.0 * legend.len() as f64
        };
    let h = t + b + 24.0 * n;
    let vmax = items
        .iter()
        .map(|i| i.1)
        .chain(reference.map(|r| r.0))
        .filter(|v| v.is_finite())
        .fold(1e-12, f64::max);
    let sx = |v: f64| l + v.max(0.0) / vmax * (w - l - r);
    let mut f = Figure::new(w, h);
    f.text(w / 2.0, 18.0, title, 14.0, Anchor::Middle);
    for (i, (label, v, color)) in items.iter().enumerate() {
        let y = t + 24.0 * i as f64;
        f.text(l - 6.0, y + 13.0, label, 12.0, Anchor::End);
        if v.is_finite() {
            f.ops.push(Op::Rect {
                x: l,
                y: y + 2.0,
                w: sx(*v) - l,
                h: 16.0,
                fill: Some(*color),
                stroke: None,
            });
        }
        let shown = if v.is_finite() {
            format!("{v:.2}")
        } else {
            "-".into()
        };
        let xv = if v.is_finite() { sx(*v) } else { l };
        f.text(xv + 4.0, y + 13.0, &shown, 12.0, Anchor::Start);
    }
    let base = t + 24.0 * n;
    if !legend.is_empty() {
        // The scale: an axis line with ticks below the bars.
        f.line((l, base + 2.0), (w - r, base + 2.0), BLACK, 1.0, false);
        let st = step(vmax);
        let mut v = 0.0;
        while v <= vmax + 1e-9 * st {
            f.line((sx(v), base + 2.0), (sx(v), base + 6.0), BLACK, 1.0, false);
            f.text(sx(v), base + 18.0, &fmt_tick(v, st), 11.0, Anchor::Middle);
            v += st;
        }
    }
    if let Some((v, label)) = reference {
        f.line((sx(v), t - 4.0), (sx(v), base + 4.0), BLACK, 1.0, true);
        if legend.is_empty() {
            f.text(sx(v), h - b + 18.0, label, 12.0, Anchor::Middle);
        } else {
            f.text(sx(v) + 4.0, t - 6.0, label, 11.0, Anchor::Start);
        }
    }
    let xl_y = if legend.is_empty() {
        h - 6.0
    } else {
        base + 34.0
    };
    f.text((l + w - r) / 2.0, xl_y, xlabel, 12.0, Anchor::Middle);
    for (k, (color, what)) in legend.iter().enumerate() {
        let (x, y) = (l, base + 52.0 + 18.0 * k as f64);
        f.ops.push(Op::Rect {
            x,
            y: y - 9.0,
            w: 12.0,
            h: 10.0,
            fill: Some(*color),
            stroke: None,
        });
        f.text(x + 18.0, y, what, 11.0, Anchor::Start);
    }
    f
}
