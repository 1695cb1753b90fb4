#!/usr/bin/env python3
"""Wall time of `obsan global M.sys` (default route), best of three, for each
SI.jl benchmark named and each binary given (docs/performance.md, "Session 38").

    python3 scripts/time_global.py Goodwin,HIV,St OLD_BINARY NEW_BINARY

REPS=1 in the environment times each once (the long refusals).
"""
import os, subprocess, sys, time

models = sys.argv[1].split(",")
for m in models:
    row = [m]
    for b in sys.argv[2:]:
        best = float("inf")
        for _ in range(int(os.environ.get("REPS", "3"))):
            t0 = time.time()
            subprocess.run([b, "global", f"systems/benchmarks/si-jl/{m}.sys", "--timeout", "60"],
                           capture_output=True)
            best = min(best, time.time() - t0)
        row.append(f"{best:.2f}")
    print(" | ".join(row), flush=True)
