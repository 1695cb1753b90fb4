"""The Python API on models with unknown inputs (docs/engine.md, "Unknown inputs").
Verdicts derived by hand in the model files (systems/benchmarks/unknown-inputs/)."""

from __future__ import annotations

from pathlib import Path

import obsan

UI = Path(__file__).resolve().parents[2] / "systems" / "benchmarks" / "unknown-inputs"


def test_rank_names_the_reconstructable_input_and_its_order() -> None:
    # chain.sys: y = x1, y' = x2, y'' = w.
    r = obsan.load(UI / "chain.sys").rank()
    assert isinstance(r, obsan.Rank)
    assert (r.rank, r.n) == (2, 2)
    assert r.observable == ["x1", "x2"]
    assert r.orders == {"x1": 0, "x2": 1}
    assert r.unknown_inputs == ["w"]
    assert r.reconstructable == {"w": 2}
    assert r.weakly_locally_observable


def test_rank_of_the_two_compartment_model_with_b_known() -> None:
    # c2m_known_b.sys: w absorbs the x1 equation; only x1 = y is observable.
    r = obsan.load(UI / "c2m_known_b.sys").rank()
    assert r.observable == ["x1"]
    assert r.unobservable == ["x2", "k1e", "k12", "k21"]
    assert r.reconstructable == {}


def test_symmetries_of_the_unicycle_with_unknown_speed() -> None:
    # unicycle_one_landmark.sys: rotation about the landmark and scaling lost.
    s = obsan.load(UI / "unicycle_one_landmark.sys").symmetries()
    assert isinstance(s, obsan.Symmetries)
    assert s.rank == 1
    assert len(s.vectors) == 2
    assert s.exact and s.certificate == "unknown_input_invariance"
    assert s["unobservable_variables"] == ["x", "y", "theta"]


def test_modes_at_full_rank_name_the_recovered_input() -> None:
    # chain.sys: rank 2 of 2, so the modes are x1, x2; w moves x2 (g = (0, 1)) and
    # y'' = w recovers it (order 2).
    m = obsan.load(UI / "chain.sys").modes()
    assert isinstance(m, obsan.Modes)
    assert m.full_rank and m.closed
    assert m.modes == ["x1", "x2"]
    assert m.unknown_inputs == ["w"]
    assert m.reduced_inputs == [
        obsan.ReducedUnknownInput(
            name="w", input="w", factor=None, offset=None, mode="x2", order=2
        )
    ]


def test_modes_of_the_unicycle_with_unknown_speed() -> None:
    # unicycle_one_landmark.sys: rank 1 of 3 (rotation about the landmark and the
    # scaling lost), so one mode; v is lost, a combination (dm . g) v drives it.
    m = obsan.load(UI / "unicycle_one_landmark.sys").modes()
    assert (m.rank, m.full_rank) == (1, False)
    assert len(m.modes) == 1 and m.closed
    [ri] = m.reduced_inputs
    assert ri.input == "v" and ri.factor is not None and ri.order is None


def test_modes_refuse_a_lost_input_with_the_reason() -> None:
    # x1' = w1 + w2, y = x1: only the sum is seen; the mode x1 needs w1.
    src = "system q\nstate x1, x2\nunknown input w1, w2\nx1' = w1 + w2\nx2' = w2\noutput y = x1\n"
    try:
        obsan.loads(src).modes()
    except obsan.ObsanError as e:
        assert "the derivative of mode x1 needs the unknown input w1" in str(e)
    else:
        raise AssertionError("modes accepted a reduced system needing a lost input")


def test_rank_with_explicit_time() -> None:
    # x' = w, y = x + t^2 (t known, t' = 1): x = y - t^2 from y, w = y' - 2t from y'.
    # The clock is not reported as a state.
    r = obsan.loads("system q\nstate x\nunknown input w\nx' = w\noutput y = x + t^2\n").rank()
    assert (r.rank, r.n) == (1, 1)
    assert r.variables == ["x"]
    assert r.orders == {"x": 0}
    assert r.reconstructable == {"w": 1}
    # Known inputs only: y = x*t with x' = 0 gives x = y/t where t != 0.
    g = obsan.loads("system g\nstate x\nx' = 0\noutput y = x*t\n").rank()
    assert (g.rank, g.n) == (1, 1)
    assert g.observable == ["x"]


def test_modes_with_explicit_time_and_global_refusing_it() -> None:
    # x' = a x, y = c x t: (x, c) -> (l x, c/l) leaves y unchanged; y = t (c x) and
    # y' = (c x)(1 + a t) give c x, then a: rank 2, modes a and c x. The clock t is the
    # analysis' coordinate, never a mode (session 25: modes handles explicit time).
    m = obsan.loads("system tg\nstate x\nparam a, c\nx' = a*x\noutput y = c*x*t\n").modes()
    assert m.rank == 2
    assert len(m.modes) == 2 and "t" not in m.modes and "a" in m.modes
    # `obsan global` still refuses it at its place.
    try:
        obsan.loads("system g\nstate x\nx' = 0\noutput y = x*t\n").global_identifiability()
    except obsan.ObsanError as e:
        assert "<string>:4:14: explicit time 't'" in str(e)
        assert "`obsan global`" in str(e)
    else:
        raise AssertionError("global accepted a model with explicit time")
