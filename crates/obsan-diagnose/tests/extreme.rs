//! Issue 14 item 5: one bearing of 1e308 made `obsan diagnose` run for
//! minutes. The dataset reader refuses such a value; the workflow, given it
//! anyway (or the largest value the reader accepts), returns.

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
        let (mut data, _) = simulate(&SimOptions::default()).unwrap();
        data.trajectories[1].outputs.values_mut(0)[2] = Some(v);
        // An error or a diagnosis are both answers; returning is the point.
        if let Ok(start) = start_values(&sys, &data, &Default::default()) {
            let _ = diagnose(
                &sys,
                Some(&lib),
                &data,
                &start,
                &DiagnoseOptions::default(),
                &|_| {},
            );
        }
    }
}
