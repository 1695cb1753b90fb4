#!/usr/bin/env python3
"""Regenerate systems/benchmarks/si-jl/ from StructuralIdentifiability.jl (SciML, MIT licence).

Usage, from the repository root after `cargo build --release`:

    python3 scripts/import_si_jl.py SIJL_CHECKOUT [COMMIT]

SIJL_CHECKOUT is a clone of https://github.com/SciML/StructuralIdentifiability.jl (a work tree, or
a bare git directory: then benchmarking/benchmarks.jl is read with `git show HEAD:`). Every
model of benchmarking/benchmarks.jl is converted by `obsan import si-jl --all` (a model outside
obsan's class is refused and reported, as p53 is); then each file gets its source and licence
line and the verdict of systems/benchmarks/si-jl/verdicts.list (made by
benches/peers/sijl_verdicts.py from SI.jl's published identifiable functions), else that of
verdicts_symident.list (made by benches/peers/sijl_symident_verdicts.py from symident, an
independent tool), or `verdict-source: none`.
"""

import glob
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "systems/benchmarks/si-jl")
OBSAN = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release/obsan")


def main():
    src = sys.argv[1]
    if os.path.isfile(os.path.join(src, "benchmarking/benchmarks.jl")):
        text = open(os.path.join(src, "benchmarking/benchmarks.jl")).read()
    else:
        text = subprocess.run(["git", "-C", src, "show", "HEAD:benchmarking/benchmarks.jl"],
                              capture_output=True, text=True, check=True).stdout
    commit = sys.argv[2] if len(sys.argv) > 2 else subprocess.run(
        ["git", "-C", src, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    verdicts = {}
    for line in open(os.path.join(OUT, "verdicts.list")):
        if line.strip() and not line.startswith("#"):
            key, spec, source = [x.strip() for x in line.split("|")]
            verdicts[key] = (spec, source)
    # symident's verdicts, for the models SI.jl publishes none for (their source line is whole).
    by_symident = {}
    sym_list = os.path.join(OUT, "verdicts_symident.list")
    if os.path.exists(sym_list):
        for line in open(sym_list):
            if line.strip() and not line.startswith("#"):
                key, spec, source = [x.strip() for x in line.split("|")]
                by_symident[key] = (spec, source)
    for old in glob.glob(os.path.join(OUT, "*.sys")):
        os.remove(old)
    with tempfile.TemporaryDirectory() as tmp:
        os.makedirs(os.path.join(tmp, "benchmarking"))
        open(os.path.join(tmp, "benchmarking/benchmarks.jl"), "w").write(text)
        r = subprocess.run([OBSAN, "import", "si-jl", "benchmarking/benchmarks.jl", "--all", OUT],
                           cwd=tmp, capture_output=True, text=True)
        sys.stdout.write(r.stdout)
        sys.stderr.write(r.stderr)
    for path in sorted(glob.glob(os.path.join(OUT, "*.sys"))):
        key = os.path.basename(path)[:-4]
        lines = open(path).read().split("\n")
        at = next(i for i, l in enumerate(lines) if not l.startswith("#"))
        add = [f"# Source: SciML/StructuralIdentifiability.jl (MIT licence), benchmarking/benchmarks.jl "
               f"at {commit[:12]}, model :{key}."]
        if key in verdicts:
            spec, source = verdicts[key]
            add.append(f"# verdict-source: independent ({source}: SI.jl's identifiable functions with "
                       "states; rank and per-variable verdict by benches/peers/sijl_verdicts.py)")
            add.append(f"# verdict: {spec}")
        elif key in by_symident:
            spec, source = by_symident[key]
            add.append(f"# verdict-source: independent ({source})")
            add.append(f"# verdict: {spec}")
        else:
            add.append("# verdict-source: none (SI.jl publishes no identifiable functions for this "
                       "version of the model)")
        lines[at:at] = add
        open(path, "w").write("\n".join(lines))


main()
