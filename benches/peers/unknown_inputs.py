#!/usr/bin/env python3
"""An independent oracle for `obsan rank` with unknown inputs (issue 33).

Usage, from the repository root after `cargo build --release`:

    python3 benches/peers/unknown_inputs.py [--order M] [--obsan PATH] [FILE ...]

(default: every systems/benchmarks/unknown-inputs/*.sys).

FISPO's extension (Villaverde et al.), computed in SymPy with nothing shared with obsan: the
time derivatives y^(m) of the outputs are built by the total derivative

    D = sum_k F_k d/dx_k + sum_{j,l} w_j^(l+1) d/dw_j^(l) + sum_{i,l} u_i^(l+1) d/du_i^(l),

plus d/dt where the model uses time `t` explicitly (a known coordinate, never a column),
F = f0 + sum f_i u_i + sum g_j w_j read from the .sys text, with the unknown inputs' and the
known inputs' derivatives as fresh symbols (no truncation: the order M decides which appear).
At order m the Jacobian of (y^(0), ..., y^(m)) with respect to (states, params,
w^(0), ..., w^(m)) is evaluated at one random rational point (known inputs' jets and constants
random too). A state is observable from order m when its unit vector lies in the row space;
an unknown input is reconstructable from order m when its unit vector (order 0) does. Ranks
are exact over Q where every entry is rational, and taken with mpmath at 60 digits (tolerance
1e-40) where a transcendental function leaves an irrational entry.

obsan is run as `obsan rank --json --order M` on the same file; the two verdicts (first order
per state and per unknown input) are compared, and the times (SymPy from the read to the
verdict, obsan the wall time of the process) printed in one Markdown table. Exit code 1 if any
verdict differs.
"""

import glob
import json
import keyword
import os
import random
import re
import subprocess
import sys
import time

import sympy as sp

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def statements(text):
    out, cur = [], ""
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].rstrip()
        if not line.strip() and not cur:
            continue
        cur = (cur + " " + line.strip()) if cur else line.strip()
        if cur.count("(") > cur.count(")") or re.search(r"[-+*/^,]$", cur):
            continue
        out.append(cur)
        cur = ""
    if cur:
        out.append(cur)
    return out


def read_sys(path):
    """States, params, consts, known inputs, unknown inputs, equations, outputs."""
    m = {"state": [], "param": [], "const": [], "input": [], "unknown": []}
    eqs, outs = {}, []
    for st in statements(open(path).read()):
        words = st.split(None, 1)
        kw = words[0]
        rest = words[1] if len(words) > 1 else ""
        if kw in ("state", "states", "param", "params", "const", "consts", "input", "inputs"):
            key = kw.rstrip("s")
            m[key] += [n.split("=")[0].strip() for n in rest.split(",")]
        elif kw == "unknown":
            m["unknown"] += [n.strip() for n in rest.split(None, 1)[1].split(",")]
        elif kw == "varying":
            m["unknown"] += [n.strip() for n in rest.split(",")]
        elif kw == "output":
            name, e = rest.split("=", 1)
            outs.append((name.strip(), e.strip()))
        elif "'" in kw or "'" in st.split("=")[0]:
            lhs, e = st.split("=", 1)
            eqs[lhs.strip().rstrip("'").strip()] = e.strip()
    return m, eqs, outs


def oracle(path, order):
    m, eqs, outs = read_sys(path)
    names = m["state"] + m["param"] + m["const"] + m["input"] + m["unknown"]
    # Fresh SymPy names (z0, z1, ...) so .sys names never meet SymPy built-ins.
    sym = {n: sp.Symbol(f"z{i}") for i, n in enumerate(names)}
    loc = dict(sym)
    loc.update({"atan2": sp.atan2, "atan": sp.atan, "sin": sp.sin, "cos": sp.cos,
                "tan": sp.tan, "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt, "pi": sp.pi})

    # Explicit time `t` (never declared): a known coordinate with t' = 1, so the total
    # derivative gains d/dt and t is no column of the Jacobian.
    time_t = sp.Symbol("time_t")
    loc["t"] = time_t

    # A .sys name that is a Python keyword (`lambda`) cannot reach sympify's
    # tokenizer: rename it to its fresh symbol's name in the text first.
    kw = {n for n in names if keyword.iskeyword(n)}

    def parse(e):
        for n in kw:
            e = re.sub(rf"\b{n}\b", sym[n].name, e)
        return sp.sympify(e.replace("^", "**"), locals=loc)

    states = [sym[n] for n in m["state"] + m["param"]]
    rhs = [parse(eqs[n]) for n in m["state"]] + [sp.Integer(0)] * len(m["param"])
    jet = lambda n, l: sym[n] if l == 0 else sp.Symbol(f"{sym[n].name}_d{l}")
    ws = m["unknown"]
    us = m["input"]

    def total(phi, lvl):
        d = sum(sp.diff(phi, x) * f for x, f in zip(states, rhs)) + sp.diff(phi, time_t)
        for nm in ws + us:
            for l in range(lvl + 1):
                d += sp.diff(phi, jet(nm, l)) * jet(nm, l + 1)
        return d

    rng = random.Random(7)
    point = {}
    for n in m["state"] + m["param"] + m["const"]:
        point[sym[n]] = sp.Rational(rng.randint(2, 97), rng.randint(2, 97))
    point[time_t] = sp.Rational(rng.randint(2, 97), rng.randint(2, 97))
    for nm in ws + us:
        for l in range(order + 3):
            point[jet(nm, l)] = sp.Rational(rng.randint(2, 97), rng.randint(2, 97))

    ys = [parse(e) for _, e in outs]
    cols = states + [jet(nm, l) for l in range(order + 2) for nm in ws]
    rows = []
    first_obs = [None] * len(states)
    first_rec = [None] * len(ws)
    lvl = 0  # highest jet order present
    for k in range(order + 1):
        if k > 0:
            ys = [total(y, lvl) for y in ys]
            lvl += 1
        for y in ys:
            rows.append([sp.diff(y, c).subs(point) for c in cols])
        r = rank(rows)
        for i in range(len(states)):
            if first_obs[i] is None and member(rows, r, i):
                first_obs[i] = k
        for j in range(len(ws)):
            if first_rec[j] is None and member(rows, r, len(states) + j):
                first_rec[j] = k
    return m["state"] + m["param"], ws, first_obs, first_rec


def numeric(rows):
    import mpmath
    mpmath.mp.dps = 60
    return mpmath.matrix([[mpmath.mpf(sp.N(v, 70)) for v in r] for r in rows])


def rank(rows):
    if all(v.is_Rational for r in rows for v in r):
        return sp.Matrix(rows).rank()
    import mpmath
    a = numeric(rows)
    s = mpmath.svd_r(a, compute_uv=False)
    top = max(abs(x) for x in s) if len(s) else 0
    return sum(1 for x in s if abs(x) > top * mpmath.mpf("1e-40"))


def member(rows, r, col):
    e = [sp.Integer(0)] * len(rows[0])
    e[col] = sp.Integer(1)
    return rank(rows + [e]) == r


def obsan_verdicts(exe, path, order):
    t = time.time()
    out = subprocess.run([exe, "rank", "--json", "--order", str(order), path],
                         capture_output=True, text=True, check=True).stdout
    dt = time.time() - t
    v = json.loads(out)
    obs = {o["name"]: o["order"] for o in v["observable_variables"]}
    rec = {o["name"]: o["order"] for o in v["reconstructable_inputs"]}
    return [obs.get(n) for n in v["state"]], [rec.get(n) for n in v["unknown_inputs"]], v, dt


def main():
    args = sys.argv[1:]
    order = 6
    exe = os.path.join(ROOT, "target", "release", "obsan")
    files = []
    while args:
        a = args.pop(0)
        if a == "--order":
            order = int(args.pop(0))
        elif a == "--obsan":
            exe = args.pop(0)
        else:
            files.append(a)
    if not files:
        files = sorted(glob.glob(os.path.join(ROOT, "systems/benchmarks/unknown-inputs/*.sys")))
    print(f"| model | order | observable (first order) | reconstructable | SymPy s | obsan s | agree |")
    print("|---|---|---|---|---|---|---|")
    bad = 0
    for f in files:
        t = time.time()
        names, ws, fo, fr = oracle(f, order)
        ts = time.time() - t
        oo, orr, v, to = obsan_verdicts(exe, f, order)
        ok = (fo == oo) and (fr == orr)
        bad += not ok
        fmt = lambda ns, fs: ", ".join(f"{n}:{x}" for n, x in zip(ns, fs) if x is not None) or "-"
        print(f"| {os.path.basename(f)} | {order} | {fmt(names, fo)} | {fmt(ws, fr)} | "
              f"{ts:.2f} | {to:.3f} | {'yes' if ok else 'NO: obsan ' + fmt(names, oo) + ' / ' + fmt(ws, orr)} |")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
