"""The package as a Python library: real signatures, typed results that
are also the CLI's JSON, Python's own exceptions, systems built from Python values,
quiet progress, and type information for mypy."""

import inspect
import json
import pathlib
import shutil
import subprocess
import sys

import pytest

import obsan
from conftest import ROOT, SYSTEMS

PUBLIC_FUNCTIONS = [
    obsan.load, obsan.loads, obsan.system, obsan.simplify, obsan.diff, obsan.verify,
    obsan.simulate, obsan.calibrate, obsan.crlb, obsan.diagnose, obsan.montecarlo,
    obsan.montecarlo_merge, obsan.schema,
]
SYSTEM_METHODS = [
    obsan.System.show, obsan.System.rank, obsan.System.experiments, obsan.System.rank_known,
    obsan.System.symmetries, obsan.System.modes, obsan.System.global_identifiability,
    obsan.System.lie, obsan.System.check, obsan.System.design,
]


@pytest.mark.parametrize("fn", PUBLIC_FUNCTIONS + SYSTEM_METHODS, ids=lambda f: f.__qualname__)
def test_every_function_has_a_real_signature_and_a_docstring(fn):
    params = inspect.signature(fn).parameters.values()
    # No **options: help() and IDEs show every keyword, and a misspelt one is a TypeError.
    assert all(p.kind is not inspect.Parameter.VAR_KEYWORD for p in params)
    assert all(p.annotation is not inspect.Parameter.empty for p in params if p.name != "self")
    assert fn.__doc__ and fn.__doc__.strip()


def test_all_names_exist_and_the_package_is_typed():
    for name in obsan.__all__:
        assert hasattr(obsan, name), name
    assert (pathlib.Path(obsan.__file__).parent / "py.typed").exists()


def test_a_rank_result_is_typed_and_is_the_json():
    r = obsan.load(SYSTEMS / "calib.sys").rank(input="q")
    # Eq. (17): four of seven directions on circles (the paper's Section IV-B).
    assert isinstance(r, obsan.Rank)
    assert (r.n, r.rank, r.weakly_locally_observable) == (7, 4, False)
    assert r.variables == ["mu", "gamma", "phi", "psi", "eta", "delta", "xi"]
    assert sorted(r.observable + r.unobservable) == sorted(r.variables)
    assert r["rank"] == r.rank and r.to_dict()["rank"] == 4
    json.dumps(r.to_dict())  # plain data
    assert "<table>" in r._repr_html_() and "rank" in repr(r)
    with pytest.raises(Exception):
        r.rank = 3  # frozen


def test_symmetries_are_vectors_of_formulas_and_render_as_latex():
    s = obsan.load(SYSTEMS / "calib.sys").symmetries(input="q")
    assert isinstance(s, obsan.Symmetries)
    assert len(s.vectors) == 7 - 4  # n - rank (eq. 17)
    assert all(set(w) <= set(s.variables) for w in s.vectors)
    assert s._repr_latex_().startswith("$") and "pmatrix" in s._repr_latex_()


# x' = 0, y' = 0, outputs x and y (log(x y) - log(x) - log(y)): the second is 0 for
# x, y > 0, so d/dy is a true symmetry, but over independent logarithms the rank
# looks full (2 of 2). Neither result may claim it exactly.
HIDDEN = (
    "system hidden\nstate x, y\nx' = 0\ny' = 0\n"
    "output h1 = x\noutput h2 = y*(log(x*y) - log(x) - log(y))\n"
)


def test_symmetries_and_modes_over_related_atoms_are_not_decided():
    s = obsan.loads(HIDDEN).symmetries()
    assert s.decided is False and s.exact is False
    assert {"log(x)", "log(x*y)"} <= set(s.undecided_atoms)
    m = obsan.loads(HIDDEN).modes()
    assert m.decided is False and m.full_rank is None
    assert "log(y)" in m.undecided_atoms
    # A decided system keeps its certificate (eq. 17: 3 symmetries, exact route).
    c = obsan.load(SYSTEMS / "calib.sys").symmetries(input="q")
    assert c.decided is True and c.undecided_atoms == []


def test_expressions_and_estimates_are_typed():
    e = obsan.simplify("sin(g-p)*cos(p) + cos(g-p)*sin(p) - sin(g)")
    assert isinstance(e, obsan.Expression) and e.is_zero is True and e.canonical == "0"
    d = obsan.diff("x^3", "x")
    assert str(d) == "3*x^2" and d._repr_latex_() == f"${d.latex}$"
    c = obsan.crlb(bearings=100)
    assert isinstance(c, obsan.CramerRao)
    # The CLI's keys carry units ("phi (deg)"); the typed value splits them.
    assert set(c.sd) == {"phi", "psi", "eta", "delta", "xi"}
    assert c.units["phi"] == "deg" and c.units["eta"] == "%"
    assert c.sd["phi"] == c.raw["crlb_sd"]["phi (deg)"]


def test_calibration_estimates_are_named_tuples(tmp_path):
    ds = obsan.simulate(tmp_path / "ds", bearings=60, seed=3)
    c = obsan.calibrate(ds, "ls", d0=1.2)
    assert isinstance(c, obsan.Calibration)
    eta = c.params["eta"]
    assert isinstance(eta, obsan.Estimate) and eta.value == c["params"]["eta"]["value"]
    assert eta.sd == c.raw["params"]["eta"]["sd"]
    assert set(c.metric) == {"rho", "r_right", "r_left", "B"}


def test_wrong_values_are_python_errors_before_anything_runs(tmp_path):
    with pytest.raises(ValueError, match="det, ls, cekf or ml"):
        obsan.calibrate(tmp_path, "gauss")
    with pytest.raises(TypeError, match="seed"):
        obsan.load(SYSTEMS / "calib.sys").rank(seed=1.5)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="set"):
        obsan.load(SYSTEMS / "calib.sys").rank(set=["q", 0.9])  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        obsan.simulate(tmp_path / "x", bearings=10, q="0.9")  # type: ignore[arg-type]
    assert not (tmp_path / "x").exists()


def test_a_system_from_python_values_is_the_file_it_describes():
    # systems/calib.sys written as Python values: the same normal form and ranks.
    s = obsan.system(
        "calib",
        states=["mu", "gamma"],
        params=["phi", "psi", "eta", "delta", "xi"],
        consts=["q"],
        inputs=["wR", "wL"],
        dynamics={
            "mu": "-mu^2*eta*(wR + delta*wL)*cos(gamma - phi)",
            "gamma": "xi*(wR - delta*wL) - mu*eta*(wR + delta*wL)*sin(gamma - phi)",
        },
        outputs={"beta": "atan2(sin(gamma), -mu - cos(gamma)) - psi"},
        restrictions={"q": "wR = nu, wL = q*nu"},
    )
    f = obsan.load(SYSTEMS / "calib.sys")
    for key in ("states", "params", "inputs", "f0", "fields", "outputs"):
        assert s.info.raw[key] == f.info.raw[key], key
    assert s.rank().rank == 7 and s.rank(input="q").rank == 4
    with pytest.raises(obsan.ObsanError, match=r"<string>:\d+:\d+"):
        obsan.system("bad", states=["x"], dynamics={"x": "x +"}, outputs={"y": "x"})


def test_progress_is_quiet_by_default(tmp_path):
    # A Monte Carlo sweep reports progress every step with OBSAN_PROGRESS_SECS=0 on a
    # non-terminal stderr; from Python it stays quiet unless obsan.PROGRESS is set.
    code = (
        "import obsan, sys\n"
        "obsan.PROGRESS = sys.argv[1] == 'on'\n"
        "obsan.montecarlo(table=5, cell=1, runs=2, threads=1)\n"
    )
    env = dict(__import__("os").environ, OBSAN_PROGRESS_SECS="0")
    quiet = subprocess.run([sys.executable, "-c", code, "off"], capture_output=True, text=True, env=env)
    loud = subprocess.run([sys.executable, "-c", code, "on"], capture_output=True, text=True, env=env)
    assert quiet.returncode == 0 and loud.returncode == 0, quiet.stderr + loud.stderr
    assert "montecarlo" not in quiet.stderr
    assert "montecarlo" in loud.stderr


def test_mypy_strict_passes_on_the_examples_and_the_package():
    mypy = shutil.which("mypy") or (str(pathlib.Path(sys.executable).parent / "mypy"))
    if not pathlib.Path(mypy).exists():
        if __import__("os").environ.get("CI"):
            pytest.fail("mypy is not installed: CI's venv must have it (.ci/run)")
        pytest.skip("mypy is not installed (CI installs it)")
    examples = sorted(str(p) for p in (ROOT / "examples" / "python").glob("*.py"))
    # The examples as a user's code, then `-p obsan`: the installed package as its users
    # import it (py.typed, _native.pyi).
    for target in (examples, ["-p", "obsan"]):
        p = subprocess.run(
            [mypy, "--strict", "--ignore-missing-imports", *target],
            capture_output=True, text=True, cwd=ROOT,
        )
        assert p.returncode == 0, p.stdout + p.stderr


def test_a_schema_names_the_keys_of_its_result():
    # The result objects are mappings of the CLI's JSON: the schema's properties are their keys.
    s = obsan.schema("simplify")
    assert set(s["properties"]) == set(obsan.simplify("x + 1").to_dict())
    assert s["additionalProperties"] is False
    d = obsan.schema("crlb")
    assert set(d["properties"]) == set(obsan.crlb(bearings=40).to_dict())
    with pytest.raises(obsan.ObsanError, match="no schema for 'nope'"):
        obsan.schema("nope")
    with pytest.raises(TypeError):
        obsan.schema(3)  # type: ignore[arg-type]
