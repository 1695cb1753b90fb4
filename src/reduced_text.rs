//! The text of derived modes and their reduced system, shared by `obsan
//! modes` with known and with unknown inputs.

use obsan_analysis::{Derivation, DerivedMode};

/// One mode's line: `  name = expr    (kind; domain)`.
pub(crate) fn push_mode(o: &mut String, m: &DerivedMode, expr: &str) {
    o.push_str(&format!(
        "  {} = {expr}    ({}; {})\n",
        m.name,
        m.kind.word(),
        m.domain
    ));
}

/// The reduced system: each mode's derivative, then each output in the
/// modes; "(not found)" where the derivation has no form for a part.
pub(crate) fn push_reduced(o: &mut String, d: &Derivation) {
    o.push_str("reduced system:\n");
    for k in d.shown() {
        o.push_str(&format!(
            "  {}' = {}\n",
            d.modes[k].name,
            d.dynamics(k).unwrap_or_else(|| "(not found)".into())
        ));
    }
    for (name, e) in d.shown_outputs() {
        o.push_str(&format!(
            "  {name} = {}\n",
            e.as_deref().unwrap_or("(not found)")
        ));
    }
}

/// What a written decomposition names: the system by its absolute path (so
/// the `.dec` reads from wherever it is written) and the `--set` values as
/// given.
pub(crate) fn dec_source(sys: &crate::cli::SystemArgs) -> (String, Vec<(String, String)>) {
    let sets = sys
        .set
        .iter()
        .filter_map(|s| {
            s.split_once('=')
                .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        })
        .collect();
    let path = std::fs::canonicalize(&sys.system)
        .map(|p| p.to_string_lossy().to_string())
        .unwrap_or_else(|_| sys.system.clone());
    (path, sets)
}
