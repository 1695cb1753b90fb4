#!/usr/bin/env python3
"""Independent local verdicts for systems/benchmarks/si-jl/ from StructuralIdentifiability.jl's
own published identifiable functions (benchmarking/IdentifiableFunctions/results/NAME/
"result_(normalforms, 2)_with_states": the field of all identifiable functions of states and
parameters, as SI.jl computed it).

Usage: python3 benches/peers/sijl_verdicts.py SIJL_GIT_DIR [OBSAN] > systems/benchmarks/si-jl/verdicts.list

For each results folder whose model matches one of ours:
1. the folder's own NAME.jl is imported with `obsan import si-jl` and compared with our .sys of
   the same name: same states, parameters, inputs and outputs, and every right-hand side equal as
   a rational function (SymPy `cancel` of the difference), so the verdict is for this model;
2. the Jacobian of SI.jl's identifiable functions with respect to the states and parameters is
   evaluated at a random rational point (exact arithmetic): its rank is the transcendence degree
   of the identifiable field, i.e. the rank of the observability codistribution, and a variable
   is locally identifiable iff adding d(variable) leaves the rank unchanged. A random point can
   only lower a rank (probability below 1e-20 here), never raise it.
The expectation is SI.jl's field plus linear algebra, never obsan's rank.
"""

import random
import re
import subprocess
import sys

import sympy

GIT = sys.argv[1]
OBSAN = sys.argv[2] if len(sys.argv) > 2 else "target/release/obsan"
RES = "benchmarking/IdentifiableFunctions/results"
NAME = re.compile(r"[A-Za-z_][A-Za-z_0-9]*")


def git_show(path):
    return subprocess.run(["git", "-C", GIT, "show", f"HEAD:{path}"], capture_output=True, text=True,
                          check=True).stdout


def sys_model(text):
    """(states, params, inputs, {lhs: rhs text}) of a .sys text as printed by the importer."""
    states, params, inputs, eqs = [], [], [], {}
    for line in text.splitlines():
        if line.startswith("#") or not line.strip():
            continue
        head, _, rest = line.partition(" ")
        if head == "state":
            states = [s.strip() for s in rest.split(",")]
        elif head == "param":
            params = [s.strip() for s in rest.split(",")]
        elif head == "input":
            inputs = [s.strip() for s in rest.split(",")]
        elif head == "output":
            lhs, _, rhs = rest.partition("=")
            eqs["out:" + lhs.strip()] = rhs.strip()
        elif "' = " in line:
            lhs, _, rhs = line.partition("' = ")
            eqs[lhs.strip()] = rhs.strip()
    return states, params, inputs, eqs


class Names:
    """Every identifier becomes a plain SymPy symbol (no clash with I, E, S, N, beta, lambda)."""

    def __init__(self):
        self.sym = {}

    def expr(self, text):
        def sub(m):
            n = m.group(0)
            if n in ("exp", "log", "sin", "cos", "tan", "atan", "sqrt"):
                return n
            self.sym.setdefault(n, sympy.Symbol(f"v{len(self.sym)}"))
            return str(self.sym[n])
        t = NAME.sub(sub, text.replace("//", "/").replace("^", "**"))
        return sympy.sympify(t, locals={str(s): s for s in self.sym.values()})


def same_model(a, b):
    sa, pa, ua, ea = a
    sb, pb, ub, eb = b
    if sorted(sa) != sorted(sb) or sorted(pa) != sorted(pb) or sorted(ua) != sorted(ub):
        return "different variables"
    if sorted(ea) != sorted(eb):
        return "different equations/outputs"
    nm = Names()
    for k in ea:
        if sympy.cancel(nm.expr(ea[k]) - nm.expr(eb[k])) != 0:
            return f"{k} differs"
    return None


def split_top(s):
    out, depth, cur = [], 0, ""
    for c in s:
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        if c == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += c
    if cur.strip():
        out.append(cur)
    return [x.strip() for x in out]


def verdict(model, result_text):
    states, params, _, _ = model
    body = result_text.strip()
    body = body[body.index("[") + 1: body.rindex("]")]
    nm = Names()
    funcs = [nm.expr(f) for f in split_top(body)]
    variables = states + params
    syms = [nm.sym.setdefault(v, sympy.Symbol(f"v{len(nm.sym)}")) for v in variables]
    extra = [s for s in nm.sym if s not in variables]
    if extra:
        raise ValueError(f"identifiable functions use {extra}, not variables of the model")
    rnd = random.Random(20261204)
    point = {s: sympy.Rational(rnd.randint(1, 10**9), rnd.randint(1, 10**9)) for s in syms}
    jac = sympy.Matrix([[sympy.diff(f, s).subs(point) for s in syms] for f in funcs])
    r = jac.rank()
    unobs = []
    for k, v in enumerate(variables):
        row = sympy.zeros(1, len(syms))
        row[k] = 1
        if jac.col_join(row).rank() > r:
            unobs.append(v)
    n = len(variables)
    spec = "observable" if not unobs else "unobservable " + " ".join(unobs)
    assert (not unobs) == (r == n)
    return f"{spec}; rank {r}"


def main():
    names = subprocess.run(["git", "-C", GIT, "ls-tree", "--name-only", f"HEAD:{RES}"], capture_output=True,
                           text=True, check=True).stdout.split("\n")
    ours = {}
    import glob
    import os
    for p in sorted(glob.glob("systems/benchmarks/si-jl/*.sys")):
        text = open(p).read()
        m = re.search(r"^description (.*)$", text, re.M)
        if m:
            ours[m.group(1).strip()] = (os.path.basename(p)[:-4], text)
    print("# KEY | SPEC | source: generated by benches/peers/sijl_verdicts.py (see its docstring)")
    for name in names:
        if not name or name not in ours:
            continue
        key, text = ours[name]
        try:
            res = git_show(f"{RES}/{name}/result_(normalforms, 2)_with_states")
            jl = git_show(f"{RES}/{name}/{name}.jl")
        except subprocess.CalledProcessError:
            print(f"# {key}: no result file in {RES}/{name}", file=sys.stderr)
            continue
        open("/tmp/sijl_res.jl", "w").write(jl)
        imp = subprocess.run([OBSAN, "import", "si-jl", "/tmp/sijl_res.jl"], capture_output=True, text=True)
        if imp.returncode != 0:
            print(f"# {key}: results model does not import: {imp.stderr.strip()}", file=sys.stderr)
            continue
        diff = same_model(sys_model(imp.stdout), sys_model(text))
        if diff:
            print(f"# {key}: results model differs from benchmarks.jl's ({diff})", file=sys.stderr)
            continue
        try:
            spec = verdict(sys_model(text), res)
        except Exception as e:  # noqa: BLE001 - reported, the model is left without a verdict
            print(f"# {key}: {e}", file=sys.stderr)
            continue
        print(f"{key} | {spec} | SI.jl {RES}/{name}/result_(normalforms, 2)_with_states")
        sys.stdout.flush()


main()
