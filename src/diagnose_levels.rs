//! `obsan diagnose`'s words for the noise levels after each naming
//! (docs/diagnose.md, "Never confidently wrong": the levels re-estimated):
//! which levels each round was weighed under, the note on stated levels the
//! residuals contradict, and the named effects weak under the final levels.

use obsan_diagnose::{Diagnosis, Relevel};

/// The range of `after / before` over the outputs, in words.
fn ratio(before: &[(String, f64)], after: &[(String, f64)]) -> String {
    let r: Vec<f64> = before
        .iter()
        .zip(after)
        .map(|(b, a)| a.1 / b.1)
        .filter(|x| x.is_finite())
        .collect();
    let lo = r.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if r.is_empty() {
        "-".into()
    } else if hi - lo < 0.005 {
        format!("{lo:.2}")
    } else {
        format!("{lo:.2}-{hi:.2}")
    }
}

fn outputs(v: &[(String, f64)]) -> String {
    match v {
        [a] => a.0.clone(),
        [a, b] => format!("{}, {}", a.0, b.0),
        [a, b, ..] => format!("{}, {}, ... ({} outputs)", a.0, b.0, v.len()),
        [] => "the outputs".into(),
    }
}

fn levels(v: &[(String, f64)]) -> String {
    let t: Vec<String> = v.iter().map(|(n, x)| format!("{n} {x:.3e}")).collect();
    t.join(", ")
}

/// The lines after round `r.round`'s table: the levels the next round
/// weighs under, or the note on stated levels.
pub fn after_round(r: &Relevel) -> Vec<String> {
    let mut out = Vec::new();
    let z = format!(
        "chi-square z {:.1} -> {:.1}",
        r.chi2_z_before, r.chi2_z_after
    );
    if r.replaced {
        let mut what = format!(
            "output sigma {} of round {}'s",
            ratio(&r.sigma_before, &r.sigma_after),
            r.round
        );
        if r.input_noise_after != r.input_noise_before {
            what += &format!(
                "; input noise c {} (was {})",
                if r.input_noise_after.is_empty() {
                    "none".into()
                } else {
                    levels(&r.input_noise_after)
                },
                if r.input_noise_before.is_empty() {
                    "none".into()
                } else {
                    levels(&r.input_noise_before)
                }
            );
        }
        out.push(format!(
            "  levels after naming {}: re-estimated under the extended model ({what}; {z}); \
             round {} is weighed under them",
            r.named,
            r.round + 1
        ));
    } else if r.note {
        out.push(format!(
            "  note: after naming {} the residuals sit at {} of the stated sigma of {} \
             (chi-square z {:.1}); the levels the data give: {}; the stated levels are kept",
            r.named,
            ratio(&r.sigma_before, &r.sigma_after),
            outputs(&r.sigma_before),
            r.chi2_z_after,
            levels(&r.sigma_after)
        ));
    }
    out
}

/// The verdict's part for the named effects that would not pass under the
/// final levels, if any.
pub fn weak_part(d: &Diagnosis) -> Option<String> {
    let weak: Vec<String> = d
        .named
        .iter()
        .filter(|n| n.weak_under_final_levels)
        .map(|n| format!("{} (LR {:.1})", n.effect, n.lr_final.unwrap_or(0.0)))
        .collect();
    (!weak.is_empty()).then(|| {
        format!(
            "weak under the final levels, named under earlier ones: {} (below the critical value \
             at the final noise levels; the naming stands)",
            weak.join(", ")
        )
    })
}
