#!/usr/bin/env python3
"""Regenerate systems/benchmarks/strike-goldd/*.sys from the model files in its src/ folder.

Each src/z_create_NAME.m was written for obsan from its model's equations (the reference is
in the file; no STRIKE-GOLDD text, which is GPL-3, is used). This runs
`obsan import strike-goldd` on each (from the folder, so the header names src/...), and puts
the source line and the verdict of verdicts.list (made by benches/peers/sg_verdicts.py, SymPy,
never obsan) at the top of NAME.sys.

A verdicts.list line `NAME<TAB>none: REASON` (SymPy did not finish) gives the header
`# verdict-source: none (REASON)` and no verdict line; `NAME<TAB>symident VERSION: SPEC`
(benches/peers/sg_symident_verdicts.py, for models SymPy did not finish) cites symident;
`NAME<TAB>mpmath DIGITS: SPEC` (sg_verdicts.py --digits, for radicals SymPy cannot rank exactly in
time) cites the floating-point evaluation; `NAME<TAB>taylor[ (NOTE)]: SPEC` cites
benches/peers/taylor_rank.py (models too large for symbolic Lie derivatives), NOTE saying how a
rank below n is bounded from above.

Usage: cargo build --release -p obsan && python3 scripts/import_strike_goldd.py
"""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIR = os.path.join(ROOT, "systems", "benchmarks", "strike-goldd")
OBSAN = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "obsan")


def main():
    verdicts = {}
    for line in open(os.path.join(DIR, "verdicts.list"), encoding="utf-8"):
        if line.strip() and not line.startswith("#"):
            name, spec = line.rstrip("\n").split("\t", 1)
            verdicts[name] = spec
    for m in sorted(os.listdir(os.path.join(DIR, "src"))):
        if not (m.startswith("z_create_") and m.endswith(".m")):
            continue
        name = m[len("z_create_"):-2]
        out = subprocess.run(
            [OBSAN, "import", "strike-goldd", f"src/{m}"], cwd=DIR, capture_output=True, text=True
        )
        if out.returncode != 0:
            sys.exit(out.stderr)
        if name not in verdicts:
            sys.exit(f"{name}: no line in verdicts.list")
        header = [f"# Source: src/{m}, written for obsan from the model's equations (reference in that file)."]
        if verdicts[name].startswith("none: "):
            # SymPy gave no verdict in time: the file says so and cites none (never obsan's).
            header.append(f"# verdict-source: none ({verdicts[name][len('none: '):]})")
        elif verdicts[name].startswith("symident "):
            # SymPy gave none; symident did (benches/peers/sg_symident_verdicts.py).
            who, spec = verdicts[name].split(": ", 1)
            header += [
                f"# verdict-source: independent ({who} detect(): rank of the output derivatives' Jacobian and the support of its kernel directions, benches/peers/sg_symident_verdicts.py)",
                f"# verdict: {spec}",
            ]
        elif verdicts[name].startswith("mpmath "):
            # SymPy's exact rank did not finish (radicals): its Lie derivatives in floating point.
            who, spec = verdicts[name].split(": ", 1)
            digits = who.split()[1]
            header += [
                f"# verdict-source: independent (SymPy's Lie derivatives, their Jacobian in mpmath at {digits} digits at a random integer point, benches/peers/sg_verdicts.py --digits {digits}; numerical, every kept singular value far above every dropped one)",
                f"# verdict: {spec}",
            ]
        elif verdicts[name].startswith("taylor"):
            # Too large for symbolic Lie derivatives: the Taylor-coefficient oracle
            # (benches/peers/taylor_rank.py); `taylor (NOTE): SPEC` adds how a rank below n is
            # bounded from above (the oracle's rank at a point is a lower bound only).
            who, spec = verdicts[name].rsplit(": ", 1)
            note = who[len("taylor"):].strip().strip("()")
            src = "benches/peers/taylor_rank.py: the Jacobian of the outputs' Taylor coefficients in (x(0), params), NumPy modulo 2^31 - 1 at a random point"
            if note:
                src += f"; {note}"
            else:
                src += ", full rank there: exact"
            header += [f"# verdict-source: independent ({src})", f"# verdict: {spec}"]
        else:
            header += [
                "# verdict-source: independent (SymPy: rank of the Lie-derivative Jacobian at a random integer point, benches/peers/sg_verdicts.py)",
                f"# verdict: {verdicts[name]}",
            ]
        with open(os.path.join(DIR, f"{name}.sys"), "w", encoding="utf-8") as f:
            f.write("\n".join(header) + "\n" + out.stdout)
        print(f"{name}.sys")


if __name__ == "__main__":
    main()
