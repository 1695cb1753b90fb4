"""obsan.import_*: foreign model files to .sys, in-process, with what was written."""

from __future__ import annotations

from pathlib import Path

import pytest

import obsan

ROOT = Path(__file__).resolve().parents[2]

# The simulator's estimated error is within 1e-9 (|v| + 1) per value; x stays below 8
# here, so 9e-9; the estimate is an estimate: allow 10x.
TOL = 9e-8

TIME = '<csymbol encoding="text" definitionURL="http://www.sbml.org/sbml/symbols/time">time</csymbol>'

# x' = k * dose (compartment of size 1, x(0) = 1, k = 0.5) with dose = D = 2 from time
# ton = 4.3 on, else 0: a dosing switch, which the import makes the known input u_dose.
DOSING = f"""<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="dosing">
    <listOfCompartments><compartment id="c" size="1" constant="true"/></listOfCompartments>
    <listOfSpecies><species id="x" compartment="c" initialConcentration="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/></listOfSpecies>
    <listOfParameters>
      <parameter id="k" value="0.5" constant="true"/>
      <parameter id="D" value="2" constant="true"/>
      <parameter id="ton" value="4.3" constant="true"/>
      <parameter id="dose" constant="false"/>
    </listOfParameters>
    <listOfRules>
      <assignmentRule variable="dose"><math xmlns="http://www.w3.org/1998/Math/MathML">
        <piecewise><piece><ci>D</ci><apply><geq/>{TIME}<ci>ton</ci></apply></piece>
        <otherwise><cn>0</cn></otherwise></piecewise>
      </math></assignmentRule>
    </listOfRules>
    <listOfReactions>
      <reaction id="R" reversible="false">
        <listOfProducts><speciesReference species="x" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>k</ci><ci>dose</ci></apply>
        </math></kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"""


def test_sbml_with_a_dosing_switch_imports_and_simulates_to_the_closed_form(tmp_path: Path) -> None:
    src = tmp_path / "dosing.xml"
    src.write_text(DOSING)
    sys_, vals, course = tmp_path / "m.sys", tmp_path / "m.values", tmp_path / "m.csv"
    r = obsan.import_sbml(src, sys_, values=vals, inputs_out=course, until=10)
    assert r.format == "sbml" and r.known_inputs == ["u_dose"] and r.refused == []
    assert (r.values_file, r.inputs_out) == (str(vals), str(course))
    [m] = r.models
    assert m.path == str(sys_) and m.text is None
    assert obsan.load(m.path).name == m.system
    # The step at ton exactly: x = 1 + k D max(0, t - ton) = 1 + max(0, t - 4.3).
    s = obsan.simulate_model(m.path, values=r.values_file, inputs_csv=r.inputs_out, until=10, every=0.5)
    for t, x in zip(s.column("time"), s.column("x")):
        assert abs(x - (1 + max(0.0, t - 4.3))) <= TOL


def test_without_out_the_text_is_returned_and_a_refusal_writes_nothing(tmp_path: Path) -> None:
    src = tmp_path / "dosing.xml"
    src.write_text(DOSING)
    r = obsan.import_sbml(src)
    [m] = r.models
    assert m.path is None and m.text is not None and "input u_dose" in m.text
    assert obsan.loads(m.text).name == m.system
    # The values target exists: refused before the .sys is written.
    (tmp_path / "m.values").write_text("keep\n")
    with pytest.raises(obsan.ObsanError, match="m.values exists"):
        obsan.import_sbml(src, tmp_path / "m.sys", values=tmp_path / "m.values")
    assert not (tmp_path / "m.sys").exists()
    assert (tmp_path / "m.values").read_text() == "keep\n"


def test_strike_goldd_file_is_the_model_it_describes(tmp_path: Path) -> None:
    src = ROOT / "systems" / "benchmarks" / "strike-goldd" / "src" / "z_create_lotka_volterra.m"
    r = obsan.import_strike_goldd(src, tmp_path / "lv.sys")
    assert r.format == "strike-goldd" and r.known_inputs == [] and r.values_file is None
    # Lotka-Volterra with the prey N measured: N' = a N - b N P gives a, b P and the
    # derivatives of b P, hence d and c (c N P - d P scaled by b); P -> l P, b -> b / l
    # leaves every output derivative unchanged: rank 5 of 6, P and b lost.
    rank = obsan.load(r.models[0].path).rank()
    assert (rank.n, rank.rank, sorted(rank.unobservable)) == (6, 5, ["P", "b"])


def test_a_missing_source_is_a_file_not_found_error(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        obsan.import_sbml(tmp_path / "absent.xml")
