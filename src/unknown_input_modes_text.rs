//! The text of `obsan modes` on a model with unknown inputs, and what
//! proves it in words (unknown_input_cmd.rs runs the command).

use crate::cli::ModesArgs;
use crate::json;
use obsan_analysis::unknown_inputs::UnknownInputModes;
use obsan_model::NormalForm;

/// How a reconstructable input is recovered, in words.
pub(crate) fn order_text(o: Option<usize>) -> String {
    match o {
        Some(0) => "from the outputs".to_string(),
        Some(m) => format!("from output derivatives of order {m}"),
        None => String::new(),
    }
}

/// What proves the modes and the reduced system with unknown inputs.
pub(crate) fn ui_modes_certificate(
    m: &UnknownInputModes,
    full: bool,
    verified: bool,
    modes_ok: bool,
    checks: &Option<Vec<obsan_analysis::Check>>,
    bound: f64,
) -> String {
    let sym = format!(
        "{} symmetr{} certified exactly ({} identities: each leaves the outputs invariant, its brackets with the fields in the span of the symmetries and the unknown inputs' fields)",
        m.symmetries.vectors.len(),
        if m.symmetries.vectors.len() == 1 { "y" } else { "ies" },
        m.symmetries.identities
    );
    if full {
        return format!(
            "every variable observable with unknown inputs (the rank test: wrong with probability <= {bound:.1e}); the reduced system is the model, each unknown input its fields move reconstructable (the rank test's order)"
        );
    }
    let Some(d) = &m.derivation else {
        return String::new();
    };
    let reduced = match checks {
        Some(c) if verified => format!(
            "the reduced system writes every output and every field (the known inputs', and each unknown input's or its combination's) in the modes, proven by exact substitution ({} checks)",
            c.len()
        ),
        Some(_) => "reduced system: a decomposition check FAILED".to_string(),
        None => format!(
            "reduced system not closed: no form in the modes found for {}",
            d.missing().join(", ")
        ),
    };
    let jets = if m.jets.is_empty() {
        String::new()
    } else {
        let shown: Vec<&str> = m
            .jets
            .iter()
            .filter(|j| j.state)
            .map(|j| j.shown.as_str())
            .collect();
        format!(
            "; the symmetries move with the known inputs: the modes are first integrals over the state and the inputs' jets {0} (coordinates no symmetry moves, so the decomposition checks count {0} among the new variables and the rank), and the reduced system reads the known inputs' time derivatives {1}",
            shown.join(", "),
            m.input_derivatives().join(", ")
        )
    };
    format!(
        "{} mode(s){}; {sym}{jets}; as many independent modes as the rank with unknown inputs (a non-zero minor, exact; the rank: wrong with probability <= {bound:.1e}); {reduced}",
        d.shown().len(),
        if modes_ok {
            ", each satisfying eq. (11) exactly (canonical forms) for every symmetry"
        } else {
            ": a mode check FAILED"
        }
    )
}

/// The text report of [`modes`].
pub(crate) fn ui_modes_text(
    a: &ModesArgs,
    nf: &NormalForm,
    m: &UnknownInputModes,
    (title, (rank, n)): (&str, (usize, usize)),
    exprs: &[String],
    inputs: &[json::ReducedUnknownInput],
    certificate: &str,
) -> String {
    let k = m.symmetries.vectors.len();
    let mut o = format!(
        "{title}: unknown inputs [{}]; rank {rank} of {n} with unknown inputs, {k} symmetr{}",
        nf.unknown_inputs.join(", "),
        if k == 1 { "y" } else { "ies" }
    );
    match &m.derivation {
        None => o.push_str(
            ": every variable is observable; the modes are the variables and the reduced system is the model itself\n",
        ),
        Some(d) => {
            let shown = d.shown();
            let k = shown.len();
            o.push_str(&format!(
                "; {k} observable mode{}:\n",
                if k == 1 { "" } else { "s" }
            ));
            for (e, md) in exprs.iter().zip(shown.iter().map(|&j| &d.modes[j])) {
                crate::reduced_text::push_mode(&mut o, md, e);
            }
            crate::reduced_text::push_reduced(&mut o, d);
            if !m.jets.is_empty() {
                o.push_str(&format!(
                    "the modes and the reduced system move with the known inputs: the reduced system reads their time derivatives along the trajectory ({}), known inputs too\n",
                    m.input_derivatives().join(", ")
                ));
            }
        }
    }
    if inputs.is_empty() {
        o.push_str("unknown inputs in the reduced system: (none)\n");
    } else {
        let items: Vec<String> = inputs
            .iter()
            .map(|i| match &i.factor {
                None => format!(
                    "{} ({}, reconstructable {})",
                    i.name,
                    i.input,
                    order_text(i.order)
                ),
                Some(f) if i.order == Some(0) => format!(
                    "{} = ({f})*{}{} (a combination: the output {} reads it, no mode sees {})",
                    i.name,
                    i.input,
                    i.offset.as_ref().map(|o| format!(" + {o}")).unwrap_or_default(),
                    i.mode,
                    i.input
                ),
                Some(f) => format!(
                    "{} = ({f})*{}{} (a combination; reconstructable from the first derivative of {})",
                    i.name,
                    i.input,
                    i.offset.as_ref().map(|o| format!(" + {o}")).unwrap_or_default(),
                    i.mode
                ),
            })
            .collect();
        o.push_str(&format!(
            "unknown inputs in the reduced system: {}\n",
            items.join("; ")
        ));
    }
    o.push_str(&format!("certificate: {certificate}\n"));
    if let Some(p) = &a.out_prefix {
        if m.derivation.is_some()
            && m.inputs.iter().all(|i| i.factor.is_none())
            && m.jets.is_empty()
        {
            o.push_str(&format!("wrote {p}.sys and {p}.dec\n"));
        }
    }
    o
}
