//! The workflow's errors are typed: each failure is its variant, with the
//! layer below as its `source()`, and the text the CLI prints.

use obsan_data::{Dataset, DatasetMeta, DerivedInputError, Series, Trajectory};
use obsan_diagnose::{prepare, start_values, DiagnoseError};
use obsan_model::System;
use std::collections::BTreeMap;
use std::error::Error;

/// One trajectory "a": input u = 1 and output y every 0.1 s for 2 s.
fn data() -> Dataset {
    let mut inputs = Series::new(vec!["u".into()]);
    let mut outputs = Series::new(vec!["y".into()]);
    for k in 0..21 {
        let t = 0.1 * k as f64;
        inputs.push(t, &[Some(1.0)]);
        outputs.push(t, &[Some(2.0 * (1.0 - (-t).exp()))]);
    }
    Dataset {
        meta: DatasetMeta::default(),
        trajectories: vec![Trajectory {
            name: "a".into(),
            inputs,
            outputs,
            meta: BTreeMap::new(),
        }],
    }
}

// `y = 2*x` does not measure x directly, and x declares no start.
const DECAY: &str = "system decay\nstate x\nparam k\ninput u\nx' = -k*x + u\noutput y = 2*x\n";

#[test]
fn a_state_without_start_is_its_variant() {
    let sys = System::parse(DECAY, "decay.sys").unwrap();
    let e = start_values(&sys, &data(), &BTreeMap::new()).unwrap_err();
    assert_eq!(
        e,
        DiagnoseError::NoStartValue {
            state: "x".into(),
            system: "decay".into(),
            trajectory: "a".into(),
        }
    );
    // Given, it starts.
    let given = BTreeMap::from([("x".to_string(), 0.0)]);
    let s = start_values(&sys, &data(), &given).unwrap();
    assert_eq!(s.1, vec![vec![0.0]]);
}

#[test]
fn an_unknown_init_name_is_its_variant() {
    let sys = System::parse(DECAY, "decay.sys").unwrap();
    let given = BTreeMap::from([("zz".to_string(), 1.0)]);
    let e = start_values(&sys, &data(), &given).unwrap_err();
    assert!(
        matches!(&e, DiagnoseError::UnknownInit { name, system } if name == "zz" && system == "decay"),
        "{e:?}"
    );
    assert!(e.source().is_none());
}

#[test]
fn a_derived_input_of_a_missing_column_wraps_the_data_error() {
    let text = "system d\nstate x\ninput u, w\ninput dw = rate(w)\nx' = u + dw\noutput y = x\n";
    let sys = System::parse(text, "d.sys").unwrap();
    let e = prepare(&sys, &data()).unwrap_err();
    let DiagnoseError::DerivedInput { trajectory, source } = &e else {
        panic!("{e:?}");
    };
    assert_eq!(trajectory, "a");
    assert!(matches!(source.as_ref(), DerivedInputError::NoColumn { column, .. } if column == "w"));
    // The text names the trajectory, then the data layer's message.
    assert_eq!(e.to_string(), format!("trajectory a: {source}"));
    assert_eq!(e.source().map(|s| s.to_string()), Some(source.to_string()));
}
