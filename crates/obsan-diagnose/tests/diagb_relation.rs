//! Input relations: a commanded wheel-speed ratio that
//! the executed one misses is tested per trajectory under the encoder-noise
//! model and, when the measured inputs contradict it, named as the missing
//! effect (in `named`, and in the extended model's restriction).

use obsan_calib::{simulate, SimOptions};
use obsan_data::Dataset;
use obsan_diagnose::{diagnose, start_values, DiagnoseOptions, Diagnosis, ORIGIN_RELATION};
use obsan_model::{EffectLibrary, System};
use rayon::prelude::*;

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn data(dq: f64, seed: u64, stated: bool) -> Dataset {
    let o = SimOptions {
        seed,
        dq,
        ..SimOptions::default()
    };
    let (mut d, _) = simulate(&o).unwrap();
    if !stated {
        d.meta.noise.remove("encoder_k");
    }
    d
}

/// The workflow with `rounds` rounds of model candidates (0: the nominal
/// fit and the input checks only).
fn run(d: &Dataset, rounds: usize) -> Diagnosis {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let start = start_values(&sys, d, &Default::default()).unwrap();
    let o = DiagnoseOptions {
        max_rounds: rounds,
        ..DiagnoseOptions::default()
    };
    diagnose(&sys, Some(&lib), d, &start, &o, &|_| {}).unwrap()
}

fn relation_named(d: &Diagnosis) -> Option<(f64, f64)> {
    d.named
        .iter()
        .find(|n| n.effect == "commanded_ratio" && n.origin == ORIGIN_RELATION)
        .map(|n| (n.estimates[0].1, n.estimates[0].2))
}

/// The first case: off by 0.0008, the old pooled test found it
/// (z 5) but named nothing. Named now, with the whole workflow run, its
/// magnitude within 3 sd, no model effect named for it, and the extended
/// model carries it in the restriction (and reads back).
#[test]
fn a_ratio_off_by_8e_4_is_named_and_written_into_the_restriction() {
    for stated in [true, false] {
        let d = run(&data(0.0008, 1, stated), usize::MAX);
        let (x, sd) = relation_named(&d).unwrap_or_else(|| panic!("not named: {:?}", d.named));
        assert!((x - 0.0008).abs() < 3.0 * sd, "dq {x} ± {sd}");
        assert!(
            d.named.iter().all(|n| n.origin == ORIGIN_RELATION),
            "a model effect named for an input error: {:?}",
            d.named.iter().map(|n| &n.effect).collect::<Vec<_>>()
        );
        let ext = System::parse(&d.extended_sys, "extended.sys").unwrap();
        let text = ext.to_sys_text();
        let line = text.lines().find(|l| l.starts_with("restrict q:")).unwrap();
        assert!(line.contains("dq"), "{line}");
        // The restricted system is the executed one: rank of the circles'
        // system is unchanged (dq is a known constant there).
        assert!(ext.normal_form(Some("q"), &[]).is_ok());
    }
}

/// The second case: off by 0.00024 the pooled test gave z 0.2; the
/// q = 0 circle (the left wheel commanded still, so its encoder is nearly
/// noiseless, and it turns) shows it alone, and the weighted test names it.
#[test]
fn a_ratio_off_by_2_4e_4_is_named_from_the_still_wheel() {
    for stated in [true, false] {
        let d = run(&data(0.00024, 2, stated), 0);
        let (x, sd) =
            relation_named(&d).unwrap_or_else(|| panic!("not named: {:?}", d.input_checks));
        assert!((x - 0.00024).abs() < 3.0 * sd, "dq {x} ± {sd}");
        let c = &d.input_checks[0];
        let q0 = c
            .per_trajectory
            .iter()
            .find(|t| t.trajectory == "q0")
            .unwrap();
        let others = c.per_trajectory.iter().filter(|t| t.trajectory != "q0");
        for t in others {
            assert!(
                q0.z > 3.0 * t.z,
                "q0 z {} vs {} z {}",
                q0.z,
                t.trajectory,
                t.z
            );
        }
    }
}

/// The sds are honest: over 20 seeds at dq = 0.0008, (estimate - truth) / sd
/// has mean near 0 and sd near 1, with the noise stated and estimated.
#[test]
fn relation_sds_match_the_scatter() {
    for stated in [true, false] {
        let z: Vec<f64> = (1..=20u64)
            .into_par_iter()
            .map(|s| {
                let d = run(&data(0.0008, 100 + s, stated), 0);
                let (_, x, sd) = d.input_checks[0].estimates[0].clone();
                (x - 0.0008) / sd
            })
            .collect();
        let n = z.len() as f64;
        let mean = z.iter().sum::<f64>() / n;
        let sd = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(mean.abs() < 0.7, "stated {stated}: mean z {mean} ({z:?})");
        assert!(
            (0.6..1.5).contains(&sd),
            "stated {stated}: sd of z {sd} ({z:?})"
        );
    }
}

/// Clean data: the relation holds, nothing is named for it (20 seeds,
/// stated and estimated noise).
#[test]
fn clean_ratio_names_nothing() {
    for stated in [true, false] {
        let hits: Vec<u64> = (1..=20u64)
            .into_par_iter()
            .filter(|&s| relation_named(&run(&data(0.0, 200 + s, stated), 0)).is_some())
            .collect();
        assert!(hits.is_empty(), "stated {stated}: named on seeds {hits:?}");
    }
}
