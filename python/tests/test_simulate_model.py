"""obsan.simulate_model: any .sys model integrated from given values."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import obsan

# The simulator's estimated error is within 1e-9 (|v| + 1) per value; values here are
# at most 2, so 3e-9, and the estimate is an estimate: allow 10x.
TOL = 3e-8


def test_decay_matches_the_closed_form(tmp_path: Path) -> None:
    # x' = -k x + u: x = u/k + (x0 - u/k) e^(-k t).
    m = tmp_path / "decay.sys"
    m.write_text("system decay\nstate x\nparam k\ninput u\nx' = -k*x + u\noutput y = x\n")
    vals = tmp_path / "decay.values"
    vals.write_text("k = 0.5\n")
    s = obsan.simulate_model(m, values=vals, init={"x": 2}, inputs={"u": 0.1}, until=4, every=0.5)
    assert s.columns == ["time", "x", "y"]
    assert s.error_estimate <= s.tolerance
    for t, x in zip(s.column("time"), s.column("x")):
        assert abs(x - (0.2 + 1.8 * math.exp(-0.5 * t))) <= TOL
    assert s["rows"][8][0] == 4.0


def test_a_missing_value_is_named(tmp_path: Path) -> None:
    m = tmp_path / "decay.sys"
    m.write_text("system decay\nstate x\nparam k\nx' = -k*x\noutput y = x\n")
    with pytest.raises(obsan.ObsanError, match="param k"):
        obsan.simulate_model(m, init={"x": 1}, until=1, every=1)


def test_inputs_of_time_and_a_time_course(tmp_path: Path) -> None:
    # x' = u with u = sin(t): x = x0 + 1 - cos(t).
    m = tmp_path / "acc.sys"
    m.write_text("system acc\nstate x\ninput u\nx' = u\noutput y = x\n")
    s = obsan.simulate_model(m, init={"x": 0.5}, inputs={"u": "sin(t)"}, until=6, every=0.5)
    for t, x in zip(s.column("time"), s.column("x")):
        assert abs(x - (1.5 - math.cos(t))) <= TOL
    # u = 2 t up to 1, then a step to -1: x = t^2, then 1 - (t - 1).
    course = tmp_path / "u.csv"
    course.write_text("t,u\n0,0\n1,2\n1,-1\n3,-1\n")
    s = obsan.simulate_model(m, init={"x": 0}, inputs_csv=course, until=3, every=0.25)
    for t, x in zip(s.column("time"), s.column("x")):
        assert abs(x - (t * t if t <= 1 else 2 - t)) <= TOL
    course.write_text("t,u\n0,0\n1,oops\n")
    with pytest.raises(obsan.ObsanError, match="u.csv:3:3"):
        obsan.simulate_model(m, init={"x": 0}, inputs_csv=course, until=1, every=1)
