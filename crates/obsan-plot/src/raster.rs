//! The display list rasterised: anti-aliased shapes by pixel coverage, text
//! from the embedded DejaVu Sans.
//!
//! Kept rather than `tiny-skia`: a chart draws four shapes (filled rectangles,
//! polylines solid or dashed, dots, glyphs whose coverage ab_glyph already
//! gives), about 200 lines here, where a general path renderer would add a
//! crate tree and still need ab_glyph for the text.

use crate::{Anchor, Figure, Op, Rgb, BLACK};

impl Figure {
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

/// A linear-light-free RGB canvas (blending in sRGB, as SVG renderers do).
pub(crate) struct Raster {
    pub(crate) w: usize,
    pub(crate) h: usize,
    pub(crate) px: Vec<[f32; 3]>,
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
}

/// Splits a polyline into dash segments (`on` drawn, `off` skipped).
pub(crate) fn dashes(pts: &[(f64, f64)], on: f64, off: f64) -> Vec<((f64, f64), (f64, f64))> {
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
