//! Outputs that read known inputs (`output y = x*(1 + k*u)`): the standard
//! augmentation, so every analysis sees an ordinary normal form.
//!
//! Each known input `u` read by an output becomes a measured coordinate: a
//! dynamic state `u` (same name and symbol) with `u' = u'`, where the new known
//! input `u'` (the input's derivative, taken as known, as STRIKE-GOLDD's
//! `nnzDerU` does) replaces `u` in the input list and has the unit field `e_u`;
//! the field `f_u` of the old input moves into the drift (`f0 + f_u u`); and
//! an output `u` (first, so its row `du` opens every basis at order 0).
//!
//! Why it changes nothing for outputs free of inputs: with `F0 = f0 + sum u_i
//! f_i` (the sum over the measured inputs), `L_{F0} h = L_{f0} h + sum u_i
//! L_{f_i} h`, and `d/du_i` of it, the bracket with the new field `e_{u_i}`, is
//! `L_{f_i} h`; by induction every word of the original fields appears as such
//! a coefficient, and conversely every Lie derivative along the augmented
//! fields is a polynomial in the `u_i` whose coefficients are original Lie
//! derivatives. So the codistribution, restricted to the original variables
//! and with the rows `du_i` added, is the original one: the rank over the
//! original `n` is the augmented rank minus the number of measured inputs
//! (docs/engine.md, "Outputs that read known inputs", has the full argument).

use crate::error::ModelError;
use crate::normal::NormalForm;
use crate::sys::System;

/// The suffix of a measured input's derivative: the input `u'` is `du/dt`.
pub const DERIVATIVE_MARK: &str = "'";

impl NormalForm {
    /// The indices of the known inputs some output reads (exactly: a non-zero
    /// derivative of an output's canonical form).
    fn inputs_read(&mut self) -> Vec<usize> {
        let outs: Vec<_> = self.outputs.iter().map(|o| o.1).collect();
        (0..self.inputs.len())
            .filter(|&i| {
                let u = self.input_vars[i];
                outs.iter().any(|&h| {
                    let d = self.ctx.diff(h, u);
                    !self.ctx.is_identically_zero(d)
                })
            })
            .collect()
    }

    /// The augmentation described in the module doc, for every known input
    /// an output reads; records their names in `measured_inputs`.
    pub(crate) fn measure_inputs(&mut self) {
        let read = self.inputs_read();
        let zero = self.ctx.int(0);
        let mut outs = Vec::new();
        for &i in &read {
            let name = self.inputs[i].clone();
            let sym = self.ctx.symbol(&name);
            // The drift gains f_i u_i (u_i is now a coordinate).
            let f0 = self.f0.clone();
            for (k, &fk) in f0.iter().enumerate() {
                let fik = self.fields[i][k];
                if self.ctx.is_zero(fik) {
                    continue;
                }
                let t = self.ctx.mul(&[fik, sym.id]);
                let s = self.ctx.add(&[fk, t]);
                let c = self.ctx.canon(s);
                self.f0[k] = self.ctx.from_canonical(&c);
            }
            // The coordinate: the last dynamic state, no drift.
            let k = self.n_dynamic;
            self.state.insert(k, name.clone());
            self.state_vars.insert(k, sym.var);
            self.f0.insert(k, zero);
            for f in self.fields.iter_mut().chain(self.unknown_fields.iter_mut()) {
                f.insert(k, zero);
            }
            self.n_dynamic += 1;
            if let Some(d) = self.delay.as_mut() {
                *d += 1;
            }
            // The input becomes its derivative, whose field is e_u.
            let dname = format!("{name}{DERIVATIVE_MARK}");
            let dsym = self.ctx.symbol(&dname);
            let one = self.ctx.int(1);
            let mut e = vec![zero; self.state.len()];
            e[k] = one;
            self.inputs[i] = dname;
            self.input_vars[i] = dsym.var;
            self.fields[i] = e;
            outs.push((name.clone(), sym.id));
            self.measured_inputs.push(name);
        }
        self.outputs.splice(0..0, outs);
    }
}

impl System {
    /// The refusals of combinations not handled with outputs that read known
    /// inputs, located at the first such input.
    pub(crate) fn check_measured(&self) -> Result<(), ModelError> {
        if self.delay.is_some() {
            if let Some(e) = self.input_output_refusal("a model with `delay`") {
                return Err(e);
            }
        }
        if self.decls_of(crate::Kind::Unknown).next().is_some() {
            if let Some(e) = self.input_output_refusal("a model with unknown inputs") {
                return Err(e);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::System;

    #[test]
    fn a_read_input_becomes_a_state_driven_by_its_derivative() {
        // x' = -a x + b u + v, y = x + u: u is read, v is not. By hand: state
        // [x, u, a, b] (u the last dynamic state), drift (-a x + b u, 0, 0, 0),
        // inputs [u', v] with fields e_u and (1, 0, 0, 0), outputs [u, y].
        let src =
            "system m\nstate x\nparam a, b\ninput u, v\nx' = -a*x + b*u + v\noutput y = x + u\n";
        let mut nf = System::parse(src, "m.sys")
            .unwrap()
            .normal_form(None, &[])
            .unwrap();
        assert_eq!(nf.state, ["x", "u", "a", "b"]);
        assert_eq!(nf.n_dynamic, 2);
        assert_eq!(nf.inputs, ["u'", "v"]);
        assert_eq!(nf.measured_inputs, ["u"]);
        let text = |nf: &mut crate::NormalForm, v: &[obsan_expr::Id]| -> Vec<String> {
            v.iter().map(|&e| nf.ctx.to_text(e)).collect()
        };
        let (f0, f_du, f_v) = (nf.f0.clone(), nf.fields[0].clone(), nf.fields[1].clone());
        assert_eq!(text(&mut nf, &f0), ["-a*x + b*u", "0", "0", "0"]);
        assert_eq!(text(&mut nf, &f_du), ["0", "1", "0", "0"]);
        assert_eq!(text(&mut nf, &f_v), ["1", "0", "0", "0"]);
        let outs: Vec<&str> = nf.outputs.iter().map(|o| o.0.as_str()).collect();
        assert_eq!(outs, ["u", "y"]);
        // An output free of inputs changes nothing.
        let plain = src.replace("output y = x + u", "output y = x");
        let nf = System::parse(&plain, "p.sys")
            .unwrap()
            .normal_form(None, &[])
            .unwrap();
        assert_eq!(nf.state, ["x", "a", "b"]);
        assert_eq!(nf.inputs, ["u", "v"]);
        assert!(nf.measured_inputs.is_empty());
    }
}
