"""``obsan global`` from Python: the counts derived by hand in systems/global/
and the typed discrete maps, checked by applying them to the model."""

import math

import pytest

import obsan
from conftest import SYSTEMS


def test_wall_reflection_map_is_typed_and_exact():
    # Hand derivation in the file: sin(theta) and x0 cos(theta) are known,
    # so (x, theta) -> (-x, pi - theta) gives the second of 2 solutions.
    g = obsan.load(SYSTEMS / "global" / "wall_reflection.sys").global_identifiability()
    assert g.solutions == 2
    values = {v.name: v.values for v in g.variables}
    assert values == {"theta": 2, "x": 2, "y": 1}
    assert len(g.maps) == 1
    m = g.maps[0]
    assert isinstance(m, obsan.DiscreteMap)
    assert str(m) == g["maps"][0]  # still a Mapping of the JSON
    assert sorted(im.var for im in m.images) == ["theta", "x"]
    # The outputs y and x^2 + y^2 are unchanged; x' = v cos(theta) changes
    # sign with x, y' = v sin(theta) is kept.
    p = {"x": 0.7, "y": 1.3, "theta": 0.4, "v": 1.1}
    q = m.apply(p)
    assert q["x"] != pytest.approx(p["x"])
    assert q["y"] == p["y"]
    assert q["x"] ** 2 + q["y"] ** 2 == pytest.approx(p["x"] ** 2 + p["y"] ** 2, rel=1e-12)
    assert q["v"] * math.cos(q["theta"]) == pytest.approx(-p["v"] * math.cos(p["theta"]), rel=1e-12)
    assert q["v"] * math.sin(q["theta"]) == pytest.approx(p["v"] * math.sin(p["theta"]), rel=1e-12)


def test_map_parse_reads_every_printed_form():
    m = obsan.DiscreteMap.parse("(a, b, c, d) -> (b, -a, c + pi, pi - d)")
    assert m.images == [
        obsan.MapImage("a", "b", 1, False),
        obsan.MapImage("b", "a", -1, False),
        obsan.MapImage("c", "c", 1, True),
        obsan.MapImage("d", "d", -1, True),
    ]
    assert obsan.DiscreteMap.parse("a -> -a").apply({"a": 2.0}) == {"a": -2.0}
    with pytest.raises(ValueError):
        obsan.DiscreteMap.parse("a")


def test_angle_outputs_read_through_their_tangent():
    # Hand derivation in the file: bearing (atan2) and range fix the landmark;
    # over the bearing's tangent l and -l agree, and the map turns the bearing by pi.
    g = obsan.load(SYSTEMS / "global" / "landmark_polar.sys").global_identifiability()
    assert g.solutions == 1 and not g.solutions_at_most
    assert {v.name: (v.values, v.at_most) for v in g.variables} == {
        "lx": (1, False),
        "ly": (1, False),
    }
    assert g.maps == []
    assert [str(m) for m in g.maps_modulo_pi] == ["(lx, ly) -> (-lx, -ly)"]
    p = {"lx": 0.3, "ly": -1.2}
    q = g.maps_modulo_pi[0].apply(p)
    assert math.atan2(q["ly"], q["lx"]) != pytest.approx(math.atan2(p["ly"], p["lx"]))
    assert q["ly"] / q["lx"] == pytest.approx(p["ly"] / p["lx"], rel=1e-12)
    # x -> -1 - x is no signed permutation: the count over the tangent stays a bound.
    g = obsan.load(SYSTEMS / "global" / "bearing_of_a_quadratic.sys").global_identifiability()
    x = next(v for v in g.variables if v.name == "x")
    assert (x.values, x.at_most) == (2, True)
    assert g.solutions_at_most


def test_the_input_output_route_counts_two_summed_decays():
    # By hand: y = x1 + x2 with x1' = -a x1, x2' = -b x2 has the relation
    # y'' + (a + b) y' + a b y = 0, whose coefficients fix {a, b} as an unordered
    # pair: 2 values each (the swap), and the route says it counted params only.
    src = "system d\nstate x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n"
    g = obsan.loads(src).global_identifiability(route="io")
    assert g.route == "input-output" and g.fallback is None
    values = {v.name: v.values for v in g.variables}
    assert values == {"a": 2, "b": 2}, g.variables
    # The swap, as a map of the parameters (a + b and a b are symmetric).
    assert [str(m) for m in g.maps_of_parameters] == ["(a, b) -> (b, a)"]
    assert g.maps_of_parameters[0].apply({"a": 2.0, "b": 3.0}) == {"a": 3.0, "b": 2.0}


def test_the_input_output_route_finds_an_affine_map():
    # By hand (systems/global/shifted_rates.sys): the rates a and a + b are known
    # as an unordered pair, so (a, b) -> (a + b, -b), no signed permutation.
    g = obsan.load(SYSTEMS / "global" / "shifted_rates.sys").global_identifiability(route="io")
    assert [str(m) for m in g.maps_of_parameters] == ["(a, b) -> (a + b, -b)"]
    assert g.maps_of_parameters[0].apply({"a": 2.0, "b": 3.0}) == {"a": 5.0, "b": -3.0}


def test_a_map_with_formulas_reads_and_applies():
    # SI.jl's Treatment by the input-output route prints this map; by hand at
    # d=2, a=3, nu=5, g=7: (14 - 3 - 7 + 5)/7, -7 + 5, 3 + 7.
    m = obsan.DiscreteMap.parse("(d, a, nu) -> ((d*g - a - g + nu)/g, -g + nu, a + g)")
    assert [im.var for im in m.images] == ["d", "a", "nu"]
    q = m.apply({"d": 2.0, "a": 3.0, "nu": 5.0, "g": 7.0})
    assert q == pytest.approx({"d": 9.0 / 7.0, "a": -2.0, "nu": 10.0, "g": 7.0})


def test_multi_experiment_counts_where_one_experiment_does_not_fix_the_relation():
    # By hand (systems/global/forced_oscillator_offset.sys): one experiment shows
    # b/omega^2 + c only; the relation y' y'' - y y''' + c y''' - b y' = 0 has a
    # zero Wronskian, and its coefficients fix b and c over several experiments.
    s = obsan.load(SYSTEMS / "global" / "forced_oscillator_offset.sys")
    one = {v.name: v.verdict for v in s.global_identifiability().variables}
    assert one["b"] == one["c"] == "not identifiable"
    g = s.global_identifiability(multi_experiment=True)
    assert g.route == "input-output" and g.multi_experiment
    assert {v.name: v.values for v in g.variables} == {"b": 1, "c": 1}


def test_the_lie_route_counts_a_cart_for_every_input():
    # By hand (systems/global/squared_range_gain.sys): h = x^2, L_u h = 2 a x,
    # L_u L_u h = 2 a^2 fix (x, a) up to a common sign, for every input.
    g = obsan.load(SYSTEMS / "global" / "squared_range_gain.sys").global_identifiability(
        route="lie"
    )
    assert g.route == "lie" and g.fallback is None
    assert {v.name: v.values for v in g.variables} == {"a": 2, "x": 2}
    assert g.solutions == 2


def test_the_default_route_counts_the_states_after_the_input_output_route():
    # SI.jl's Goodwin oscillator (its own test's verdicts, in the file): the Taylor
    # system is long, so the relations count the params; the initial states follow
    # with b, c, sigma known. SI.jl's identifiable functions with states
    # (benchmarking/IdentifiableFunctions/results/Goodwin oscillator) hold x1 and x4,
    # and no function of x2 or x3 alone.
    g = obsan.load(SYSTEMS / "global" / "sijl_tests" / "goodwin.sys").global_identifiability()
    assert g.route == "input-output" and g.states_counted_after_io
    assert g.fixed_params == ["b", "c", "sigma"]
    verdicts = {(v.name, v.kind): v.verdict for v in g.variables}
    assert verdicts[("x1", "state")] == verdicts[("x4", "state")] == "global"
    assert verdicts[("x2", "state")] == verdicts[("x3", "state")] == "not identifiable"
    assert verdicts[("beta", "param")] == "local"
