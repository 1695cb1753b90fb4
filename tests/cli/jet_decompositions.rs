//! Decomposition files and reduced systems that read the known inputs'
//! derivatives (issue 33; docs/decomposition-format.md, "Inputs'
//! derivatives and unknown-input combinations"): `obsan modes --out` writes
//! them, `obsan verify` checks them exactly, and hand-written files with the
//! forms derived beside each test pass, wrong ones fail.

use crate::util::*;

/// x1' = p u + x2, x2' = w, y = x1. By hand: y' = p u + x2, y'' = p u' + w,
/// so x1 and z = x2 + p u are the modes (x2 and p enter y's derivatives
/// only so), and z' = x2' + p u' = w + p u': the reduced system reads u'
/// and is driven by the combination w~ = w + p u' (recovered as y'').
const SMALL: &str = "system small_jets
state x1, x2
param p
input u
unknown input w
x1' = p*u + x2
x2' = w
output y = x1
";

/// Two unknown inputs (unknown_input_jet_modes.rs, MIXED): x4' = w1 + x4
/// is driven by w1 itself (reconstructable from y2' - y2), z1 = x2 + p u by
/// the combination w2 + p u'.
const MIXED: &str = "system mixed_jets
state x1, x2, x4
param p
input u
unknown input w1, w2
x1' = p*u + x2
x2' = w2
x4' = w1 + x4
output y1 = x1
output y2 = x4
";

/// `modes --out` then `verify` on the written file: exit 0, every check a
/// PASS; returns (the .dec text, the .sys text, verify's output).
fn round_trip(sys: &str, name: &str) -> (String, String, String) {
    let dir = fresh_dir(&format!("jet-dec-{name}"));
    let prefix = format!("{dir}/{name}");
    ok(&["modes", sys, "--out", &prefix]);
    let dec = std::fs::read_to_string(format!("{prefix}.dec")).unwrap();
    let red = std::fs::read_to_string(format!("{prefix}.sys")).unwrap();
    let out = ok(&["verify", &format!("{prefix}.dec")]);
    assert!(!out.contains("FAIL"), "{dec}\n{out}");
    assert!(out.contains("decomposition verified"), "{out}");
    // The reduced system reads as a .sys file.
    ok(&["show", &format!("{prefix}.sys")]);
    (dec, red, out)
}

#[test]
fn cstr_observer_round_trip_through_modes_out_and_verify() {
    let f = "systems/benchmarks/unknown-inputs/cstr_observer.sys";
    let (dec, red, out) = round_trip(f, "cstr");
    // The modes read u3' (z2 holds delta1 qc u3', from y'' = ... +
    // delta1 qc u3'), the reduced dynamics u3'' through the combination
    // (y''' reads u3''): both declared, and the reduced .sys has them as
    // derived inputs.
    assert!(dec.contains("derivative u3_d1 = u3'\n"), "{dec}");
    assert!(dec.contains("derivative u3_d2 = u3''\n"), "{dec}");
    assert!(dec.contains("combination d_z2 = "), "{dec}");
    assert!(red.contains("input u3_d1 = rate(u3)\n"), "{red}");
    assert!(red.contains("input u3_d2 = rate(u3_d1)\n"), "{red}");
    assert!(red.contains("unknown input d_z2\n"), "{red}");
    // Rank 3 with unknown inputs plus the jets u3, u3' (coordinates no
    // symmetry moves): 5 new variables, the jets' equations added.
    assert!(
        out.contains("PASS they are complete (rank of the system is 5), the known inputs' jets u3, u3' counted"),
        "{out}"
    );
    assert!(
        out.contains("PASS u3 has the time derivative u3' (a known input's jet"),
        "{out}"
    );
    assert!(
        out.contains("PASS the combination d_z2 is recovered"),
        "{out}"
    );
    // A wrong claim fails: twice the combination.
    let dir = fresh_dir("jet-dec-cstr-wrong");
    let wrong = dec.replace("z2' = d_z2", "z2' = 2*d_z2");
    let w = format!("{dir}/wrong.dec");
    std::fs::write(&w, wrong).unwrap();
    let r = obsan(&["verify", &w]);
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("FAIL z2' = 2*d_z2"), "{}", r.stdout);
}

#[test]
fn small_and_mixed_round_trips() {
    let f = temp_file("small_jets.sys", SMALL);
    let (dec, red, _) = round_trip(&f, "small");
    assert!(dec.contains("derivative u_d1 = u'\n"), "{dec}");
    assert!(red.contains("input u_d1 = rate(u)\n"), "{red}");
    let f = temp_file("mixed_jets.sys", MIXED);
    let (_, red, out) = round_trip(&f, "mixed");
    assert!(red.contains("unknown input"), "{red}");
    assert!(
        out.contains(
            "PASS unknown input w1, which drives the reduced dynamics, is reconstructable"
        ),
        "{out}"
    );
}

#[test]
fn a_hand_written_decomposition_that_reads_u_prime() {
    let f = temp_file("small_jets_hand.sys", SMALL);
    // The forms derived above, under a name of the user's (du for u').
    let good = format!(
        "system {f}\nderivative du = u'\nlet z = x2 + p*u\ncombination wt = w + p*du\nstate x1, z\nx1' = z\nz' = wt\noutput y = x1\n"
    );
    let dec = temp_file("small_jets_hand.dec", &good);
    let out = ok(&["verify", &dec]);
    assert!(!out.contains("FAIL"), "{out}");
    // Without p u' the claim misses p u'; u' is the view's top-order input
    // here (the symmetries read u alone), so its coefficient is off by p.
    let dec = temp_file(
        "small_jets_hand_wrong.dec",
        &good.replace("combination wt = w + p*du", "combination wt = w"),
    );
    let r = obsan(&["verify", &dec]);
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("FAIL z' = wt"), "{}", r.stdout);
    assert!(
        r.stdout
            .contains("coefficient of u_d1: L_fu_d1 z - claimed = p"),
        "{}",
        r.stdout
    );
}

#[test]
fn a_derivative_the_modes_do_not_read_is_a_located_error() {
    let f = temp_file("small_jets_err.sys", SMALL);
    // The symmetries read u only (xi = (0, -u, 1)): the view holds u, u'.
    let text = format!("system {f}\nderivative dddu = u'''\nlet z = x2 + p*u\nstate x1, z\nx1' = z\nz' = w\noutput y = x1\n");
    let dec = temp_file("small_jets_err.dec", &text);
    let e = bad(&["verify", &dec], "small_jets_err.dec:2:");
    assert!(e.contains("u'''") && e.contains("u, u'"), "{e}");
    for (line, want) in [
        ("derivative du = 3", "small_jets_err2.dec:2:17:"),
        ("derivative du = u'x", "small_jets_err2.dec:2:17:"),
        ("derivative = u'", "small_jets_err2.dec:2:12:"),
        ("combination c = w +", "small_jets_err2.dec:2:"),
    ] {
        let dec = temp_file(
            "small_jets_err2.dec",
            &format!("system {f}\n{line}\nstate x1\nx1' = 0\n"),
        );
        bad(&["verify", &dec], want);
    }
    // Without unknown inputs neither statement has a meaning.
    let k = temp_file(
        "known_only.sys",
        "system k\nstate x\ninput u\nx' = u\noutput y = x\n",
    );
    for (line, want) in [
        ("derivative du = u'", "known_only.dec:2:17:"),
        ("combination c = x", "known_only.dec:2:17:"),
    ] {
        let dec = temp_file(
            "known_only.dec",
            &format!("system {k}\n{line}\nstate x\nx' = u\noutput y = x\n"),
        );
        bad(&["verify", &dec], want);
    }
}
