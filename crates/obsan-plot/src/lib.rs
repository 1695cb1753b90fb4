//! Charts for reports and figures. A chart is drawn once into a display list
//! ([`Figure`]) and written either as SVG text or as a PNG that is rasterised
//! here: anti-aliased shapes by pixel coverage, text from the embedded DejaVu
//! Sans (ab_glyph), zlib by miniz_oxide. No system library or font is needed,
//! so the figures look the same on every machine.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

use std::fmt::Write;

/// An sRGB colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    fn hex(self) -> String {
        format!("#{:02x}{:02x}{:02x}", self.0, self.1, self.2)
    }
}

pub const BLACK: Rgb = Rgb(0, 0, 0);
pub const GREY: Rgb = Rgb(0x88, 0x88, 0x88);
const LIGHT: Rgb = Rgb(0xdd, 0xdd, 0xdd);
const FRAME: Rgb = Rgb(0x44, 0x44, 0x44);
pub const PALE: Rgb = Rgb(0xbb, 0xbb, 0xbb);

/// The series colours (matplotlib's first six).
pub const COLORS: [Rgb; 6] = [
    Rgb(0x1f, 0x77, 0xb4),
    Rgb(0xd6, 0x27, 0x28),
    Rgb(0x2c, 0xa0, 0x2c),
    Rgb(0xff, 0x7f, 0x0e),
    Rgb(0x94, 0x67, 0xbd),
    Rgb(0x8c, 0x56, 0x4b),
];

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Style {
    Line,
    Points,
    /// Large asterisks (the paper's red stars on the detected nodes).
    Stars,
}

pub struct Series<'a> {
    pub name: &'a str,
    pub color: Rgb,
    pub style: Style,
    pub xy: Vec<(f64, f64)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Anchor {
    Start,
    Middle,
    End,
}

#[derive(Clone, Debug)]
enum Op {
    Rect {
        x: f64,
        y: f64,
        w: f64,
        h: f64,
        fill: Option<Rgb>,
        stroke: Option<Rgb>,
    },
    /// An open polyline.
    Path {
        pts: Vec<(f64, f64)>,
        color: Rgb,
        width: f64,
        dashed: bool,
        /// 1 opaque; below 1 what is under the line shows through.
        opacity: f64,
    },
    Dot {
        x: f64,
        y: f64,
        r: f64,
        color: Rgb,
    },
    Text {
        x: f64,
        y: f64,
        text: String,
        size: f64,
        anchor: Anchor,
        /// Rotated by -90 degrees about (x, y) (a y-axis label).
        vertical: bool,
    },
}

/// A drawing in pixel coordinates (origin top left), written as SVG or PNG.
#[derive(Clone, Debug)]
pub struct Figure {
    w: f64,
    h: f64,
    ops: Vec<Op>,
}

impl Figure {
    fn new(w: f64, h: f64) -> Figure {
        Figure {
            w,
            h,
            ops: vec![Op::Rect {
                x: 0.0,
                y: 0.0,
                w,
                h,
                fill: Some(Rgb(255, 255, 255)),
                stroke: None,
            }],
        }
    }

    fn line(&mut self, a: (f64, f64), b: (f64, f64), color: Rgb, width: f64, dashed: bool) {
        self.ops.push(Op::Path {
            pts: vec![a, b],
            color,
            width,
            dashed,
            opacity: 1.0,
        });
    }

    fn text(&mut self, x: f64, y: f64, text: &str, size: f64, anchor: Anchor) {
        self.ops.push(Op::Text {
            x,
            y,
            text: text.to_string(),
            size,
            anchor,
            vertical: false,
        });
    }

    /// SVG text of the figure.
    pub fn to_svg(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{}" font-family="DejaVu Sans, sans-serif" font-size="12">"#,
            self.w, self.h
        );
        for op in &self.ops {
            match op {
                Op::Rect {
                    x,
                    y,
                    w,
                    h,
                    fill,
                    stroke,
                } => {
                    let _ = writeln!(
                        s,
                        r#"<rect x="{x:.1}" y="{y:.1}" width="{w:.1}" height="{h:.1}" fill="{}" stroke="{}"/>"#,
                        fill.map_or("none".into(), Rgb::hex),
                        stroke.map_or("none".into(), Rgb::hex)
                    );
                }
                Op::Path {
                    pts,
                    color,
                    width,
                    dashed,
                    opacity,
                } => {
                    let mut d = String::new();
                    for (i, p) in pts.iter().enumerate() {
                        let _ = write!(
                            d,
                            "{}{:.1},{:.1} ",
                            if i == 0 { "M" } else { "L" },
                            p.0,
                            p.1
                        );
                    }
                    let _ = writeln!(
                        s,
                        r#"<path d="{}" fill="none" stroke="{}" stroke-width="{width}"{}{}/>"#,
                        d.trim_end(),
                        color.hex(),
                        if *dashed {
                            r#" stroke-dasharray="4 3""#
                        } else {
                            ""
                        },
                        if *opacity < 1.0 {
                            format!(r#" stroke-opacity="{opacity}""#)
                        } else {
                            String::new()
                        }
                    );
                }
                Op::Dot { x, y, r, color } => {
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" fill="{}"/>"#,
                        color.hex()
                    );
                }
                Op::Text {
                    x,
                    y,
                    text,
                    size,
                    anchor,
                    vertical,
                } => {
                    let a = match anchor {
                        Anchor::Start => "start",
                        Anchor::Middle => "middle",
                        Anchor::End => "end",
                    };
                    let rot = if *vertical {
                        format!(r#" transform="rotate(-90 {x:.1} {y:.1})""#)
                    } else {
                        String::new()
                    };
                    let _ = writeln!(
                        s,
                        r#"<text x="{x:.1}" y="{y:.1}" font-size="{size}" text-anchor="{a}"{rot}>{}</text>"#,
                        esc(text)
                    );
                }
            }
        }
        s.push_str("</svg>\n");
        s
    }

    /// PNG bytes of the figure at `scale` times its size (2 gives crisp
    /// figures for papers and high-density screens).
    pub fn to_png(&self, scale: f64) -> Vec<u8> {
        let mut r = Raster::new(
            (self.w * scale).round() as usize,
            (self.h * scale).round() as usize,
        );
        let sc = |p: &(f64, f64)| (p.0 * scale, p.1 * scale);
        for op in &self.ops {
            match op {
                Op::Rect {
                    x,
                    y,
                    w,
                    h,
                    fill,
                    stroke,
                } => {
                    let (x0, y0, x1, y1) = (x * scale, y * scale, (x + w) * scale, (y + h) * scale);
                    if let Some(c) = fill {
                        r.fill_rect(x0, y0, x1, y1, *c);
                    }
                    if let Some(c) = stroke {
                        let corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)];
                        r.polyline(&corners, *c, scale, false, 1.0);
                    }
                }
                Op::Path {
                    pts,
                    color,
                    width,
                    dashed,
                    opacity,
                } => {
                    let p: Vec<(f64, f64)> = pts.iter().map(sc).collect();
                    r.polyline(&p, *color, width * scale, *dashed, *opacity as f32);
                }
                Op::Dot {
                    x,
                    y,
                    r: rad,
                    color,
                } => r.dot(x * scale, y * scale, rad * scale, *color),
                Op::Text {
                    x,
                    y,
                    text,
                    size,
                    anchor,
                    vertical,
                } => r.text(x * scale, y * scale, text, size * scale, *anchor, *vertical),
            }
        }
        r.png()
    }
}

/// A figure as `stem.svg` and `stem.png`.
pub fn figure_files(stem: &str, f: &Figure) -> [(std::path::PathBuf, Vec<u8>); 2] {
    [
        (
            std::path::PathBuf::from(format!("{stem}.svg")),
            f.to_svg().into_bytes(),
        ),
        (
            std::path::PathBuf::from(format!("{stem}.png")),
            f.to_png(2.0),
        ),
    ]
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
    let n = items.len().max(1) as f64;
    let (w, l, r, t, b) = (760.0, 170.0, 80.0, 30.0, 40.0);
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
    if let Some((v, label)) = reference {
        f.line((sx(v), t - 4.0), (sx(v), h - b + 4.0), BLACK, 1.0, true);
        f.text(sx(v), h - b + 18.0, label, 12.0, Anchor::Middle);
    }
    f.text((l + w - r) / 2.0, h - 6.0, xlabel, 12.0, Anchor::Middle);
    f
}

/// A linear-light-free RGB canvas (blending in sRGB, as SVG renderers do).
struct Raster {
    w: usize,
    h: usize,
    px: Vec<[f32; 3]>,
}

impl Raster {
    fn new(w: usize, h: usize) -> Raster {
        Raster {
            w,
            h,
            px: vec![[255.0; 3]; w * h],
        }
    }

    fn blend(&mut self, x: i64, y: i64, c: Rgb, a: f32) {
        if a <= 0.0 || x < 0 || y < 0 || x >= self.w as i64 || y >= self.h as i64 {
            return;
        }
        let a = a.min(1.0);
        let p = &mut self.px[y as usize * self.w + x as usize];
        for (v, t) in p.iter_mut().zip([c.0, c.1, c.2]) {
            *v += (t as f32 - *v) * a;
        }
    }

    /// Axis-aligned fill with fractional edge coverage.
    fn fill_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, c: Rgb) {
        let (x0, x1) = (x0.min(x1), x0.max(x1));
        let (y0, y1) = (y0.min(y1), y0.max(y1));
        for y in y0.floor() as i64..y1.ceil() as i64 {
            let cy = ((y + 1) as f64).min(y1) - (y as f64).max(y0);
            for x in x0.floor() as i64..x1.ceil() as i64 {
                let cx = ((x + 1) as f64).min(x1) - (x as f64).max(x0);
                self.blend(x, y, c, (cx * cy) as f32);
            }
        }
    }

    /// A stroked polyline: the coverage of each pixel is the largest over the
    /// segments (so joints are not painted twice), then blended once.
    fn polyline(&mut self, pts: &[(f64, f64)], c: Rgb, width: f64, dashed: bool, opacity: f32) {
        if pts.len() < 2 {
            return;
        }
        let segs: Vec<((f64, f64), (f64, f64))> = if dashed {
            dashes(pts, 4.0 * width.max(1.0), 3.0 * width.max(1.0))
        } else {
            pts.windows(2).map(|w| (w[0], w[1])).collect()
        };
        let half = width / 2.0;
        let (mut bx0, mut by0, mut bx1, mut by1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
        for (a, b) in &segs {
            bx0 = bx0.min((a.0.min(b.0) - half - 1.0).floor() as i64);
            by0 = by0.min((a.1.min(b.1) - half - 1.0).floor() as i64);
            bx1 = bx1.max((a.0.max(b.0) + half + 1.0).ceil() as i64);
            by1 = by1.max((a.1.max(b.1) + half + 1.0).ceil() as i64);
        }
        bx0 = bx0.max(0);
        by0 = by0.max(0);
        bx1 = bx1.min(self.w as i64);
        by1 = by1.min(self.h as i64);
        if bx0 >= bx1 || by0 >= by1 {
            return;
        }
        let bw = (bx1 - bx0) as usize;
        let mut cov = vec![0f32; bw * (by1 - by0) as usize];
        // Lines thinner than a pixel are drawn one pixel wide and faded.
        let (hw, fade) = if width < 1.0 {
            (0.5, width as f32)
        } else {
            (half, 1.0)
        };
        for (a, b) in &segs {
            let xa = ((a.0.min(b.0) - hw - 1.0).floor() as i64).max(bx0);
            let xb = ((a.0.max(b.0) + hw + 1.0).ceil() as i64).min(bx1);
            let ya = ((a.1.min(b.1) - hw - 1.0).floor() as i64).max(by0);
            let yb = ((a.1.max(b.1) + hw + 1.0).ceil() as i64).min(by1);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len2 = dx * dx + dy * dy;
            for y in ya..yb {
                for x in xa..xb {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let u = if len2 > 0.0 {
                        (((px - a.0) * dx + (py - a.1) * dy) / len2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let d = (px - a.0 - u * dx).hypot(py - a.1 - u * dy);
                    let v = ((hw + 0.5 - d).clamp(0.0, 1.0)) as f32 * fade;
                    let k = (y - by0) as usize * bw + (x - bx0) as usize;
                    if v > cov[k] {
                        cov[k] = v;
                    }
                }
            }
        }
        for y in by0..by1 {
            for x in bx0..bx1 {
                let v = cov[(y - by0) as usize * bw + (x - bx0) as usize];
                self.blend(x, y, c, v * opacity);
            }
        }
    }

    fn dot(&mut self, x: f64, y: f64, r: f64, c: Rgb) {
        for py in (y - r - 1.0).floor() as i64..=(y + r + 1.0).ceil() as i64 {
            for px in (x - r - 1.0).floor() as i64..=(x + r + 1.0).ceil() as i64 {
                let d = (px as f64 + 0.5 - x).hypot(py as f64 + 0.5 - y);
                self.blend(px, py, c, (r + 0.5 - d).clamp(0.0, 1.0) as f32);
            }
        }
    }

    /// Text with its baseline at y; `size` is the em size in pixels (as SVG's
    /// font-size). Vertical text is turned -90 degrees about (x, y).
    fn text(&mut self, x: f64, y: f64, s: &str, size: f64, anchor: Anchor, vertical: bool) {
        use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
        let Ok(font) = FontRef::try_from_slice(dejavu::sans::regular()) else {
            return;
        };
        let em = font.units_per_em().unwrap_or(2048.0);
        let scale = PxScale::from((size as f32) * font.height_unscaled() / em);
        let sf = font.as_scaled(scale);
        let mut glyphs = Vec::new();
        let mut caret = 0f32;
        let mut prev = None;
        for ch in s.chars() {
            let id = font.glyph_id(ch);
            if let Some(p) = prev {
                caret += sf.kern(p, id);
            }
            glyphs.push(id.with_scale_and_position(scale, ab_glyph::point(caret, 0.0)));
            caret += sf.h_advance(id);
            prev = Some(id);
        }
        let shift = match anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => -caret as f64 / 2.0,
            Anchor::End => -caret as f64,
        };
        for g in glyphs {
            let Some(og) = font.outline_glyph(g) else {
                continue;
            };
            let bb = og.px_bounds();
            og.draw(|gx, gy, c| {
                // (u, v): the pixel relative to the text origin.
                let u = bb.min.x as f64 + gx as f64 + shift;
                let v = bb.min.y as f64 + gy as f64;
                let (px, py) = if vertical {
                    (x + v, y - u - 1.0)
                } else {
                    (x + u, y + v)
                };
                self.blend(px.floor() as i64, py.floor() as i64, BLACK, c);
            });
        }
    }

    fn png(&self) -> Vec<u8> {
        let mut raw = Vec::with_capacity(self.h * (1 + 3 * self.w));
        for row in self.px.chunks(self.w) {
            raw.push(0); // filter: none
            for p in row {
                raw.extend(p.iter().map(|v| v.round().clamp(0.0, 255.0) as u8));
            }
        }
        let mut out = vec![0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
        let mut ihdr = Vec::new();
        ihdr.extend((self.w as u32).to_be_bytes());
        ihdr.extend((self.h as u32).to_be_bytes());
        ihdr.extend([8, 2, 0, 0, 0]); // 8-bit RGB, deflate, no filter set, no interlace
        chunk(&mut out, b"IHDR", &ihdr);
        chunk(
            &mut out,
            b"IDAT",
            &miniz_oxide::deflate::compress_to_vec_zlib(&raw, 6),
        );
        chunk(&mut out, b"IEND", &[]);
        out
    }
}

/// Splits a polyline into dash segments (`on` drawn, `off` skipped).
fn dashes(pts: &[(f64, f64)], on: f64, off: f64) -> Vec<((f64, f64), (f64, f64))> {
    let mut out = Vec::new();
    let (mut drawing, mut left) = (true, on);
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        let mut pos = 0.0;
        while pos < len {
            let take = left.min(len - pos);
            let p = |s: f64| (a.0 + (b.0 - a.0) * s / len, a.1 + (b.1 - a.1) * s / len);
            if drawing {
                out.push((p(pos), p(pos + take)));
            }
            pos += take;
            left -= take;
            if left <= 1e-12 {
                drawing = !drawing;
                left = if drawing { on } else { off };
            }
        }
    }
    out
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend((data.len() as u32).to_be_bytes());
    out.extend(kind);
    out.extend(data);
    out.extend(crc32(kind.iter().chain(data)).to_be_bytes());
}

/// CRC-32 (ISO 3309, as PNG requires), bitwise: PNG files here are small.
fn crc32<'a>(bytes: impl Iterator<Item = &'a u8>) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    c ^ 0xffff_ffff
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes our own PNG (8-bit RGB, filter 0) back to pixels, checking
    /// the chunk CRCs on the way.
    fn decode(png: &[u8]) -> (usize, usize, Vec<u8>) {
        assert_eq!(&png[..8], &[0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a]);
        let (mut i, mut w, mut h, mut idat) = (8, 0, 0, Vec::new());
        while i < png.len() {
            let n = u32::from_be_bytes(png[i..i + 4].try_into().unwrap()) as usize;
            let kind = &png[i + 4..i + 8];
            let data = &png[i + 8..i + 8 + n];
            let crc = u32::from_be_bytes(png[i + 8 + n..i + 12 + n].try_into().unwrap());
            assert_eq!(crc, crc32(png[i + 4..i + 8 + n].iter()), "crc of {kind:?}");
            match kind {
                b"IHDR" => {
                    w = u32::from_be_bytes(data[0..4].try_into().unwrap()) as usize;
                    h = u32::from_be_bytes(data[4..8].try_into().unwrap()) as usize;
                    assert_eq!(&data[8..], &[8, 2, 0, 0, 0]);
                }
                b"IDAT" => idat.extend_from_slice(data),
                _ => {}
            }
            i += 12 + n;
        }
        let raw = miniz_oxide::inflate::decompress_to_vec_zlib(&idat).unwrap();
        assert_eq!(raw.len(), h * (1 + 3 * w));
        let mut px = Vec::new();
        for row in raw.chunks(1 + 3 * w) {
            assert_eq!(row[0], 0);
            px.extend_from_slice(&row[1..]);
        }
        (w, h, px)
    }

    #[test]
    fn crc_of_known_string() {
        // The CRC-32 check value of "123456789".
        assert_eq!(crc32(b"123456789".iter()), 0xcbf4_3926);
    }

    #[test]
    fn png_puts_series_where_the_axes_say() {
        // A horizontal red line at y = 0.5 over x in [0, 1]: the chart's y
        // range is [0.5 - 0.5 - pad, 0.5 + 0.5 + pad] -> its middle row.
        let s = [Series {
            name: "red",
            color: COLORS[1],
            style: Style::Line,
            xy: vec![(0.0, 0.5), (1.0, 0.5)],
        }];
        let f = chart("title", "x", "y", &s);
        let (w, h, px) = decode(&f.to_png(1.0));
        assert_eq!((w, h), (760, 360));
        let at = |x: usize, y: usize| {
            let k = 3 * (y * w + x);
            (px[k], px[k + 1], px[k + 2])
        };
        // Plot area: x 70..610, y 30..315; middle row 172.5.
        let red = |p: (u8, u8, u8)| p.0 > 150 && p.1 < 120 && p.2 < 120;
        assert!(red(at(300, 172)) || red(at(300, 173)));
        assert!(!red(at(300, 100)));
        // The title is drawn in black around (340, 18).
        let dark = (0..30)
            .flat_map(|y| (300..380).map(move |x| (x, y)))
            .filter(|&(x, y)| at(x, y).0 < 100)
            .count();
        assert!(dark > 30, "title pixels: {dark}");
        // Twice the scale, twice the size.
        let (w2, h2, _) = decode(&f.to_png(2.0));
        assert_eq!((w2, h2), (1520, 720));
    }

    #[test]
    fn svg_and_png_draw_the_same_list() {
        let items = vec![
            ("a".to_string(), 2.0, COLORS[0]),
            ("b".into(), f64::NAN, PALE),
        ];
        let f = bars("t", "x", &items, Some((1.0, "crit")));
        let svg = f.to_svg();
        assert_eq!(svg.matches("<rect").count(), 2); // background + one finite bar
        assert!(svg.contains("stroke-dasharray"));
        let (w, _, px) = decode(&f.to_png(1.0));
        // The bar of value 2 spans x from 170 to 730, at y 32..48.
        let k = 3 * (40 * w + 600);
        assert_eq!((px[k], px[k + 1], px[k + 2]), (0x1f, 0x77, 0xb4));
    }

    #[test]
    fn dashes_cover_the_on_fraction() {
        let d = dashes(&[(0.0, 0.0), (70.0, 0.0)], 4.0, 3.0);
        let on: f64 = d.iter().map(|(a, b)| b.0 - a.0).sum();
        assert!((on - 40.0).abs() < 1e-9, "{on}");
    }

    fn pixel(px: &[u8], w: usize, x: usize, y: usize) -> (u8, u8, u8) {
        let k = 3 * (y * w + x);
        (px[k], px[k + 1], px[k + 2])
    }

    fn reddish(p: (u8, u8, u8)) -> bool {
        p.0 > 150 && p.1 < 140 && p.2 < 140
    }

    fn wrap(a: f64) -> f64 {
        let t = 2.0 * std::f64::consts::PI;
        a - t * ((a + std::f64::consts::PI) / t).floor()
    }

    #[test]
    fn a_wrapped_angle_draws_no_stroke_across_the_plot() {
        use std::f64::consts::PI;
        // A sawtooth: y = 3x wrapped to [-pi, pi), wrapping at x = pi/3 and pi.
        let xy: Vec<(f64, f64)> = (0..=400)
            .map(|i| {
                let x = i as f64 / 100.0;
                (x, wrap(3.0 * x))
            })
            .collect();
        let draw = |xy: Vec<(f64, f64)>| {
            let s = [Series {
                name: "angle",
                color: COLORS[1],
                style: Style::Line,
                xy,
            }];
            decode(&chart("t", "x (s)", "angle (rad)", &s).to_png(1.0))
        };
        // The axes: x in [0, 4] over columns 70..610; y in [-1.1 pi, 1.1 pi]
        // (the edges +-pi and a 5% pad) over rows 30..315.
        let col = |x: f64| 70.0 + x / 4.0 * 540.0;
        let row = |y: f64| 30.0 + (1.1 * PI - y) / (2.2 * PI) * 285.0;
        let band = |px: &[u8], w: usize, xw: f64| {
            let (c, r0, r1) = (col(xw), row(1.5), row(-1.5));
            (c as usize - 4..c as usize + 5)
                .flat_map(|x| (r0 as usize + 2..r1 as usize - 2).map(move |y| (x, y)))
                .filter(|&(x, y)| reddish(pixel(px, w, x, y)))
                .count()
        };
        // Drawn as is, the wraps are vertical strokes through the middle.
        let (w, _, raw) = draw(xy.clone());
        assert!(band(&raw, w, PI / 3.0) > 50 && band(&raw, w, PI) > 50);
        let (w, h, px) = draw(wrapped_angles(&xy));
        assert_eq!((w, h), (760, 360));
        for xw in [PI / 3.0, PI] {
            assert_eq!(band(&px, w, xw), 0, "stroke across the middle at x = {xw}");
            // The curve runs up to the top edge, and on from the bottom one.
            let c = col(xw) as usize;
            let near = |y: f64, x0: usize, x1: usize| {
                (x0..x1).any(|x| {
                    (row(y) as usize - 2..row(y) as usize + 3).any(|y| reddish(pixel(&px, w, x, y)))
                })
            };
            assert!(near(PI, c - 4, c + 1), "no line to +pi at x = {xw}");
            assert!(near(-PI, c, c + 5), "no line from -pi at x = {xw}");
        }
        // Elsewhere the line is unbroken: it crosses y = 0 at x = 2 pi / 3.
        let (c, r) = (col(2.0 * PI / 3.0) as usize, row(0.0) as usize);
        assert!((c - 2..c + 3).any(|x| (r - 2..r + 3).any(|y| reddish(pixel(&px, w, x, y)))));
    }

    #[test]
    fn wrapped_angles_cut_at_the_edge_crossed() {
        use std::f64::consts::PI;
        // Down through -pi halfway between x = 0 and x = 1.
        let out = wrapped_angles(&[(0.0, -PI + 0.1), (1.0, PI - 0.1)]);
        assert_eq!(out.len(), 5);
        assert!((out[1].0 - 0.5).abs() < 1e-12 && out[1].1 == -PI);
        assert!(out[2].0.is_nan());
        assert!((out[3].0 - 0.5).abs() < 1e-12 && out[3].1 == PI);
        // Up through +pi a quarter of the way.
        let out = wrapped_angles(&[(0.0, PI - 0.1), (1.0, -PI + 0.3)]);
        assert!((out[1].0 - 0.25).abs() < 1e-12 && out[1].1 == PI);
        assert!(out[3].1 == -PI);
        // No wrap, no change; a gap resets.
        let xy = [(0.0, 3.0), (1.0, 0.5), (2.0, f64::NAN), (3.0, -3.0)];
        let out = wrapped_angles(&xy);
        assert_eq!(out.len(), 4);
        assert_eq!(out[3], (3.0, -3.0));
    }

    #[test]
    fn a_point_under_a_fitted_line_stays_visible() {
        // A measured point at (0.5, 0.5) and a fitted line through it, the
        // point given first (as the figures do) and then last.
        let point = || Series {
            name: "measured",
            color: COLORS[0],
            style: Style::Points,
            xy: vec![(0.5, 0.5)],
        };
        let line = || Series {
            name: "fit",
            color: COLORS[1],
            style: Style::Line,
            xy: vec![(0.0, 0.5), (1.0, 0.5)],
        };
        for s in [[point(), line()], [line(), point()]] {
            let f = chart("t", "time (s)", "y (m)", &s);
            let (w, _, px) = decode(&f.to_png(1.0));
            // The point at column 340, row 172.5; the line over rows 171.75..173.25.
            let line_alone = pixel(&px, w, 300, 172);
            assert!(reddish(line_alone), "{line_alone:?}");
            let centre = pixel(&px, w, 340, 172);
            assert!(
                centre.0 + 20 < line_alone.0,
                "the point does not show through the line: {centre:?} vs {line_alone:?}"
            );
            // Above and below the line the point's own colour shows.
            for y in [170, 174] {
                let p = pixel(&px, w, 340, y);
                assert!(p.2 as i32 > p.0 as i32 + 80, "row {y}: {p:?}");
            }
            assert!(f.to_svg().contains("stroke-opacity"));
        }
    }
}
