#!/usr/bin/env python3
"""Run the obsan benchmark suite in StrikePy (PyPI, the Python port of STRIKE-GOLDD's FISPO) and
obsan side by side, in the same run (issue 32's "one table").

Usage, from the repository root after `cargo build --release`, with StrikePy installed in a
separate environment (it is GPL-3: a peer for benchmarks only, never a dependency):

    python3 -m venv /tmp/venv-strikepy && /tmp/venv-strikepy/bin/pip install strikepy
    python3 benches/peers/strikepy_suite.py --python /tmp/venv-strikepy/bin/python \\
        [--timeout S] [--si-jl] [FILTER ...]

Each entry (the suite of symident_suite.py: systems/benchmarks/*.sys, systems/vins.sys,
paper.list; or with --si-jl systems/benchmarks/si-jl/) is translated by symident_suite.py's
reader (names renamed z0, z1, ... so that I, E, S cannot collide with SymPy's), then given to
StrikePy as a model module (states x, outputs h, known inputs u with `nnzDerU = inf`: generic
inputs, as obsan assumes; parameters p; consts stay free symbols, which StrikePy takes as known)
in a child interpreter per model, killed after --timeout seconds. StrikePy's own summary is
read: its unobservable states and unidentifiable parameters, or, where it stops before
classifying a parameter ("These parameters are identifiable" alone), the rest as no verdict.
Its time is the child's CPU time (the interpreter and SymPy import included; about 1 s), obsan's
the CPU time of one `obsan rank --json` process. Prints one Markdown table and a summary.
"""

import json
import os
import re
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import symident_suite as suite  # noqa: E402  (its reader, entries and judge; no symident import)

ROOT = suite.ROOT
CPU_FLOOR = 0.001


def child(path, restriction):
    """In StrikePy's interpreter: build the model and options modules, run, print a JSON line."""
    import contextlib
    import io
    import math
    import types

    import numpy
    import sympy

    m = suite.read_sys(os.path.join(ROOT, path))
    kw, back = suite.translate(m, restriction)
    sym = {}

    def s(name):
        return sym.setdefault(name, sympy.Symbol(name))

    def expr(text):
        names = set(re.findall(r"z\d+", text))
        return sympy.sympify(text, locals={n: s(n) for n in names})

    states = list(kw["odes"])
    model = types.ModuleType("StrikePy.models.obsan_model")
    # StrikePy takes a single state or parameter as a flat list (its own examples), several as
    # a column ([[x1], [x2]]).
    def column(v):
        return v if len(v) == 1 else [[e] for e in v]

    model.x = column([s(x) for x in states])
    model.f = column([expr(kw["odes"][x]) for x in states])
    model.h = [expr(e) for e in kw["observables"].values()]
    model.u = column([s(u) for u in kw["known_inputs"]])
    # Parameters always a column, none an empty one (it is stacked below the states).
    model.p = [[s(p)] for p in kw["parameters"]] or numpy.empty((0, 1), dtype=object)
    model.w = []
    opts = types.ModuleType("StrikePy.custom_options.options_obsan_model")
    opts.modelname = "obsan_model"
    opts.checkObser = 1
    opts.maxLietime = math.inf
    opts.nnzDerU = [math.inf] * max(1, len(model.u))
    opts.nnzDerW = [math.inf]
    opts.prev_ident_pars = []
    sys.modules[model.__name__] = model
    sys.modules[opts.__name__] = opts
    from StrikePy.strike_goldd import strike_goldd

    out = io.StringIO()
    c = time.process_time()
    with contextlib.redirect_stdout(out):
        strike_goldd("options_obsan_model")
    cpu = time.process_time() - c
    text = out.getvalue()

    def listed(header):
        mm = re.search(re.escape(header) + r"[^\n]*:\s*\n\s*(\[[^\n]*\])", text)
        return re.findall(r"z\d+", mm.group(1)) if mm else []

    ranks = [int(r) for r in re.findall(r"Rank = (\d+)", text)]
    fispo = "Fully Input-State-Parameter Observable" in text
    un_states = listed(">>> These states are unobservable")
    p_id = listed(">>> These parameters are identifiable")
    if fispo or "All its parameters are structurally identifiable" in text:
        p_un, p_open = [], []
    elif "structurally unidentifiable" in text:
        p_un, p_open = listed(">>> These parameters are unidentifiable"), []
    else:
        p_un, p_open = [], [p for p in kw["parameters"] if p not in p_id]
    print(json.dumps({
        "rank": ranks[-1] if ranks else None,
        "unobservable": sorted(back[z] for z in un_states + p_un),
        "open": sorted(back[z] for z in p_open),
        "cpu": cpu,
    }))


def main():
    args = sys.argv[1:]
    if args[:1] == ["--child"]:
        child(args[1], args[2] or None)
        return
    timeout, python, filt = 120.0, None, []
    obsan = os.path.join(ROOT, "target", "release", "obsan")
    entries = suite.entries
    i = 0
    while i < len(args):
        if args[i] == "--timeout":
            timeout, i = float(args[i + 1]), i + 2
        elif args[i] == "--python":
            python, i = args[i + 1], i + 2
        elif args[i] == "--si-jl":
            entries, i = suite.si_jl_entries, i + 1
        elif args[i] == "--obsan":
            obsan, i = args[i + 1], i + 2
        else:
            filt.append(args[i])
            i += 1
    if python is None:
        sys.exit("--python PATH: the interpreter StrikePy is installed in")
    version = subprocess.run([python, "-c", "import importlib.metadata as m; print(m.version('strikepy'))"],
                             capture_output=True, text=True).stdout.strip()
    print("| model | n | obsan rank | obsan verdict | obsan CPU s | StrikePy rank | StrikePy verdict "
          "| StrikePy CPU s | CPU ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    score = {"total": 0, "obsan": 0, "strikepy": 0, "answered": 0, "faster": 0}
    ratios = []
    for path, restriction, cited in entries():
        if filt and not any(f in path for f in filt):
            continue
        label = path + (f" --input {restriction}" if restriction else "")
        n, orank, overdict, _, ocpu, answered = suite.run_obsan(obsan, path, restriction, cited, timeout)
        judged = cited["rank"] is not None or cited["unobservable"] is not None
        ratio = "-"
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            q = subprocess.run([python, __file__, "--child", path, restriction or ""], cwd=ROOT,
                               capture_output=True, text=True, timeout=timeout)
            rv = resource.getrusage(resource.RUSAGE_CHILDREN)
            scpu = (rv.ru_utime - ru.ru_utime) + (rv.ru_stime - ru.ru_stime)
            line = q.stdout.strip().splitlines()[-1] if q.stdout.strip() else ""
            if q.returncode != 0 or not line.startswith("{"):
                lines = q.stderr.strip().splitlines() or ["no output"]
                err = next((ln for ln in lines if re.match(r"^\w+(Error|Exception):", ln)), lines[-1])
                srank, sverdict, ssecs = "-", "fails: " + err[:110].replace("|", "/"), "-"
            else:
                s = json.loads(line)
                srank = s["rank"] if s["rank"] is not None else "-"
                if s["open"]:
                    sverdict = f"no verdict on {', '.join(s['open'])}"
                elif judged:
                    sverdict = suite.judge(s["rank"], n if n != "-" else s["rank"], s["unobservable"], cited)
                else:
                    sverdict = "no cited verdict"
                ssecs = f"{scpu:.2f}"
                score["answered"] += 1
                if answered:
                    r = scpu / max(ocpu, CPU_FLOOR)
                    ratios.append(r)
                    ratio = f"{r:.0f}x"
                    score["faster"] += ocpu < scpu
        except subprocess.TimeoutExpired:
            srank, sverdict, ssecs = "-", f"no answer in {timeout:.0f} s", f">{timeout:.0f}"
            score["faster"] += answered
        score["total"] += 1
        score["obsan"] += overdict == "agrees"
        score["strikepy"] += sverdict == "agrees"
        print(f"| {label} | {n} | {orank} | {overdict} | {ocpu:.2f} | {srank} | {sverdict} | {ssecs} | {ratio} |",
              flush=True)
    print()
    if ratios:
        print(f"CPU ratio (StrikePy child CPU, interpreter start included / obsan process CPU) on the "
              f"{len(ratios)} models StrikePy answered: {suite.ratio_summary(ratios)}")
    print(f"{score['total']} entries; cited verdict matched: obsan {score['obsan']}, StrikePy "
          f"{score['strikepy']}; StrikePy answered {score['answered']}; obsan faster on {score['faster']}; "
          f"StrikePy {version}, timeout {timeout:.0f} s")


if __name__ == "__main__":
    main()
