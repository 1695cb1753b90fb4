//! `obsan calibrate --plot DIR`: the paper's Figures 5-7 as PNG and SVG files.

use crate::fsio::write_folder_atomically;
use crate::Failure;
use obsan_calib::CalibrateOptions;
use obsan_data::Dataset;
use obsan_fit::Predictor;
use obsan_plot::{self as plot, chart, Style, BLACK, COLORS};

/// The paper's Figures 5-7 for each trajectory, as PNG and SVG: the
/// observation function with the nodes (5c-d, 6a-b), sigma(s_c) of
/// Algorithm 1 (5e-f, 6c-d), and observed vs DET vs LS vs ML (6e-f).
pub(crate) fn write_figures(
    dir: &str,
    force: bool,
    reads: &[&str],
    data: &Dataset,
    p: &Predictor,
    o: &CalibrateOptions,
    done: &obsan_calib::CalibrationReport,
) -> Result<usize, Failure> {
    let curves = done
        .figure_curves(data, p, o)
        .map_err(|e| Failure(format!("--plot: {e}")))?;
    let mut files = Vec::new();
    let mut index = String::from("# Figures 5-7 (Martinelli 2011)\n\n");
    let xlabel = "s (rad of right-wheel rotation)";
    for c in &curves {
        let zip = |y: &[f64]| {
            c.s.iter()
                .copied()
                .zip(y.iter().copied())
                .collect::<Vec<_>>()
        };
        // Angles are drawn in degrees, as the CLI prints them (curves.json keeps radians);
        // wrapping (plot::wrapped_angles) works in radians, so convert after it.
        let deg = |xy: Vec<(f64, f64)>| -> Vec<(f64, f64)> {
            xy.into_iter().map(|(x, y)| (x, y.to_degrees())).collect()
        };
        let observed = plot::Series {
            name: "observed",
            color: COLORS[0],
            style: Style::Points,
            xy: deg(zip(&c.observed)),
        };
        let stem = |kind: &str| format!("{}_{kind}", c.name.replace(['/', '\\', ' '], "_"));
        let fig = chart(
            &format!("{} (q = {}): observation function and nodes", c.name, c.q),
            xlabel,
            "beta (deg)",
            &[
                observed,
                plot::Series {
                    name: "nodes",
                    color: COLORS[1],
                    style: Style::Stars,
                    xy: deg(c.nodes.clone()),
                },
            ],
        );
        files.extend(plot::figure_files(&stem("observation"), &fig));
        let best = c
            .sigma_curve
            .iter()
            .copied()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .into_iter()
            .collect();
        let fig = chart(
            &format!("{} (q = {}): sigma(s_c) of Algorithm 1", c.name, c.q),
            "s_c (rad of right-wheel rotation)",
            "sigma (deg)",
            &[
                plot::Series {
                    name: "sigma(s_c)",
                    color: COLORS[0],
                    style: Style::Line,
                    xy: deg(c.sigma_curve.clone()),
                },
                plot::Series {
                    name: "minimum",
                    color: COLORS[1],
                    style: Style::Stars,
                    xy: deg(best),
                },
            ],
        );
        files.extend(plot::figure_files(&stem("sigma"), &fig));
        let mut series = vec![
            plot::Series {
                name: "observed",
                color: COLORS[0],
                style: Style::Points,
                xy: deg(zip(&c.observed)),
            },
            plot::Series {
                name: "DET",
                color: COLORS[1],
                style: Style::Line,
                xy: deg(plot::wrapped_angles(&zip(&c.det))),
            },
            plot::Series {
                name: "LS",
                color: BLACK,
                style: Style::Line,
                xy: deg(plot::wrapped_angles(&zip(&c.ls))),
            },
        ];
        if let Some(ml) = &c.ml {
            series.push(plot::Series {
                name: "ML",
                color: COLORS[2],
                style: Style::Line,
                xy: deg(plot::wrapped_angles(&zip(ml))),
            });
        }
        let fig = chart(
            &format!("{} (q = {}): observed, DET, LS, ML", c.name, c.q),
            xlabel,
            "beta (deg)",
            &series,
        );
        files.extend(plot::figure_files(&stem("fits"), &fig));
        index.push_str(&format!(
            "## {} (q = {})\n\n![observation]({o}.png)\n\n![sigma]({s}.png)\n\n![fits]({f}.png)\n\n",
            c.name,
            c.q,
            o = stem("observation"),
            s = stem("sigma"),
            f = stem("fits")
        ));
        if c.ml.is_none() {
            index.push_str(
                "(maximum likelihood did not converge on these data; its curve is left out)\n\n",
            );
        }
    }
    let n = files.len() / 2;
    files.push((std::path::PathBuf::from("index.md"), index.into_bytes()));
    // The same curves as data, for other plotting tools (the Python example
    // draws Figure 5 from them).
    let data: Vec<serde_json::Value> = curves
        .iter()
        .map(|c| {
            serde_json::json!({
                "name": c.name, "q": c.q, "s": c.s, "observed": c.observed, "det": c.det,
                "ls": c.ls, "ml": c.ml, "nodes": c.nodes, "sigma_curve": c.sigma_curve,
                "node": c.node,
            })
        })
        .collect();
    files.push((
        std::path::PathBuf::from("curves.json"),
        (serde_json::to_string(&data)? + "\n").into_bytes(),
    ));
    write_folder_atomically(dir, force, reads, &files)?;
    Ok(n)
}
