//! Decompositions whose modes move with the known inputs, and those driven
//! by an unknown-input combination (docs/decomposition-format.md, "Inputs'
//! derivatives and combinations").
//!
//! The file names a known input's derivative by a declared name
//! (`derivative u_d1 = u'`), as the reduced `.sys` declares it (`input u_d1 =
//! rate(u)`). The checks run over the view of unknown_input_jet_view.rs, in
//! which the jets `u, u', ...` the symmetries read are states and the next
//! order an input: like the clock, the jets are modes of every such
//! decomposition, so the file leaves them implicit and they are added here
//! with their equations `u^(l)' = u^(l+1)` and outputs (the input is known).

use crate::decomp::Decomposition;
use crate::rank::AnalysisError;
use crate::unknown_input_jet_view::JetName;
use obsan_expr::{line_col, parse_ast};
use obsan_model::NormalForm;

/// A jet's input and order, from its shown name (`u3''` -> (`u3`, 2)).
fn input_order(j: &JetName) -> (&str, usize) {
    let base = j.shown.trim_end_matches('\'');
    (base, j.shown.len() - base.len())
}

impl Decomposition {
    /// The decomposition over the view `nf` whose jets are `jets`: each
    /// declared derivative resolved to its jet (an error at its line when
    /// the model's symmetries do not read it), and the jets added as new
    /// variables with their equations and outputs.
    pub fn with_input_jets(
        &self,
        nf: &NormalForm,
        jets: &[JetName],
    ) -> Result<Decomposition, AnalysisError> {
        let mut d = self.clone();
        for (name, input, order, at) in &self.derivatives {
            let shown = format!("{input}{}", "'".repeat(*order));
            let Some(j) = jets.iter().find(|j| j.shown == shown) else {
                let read: Vec<&str> = jets.iter().map(|j| j.shown.as_str()).collect();
                let why = if read.is_empty() {
                    "the model's lost directions do not move with the known inputs, so no derivative is read".to_string()
                } else {
                    format!("the model's modes read {}", read.join(", "))
                };
                return Err(self.located(
                    *at,
                    format!("'{shown}' is not an input derivative of this model's modes ({why})"),
                ));
            };
            let clash = (nf.state.contains(name)
                || nf.inputs.contains(name)
                || nf.consts.iter().any(|c| &c.0 == name))
                && *name != j.internal;
            if clash {
                return Err(
                    self.located(*at, format!("'{name}' is already a variable of the system"))
                );
            }
            d.aliases.push((name.clone(), j.internal.clone()));
        }
        for j in jets.iter().filter(|j| j.state) {
            let (input, order) = input_order(j);
            if !d.new_state.contains(&j.internal) {
                d.new_state.push(j.internal.clone());
            }
            if !d.dynamics.iter().any(|x| x.0 == j.internal) {
                let next = jets
                    .iter()
                    .find(|k| input_order(k) == (input, order + 1))
                    .map(|k| k.internal.clone())
                    .ok_or_else(|| {
                        AnalysisError::Invalid(format!(
                            "internal: no jet after {} in the view",
                            j.shown
                        ))
                    })?;
                d.push_line(&format!("{}' = {next}", j.internal), true)?;
            }
            let id = nf.ctx.lookup(&j.internal).map(|s| s.id);
            for (oname, oid) in &nf.outputs {
                if Some(*oid) == id && !d.outputs.iter().any(|o| &o.0 == oname) {
                    d.push_line(&format!("output {oname} = {}", j.internal), false)?;
                }
            }
        }
        Ok(d)
    }

    /// A model without unknown inputs has no jets in its modes and no
    /// combination: a file declaring either is refused at its line.
    pub fn without_jets_or_combinations(&self) -> Result<(), AnalysisError> {
        if let Some(&(_, ref input, order, at)) = self.derivatives.first() {
            return Err(self.located(at, format!("'{input}{}' is not an input derivative of this model's modes (its modes are functions of the state: the analysis with known inputs alone never reads the inputs' derivatives)", "'".repeat(order))));
        }
        if let Some((name, _, at)) = self.combinations.first() {
            return Err(self.located(
                *at,
                format!("the combination '{name}' needs unknown inputs, and the system has none"),
            ));
        }
        Ok(())
    }

    /// Append a dynamics or output line to the source (so offsets stay
    /// valid) and record it.
    fn push_line(&mut self, line: &str, dynamics: bool) -> Result<(), AnalysisError> {
        let (lhs, rhs) = line.split_once(" = ").unwrap_or((line, ""));
        let text = format!("\n{line}\n");
        let at = self.src.len() + 1 + lhs.len() + 3;
        self.src.push_str(&text);
        let ast = parse_ast(rhs).map_err(|e| AnalysisError::Invalid(format!("internal: {e:?}")))?;
        if dynamics {
            self.dynamics
                .push((lhs.trim_end_matches('\'').to_string(), ast, at));
        } else {
            let name = lhs.trim_start_matches("output ").to_string();
            self.outputs.push((name, ast, at));
        }
        Ok(())
    }

    fn located(&self, at: usize, msg: String) -> AnalysisError {
        let (l, c) = line_col(&self.src, at);
        AnalysisError::Invalid(format!("{}:{l}:{c}: {msg}", self.origin))
    }

    /// The names of the unknown-input combinations the file declares.
    pub fn combination_names(&self) -> Vec<String> {
        self.combinations.iter().map(|c| c.0.clone()).collect()
    }
}

/// The checks list's wording for a check the reader added for a jet (its
/// equation `u3_d1' = u3_d2` or its output): what it states, in the jets'
/// shown names (`u3' has the derivative u3''`), instead of a line that
/// would read `u3'' = u3''`. `None` for every other check.
pub fn jet_check_text(name: &str, jets: &[JetName]) -> Option<String> {
    let shown = |n: &str| {
        jets.iter()
            .find(|j| j.internal == n)
            .map_or(n.to_string(), |j| j.shown.clone())
    };
    let counted: Vec<&str> = jets
        .iter()
        .filter(|j| j.state)
        .map(|j| j.shown.as_str())
        .collect();
    let is_count = name.starts_with("the ") && name.ends_with(" new variables are independent")
        || name.starts_with("they are complete (rank of the system is ");
    if is_count && !counted.is_empty() {
        return Some(format!(
            "{name}, the known inputs' jets {} counted",
            counted.join(", ")
        ));
    }
    for j in jets.iter().filter(|j| j.state) {
        if let Some(next) = name.strip_prefix(&format!("{}' = ", j.internal)) {
            return Some(format!(
                "{} has the time derivative {} (a known input's jet: known, a mode of every such decomposition)",
                j.shown,
                shown(next.trim())
            ));
        }
        if name.starts_with("output ") && name.contains(&format!(" = {} (", j.internal)) {
            return Some(format!(
                "{} is known (a known input's jet: an output of the analysis)",
                j.shown
            ));
        }
    }
    None
}
