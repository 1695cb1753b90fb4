//! Minimal SVG charts for reports (no font or system library needed): line
//! and point series over shared axes, and horizontal bars.

use std::fmt::Write;

pub const COLORS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
];

pub enum Style {
    Line,
    Points,
}

pub struct Series<'a> {
    pub name: &'a str,
    pub color: &'a str,
    pub style: Style,
    pub xy: Vec<(f64, f64)>,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

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

/// A chart of series against shared axes, 760 x 360 px.
pub fn chart(title: &str, xlabel: &str, ylabel: &str, series: &[Series]) -> String {
    let (w, h, l, r, t, b) = (760.0, 360.0, 70.0, 150.0, 30.0, 45.0);
    let pts = series
        .iter()
        .flat_map(|s| &s.xy)
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts {
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
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">
<rect width="100%" height="100%" fill="white"/>
<text x="{}" y="18" text-anchor="middle" font-size="14">{}</text>
"#,
        (l + w - r) / 2.0,
        esc(title)
    );
    let (xs, ys) = (step(x1 - x0), step(y1 - y0));
    let mut v = (x0 / xs).ceil() * xs;
    while v <= x1 + 1e-9 * xs {
        let _ = writeln!(
            s,
            r##"<line x1="{0:.1}" x2="{0:.1}" y1="{1}" y2="{2}" stroke="#ddd"/><text x="{0:.1}" y="{3}" text-anchor="middle">{4}</text>"##,
            sx(v),
            t,
            h - b,
            h - b + 15.0,
            fmt_tick(v, xs)
        );
        v += xs;
    }
    let mut v = (y0 / ys).ceil() * ys;
    while v <= y1 + 1e-9 * ys {
        let _ = writeln!(
            s,
            r##"<line x1="{0}" x2="{1}" y1="{2:.1}" y2="{2:.1}" stroke="#ddd"/><text x="{3}" y="{4:.1}" text-anchor="end">{5}</text>"##,
            l,
            w - r,
            sy(v),
            l - 5.0,
            sy(v) + 4.0,
            fmt_tick(v, ys)
        );
        v += ys;
    }
    let _ = writeln!(
        s,
        r##"<rect x="{l}" y="{t}" width="{}" height="{}" fill="none" stroke="#444"/>"##,
        w - l - r,
        h - t - b
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        (l + w - r) / 2.0,
        h - 8.0,
        esc(xlabel)
    );
    let _ = writeln!(
        s,
        r#"<text x="15" y="{}" text-anchor="middle" transform="rotate(-90 15 {})">{}</text>"#,
        (t + h - b) / 2.0,
        (t + h - b) / 2.0,
        esc(ylabel)
    );
    for (i, se) in series.iter().enumerate() {
        match se.style {
            Style::Line => {
                let mut d = String::new();
                let mut pen = false;
                for p in &se.xy {
                    if !(p.0.is_finite() && p.1.is_finite()) {
                        pen = false;
                        continue;
                    }
                    let _ = write!(
                        d,
                        "{}{:.1},{:.1} ",
                        if pen { "L" } else { "M" },
                        sx(p.0),
                        sy(p.1)
                    );
                    pen = true;
                }
                let _ = writeln!(
                    s,
                    r#"<path d="{d}" fill="none" stroke="{}" stroke-width="1.5"/>"#,
                    se.color
                );
            }
            Style::Points => {
                for p in se.xy.iter().filter(|p| p.0.is_finite() && p.1.is_finite()) {
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{:.1}" cy="{:.1}" r="1.8" fill="{}"/>"#,
                        sx(p.0),
                        sy(p.1),
                        se.color
                    );
                }
            }
        }
        let ly = t + 15.0 + 18.0 * i as f64;
        let _ = writeln!(
            s,
            r#"<rect x="{}" y="{}" width="12" height="8" fill="{}"/><text x="{}" y="{}">{}</text>"#,
            w - r + 10.0,
            ly - 8.0,
            se.color,
            w - r + 26.0,
            ly,
            esc(se.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn fmt_tick(v: f64, step: f64) -> String {
    let v = if v.abs() < step * 1e-9 { 0.0 } else { v };
    let digits = (-(step.log10().floor())).max(0.0) as usize;
    format!("{v:.digits$}")
}

/// Horizontal bars (label, value), with an optional vertical reference line.
pub fn bars(
    title: &str,
    xlabel: &str,
    items: &[(String, f64, &str)],
    reference: Option<(f64, &str)>,
) -> String {
    let n = items.len().max(1) as f64;
    let (w, l, r, t, b) = (760.0, 170.0, 30.0, 30.0, 40.0);
    let h = t + b + 24.0 * n;
    let vmax = items
        .iter()
        .map(|i| i.1)
        .chain(reference.map(|r| r.0))
        .filter(|v| v.is_finite())
        .fold(1e-12, f64::max);
    let sx = |v: f64| l + v.max(0.0) / vmax * (w - l - r);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12"><rect width="100%" height="100%" fill="white"/><text x="{}" y="18" text-anchor="middle" font-size="14">{}</text>"#,
        w / 2.0,
        esc(title)
    );
    for (i, (label, v, color)) in items.iter().enumerate() {
        let y = t + 24.0 * i as f64;
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="end">{}</text><rect x="{l}" y="{}" width="{:.1}" height="16" fill="{color}"/><text x="{:.1}" y="{}">{}</text>"#,
            l - 6.0,
            y + 13.0,
            esc(label),
            y + 2.0,
            sx(*v) - l,
            sx(*v) + 4.0,
            y + 13.0,
            if v.is_finite() {
                format!("{v:.2}")
            } else {
                "-".into()
            }
        );
    }
    if let Some((v, label)) = reference {
        let _ = writeln!(
            s,
            r##"<line x1="{0:.1}" x2="{0:.1}" y1="{1}" y2="{2}" stroke="#000" stroke-dasharray="4 3"/><text x="{0:.1}" y="{3}" text-anchor="middle">{4}</text>"##,
            sx(v),
            t - 4.0,
            h - b + 4.0,
            h - b + 18.0,
            esc(label)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text></svg>"#,
        (l + w - r) / 2.0,
        h - 6.0,
        esc(xlabel)
    );
    s
}
