//! What of a derivation is shown and what the files state: the clock and
//! the known inputs' jets are modes of the derivation hidden from the user,
//! the decomposition and reduced `.sys` texts.

use super::*;

impl Derivation {
    /// Whether mode `k` is the clock of a system with explicit time: the
    /// variable `t` (observable through the clock's output `t`), a mode of
    /// every such system, which the files and the text leave implicit
    /// (`t` is time, never declared; docs/sys-format.md, "Explicit time").
    pub fn is_clock(&self, k: usize) -> bool {
        let m = &self.modes[k];
        m.kind == ModeKind::Variable && m.name == obsan_model::TIME
    }

    /// Whether mode `k` is a known input's jet of the view (`jets`).
    pub fn is_jet(&self, k: usize) -> bool {
        let m = &self.modes[k];
        m.kind == ModeKind::Variable && self.jets.contains(&m.name)
    }

    /// The modes the user sees: every one but the clock and the jets.
    pub fn shown(&self) -> Vec<usize> {
        (0..self.modes.len())
            .filter(|&k| !self.is_clock(k) && !self.is_jet(k))
            .collect()
    }

    /// The outputs the user sees: every one but the clock's output `t` and
    /// the jets'.
    pub fn shown_outputs(&self) -> impl Iterator<Item = &(String, Option<String>)> {
        self.outputs
            .iter()
            .filter(|o| o.0 != obsan_model::TIME && !self.jets.contains(&o.0))
    }

    /// The modes the files state: every one but the clock and the jets,
    /// which the decomposition reader adds (decomp_jets.rs).
    fn filed(&self) -> Vec<usize> {
        (0..self.modes.len())
            .filter(|&k| !self.is_clock(k) && !self.is_jet(k))
            .collect()
    }

    /// The inputs' derivatives the files declare, `(name, input, order)`:
    /// every jet of order >= 1 (`u3_d1`, `u3`, 1).
    fn declared_derivatives(&self) -> Vec<(&str, &str, usize)> {
        self.jet_names
            .iter()
            .filter_map(|(name, shown)| {
                let input = shown.trim_end_matches('\'');
                let order = shown.len() - input.len();
                (order > 0).then_some((name.as_str(), input, order))
            })
            .collect()
    }

    /// A decomposition file (docs/decomposition-format.md) stating the result.
    pub fn decomposition_text(
        &self,
        system_path: &str,
        restriction: Option<&str>,
        set: &[(String, String)],
    ) -> Option<String> {
        let mut o =
            String::from("# Observable modes and reduced dynamics derived by `obsan modes`.\n");
        o.push_str(&format!("system {system_path}\n"));
        if let Some(r) = restriction {
            o.push_str(&format!("input {r}\n"));
        }
        for (k, v) in set {
            o.push_str(&format!("set {k} = {v}\n"));
        }
        for (name, input, order) in self.declared_derivatives() {
            o.push_str(&format!(
                "derivative {name} = {input}{}\n",
                "'".repeat(order)
            ));
        }
        for m in &self.modes {
            if m.kind != ModeKind::Variable {
                o.push_str(&format!("let {} = {}\n", m.name, m.text));
            }
        }
        // The clock and the jets stay implicit: the decomposition reader adds them.
        let names: Vec<&str> = self
            .filed()
            .into_iter()
            .map(|k| self.modes[k].name.as_str())
            .collect();
        o.push_str(&format!("state {}\n", names.join(", ")));
        self.push_equations(&mut o, |_| true)?;
        Some(o)
    }

    /// The dynamics of the modes `keep` selects, then the outputs, as `.sys`
    /// lines (shared by the decomposition and the reduced system).
    /// The clock's `t' = 1` and output `t` are never written.
    fn push_equations(&self, o: &mut String, keep: impl Fn(usize) -> bool) -> Option<()> {
        for k in self.filed().into_iter().filter(|&k| keep(k)) {
            o.push_str(&format!(
                "{}' = {}\n",
                self.modes[k].name,
                self.dynamics(k)?
            ));
        }
        for (name, e) in self
            .outputs
            .iter()
            .filter(|o| o.0 != obsan_model::TIME && !self.jets.contains(&o.0))
        {
            o.push_str(&format!("output {name} = {}\n", e.as_deref()?));
        }
        Some(())
    }

    /// A `.sys` file of the reduced system. With input jets the inputs'
    /// derivatives it reads are derived inputs (`input u3_d1 = rate(u3)`),
    /// the input itself a known input (docs/sys-format.md).
    pub fn sys_text(&self, name: &str, description: &str) -> Option<String> {
        let mut o = format!(
            "# The reduced system of {name} in its observable modes (derived by `obsan modes`).\n"
        );
        o.push_str(&format!("system {name}_modes\n"));
        o.push_str(&format!("description {description}\n"));
        for k in self.shown() {
            let m = &self.modes[k];
            o.push_str(&format!("# {} = {}\n", m.name, m.text));
        }
        let states: Vec<&str> = self
            .shown()
            .into_iter()
            .filter(|&k| !self.is_constant(k))
            .map(|k| self.modes[k].name.as_str())
            .collect();
        let params: Vec<&str> = self
            .shown()
            .into_iter()
            .filter(|&k| self.is_constant(k))
            .map(|k| self.modes[k].name.as_str())
            .collect();
        if !states.is_empty() {
            o.push_str(&format!("state {}\n", states.join(", ")));
        }
        if !params.is_empty() {
            o.push_str(&format!("param {}\n", params.join(", ")));
        }
        if !self.consts.is_empty() {
            o.push_str(&format!("const {}\n", self.consts.join(", ")));
        }
        let derived = self.declared_derivatives();
        let mut inputs: Vec<String> = self
            .jet_names
            .iter()
            .filter(|(_, shown)| !shown.ends_with('\''))
            .map(|(n, _)| n.clone())
            .collect();
        inputs.extend(
            self.inputs()
                .into_iter()
                .filter(|i| !derived.iter().any(|d| d.0 == i)),
        );
        if !inputs.is_empty() {
            o.push_str(&format!("input {}\n", inputs.join(", ")));
        }
        for (name, input, order) in &derived {
            let of = match order {
                1 => input.to_string(),
                _ => self
                    .jet_names
                    .iter()
                    .find(|(_, s)| *s == format!("{input}{}", "'".repeat(order - 1)))
                    .map(|(n, _)| n.clone())?,
            };
            o.push_str(&format!("input {name} = rate({of})\n"));
        }
        self.push_equations(&mut o, |k| !self.is_constant(k))?;
        Some(o)
    }
}
