"""diagnose: a named effect whose outputs still curve in their predicted value is a
stand-in, typed as NamedEffect.stand_in and NamedEffect.curvature."""

import json
import math
import random
import re

import obsan
from conftest import SYSTEMS

SIGMA_RANGE = 0.05


def _unicycle_circles(out, seed, range_of):
    """systems/mrclam.sys's unicycle on circles (v 0.2 m/s, omega 0.3 rad/s) among its
    15 landmarks on a ring of radius 4 m, as scripts/false_alarms.sh simulates it: six
    60 s windows at 50 Hz, one landmark's range and bearing every 0.2 s, each row moved
    by its exact arc. The range sensor reads ``range_of(r)`` plus noise."""
    rng = random.Random(seed)
    text = (SYSTEMS / "mrclam.sys").read_text()
    codes = re.findall(r"^const lx(\w+),", text, re.M)
    outs = re.findall(r"^output (\w+) =", text, re.M)
    ring = [2 * math.pi * i / len(codes) for i in range(len(codes))]
    marks = {c: (4 * math.cos(a), 4 * math.sin(a)) for c, a in zip(codes, ring)}
    meta = {}
    for c, (lx, ly) in marks.items():
        meta["lx" + c], meta["ly" + c] = lx, ly
    out.mkdir()
    (out / "dataset.json").write_text(json.dumps({"model": "systems/mrclam.sys"}))
    dt, v, om = 0.02, 0.2, 0.3
    for w in range(6):
        d = out / f"w{w}"
        d.mkdir()
        (d / "meta.json").write_text(json.dumps(meta))
        x, y, th = rng.random() - 0.5, rng.random() - 0.5, 2 * math.pi * rng.random()
        ins, obs = ["t,v,omega"], ["t," + ",".join(outs)]
        for k in range(3000):
            t = k * dt
            if k > 0 and k % 10 == 0:
                c = codes[int(rng.random() * len(codes))]
                lx, ly = marks[c]
                r = range_of(math.hypot(lx - x, ly - y)) + SIGMA_RANGE * rng.gauss(0, 1)
                b = math.atan2(ly - y, lx - x) - th + 0.02 * rng.gauss(0, 1)
                row = {"r" + c: r, "b" + c: math.atan2(math.sin(b), math.cos(b))}
                obs.append(f"{t:.2f}," + ",".join(repr(row[o]) if o in row else "" for o in outs))
            ins.append(f"{t:.2f},{v!r},{om!r}")
            th1 = th + om * dt
            x += v / om * (math.sin(th1) - math.sin(th))
            y -= v / om * (math.cos(th1) - math.cos(th))
            th = th1
        (d / "inputs.csv").write_text("\n".join(ins) + "\n")
        (d / "outputs.csv").write_text("\n".join(obs) + "\n")
    return out


def test_a_range_bias_growing_with_range_squared_makes_the_named_range_effects_stand_ins(tmp_path):
    # r + 0.04 r^2 on the 2-6 m ranges of the circles: the file's range scale and bias
    # absorb its linear part and leave about (2/3) 0.04 h^2 = 0.08 m of curvature at the
    # span's ends (h ~ 2 m, the span's half-width), some 16-25 sds (tests/cli/diagnose.rs
    # derives the expected z from the simulated ranges); a clean fit exceeds z 3.5 with
    # probability below 7e-4.
    data = _unicycle_circles(tmp_path / "sq", 1, lambda r: r + 0.04 * r * r)
    d = obsan.diagnose(SYSTEMS / "mrclam.sys", data, effects=SYSTEMS / "mrclam.eff", generated=False)
    ranges = [n for n in d.named if n.effect.startswith("range_")]
    assert ranges, d.named
    for n, raw in zip(d.named, d["named"]):
        assert n.stand_in == raw["stand_in"]
        if raw["curvature"] is None:
            assert n.curvature is None
            continue
        c = n.curvature
        assert c is not None
        assert c.z == raw["curvature"]["z"] and c.outputs == raw["curvature"]["outputs"]
        assert c.span == tuple(raw["curvature"]["span"])
    for n in ranges:
        c = n.curvature
        assert n.stand_in and c is not None and c.z > 3.5, n
        assert len(c.outputs) == 15 and all(o.startswith("r") for o in c.outputs)
        assert 0.04 < c.coefficient < 0.15, c


def test_a_true_bearing_scale_is_not_a_stand_in(tmp_path):
    # The form is right: the curvature z is at most Student's t, |z| > 3.5 with
    # probability below 7e-4.
    data = obsan.simulate(tmp_path / "eff", bearings=60, seed=2, effect={"bearing_scale": 0.05})
    d = obsan.diagnose(SYSTEMS / "calib.sys", data, effects=SYSTEMS / "calib.eff")
    named = {n.effect: n for n in d.named}
    assert "bearing_scale" in named
    n = named["bearing_scale"]
    assert not n.stand_in and n.curvature is not None
    assert n.curvature.outputs == ["beta"] and abs(n.curvature.z) < 3.5
    # Suggested candidates carry no curvature test.
    assert all(not s.stand_in and s.curvature is None for s in d.suggested)
