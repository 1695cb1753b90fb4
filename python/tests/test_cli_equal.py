"""The Python values are the CLI's --json output, key for key."""

import json

import pytest

import obsan
from conftest import ROOT, SYSTEMS


def _plain(v):
    """numpy arrays back to lists."""
    if hasattr(v, "tolist"):
        return v.tolist()
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_plain(x) for x in v]
    return v


CASES = [
    ("show", lambda: obsan.load("systems/calib.sys").show(input="q", set={"q": 0.9}),
     ["show", "systems/calib.sys", "--input", "q", "--set", "q=0.9"]),
    ("rank", lambda: obsan.load("systems/calib.sys").rank(input="q"),
     ["rank", "systems/calib.sys", "--input", "q"]),
    ("symmetries", lambda: obsan.load("systems/localization.sys").symmetries(),
     ["symmetries", "systems/localization.sys"]),
    ("lie", lambda: obsan.load("systems/localization.sys").lie(2),
     ["lie", "systems/localization.sys", "--order", "2"]),
    ("simplify", lambda: obsan.simplify("(a^2-b^2)/(a-b)"), ["simplify", "(a^2-b^2)/(a-b)"]),
    ("diff", lambda: obsan.diff("atan2(sin(g), -mu - cos(g))", "g"),
     ["diff", "atan2(sin(g), -mu - cos(g))", "g"]),
    ("crlb", lambda: obsan.crlb(bearings=100), ["crlb", "--bearings", "100"]),
    ("verify", lambda: obsan.verify("systems/decomp_localization.dec"),
     ["verify", "systems/decomp_localization.dec"]),
]


@pytest.mark.parametrize("name,py,argv", CASES, ids=[c[0] for c in CASES])
def test_same_value_as_cli(name, py, argv, cli, monkeypatch):
    # Paths as the CLI sees them (relative to the repository).
    monkeypatch.chdir(ROOT)
    code, out, err = cli(*argv, "--json")
    assert code == 0, err
    assert _plain(py()) == json.loads(out)


def test_loads_equals_load_but_for_its_name():
    text = (SYSTEMS / "calib.sys").read_text()
    a = obsan.loads(text).rank(input="q")
    b = obsan.load(SYSTEMS / "calib.sys").rank(input="q")
    assert _plain(a) == _plain(b)


def test_numeric_lists_are_arrays_only_with_numpy(monkeypatch):
    np = pytest.importorskip("numpy")
    v = obsan._arrays({"a": [1.0, 2.0], "b": [[1, 2], [3, 4]], "c": ["x"], "d": [True, 1]})
    assert isinstance(v["a"], np.ndarray) and v["a"].dtype == float
    assert v["b"].shape == (2, 2)
    assert v["c"] == ["x"] and v["d"] == [True, 1]
    monkeypatch.setattr(obsan, "NUMPY", False)
    assert obsan._arrays({"a": [1.0]}) == {"a": [1.0]}
