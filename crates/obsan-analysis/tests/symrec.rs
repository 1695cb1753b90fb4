//! Symmetries by reconstruction (sym_recon.rs), compared by span with known
//! symmetries and with the exact route, and the certificate's teeth.

mod common;

use common::rank_fp;
use obsan_analysis::{
    certify::certify_symmetries, rank, symmetries_with, Certificate, RankOptions, RankReport,
    Route, SymmetryOptions, SymmetryReport,
};
use obsan_expr::{lie::LieJets, Fp, RatFun, SplitMix};
use obsan_model::{NormalForm, System};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn load(path: &str, input: Option<&str>) -> (NormalForm, RankReport) {
    let src = std::fs::read_to_string(format!("{ROOT}/{path}")).unwrap();
    let sys = System::parse(&src, path).unwrap();
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let r = rank(&mut nf, RankOptions::default()).unwrap();
    (nf, r)
}

/// The basis as vectors: the free directions d/dx (variables no output
/// reaches) become unit vectors after the others (`free` still lists them).
fn run(nf: &mut NormalForm, r: &RankReport, route: Route) -> SymmetryReport {
    let mut s = symmetries_with(
        nf,
        r,
        &SymmetryOptions {
            deadline: None,
            route,
        },
    )
    .unwrap();
    for &j in &s.free {
        let mut e = vec![RatFun::zero(); s.n];
        e[j] = RatFun::one();
        s.vectors.push(e);
    }
    s
}

/// Reconstruction route; the certificate must be the random one with a tiny bound.
fn recon(path: &str, input: Option<&str>) -> (NormalForm, RankReport, SymmetryReport) {
    let (mut nf, r) = load(path, input);
    let s = run(&mut nf, &r, Route::Reconstruct);
    assert_eq!(
        s.vectors.len(),
        r.n - r.rank,
        "{path}: one vector per missing rank"
    );
    match &s.certificate {
        Certificate::Random(c) => {
            assert!(c.error_bound < 1e-30, "{path}: bound {}", c.error_bound);
            assert!(c.points >= 4 && c.primes >= 2 && c.identities > 0);
        }
        // Only variables no output reaches: exact, nothing to reconstruct
        // (the reached part has full rank, proven by the rank test's minor).
        Certificate::Closure if s.vectors.len() == s.free.len() => assert!(s.exact),
        other => panic!("{path}: expected the random certificate, got {other:?}"),
    }
    (nf, r, s)
}

fn values(nf: &mut NormalForm, v: &[RatFun], pt: &obsan_expr::evaluate::FpPoint) -> Vec<Fp> {
    let ids: Vec<_> = v.iter().map(|e| nf.ctx.from_canonical(e)).collect();
    nf.ctx.eval_fp(&ids, pt).unwrap()
}

/// `a` and `b` span the same space of dimension `a.len()` (at two random points).
fn same_span(nf: &mut NormalForm, a: &[Vec<RatFun>], b: &[Vec<RatFun>]) {
    assert_eq!(a.len(), b.len());
    for seed in [3, 11] {
        let mut rng = SplitMix(seed);
        let pt = nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap();
        let ra: Vec<Vec<Fp>> = a.iter().map(|v| values(nf, v, &pt)).collect();
        let rb: Vec<Vec<Fp>> = b.iter().map(|v| values(nf, v, &pt)).collect();
        let both: Vec<Vec<Fp>> = ra.iter().chain(&rb).cloned().collect();
        assert_eq!(rank_fp(ra), a.len(), "found vectors dependent");
        assert_eq!(rank_fp(rb), b.len(), "known vectors dependent");
        assert_eq!(rank_fp(both), a.len(), "spans differ");
    }
}

fn known(nf: &mut NormalForm, vs: &[&[&str]]) -> Vec<Vec<RatFun>> {
    vs.iter()
        .map(|v| {
            v.iter()
                .map(|e| {
                    let id = nf.parse_expr(e, false).unwrap();
                    nf.ctx.canon(id)
                })
                .collect()
        })
        .collect()
}

fn against_known(path: &str, input: Option<&str>, vs: &[&[&str]]) {
    let (mut nf, _, s) = recon(path, input);
    let k = known(&mut nf, vs);
    same_span(&mut nf, &s.vectors, &k);
}

/// Reconstruction and the exact route (an independent computation) agree.
fn against_exact(path: &str, input: Option<&str>) {
    let (mut nf, r, s) = recon(path, input);
    let e = run(&mut nf, &r, Route::Exact);
    assert!(e.exact, "{path}: the exact route's closure check");
    same_span(&mut nf, &s.vectors, &e.vectors);
}

#[test]
fn eq3_localization() {
    // State [D, phiR, thetaR]: phiR and thetaR move together (eq. 3).
    against_known("systems/localization.sys", None, &[&["0", "1", "1"]]);
}

#[test]
fn eq16_calibration_with_q_agrees_with_the_exact_route() {
    against_exact("systems/calib.sys", Some("q"));
}

#[test]
fn eq20_and_psi_agree_with_the_exact_route() {
    against_exact("systems/calib_q_nopsi.sys", None);
    against_exact("systems/psi.sys", None);
}

#[test]
fn classic_scalings() {
    // Lotka–Volterra, state [x, y, a, b, c, d]: y -> l y, b -> b/l.
    against_known(
        "systems/classic/lotka_volterra.sys",
        None,
        &[&["0", "y", "0", "-b", "0", "0"]],
    );
    // Two compartments, state [x1, x2, k01, k02, k12, k21]: x2 -> l x2,
    // k12 -> k12/l, k21 -> l k21 (the file's comment), and the exact route.
    against_exact("systems/classic/two_compartment.sys", None);
}

#[test]
fn seir_free_variable() {
    // R appears in no equation and no output: d/dR (state S, E, I, R, b, a, g, mu, k).
    against_known(
        "systems/benchmarks/seir.sys",
        None,
        &[&["0", "0", "0", "1", "0", "0", "0", "0", "0"]],
    );
}

#[test]
fn vins_global_position_and_yaw() {
    // State [rx, ry, rz, vx, vy, vz, qw, qx, qy, qz, ba (3), bg (3), pf (3)].
    // Translations move r and pf together; the yaw rotation about the world
    // z axis: r, v, pf rotate (-y, x, 0), and q -> (0,0,0,1)/2 (x) q.
    let z = "0";
    let tx: [&str; 19] = ["1", z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, "1", z, z];
    let ty: [&str; 19] = [z, "1", z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, "1", z];
    let tz: [&str; 19] = [z, z, "1", z, z, z, z, z, z, z, z, z, z, z, z, z, z, z, "1"];
    let yaw: [&str; 19] = [
        "-ry", "rx", z, "-vy", "vx", z, "-qz/2", "-qy/2", "qx/2", "qw/2", z, z, z, z, z, z, "-pfy",
        "pfx", z,
    ];
    against_known("systems/vins.sys", None, &[&tx, &ty, &tz, &yaw]);
}

#[test]
fn a_corrupted_vector_fails_certification() {
    let (mut nf, r, s) = recon("systems/calib.sys", Some("q"));
    // The printed vectors pass ...
    assert!(certify_symmetries(&mut nf, &r, &s.vectors, None)
        .unwrap()
        .is_some());
    // ... a vector scaled by a non-constant is still a symmetry ...
    let mut scaled = s.vectors.clone();
    let mu = nf.ctx.lookup("mu").unwrap().var;
    scaled[0] = scaled[0]
        .iter()
        .map(|e| nf.ctx.rf_mul(e, &RatFun::var(mu)))
        .collect();
    assert!(certify_symmetries(&mut nf, &r, &scaled, None)
        .unwrap()
        .is_some());
    // ... but changing one coefficient by a little breaks it.
    for k in 0..s.vectors.len() {
        let mut bad = s.vectors.clone();
        let j = bad[k].iter().position(|e| !e.is_zero()).unwrap();
        let two = RatFun::from_q(&obsan_expr::Q::new(1001.into(), 1000.into()));
        bad[k][j] = nf.ctx.rf_mul(&bad[k][j], &two);
        assert!(
            certify_symmetries(&mut nf, &r, &bad, None)
                .unwrap()
                .is_none(),
            "vector {k} corrupted at {j} passed"
        );
    }
}

#[test]
fn prefix_rows_agree_with_rows() {
    for (path, input) in [
        ("systems/calib.sys", None),
        ("systems/vins.sys", None),
        ("systems/benchmarks/goodwin.sys", None),
    ] {
        let (mut nf, r) = load(path, input);
        let outputs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let jets = LieJets::new(&nf.ctx, &nf.state_vars, &r.fields.vectors, &outputs);
        let mut rng = SplitMix(9);
        let pt = nf.ctx.random_fp_point(&mut rng, &|_| None).unwrap();
        for w in &r.basis {
            let rows = jets.prefix_rows(w.output, &w.fields, &pt).unwrap();
            assert_eq!(rows.len(), w.fields.len() + 1);
            for (len, row) in rows.iter().enumerate() {
                let one = jets.row(w.output, &w.fields[..len], &pt, false).unwrap();
                assert_eq!(row.value, one.value, "{path}");
                assert_eq!(row.gradient, one.gradient, "{path}");
            }
        }
    }
}

/// `height_bounds` (the content term of the certificate's bound) bounds the
/// L1 norm of the coefficients: for a polynomial with non-negative
/// coefficients that norm is its value at the all-ones point, computed here
/// exactly and independently of the bound.
#[test]
fn height_bounds_cover_the_coefficient_norm() {
    use obsan_expr::{lie::height_bounds, Ctx, Q};
    let cases = [
        "(2*x + 3*y)^3*(x + 5)^2 + 7*x*y",
        "(x + y + z)^6",
        "11*x^2*(4 + y)^3 + (x*y + 2)^4*(3*z + 1)",
    ];
    for src in cases {
        let mut ctx = Ctx::new();
        let id = ctx.parse(src).unwrap();
        let ones = ctx.eval_q(&[id], &|_| Some(Q::from_i64(1))).unwrap();
        let norm = ones[0].to_f64();
        let (hn, hd) = height_bounds(&ctx, &[id])[0];
        assert!(
            norm.log2() <= hn + 1e-9,
            "{src}: |P|_1 = {norm}, bound 2^{hn}"
        );
        assert!(hd >= 0.0, "{src}: denominator bound {hd}");
    }
    // A quotient: (x + 2)/(3 y + 1) is 3 over 4 in L1 norm.
    let mut ctx = Ctx::new();
    let id = ctx.parse("(x + 2)/(3*y + 1)").unwrap();
    let (hn, hd) = height_bounds(&ctx, &[id])[0];
    assert!(
        3f64.log2() <= hn + 1e-9 && 2.0 <= hd + 1e-9,
        "bounds {hn}, {hd}"
    );
}
