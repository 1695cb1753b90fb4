//! Blocks of the ansatz read off the fields: the combinations of the
//! constant variables through which the dynamics see them.

use super::*;

/// The coefficients of the fields as polynomials in the moving variables
/// (those some field changes, with cos/sin of the moving angles): the
/// combinations of the constant variables the dynamics see, such as
/// `eta (1 + q delta) cos(phi)` of eq. (16). An invariant of degree 5 in the
/// variables (eq. 23's V) is of degree 3 in these blocks, which a
/// cross-section of the symmetry group would also give. `None` when a
/// coefficient holds anything but constant variables (an atom of a moving one).
#[allow(clippy::type_complexity)]
/// The block coordinates of one state: the symbol itself unless it is an
/// angle seen only through its cosine and sine, then `cos` and `sin` if any.
pub(super) fn push_state_blocks(
    blocks: &mut Vec<Id>,
    bnames: &mut Vec<String>,
    name: &str,
    sym: Id,
    as_symbol: bool,
    trig: Option<(Id, Id)>,
) {
    if as_symbol {
        blocks.push(sym);
        bnames.push(name.to_string());
    }
    if let Some((c, s)) = trig {
        blocks.push(c);
        bnames.push(format!("cos({name})"));
        blocks.push(s);
        bnames.push(format!("sin({name})"));
    }
}

pub(super) fn coefficient_blocks(
    nf: &mut NormalForm,
    fields: &[Vec<Id>],
    names: &[String],
    angle: &[bool],
    trig: &[Option<(Id, Id)>],
    used_vars: &[u32],
    vars: &[u32],
) -> Option<(Vec<Id>, Vec<String>, Vec<bool>)> {
    let n = names.len();
    let mut blocks = Vec::new();
    let mut bnames = Vec::new();
    let mut moving: Vec<u32> = Vec::new();
    let mut fixed: Vec<u32> = Vec::new();
    for i in 0..n {
        let sym_var = nf.ctx.symbol(&names[i]).id;
        let mut vs = nf.ctx.canon(sym_var).vars();
        if let Some((c, s)) = trig[i] {
            vs.extend(nf.ctx.canon(c).vars());
            vs.extend(nf.ctx.canon(s).vars());
        }
        if fields.iter().all(|f| nf.ctx.is_zero(f[i])) {
            fixed.extend(vs);
            continue;
        }
        moving.extend(vs);
        let as_symbol = !angle[i] || used_vars.contains(&vars[i]);
        push_state_blocks(
            &mut blocks,
            &mut bnames,
            &names[i],
            sym_var,
            as_symbol,
            trig[i],
        );
    }
    let mut const_vars: Vec<u32> = Vec::new();
    for (name, val) in nf.consts.clone() {
        if val.is_none() {
            if let Some(s) = nf.ctx.lookup(&name) {
                const_vars.extend(nf.ctx.canon(s.id).vars());
            }
        }
    }
    fixed.extend(&const_vars);
    let nmoving = blocks.len();
    let mut seen: Vec<Poly> = Vec::new();
    for f in fields {
        for &e in f {
            let c = nf.ctx.canon(e);
            for p in [c.numerator(), c.denominator()] {
                // Group the terms by their monomial in the moving variables.
                let mut groups: Vec<(Mono, Vec<(Mono, Int)>)> = Vec::new();
                for (m, k) in p.terms() {
                    let mv = Mono::from_pairs(m.iter().filter(|(v, _)| moving.contains(v)));
                    let rest = Mono::from_pairs(m.iter().filter(|(v, _)| !moving.contains(v)));
                    match groups.iter_mut().find(|g| g.0 == mv) {
                        Some(g) => g.1.push((rest, k.clone())),
                        None => groups.push((mv, vec![(rest, k.clone())])),
                    }
                }
                for (_, ts) in groups {
                    let q = Poly::from_terms(ts);
                    if q.is_constant() {
                        continue;
                    }
                    if q.vars().iter().any(|v| !fixed.contains(v)) {
                        return None;
                    }
                    let content = q.content();
                    let q = q.div_exact(&Poly::constant(content))?.normalize_sign();
                    if !seen.contains(&q) {
                        seen.push(q);
                    }
                }
            }
        }
    }
    let mut is_const = vec![false; nmoving];
    for q in seen {
        is_const.push(q.vars().iter().all(|v| const_vars.contains(v)));
        let text = nf.ctx.poly_text(&q);
        bnames.push(text);
        blocks.push(nf.ctx.from_canonical(&RatFun::from_poly(q)));
    }
    Some((blocks, bnames, is_const))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. (16) on circles (17): the fields see the parameters only through
    /// eta_q cos(phi), eta_q sin(phi) and xi_q of eq. (18) (ERRATA.md), with
    /// eta_q = eta (1 + q delta), xi_q = xi (1 - q delta).
    #[test]
    fn eq16_with_q_blocks_are_eta_q_cos_phi_eta_q_sin_phi_and_xi_q() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../systems/calib.sys");
        let src = std::fs::read_to_string(path).unwrap();
        let sys = obsan_model::System::parse(&src, "calib.sys").unwrap();
        let mut nf = sys.normal_form(Some("q"), &[]).unwrap();
        let (_, fields) = crate::fields::field_names(&mut nf);
        let names = nf.state.clone();
        let vars = nf.state_vars.clone();
        let mut trig = Vec::new();
        let mut angle = Vec::new();
        for s in &names {
            let is_angle = s == "gamma" || s == "phi";
            angle.push(is_angle);
            trig.push(if is_angle {
                let c = nf.parse_expr(&format!("cos({s})"), false).unwrap();
                let s = nf.parse_expr(&format!("sin({s})"), false).unwrap();
                Some((c, s))
            } else {
                None
            });
        }
        // No angle enters polynomially, so no angle is a block itself.
        let (blocks, bnames, is_const) =
            coefficient_blocks(&mut nf, &fields, &names, &angle, &trig, &[], &vars).unwrap();
        // The moving blocks: mu, cos(gamma), sin(gamma).
        assert_eq!(&bnames[..3], &["mu", "cos(gamma)", "sin(gamma)"]);
        let coef = &blocks[3..];
        assert_eq!(coef.len(), 3, "{bnames:?}");
        assert!(is_const.iter().all(|c| !c));
        for want in [
            "eta*(1 + q*delta)*cos(phi)",
            "eta*(1 + q*delta)*sin(phi)",
            "xi*(1 - q*delta)",
        ] {
            let w = nf.parse_expr(want, false).unwrap();
            let found = coef.iter().any(|&b| {
                let d = nf.ctx.sub(b, w);
                let s = nf.ctx.add(&[b, w]);
                nf.ctx.canon(d).is_zero() || nf.ctx.canon(s).is_zero()
            });
            assert!(found, "{want} not among {bnames:?}");
        }
    }
}
