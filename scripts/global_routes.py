#!/usr/bin/env python3
"""Checks `obsan global`'s two routes against each other (issue 36): on every
model of systems/benchmarks/si-jl (or the files given), runs `--route taylor`
and `--route io` with `--timeout T` (default 10 s) and compares the
parameters' verdicts and counts wherever both answer. Prints one line per
model and exits 1 on a disagreement.

    python3 scripts/global_routes.py [--obsan target/release/obsan] [--timeout 10] [FILES...]
"""
import argparse, glob, json, subprocess, sys, time


def run(obsan, route, path, timeout):
    t0 = time.time()
    p = subprocess.run([obsan, "global", path, "--route", route, "--json", "--timeout", str(timeout)],
                       capture_output=True, text=True, timeout=timeout * 3 + 30)
    dt = time.time() - t0
    if p.returncode != 0:
        why = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
        return None, dt, why[:90]
    v = json.loads(p.stdout)
    params = {x["name"]: (x["verdict"], x["values"]) for x in v["variables"] if x["kind"] == "param"}
    return params, dt, ""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--obsan", default="target/release/obsan")
    ap.add_argument("--timeout", type=float, default=10)
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    files = a.files or sorted(glob.glob("systems/benchmarks/si-jl/*.sys"))
    bad = both = 0
    for f in files:
        t, tt, tw = run(a.obsan, "taylor", f, a.timeout)
        i, ti, iw = run(a.obsan, "io", f, a.timeout)
        name = f.split("/")[-1]
        if t is not None and i is not None:
            both += 1
            same = t == i
            bad += not same
            print(f"{name:28} both   taylor {tt:6.2f} s  io {ti:6.2f} s  {'agree' if same else 'DISAGREE ' + str(t) + ' vs ' + str(i)}")
        else:
            ts = f"{tt:6.2f} s" if t is not None else f"-- ({tw})"
            is_ = f"{ti:6.2f} s" if i is not None else f"-- ({iw})"
            print(f"{name:28} taylor {ts}  io {is_}")
        sys.stdout.flush()
    print(f"{both} answered by both routes, {bad} disagree")
    sys.exit(1 if bad else 0)


main()
