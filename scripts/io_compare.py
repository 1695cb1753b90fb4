#!/usr/bin/env python3
"""Each SI.jl model under `obsan global --route ROUTE --json` with two binaries
(docs/performance.md, "Session 42"):

    python3 scripts/io_compare.py OLD NEW TIMEOUT [ROUTE [FILES...]]

prints per model `same` (both answered, the same verdicts, counts, maps and orders),
`DIFFERENT`, `LOST` (only OLD answered), `NEW` or `neither`, with both wall times.
"""
import json, subprocess, sys, time, glob, os
old, new, tmo = sys.argv[1], sys.argv[2], float(sys.argv[3])
route = sys.argv[4] if len(sys.argv) > 4 else "io"
files = sys.argv[5:] or sorted(glob.glob(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "systems", "benchmarks", "si-jl", "*.sys")))
KEEP = ("variables", "solutions", "solutions_at_most", "group_order", "maps", "maps_modulo_pi",
        "all_local", "route", "output_orders", "states_after_io", "multi_experiment")
def run(b, f):
    t0 = time.time()
    try:
        p = subprocess.run([b, "global", f, "--route", route, "--json"], capture_output=True, text=True, timeout=tmo)
    except subprocess.TimeoutExpired:
        return None, time.time() - t0
    dt = time.time() - t0
    if p.returncode != 0:
        return ("error", p.stderr.strip()[-100:]), dt
    d = json.loads(p.stdout)
    return {k: d.get(k) for k in KEEP}, dt
for f in files:
    name = os.path.basename(f)[:-4]
    a, ta = run(old, f)
    b, tb = run(new, f)
    ok = lambda r: r is not None and not (isinstance(r, tuple))
    if ok(a) and ok(b):
        tag = "same" if a == b else "DIFFERENT"
    elif ok(a):
        tag = "LOST"
    elif ok(b):
        tag = "NEW"
    else:
        tag = "neither"
    print(f"{name:22} {tag:10} {ta:7.2f} {tb:7.2f}", flush=True)
    if tag == "DIFFERENT":
        print("   old", json.dumps(a)[:300]); print("   new", json.dumps(b)[:300])
