"""The tutorial's calibration analysis from Python, and the paper's Figure 5.

    pip install './python[plot]'
    python examples/python/calibration.py [OUT_DIR]

Martinelli (IEEE T-RO 2011): eq. (16) is observable (rank 7), circular trajectories (17)
lose three directions (rank 4, three symmetries, Appendix B); the ideal case of Figure 5
(no noise, q = 0.8, the feature inside and outside the circle) shows the observation
function with its nodes and the function sigma(s_c) of Algorithm 1, minimal (zero) at the
node. matplotlib is optional: without it the analysis runs and the plot is skipped.
"""

import json
import math
import pathlib
import sys
import tempfile
from typing import Any, Dict, List, Tuple

import obsan

ROOT = pathlib.Path(__file__).resolve().parents[2]
CALIB = ROOT / "systems" / "calib.sys"


def analysis() -> None:
    s = obsan.load(CALIB)
    r = s.rank()
    print(f"{s.name}: rank {r.rank} of {r.n} (exact: {r.exact})")
    r = s.rank(input="q")
    print(f"on circles (eq. 17): rank {r.rank} of {r.n}, error bound {r.error_bound or 0:.1e}")
    sym = s.symmetries(input="q")
    print(f"{len(sym.vectors)} symmetries, certified {sym.certificate}")
    for i, w in enumerate(sym.vectors, 1):
        print(f"  w{i} = [" + ", ".join(w.get(x, "0") for x in r.variables) + "]")


def path_xy(dataset: pathlib.Path, name: str, truth: Dict[str, Any]) -> Tuple[List[float], List[float]]:
    """The robot's path from the wheel speeds and the true odometry (for panels a, b)."""
    t = next(t for t in truth["trajectories"] if t["name"] == name)
    rows = (dataset / name / "inputs.csv").read_text().split("\n")
    head = rows[0].split(",")
    cols = [dict(zip(head, map(float, r.split(",")))) for r in rows[1:] if r.strip()]
    x, y, th = float(t["x0"]), float(t["y0"]), float(t["theta0"])
    xs, ys = [x], [y]
    for a, b in zip(cols, cols[1:]):
        dt = b["t"] - a["t"]
        v = (truth["r_right"] * a["wR"] + truth["r_left"] * a["wL"]) / 2
        w = (truth["r_right"] * a["wR"] - truth["r_left"] * a["wL"]) / truth["wheel_base"]
        # Exact for constant speeds over the step (a circular arc).
        if abs(w) > 1e-12:
            x += v / w * (math.sin(th + w * dt) - math.sin(th))
            y -= v / w * (math.cos(th + w * dt) - math.cos(th))
        else:
            x += v * dt * math.cos(th)
            y += v * dt * math.sin(th)
        th += w * dt
        xs.append(x)
        ys.append(y)
    return xs, ys


def figure5(out: pathlib.Path) -> None:
    cases: List[Tuple[str, pathlib.Path, Dict[str, Any], Dict[str, Any]]] = []
    for label, d0 in (("inside", 1.2), ("outside", 5.0)):
        data = pathlib.Path(
            obsan.simulate(out / f"ideal_{label}", q=[0.8, 0, -1], sigma_beta_deg=0, k=0, d0=d0, force=True)
        )
        figs = out / f"figures_{label}"
        c = obsan.calibrate(data, method="ls", plot=figs, force=True)
        p = c.params
        print(f"feature {label} (d0 = {d0} m): eta = {p['eta'].value:.6f}, "
              f"delta = {p['delta'].value:.6f}, xi = {p['xi'].value:.6f}")
        curves = json.loads((figs / "curves.json").read_text())
        truth = json.loads((data / "truth.json").read_text())
        cases.append((label, data, truth, next(k for k in curves if k["q"] == 0.8)))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: Figure 5 is not drawn (pip install matplotlib)")
        return
    fig, ax = plt.subplots(3, 2, figsize=(10, 12))
    for j, (label, data, truth, k) in enumerate(cases):
        xs, ys = path_xy(data, k["name"], truth)
        a = ax[0][j]
        a.plot(xs, ys, "b-", lw=1, label="robot")
        a.plot([0], [0], "r*", ms=12, label="feature")
        a.set_aspect("equal")
        a.set(title=f"({'ab'[j]}) trajectory, feature {label}", xlabel="x (m)", ylabel="y (m)")
        a.legend()
        a = ax[1][j]
        a.plot(k["s"], k["observed"], "b.", ms=3, label="observed")
        if k["nodes"]:
            ns, nb = zip(*k["nodes"])
            a.plot(ns, nb, "r*", ms=12, label="nodes")
        a.set(title=f"({'cd'[j]}) observation function", xlabel="s (rad)", ylabel="beta (rad)")
        a.legend()
        a = ax[2][j]
        sc, sig = zip(*k["sigma_curve"])
        a.plot(sc, sig, "k-", lw=1)
        a.axvline(k["node"], color="r", ls=":", label=f"node s_c = {k['node']:.3f} rad")
        a.set(title=f"({'ef'[j]}) sigma(s_c)", xlabel="s_c (rad)", ylabel="sigma (rad)")
        a.legend()
    fig.suptitle("Figure 5: node detection, ideal case (no noise), q = 0.8")
    fig.tight_layout()
    fig.savefig(out / "fig5.png", dpi=100)
    print(f"wrote {out / 'fig5.png'}")


if __name__ == "__main__":
    analysis()
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(tempfile.mkdtemp())
    out.mkdir(parents=True, exist_ok=True)
    figure5(out)
