"""The analysis commands against the paper's results and against the CLI."""

import json
import math
import random

import numpy as np

import obsan
from conftest import SYSTEMS

CALIB = SYSTEMS / "calib.sys"
STATE = ["mu", "gamma", "phi", "psi", "eta", "delta", "xi"]


def test_calib_rank_is_full_without_restriction():
    # Section V: eq. (16) is weakly locally observable, rank 7 of 7, proven.
    r = obsan.load(CALIB).rank()
    assert (r["rank"], r["n"]) == (7, 7)
    assert r["exact"] is True and r["error_bound"] == 0.0
    assert r["weakly_locally_observable"] is True


def test_calib_rank_on_circles_is_4():
    # Eq. (17), circular trajectories: rank 4 of 7 (three symmetries, Appendix B).
    r = obsan.load(CALIB).rank(input="q")
    assert (r["rank"], r["n"]) == (4, 7)
    assert r["restriction"] == "q"
    # Below n the rank is a lower bound with a stated error probability.
    assert r["exact"] is False and 0 < r["error_bound"] < 1e-6
    # A fixed q keeps the same rank.
    assert obsan.load(CALIB).rank(input="q", set={"q": 0.9})["rank"] == 4


def test_localization_from_text():
    # Section II, eq. (3): rank 2 of 3, symmetry [0, 1, 1].
    text = (SYSTEMS / "localization.sys").read_text()
    s = obsan.loads(text)
    assert s.name == "localization"
    assert s.rank()["rank"] == 2
    sym = s.symmetries()["symmetries"]
    assert len(sym) == 1 == 3 - s.rank()["rank"]
    # Compared by span, not as printed text: w and [0, 1, 1] are parallel.
    names = ("D", "phiR", "thetaR")
    w = {x: sym[0][x]["text"] for x in names}
    assert _span_rank([w], names) == 1
    assert _span_rank([w, {"D": "0", "phiR": "1", "thetaR": "1"}], names) == 1


def _eval(text, point):
    """A formula printed by obsan, evaluated in floating point."""
    env = dict(vars(math))
    env.update(point)
    return eval(text.replace("^", "**"), {"__builtins__": {}}, env)


def _span_rank(vectors, names, consts=()):
    """Numerical rank at random points of vectors of formulas (an independent check)."""
    best = 0
    rng = random.Random(7)
    for _ in range(3):
        point = {n: rng.uniform(0.2, 1.3) for n in [*names, *consts]}
        m = np.array([[_eval(v[n], point) for n in names] for v in vectors], dtype=float)
        best = max(best, np.linalg.matrix_rank(m, tol=1e-9 * max(1.0, abs(m).max())))
    return best


def test_symmetries_span_the_same_space_as_the_cli(cli):
    s = obsan.load(CALIB).symmetries(input="q")
    code, out, _ = cli("symmetries", CALIB, "--input", "q", "--json")
    assert code == 0
    c = json.loads(out)
    ours = [{n: w[n]["text"] for n in STATE} for w in s["symmetries"]]
    theirs = [{n: w[n]["text"] for n in STATE} for w in c["symmetries"]]
    assert len(ours) == 3 == 7 - s["rank"]
    assert _span_rank(ours, STATE, ["q"]) == 3
    assert _span_rank(ours + theirs, STATE, ["q"]) == 3
    # Appendix B: delta -> lambda with eta(1 + q delta), xi(1 - q delta) fixed.
    b = {"mu": "0", "gamma": "0", "phi": "0", "psi": "0", "eta": "-q*eta/(1 + q*delta)",
         "delta": "1", "xi": "q*xi/(1 - q*delta)"}
    assert _span_rank(ours + [b], STATE, ["q"]) == 3


def test_lie_derivatives_of_localization():
    lie = obsan.load(SYSTEMS / "localization.sys").lie(1)["lie_derivatives"]
    by_name = {d["lie_derivative"]: d["text"] for d in lie}
    # h = D; L_v h = cos(thetaR - phiR), L_omega h = 0 (eq. 3).
    assert by_name["y"] == "D"
    zero = obsan.simplify(f"({by_name['L_v y']}) - cos(thetaR - phiR)")
    assert zero["is_zero"] is True


def test_check_failure_is_a_value():
    s = obsan.load(SYSTEMS / "localization.sys")
    r = s.check(["D", "thetaR - phiR"])
    assert [c["observable_mode"] for c in r["checks"]] == [True, True]
    bad = s.check("phiR")
    assert bad["checks"][0]["observable_mode"] is False
    assert obsan.run("check", SYSTEMS / "localization.sys", "--mode", "phiR", "--json").code == 1


def test_modes_of_localization_from_text():
    # Section II: the observable modes are D and thetaR - phiR, proven.
    m = obsan.loads((SYSTEMS / "localization.sys").read_text()).modes()
    assert m["certificate"]["verified"] is True
    # Compared by invariance, not as printed text: rank 2 gives two modes, each constant
    # along the symmetry's flow (D, phiR + t, thetaR + t), and independent (their
    # gradients by central differences have rank 2). Whatever form obsan prints them in.
    modes = [x["expr"] for x in m["modes"]]
    assert len(modes) == 2
    rng = random.Random(11)
    p = {"D": rng.uniform(0.5, 2), "phiR": rng.uniform(-1, 1), "thetaR": rng.uniform(-1, 1)}
    grads = []
    for mode in modes:
        for t in (0.3, -1.1):
            moved = dict(p, phiR=p["phiR"] + t, thetaR=p["thetaR"] + t)
            assert math.isclose(_eval(mode, p), _eval(mode, moved), rel_tol=1e-12, abs_tol=1e-12)
        h = 1e-6
        grads.append([(_eval(mode, dict(p, **{x: p[x] + h})) - _eval(mode, dict(p, **{x: p[x] - h}))) / (2 * h)
                      for x in ("D", "phiR", "thetaR")])
    assert np.linalg.matrix_rank(np.array(grads), tol=1e-6) == 2


def test_experiments_auto_finds_three_circles():
    # Table I: a circle keeps A_q, V_q (its states) and xi_q, L_q (params); every
    # xi_q lies in span{d xi, d(xi delta)}, so 2 circles reach 4 of 5 param
    # directions and 3 all: ranks 4 of 7, 8 of 9, 11 of 11 (the paper's design).
    r = obsan.load(CALIB).experiments("auto", input="q")
    assert r["experiments"] == 3
    assert [x["rank"] for x in r["ranks"]][:3] == [4, 8, 11]
    # q = +-1 are ordinary circles: a straight line is q = 1/delta, delta unknown.
    assert not any(s["degenerate"] for s in r["special_values"])


def test_experiments_listed_stack_like_the_cli():
    specs = ["q: q=0.9", "q: q=0", "q: q=-1"]
    r = obsan.load(CALIB).experiments(specs)
    assert (r["rank"], r["n"]) == (11, 11)
    assert r["experiments"][2]["set"] == {"q": "-1"}
    assert r["state"][:2] == ["mu@1", "gamma@1"]


def test_design_sensors_and_families():
    # vins.sys: symmetries T_x, T_y, T_z (r and pf together) and the yaw about the
    # feature. mag breaks yaw only (cost 2), gps_xy yaw and T_x, T_y (6), gps all (10):
    # the yaw alone needs one of them (derivation in tests/cli/design.rs).
    r = obsan.load(SYSTEMS / "vins.sys").design(
        candidates=str(SYSTEMS / "design" / "vins_sensors.cand"), target=["qw", "qx", "qy", "qz"]
    )
    assert [s["candidates"] for s in r["sensors"]["sets"]] == [["mag"], ["gps_xy"], ["gps"]]
    # Two compartments (Villaverde et al. 2019): x1'' + a1 x1' + a0 x1 = b k21 u + b u';
    # a constant u shows a1, a0, b k21 only (never), a ramp also b c (everything).
    f = obsan.load(SYSTEMS / "design" / "c2m_inputs.sys").design()["inputs"]["families"]
    by = {x["restriction"]: x for x in f}
    assert by["constant"]["full"] is False and by["ramp"]["single_full"] is True


def test_known_initial_condition_riccati():
    # strike-goldd issue 7: S' = 1 + a S^2, y = S, S(0) = 0; y'''(0) = 2a.
    s = obsan.loads("system riccati\nstate S\nparam a\nS' = 1 + a*S^2\noutput y = S\n")
    r = s.rank_known(known={"S": 0})
    assert r["identifiable"] is True and r["point_rank"] == 1
    assert r["order_checked"] == 3
    g = s.rank_known(generic="S")
    assert g["rank"] == 1 and g["point_rank"] is None


def test_rank_along_circles(tmp_path):
    # The paper's circles with noise-free encoders (docs/experiments.md): Table I, a
    # circle keeps 4 of 7, so every window has rank 4 and loses the 3 circle
    # symmetries; the three circles together fix all 11 (5 params, 2 states each).
    d = obsan.simulate(tmp_path / "circles", k=0, speed_profile="sine:0.5:20")
    r = obsan.load(CALIB).rank_along(d, window=30)
    assert r.n == 7 and r.ranks and set(r.ranks) == {4}
    assert len(r.stretches) == 3
    for s in r.stretches:
        assert len(s.lost) == 3 and s.matches_symmetries
    assert r.stretches[0].input_relations in (["wL = 0.9*wR"], ["wL = 0"], ["wL = -wR"])
    assert (r.dataset_rank, r.dataset_n) == (11, 11)


def test_an_output_reading_a_known_input_measures_it(cli, tmp_path):
    # y = x + c u, x' = u: y' = u + c u' with u and u' known gives c = (y' - u)/u', then
    # x = y - c u: rank 2 of 2 over (x, c); u is measured, not a variable (docs/sys-format.md).
    text = "system offset\nstate x\nparam c\ninput u\nx' = u\noutput y = x + c*u\n"
    r = obsan.loads(text).rank()
    assert (r["rank"], r["n"]) == (2, 2)
    assert r["state"] == ["x", "c"]
    assert r["measured_inputs"] == ["u"]
    assert r["exact"] is True
    # The library and the CLI take the same entry.
    f = tmp_path / "offset.sys"
    f.write_text(text)
    code, out, _ = cli("rank", f, "--json")
    assert code == 0
    assert json.loads(out)["measured_inputs"] == ["u"]
