//! The fields of a system in the order every analysis uses them.

use obsan_expr::Id;
use obsan_model::NormalForm;

/// Names and vectors of the fields: `f0` when the drift is not zero, then one per input.
pub(crate) fn field_names(nf: &mut NormalForm) -> (Vec<String>, Vec<Vec<Id>>) {
    let mut names = Vec::new();
    let mut vectors = Vec::new();
    if !nf.drift_is_zero() {
        names.push("f0".to_string());
        vectors.push(nf.f0.clone());
    }
    for (i, f) in nf.fields.iter().enumerate() {
        names.push(nf.inputs[i].clone());
        vectors.push(f.clone());
    }
    // A delay tau (inputs u(t - tau)) to first order: u - tau du/dt, the rates
    // du/dt being further free inputs with fields -tau f_i.
    if let Some(d) = nf.delay {
        #[allow(clippy::expect_used)]
        // normal_form puts the delay param in the state and the context
        let tau = nf.ctx.lookup(&nf.state[d]).expect("delay param").id;
        let minus_tau = nf.ctx.neg(tau);
        for i in 0..nf.fields.len() {
            let v: Vec<Id> = nf.fields[i]
                .clone()
                .into_iter()
                .map(|x| nf.ctx.mul(&[minus_tau, x]))
                .collect();
            names.push(format!("rate_{}", nf.inputs[i]));
            vectors.push(v);
        }
    }
    (names, vectors)
}
