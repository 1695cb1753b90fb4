#!/usr/bin/env python3
"""Checks `obsan global`'s two routes against each other (issue 36): on every
model of systems/benchmarks/si-jl (or the files given), runs `--route taylor`
and `--route io` with `--timeout T` (default 10 s) and compares the
parameters' verdicts and counts wherever both answer. Prints one line per
model and exits 1 on a disagreement.

    python3 scripts/global_routes.py [--obsan target/release/obsan] [--timeout 10] [FILES...]

With `--auto-against OTHER` it instead runs `--route auto` with both binaries
and compares every variable's verdict (parameters and states): exit 1 when
`--obsan` loses an answer (or a variable's verdict) OTHER gives or differs from
it (session 32: the early Taylor attempt must lose nothing against main's
binary); verdicts `--obsan` adds (session 36: the initial states after the io
route) are reported as `same, more`.
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


def auto_against(a, files):
    lost = diff = 0
    for f in files:
        got = []
        for b in (a.auto_against, a.obsan):
            t0 = time.time()
            p = subprocess.run([b, "global", f, "--json", "--timeout", str(a.timeout)],
                               capture_output=True, text=True, timeout=a.timeout * 3 + 30)
            v = json.loads(p.stdout) if p.returncode == 0 else None
            got.append((v, time.time() - t0))
        (o, to), (n, tn) = got
        verdicts = lambda v: {x["name"]: (x["verdict"], x["values"]) for x in v["variables"]}
        if o is None:
            st = "both fail" if n is None else "new answer (" + n["route"] + ")"
        elif n is None:
            st, lost = "LOST", lost + 1
        elif any(verdicts(o)[k] != verdicts(n).get(k, verdicts(o)[k]) for k in verdicts(o)):
            st, diff = "DIFFERENT", diff + 1
        elif not set(verdicts(o)) <= set(verdicts(n)):
            st, lost = "LOST (variables)", lost + 1
        elif set(verdicts(n)) != set(verdicts(o)):
            # Session 36: auto counts the initial states after the io route.
            st = "same, more (" + n["route"] + ")"
        else:
            st = "same (" + n["route"] + ")"
        print(f"{f.split('/')[-1]:28} {st:28} other {to:6.2f} s  this {tn:6.2f} s")
        sys.stdout.flush()
    print(f"auto: {lost} lost, {diff} different")
    sys.exit(1 if lost or diff else 0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--obsan", default="target/release/obsan")
    ap.add_argument("--timeout", type=float, default=10)
    ap.add_argument("--auto-against", metavar="OTHER")
    ap.add_argument("files", nargs="*")
    a = ap.parse_args()
    files = a.files or sorted(glob.glob("systems/benchmarks/si-jl/*.sys"))
    if a.auto_against:
        auto_against(a, files)
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
