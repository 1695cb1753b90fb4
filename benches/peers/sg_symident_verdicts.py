#!/usr/bin/env python3
"""Verdicts from symident for the systems/benchmarks/strike-goldd/ models SymPy gave none for.

Usage, from the repository root, with symident installed (PyPI; never a runtime dependency):

    /tmp/venv-sym/bin/python benches/peers/sg_symident_verdicts.py [--apply] [--timeout S]

For every model whose verdicts.list line says `none: ...` (benches/peers/sg_verdicts.py, SymPy,
did not finish), symident's `detect()` runs on its .sys (translated mechanically by
symident_suite.py, in a child process, known inputs as the SymPy verdicts take them): its rank
is the rank of the output derivatives' Jacobian modulo a prime at random points, and a variable
is unobservable when it lies in the support of one of its symmetry directions. A result symident
marks `lower bound` gives no verdict. Prints `NAME<TAB>symident: SPEC` lines; with --apply they
replace the `none:` lines of verdicts.list, and scripts/import_strike_goldd.py then writes
`verdict-source: independent (symident ...)` into each file. obsan's output is never read.

A model whose outputs read known inputs (bachmann_jakstat) runs augmented (augment() below): each
such input `v` becomes a state with `v' = v_dot` (a new known input) and an extra output `v`, as
sg_verdicts.py takes them (the input measured, its derivative known); the verdict is over the
original variables: symident's rank minus one per such input, the inputs out of the list.
"""

import importlib.metadata
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DIR = os.path.join(ROOT, "systems", "benchmarks", "strike-goldd")
LIST = os.path.join(DIR, "verdicts.list")


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sijl_symident_verdicts import detect, spec  # noqa: E402 (the same translation and spec)


def augment(path):
    """The .sys text with every known input an output reads made a measured state, and the
    names of those inputs (empty: the file as it is)."""
    text = open(path, encoding="utf-8").read()
    lines = text.split("\n")
    inputs = []
    for line in lines:
        m = re.match(r"^input\s+(.*)$", line.split("#", 1)[0].strip())
        if m:
            inputs += [n.strip() for n in m.group(1).split(",")]
    outs = [l.split("=", 1)[1] for l in lines if re.match(r"^output\s", l)]
    read = [u for u in inputs if any(re.search(rf"\b{re.escape(u)}\b", o) for o in outs)]
    if not read:
        return path, []
    out, first_output = [], True
    for line in lines:
        if re.match(r"^input\s", line):
            kept = [u if u not in read else f"{u}_dot" for u in inputs]
            line = "input " + ", ".join(kept)
        elif re.match(r"^state\s", line):
            line = line + ", " + ", ".join(read)
        elif re.match(r"^output\s", line) and first_output:
            first_output = False
            out += [f"{u}' = {u}_dot" for u in read] + [f"output m_{u} = {u}" for u in read]
        out.append(line)
    fd, tmp = tempfile.mkstemp(suffix=".sys", dir=os.path.join(ROOT, "target"))
    with os.fdopen(fd, "w") as f:
        f.write("\n".join(out))
    return tmp, read


def main():
    args = sys.argv[1:]
    apply = "--apply" in args
    timeout = int(args[args.index("--timeout") + 1]) if "--timeout" in args else 300
    version = importlib.metadata.version("symident")
    lines = open(LIST, encoding="utf-8").read().split("\n")
    new = {}
    for line in lines:
        if not line or line.startswith("#"):
            continue
        name, sp = line.split("\t", 1)
        if not sp.startswith("none: "):
            continue
        path, read = augment(os.path.join(DIR, name + ".sys"))
        rel = os.path.relpath(path, ROOT)
        try:
            res = detect(rel, timeout)
        except subprocess.TimeoutExpired:
            print(f"# {name}: no answer within {timeout} s", file=sys.stderr)
            continue
        finally:
            if read:
                os.remove(path)
        if "error" in res:
            print(f"# {name}: {res['error']}", file=sys.stderr)
            continue
        if res.get("status") == "lower bound":
            print(f"# {name}: symident's rank is a lower bound: no verdict", file=sys.stderr)
            continue
        if read:
            res["rank"] -= len(read)
            res["unobservable"] = [v for v in res["unobservable"] if v not in read]
        new[name] = f"symident {version}: {spec(res)}"
        print(f"{name}\t{new[name]}", flush=True)
    if apply:
        out = []
        for line in lines:
            name = line.split("\t", 1)[0]
            out.append(f"{name}\t{new[name]}" if name in new and not line.startswith("#") else line)
        open(LIST, "w", encoding="utf-8").write("\n".join(out))


if __name__ == "__main__":
    main()
