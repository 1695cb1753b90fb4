//! `obsan diagnose`: every printed estimate with its unit (issue 37,
//! failure 8). The units come from obsan-diagnose's dimensional analysis
//! of the effects (`dimensions::param_units`, docs/diagnose.md, Units);
//! this module only writes them: rad also in deg, a pure number also in %,
//! a column's own unit as the file it is read from.

use obsan_diagnose::{dimensions::param_units, generate, Diagnosis, Generation};
use obsan_model::{EffectLibrary, System, Unit};
use std::collections::BTreeMap;

/// The units of the params diagnose printed, and where each column is read.
#[derive(Default)]
pub struct Units {
    of: BTreeMap<String, Unit>,
    /// Names of the model's outputs (their columns are in outputs.csv).
    outputs: Vec<String>,
}

impl Units {
    /// From the model, the effects file and, when diagnose generated
    /// candidates, the same generated ones (the same call as the workflow's).
    pub fn new(sys: &System, lib: Option<&EffectLibrary>, generated: bool, d: &Diagnosis) -> Units {
        let gen = if generated {
            let file: Vec<_> = lib
                .map(|l| l.effects.iter().filter(|e| !e.is_input_side()).collect())
                .unwrap_or_default();
            generate(sys, &file)
        } else {
            Generation::default()
        };
        // Angle outputs as the fit read them (and as the report's axes).
        let angular = |y: &str| d.nominal.series.iter().any(|s| s.output == y && s.angular);
        Units {
            of: param_units(sys, lib, &gen.candidates, &angular),
            outputs: sys.output_names().iter().map(|s| s.to_string()).collect(),
        }
    }

    /// The unit as JSON gives it: `rad`, `s`, `1/s`, `1` (a pure number),
    /// `[r]` (r's column's own unit); `None`: not derived.
    pub fn json(&self, param: &str) -> Option<String> {
        self.of.get(param).map(Unit::to_string)
    }

    /// The unit in a table's column: `rad`, `1` (a pure number), `1/s`,
    /// `units of r in outputs.csv`; `-` when none was derived.
    pub fn label(&self, param: &str) -> String {
        match self.of.get(param) {
            None => "-".into(),
            Some(u) if u.is_one() || u.is("rad") => u.to_string(),
            Some(u) => {
                let w = self.words(u, 0.0);
                match w.strip_prefix('(').and_then(|w| w.strip_suffix(')')) {
                    Some(inner) => inner.to_string(),
                    None => w,
                }
            }
        }
    }

    /// A combination's text, `(in the units of p0: rad; ...)` where p0's
    /// unit is known.
    pub fn combination(&self, c: &obsan_diagnose::statistics::Combination) -> String {
        let p0 = &c.params[0];
        let t = c.text();
        match self.of.get(p0) {
            None => t,
            Some(_) => t.replacen(
                &format!("(in the units of {p0};"),
                &format!("(in the units of {p0}: {};", self.label(p0)),
                1,
            ),
        }
    }

    /// `v ± sd UNIT (the same in deg or %)`; without a unit, `v ± sd`.
    pub fn pm(&self, param: &str, v: f64, sd: f64) -> String {
        let base = format!("{v:.4e} ± {sd:.1e}");
        match self.of.get(param) {
            None => base,
            Some(u) => format!("{base} {}", self.words(u, v)),
        }
    }

    /// The unit after a value `v`: `rad (3.44 deg)`, `(4.07 %)`, `s`,
    /// `(units of r in outputs.csv)`.
    fn words(&self, u: &Unit, v: f64) -> String {
        if u.is_one() {
            return format!("({} %)", sig3(100.0 * v));
        }
        if u.is("rad") {
            return format!("rad ({} deg)", sig3(v.to_degrees()));
        }
        let cols = u.columns();
        let file = |c: &str| match self.outputs.iter().any(|o| o == c) {
            true => "outputs.csv",
            false => "inputs.csv",
        };
        match cols.as_slice() {
            [] => u.to_string(),
            [c] if u.is(&format!("[{c}]")) => format!("(units of {c} in {})", file(c)),
            _ => {
                let legend: Vec<String> = cols
                    .iter()
                    .map(|c| format!("[{c}] the unit of {c} in {}", file(c)))
                    .collect();
                format!("{u} ({})", legend.join(", "))
            }
        }
    }
}

/// `x` with three significant digits, in fixed notation.
fn sig3(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (2 - x.abs().log10().floor() as i32).clamp(0, 12) as usize;
    format!("{x:.digits$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_carry_their_units_in_words() {
        let u = Units {
            of: [
                ("db", "rad"),
                ("kb", "1"),
                ("tau", "s"),
                ("gd", "1/s"),
                ("c", "m"),
            ]
            .into_iter()
            .map(|(p, t)| (p.to_string(), Unit::parse(t).unwrap()))
            .chain([
                ("gb".to_string(), Unit::column("r")),
                (
                    "gq".to_string(),
                    Unit::one().times_pow(&Unit::column("r"), -1).unwrap(),
                ),
            ])
            .collect(),
            outputs: vec!["r".into()],
        };
        // 0.0209 rad = 0.0209 * 180 / pi deg = 1.1975 deg.
        assert_eq!(
            u.pm("db", 0.0209, 0.001),
            "2.0900e-2 ± 1.0e-3 rad (1.20 deg)"
        );
        assert_eq!(u.pm("kb", 0.0407, 0.002), "4.0700e-2 ± 2.0e-3 (4.07 %)");
        assert_eq!(u.pm("tau", 0.31, 0.02), "3.1000e-1 ± 2.0e-2 s");
        assert_eq!(u.pm("gd", 1e-4, 1e-5), "1.0000e-4 ± 1.0e-5 1/s");
        assert_eq!(u.pm("c", -0.06, 0.01), "-6.0000e-2 ± 1.0e-2 m");
        assert_eq!(
            u.pm("gb", -0.06, 0.01),
            "-6.0000e-2 ± 1.0e-2 (units of r in outputs.csv)"
        );
        assert_eq!(
            u.pm("gq", 0.01, 0.001),
            "1.0000e-2 ± 1.0e-3 1/[r] ([r] the unit of r in outputs.csv)"
        );
        assert_eq!(u.pm("dq", 0.01, 0.001), "1.0000e-2 ± 1.0e-3");
        let labels: Vec<String> = ["db", "kb", "gd", "gb", "gq", "dq"]
            .map(|p| u.label(p))
            .into();
        assert_eq!(
            labels,
            [
                "rad",
                "1",
                "1/s",
                "units of r in outputs.csv",
                "1/[r] ([r] the unit of r in outputs.csv)",
                "-"
            ]
        );
        assert_eq!(u.json("gd").as_deref(), Some("1/s"));
        assert_eq!(u.json("dq"), None);
    }
}
