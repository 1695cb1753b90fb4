use super::{add_derived_inputs, Series};
use std::collections::BTreeMap;

#[test]
fn series_rows_keep_the_columns_aligned() {
    let mut s = Series::new(vec!["a".into(), "b".into()]);
    s.push(0.0, &[Some(1.0), None]);
    s.push(0.0, &[Some(2.0), Some(3.0)]);
    s.push(1.0, &[None, Some(4.0)]);
    assert_eq!(s.t(), &[0.0, 0.0, 1.0]);
    assert_eq!(s.values()[1], [None, Some(3.0), Some(4.0)]);
    s.values_mut(0)[2] = Some(5.0);
    assert_eq!(s.column("a").unwrap(), &[Some(1.0), Some(2.0), Some(5.0)]);
    s.truncate(1);
    assert_eq!(
        (s.len(), s.values()[0].len(), s.values()[1].len()),
        (1, 1, 1)
    );
}

#[test]
#[should_panic(expected = "non-decreasing")]
fn a_series_refuses_a_time_going_back() {
    let mut s = Series::new(vec!["a".into()]);
    s.push(1.0, &[Some(1.0)]);
    s.push(0.5, &[Some(1.0)]);
}

#[test]
#[should_panic(expected = "one value per column")]
fn a_series_refuses_a_short_row() {
    let mut s = Series::new(vec!["a".into(), "b".into()]);
    s.push(0.0, &[Some(1.0)]);
}

#[test]
fn derived_inputs_take_the_real_root_and_the_known_constants() {
    let mut s = Series::new(vec!["u".into()]);
    for (t, u) in [(0.0, -2.0), (1.0, 3.0), (2.0, -0.5)] {
        s.push(t, &[Some(u)]);
    }
    let consts = BTreeMap::from([("k".to_string(), 10.0)]);
    let defs = [
        ("a".to_string(), "sqrt(u^2)".to_string()),
        ("b".to_string(), "k*u + log(u)".to_string()),
        ("r".to_string(), "rate(u)".to_string()),
        // A rate of an earlier rate (`obsan modes --out` declares u'' so).
        ("rr".to_string(), "rate(r)".to_string()),
    ];
    add_derived_inputs(&mut s, &defs, &consts).unwrap();
    assert_eq!(s.column("a").unwrap(), &[Some(2.0), Some(3.0), Some(0.5)]);
    // log of a negative value is no value, not NaN in the data.
    assert_eq!(s.column("b").unwrap()[0], None);
    assert_eq!(s.column("b").unwrap()[1], Some(30.0 + 3f64.ln()));
    assert_eq!(s.column("r").unwrap(), &[Some(5.0), Some(-3.5), Some(0.0)]);
    // (-3.5 - 5)/1 and (0 - (-3.5))/1, 0 on the last row.
    assert_eq!(s.column("rr").unwrap(), &[Some(-8.5), Some(3.5), Some(0.0)]);
}
