//! Cheap symmetries (free variables, translations, scalings) against known
//! symmetries, compared by span.

mod common;

use common::rank_fp;
use obsan_analysis::{rank, symmetries, Certificate, RankOptions, SymmetryKind};
use obsan_expr::SplitMix;
use obsan_model::{NormalForm, System};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// The symmetries of `src` (with `input`), checked to span the same space as
/// `known` (expressions per state component); returns the kinds found.
fn check(src: &str, input: Option<&str>, known: &[&[&str]]) -> Vec<SymmetryKind> {
    let sys = System::parse(src, "test.sys").unwrap();
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    assert_eq!(r.n - r.rank, known.len(), "deficiency");
    let s = symmetries(&mut nf, &r).unwrap();
    assert!(s.exact);
    assert_eq!(s.count(), known.len());
    // Variables no output reaches come as free directions d/dx, first.
    let mut kinds: Vec<SymmetryKind> = s.free.iter().map(|&j| SymmetryKind::Free(j)).collect();
    match &s.certificate {
        Certificate::Invariance(k) => kinds.extend(k.iter().copied()),
        _ => panic!("expected the cheap structure"),
    };
    // Span: found and known together have rank k at a random point.
    let mut rows: Vec<Vec<obsan_expr::Fp>> = Vec::new();
    let mut rng = SplitMix(5);
    let pt = nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap();
    for v in &s.vectors {
        let ids: Vec<_> = v.iter().map(|e| nf.ctx.from_canonical(e)).collect();
        rows.push(nf.ctx.eval_fp(&ids, &pt).unwrap());
    }
    for &j in &s.free {
        let mut e = vec![obsan_expr::Fp::ZERO; s.n];
        e[j] = obsan_expr::Fp::ONE;
        rows.push(e);
    }
    for k in known {
        let ids: Vec<_> = k.iter().map(|e| parse(&mut nf, e)).collect();
        rows.push(nf.ctx.eval_fp(&ids, &pt).unwrap());
    }
    assert_eq!(rank_fp(rows.clone()), known.len(), "span differs");
    assert_eq!(rank_fp(rows[..known.len()].to_vec()), known.len());
    kinds
}

fn parse(nf: &mut NormalForm, e: &str) -> obsan_expr::Id {
    nf.parse_expr(e, false).unwrap()
}

#[test]
fn seir_free_variable_and_scaling() {
    let src = std::fs::read_to_string(format!("{ROOT}/crates/obsan-analysis/tests/data/seir.sys"))
        .unwrap();
    // State order: S, E, I, R, N, beta, gamma, sigma.
    let kinds = check(
        &src,
        None,
        &[
            &["0", "0", "0", "1", "0", "0", "0", "0"],
            &["0", "0", "0", "0", "N", "beta", "0", "0"],
        ],
    );
    assert_eq!(kinds, vec![SymmetryKind::Free(3), SymmetryKind::Scaling]);
}

#[test]
fn classic_scalings() {
    let lv = std::fs::read_to_string(format!("{ROOT}/systems/classic/lotka_volterra.sys")).unwrap();
    // y -> l y, b -> b/l.
    let k = check(&lv, None, &[&["0", "y", "0", "-b", "0", "0"]]);
    assert_eq!(k, vec![SymmetryKind::Scaling]);
    let mm =
        std::fs::read_to_string(format!("{ROOT}/systems/classic/michaelis_menten_pk.sys")).unwrap();
    // Without input: x, Vm, Km, V all scale together.
    check(&mm, Some("noinput"), &[&["x", "Vm", "Km", "V"]]);
}

#[test]
fn translation_of_a_line_scene() {
    // A robot on a line at p with speed v, landmarks l1 (displacement
    // measured) and l2 (squared distance measured): moving everything
    // together changes nothing.
    let src = "system line\nstate p\nparam l1, l2\ninput v\np' = v\n\
               output y1 = l1 - p\noutput y2 = (l2 - p)^2\n";
    let k = check(src, None, &[&["1", "1", "1"]]);
    assert_eq!(k, vec![SymmetryKind::Translation]);
}

#[test]
fn eq3_rotation_is_a_translation_of_the_angles() {
    // Eq. (3) in polar coordinates (D, phiR, thetaR): turning the scene about
    // the feature shifts both angles.
    let src = std::fs::read_to_string(format!("{ROOT}/systems/localization.sys")).unwrap();
    let k = check(&src, None, &[&["0", "1", "1"]]);
    assert_eq!(k, vec![SymmetryKind::Translation]);
}

#[test]
fn rotations_fall_through_to_the_general_route() {
    // The same problem in Cartesian coordinates: the rotation (-y, x, 1) is
    // neither a translation nor a scaling.
    let src = std::fs::read_to_string(format!("{ROOT}/systems/localization_xy.sys")).unwrap();
    let sys = System::parse(&src, "localization_xy.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    let s = symmetries(&mut nf, &r).unwrap();
    assert_eq!(s.certificate, Certificate::Closure);
    assert_eq!(s.vectors.len(), 1);
}
