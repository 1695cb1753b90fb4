//! The display list as SVG text.

use crate::{Anchor, Figure, Op, Rgb};
use std::fmt::Write;

impl Figure {
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
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
