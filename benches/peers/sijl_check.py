#!/usr/bin/env python3
"""Check systems/benchmarks/si-jl/*.sys against SI.jl's benchmarking/benchmarks.jl with a second,
independent reader: each `:KEY => Dict(... @ODEmodel(...))` block is cut out by bracket matching,
`x(t)` -> `x`, `//` -> `/`, `^` -> `**`, and SymPy compares every right-hand side with the .sys
one (cancel of the difference; bare names renamed `_p` by the importer are mapped back first,
and `set_parameter_values` / `linear_compartment_model` models are skipped: they have no
@ODEmodel text of their own to compare).

Usage: python3 benches/peers/sijl_check.py PATH/TO/benchmarks.jl
"""

import glob
import os
import re
import sys

import sympy

NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def blocks(text):
    out = {}
    for m in re.finditer(r":(\w+)\s*=>\s*Dict\(", text):
        key = m.group(1)
        i = text.find("@ODEmodel(", m.end())
        nxt = re.compile(r":\w+\s*=>\s*Dict\(").search(text, m.end())
        if i < 0 or (nxt and nxt.start() < i):
            continue
        j, depth = i + len("@ODEmodel"), 0
        while j < len(text):
            depth += text[j] == "("
            depth -= text[j] == ")"
            if depth == 0:
                break
            j += 1
        out[key] = text[i + len("@ODEmodel("): j]
    return out


def split_top(s):
    out, depth, cur = [], 0, ""
    for c in s:
        depth += c in "(["
        depth -= c in ")]"
        if c == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += c
    out.append(cur)
    return [x.strip() for x in out if x.strip()]


def sym(text, table):
    text = re.sub(r"#[^\n]*", "", text)
    text = re.sub(r"\b([A-Za-z_]\w*)\(t\)", r"\1", text).replace("//", "/").replace("^", "**")
    text = re.sub(r"(\d)([A-Za-z_(])", r"\1*\2", text)

    def sub(m):
        n = m.group(0)
        if n in ("exp", "log", "sin", "cos", "tan", "atan", "sqrt"):
            return n
        table.setdefault(n, sympy.Symbol(f"v{len(table)}"))
        return str(table[n])
    return sympy.sympify(NAME.sub(sub, text), locals={str(s): s for s in table.values()})


def main():
    src = open(sys.argv[1]).read()
    jl = blocks(src)
    bad = 0
    checked = 0
    for p in sorted(glob.glob("systems/benchmarks/si-jl/*.sys")):
        key = os.path.basename(p)[:-4]
        text = open(p).read()
        if key not in jl or "parameter values set" in text:
            print(f"{key}: skipped (no @ODEmodel text of its own)")
            continue
        ren = {}
        m = re.search(r"^# renamed.*?: (.*)$", text, re.M)
        if m:
            for pair in m.group(1).split(", "):
                a, b = pair.split(" -> ")
                ren[b] = a.replace(" (bare)", "")
        eqs = {}
        for line in text.splitlines():
            if line.startswith("#"):
                continue
            if line.startswith("output "):
                lhs, _, rhs = line[7:].partition(" = ")
                eqs["y:" + lhs] = rhs
            elif "' = " in line:
                lhs, _, rhs = line.partition("' = ")
                eqs["x:" + lhs] = rhs
        table = {}
        src_eqs = {}
        for eq in split_top(re.sub(r"#[^\n]*", "", jl[key])):
            lhs, _, rhs = eq.partition("=")
            lhs = lhs.strip()
            k = ("x:" + lhs.split("'")[0]) if "'" in lhs else ("y:" + lhs.split("(")[0])
            src_eqs[k] = rhs
        # The bare twin of a timed name (q vs q(t)) is a separate symbol on both sides.
        fix = lambda s: NAME.sub(lambda m: ren.get(m.group(0), m.group(0)) if m.group(0).endswith("_") else m.group(0), s)
        if set(src_eqs) != {k if k[2:] not in ren else k[:2] + ren[k[2:]] for k in eqs}:
            print(f"{key}: DIFFERENT equation sets")
            bad += 1
            continue
        for k, rhs in eqs.items():
            twin = {b: a for b, a in ren.items() if b.endswith("_p")}
            r = NAME.sub(lambda m: "TWIN_" + twin[m.group(0)] if m.group(0) in twin else m.group(0), rhs)
            r = fix(r)
            s = src_eqs[k]
            for a in twin.values():
                s = re.sub(r"\b" + a + r"\b(?!\s*\(t\))", "TWIN_" + a, s)
            if sympy.cancel(sym(s, table) - sym(r, table)) != 0:
                print(f"{key}: {k} DIFFERS")
                bad += 1
        checked += 1
    print(f"{checked} models compared, {bad} differences")


main()
