#!/usr/bin/env python3
"""Independent verdicts for systems/benchmarks/strike-goldd/ (issue 32): SymPy, not obsan.

For each .sys file given, reads the states, params, inputs, equations and outputs (the plain
subset the importers write), and computes the observability-identifiability rank with the
inputs free: the span of the gradients (in states and params) of the outputs' Lie derivatives
along every word of the fields f0, f_1..f_m (the input-affine form, f_i = d rhs / d u_i),
level by level until a level adds no rank (then no later level does). The Jacobian is
evaluated exactly at a random integer point (entries 2..1000): a rank below the generic one
happens only on a proper algebraic subset, i.e. with small probability; a variable is
observable when its unit vector lies in the row span. Prints one '# verdict:' line per file.

Usage: python3 benches/peers/sg_verdicts.py systems/benchmarks/strike-goldd/*.sys
"""

import random
import re
import sys

import sympy as sp


def read_sys(path):
    decl = {"state": [], "param": [], "input": [], "const": []}
    eqs, outs = {}, []
    for raw in open(path, encoding="utf-8"):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.match(r"^(state|param|input|const)\s+(.*)$", line)
        if m:
            decl[m.group(1)] += [n.strip() for n in m.group(2).split(",")]
            continue
        m = re.match(r"^output\s+(\w+)\s*=\s*(.*)$", line)
        if m:
            outs.append(m.group(2))
            continue
        m = re.match(r"^(\w+)'\s*=\s*(.*)$", line)
        if m:
            eqs[m.group(1)] = m.group(2)
    names = {n: sp.Symbol(n) for k in decl for n in decl[k]}
    parse = lambda s: sp.sympify(s.replace("^", "**"), locals=names)
    x = [names[n] for n in decl["state"]]
    p = [names[n] for n in decl["param"]]
    u = [names[n] for n in decl["input"]]
    rhs = [parse(eqs[n]) for n in decl["state"]]
    h = [parse(o) for o in outs]
    return decl, x, p, u, rhs, h, [names[n] for n in decl["const"]]


def verdict(path, seed=1):
    decl, x, p, u, rhs, h, consts = read_sys(path)
    z = x + p
    f0 = [r.subs({ui: 0 for ui in u}) for r in rhs]
    fields = [f0] + [[sp.diff(r, ui) for r in rhs] for ui in u]
    rng = random.Random(seed)
    point = {s: sp.Integer(rng.randint(2, 1000)) for s in z + consts}
    level = list(h)
    rows = [[sp.diff(g, v).subs(point) for v in z] for g in level]
    rank = sp.Matrix(rows).rank()
    for _ in range(len(z)):
        nxt = []
        for g in level:
            for fld in fields:
                nxt.append(sp.expand(sum(sp.diff(g, xi) * fi for xi, fi in zip(x, fld))))
        level = nxt
        rows += [[sp.diff(g, v).subs(point) for v in z] for g in level]
        r = sp.Matrix(rows).rank()
        if r == rank or r == len(z):
            rank = r
            break
        rank = r
    m = sp.Matrix(rows)
    unobs = []
    for j, v in enumerate(z):
        e = [0] * len(z)
        e[j] = 1
        if m.col_join(sp.Matrix([e])).rank() > rank:
            unobs.append(str(v))
    if unobs:
        return f"unobservable {' '.join(unobs)}; rank {rank}"
    return f"observable; rank {rank}"


if __name__ == "__main__":
    for path in sys.argv[1:]:
        print(f"{path}\t# verdict: {verdict(path)}", flush=True)
