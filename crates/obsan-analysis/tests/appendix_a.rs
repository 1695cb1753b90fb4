//! Appendix A of Martinelli (IEEE T-RO 2011): the determinant of the gradients
//! of L0, L_f1, L_f2, L_f1f1, L_f1f2, L_f2f1, L_f2f2 of eq. (16), as an exact
//! identity, with the fields and the sign convention of ERRATA.md.

use obsan_analysis::{canonical_lie, determinant, rank, LieWord, RankOptions};
use obsan_expr::RatFun;

fn matrix(words: &[Vec<usize>]) -> (obsan_model::NormalForm, Vec<Vec<RatFun>>) {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/calib.sys"
    ))
    .unwrap();
    let sys = obsan_model::System::parse(&src, "calib.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let report = rank(&mut nf, RankOptions::default()).unwrap();
    // Fields: 0 = f_wR = f1, 1 = f_wL = f2 (ERRATA.md: f1 = f_R, f2 = f_L).
    assert_eq!(report.fields.names, vec!["wR", "wL"]);
    let vars = nf.state_vars.clone();
    let mut rows = Vec::new();
    for w in words {
        let f = canonical_lie(
            &mut nf,
            &report.fields,
            &LieWord {
                output: 0,
                fields: w.clone(),
            },
        );
        rows.push(vars.iter().map(|&x| nf.ctx.rf_diff(&f, x)).collect());
    }
    (nf, rows)
}

const FORMULA: &str =
    "-16*delta^4*mu^5*eta^3*xi^5*cos(gamma - phi)*(mu*cos(phi) - cos(gamma - phi))/(mu^2 + 2*mu*cos(gamma) + 1)^5";

#[test]
fn appendix_a_determinant_is_exact() {
    // L_f1f2 h = L_f2 L_f1 h: f1 applied first; a word lists fields in the order applied.
    let words = vec![
        vec![],
        vec![0],
        vec![1],
        vec![0, 0],
        vec![0, 1],
        vec![1, 0],
        vec![1, 1],
    ];
    let (mut nf, rows) = matrix(&words);
    let det = determinant(&mut nf.ctx, &rows);
    let want = nf.parse_expr(FORMULA, false).unwrap();
    let want = nf.ctx.canon(want);
    assert_eq!(det, want, "det = {}", nf.ctx.ratfun_text(&det));
}

#[test]
fn the_other_word_convention_flips_the_sign() {
    // Reading L_f1f2 as L_f1 L_f2 swaps two rows.
    let words = vec![
        vec![],
        vec![0],
        vec![1],
        vec![0, 0],
        vec![1, 0],
        vec![0, 1],
        vec![1, 1],
    ];
    let (mut nf, rows) = matrix(&words);
    let det = determinant(&mut nf.ctx, &rows);
    let want = nf.parse_expr(&format!("-({FORMULA})"), false).unwrap();
    let want = nf.ctx.canon(want);
    assert_eq!(det, want);
}
