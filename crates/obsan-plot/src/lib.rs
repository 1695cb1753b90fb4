//! Charts for reports and figures. A chart is drawn once into a display list
//! ([`Figure`]) and written either as SVG text or as a PNG that is rasterised
//! here: anti-aliased shapes by pixel coverage, text from the embedded DejaVu
//! Sans (ab_glyph), zlib by miniz_oxide. No system library or font is needed,
//! so the figures look the same on every machine.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod chart;
mod png;
mod raster;
mod svg;

pub use chart::{bars, bars_with_legend, chart, wrapped_angles};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::png::crc32;
    use crate::raster::dashes;

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
