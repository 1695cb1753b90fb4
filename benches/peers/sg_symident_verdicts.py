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
"""

import importlib.metadata
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DIR = os.path.join(ROOT, "systems", "benchmarks", "strike-goldd")
LIST = os.path.join(DIR, "verdicts.list")


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sijl_symident_verdicts import detect, spec  # noqa: E402 (the same translation and spec)


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
        rel = os.path.relpath(os.path.join(DIR, name + ".sys"), ROOT)
        try:
            res = detect(rel, timeout)
        except subprocess.TimeoutExpired:
            print(f"# {name}: no answer within {timeout} s", file=sys.stderr)
            continue
        if "error" in res:
            print(f"# {name}: {res['error']}", file=sys.stderr)
            continue
        if res.get("status") == "lower bound":
            print(f"# {name}: symident's rank is a lower bound: no verdict", file=sys.stderr)
            continue
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
