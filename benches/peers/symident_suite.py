#!/usr/bin/env python3
"""Run the obsan benchmark suite in symident (PyPI) and obsan side by side.

Usage, from the repository root after `cargo build --release`:

    python3 benches/peers/symident_suite.py [--timeout S] [--obsan PATH] [--si-jl] [--repeat K]
        [--inprocess FILE] [FILTER ...]

--si-jl runs the StructuralIdentifiability.jl models (systems/benchmarks/si-jl/) instead of the
suite; models without a cited verdict are compared by rank only. The last column is the CPU
ratio: symident's detect() CPU time over the obsan process's CPU time (user + system).
--repeat K runs each tool K times per model and keeps each one's least CPU time (and least wall
time): a CPU time measured once on a shared machine is inflated by whatever else runs, more so
for a 3 ms process than for a 1 s one, so one run understates the ratio.
--inprocess FILE (written by `cargo bench --bench rank_inprocess -- --tsv FILE`) adds the
like-for-like column: symident's detect() CPU time (in a running interpreter) over obsan's rank
CPU time in-process (no process start), and its median.

Each suite entry (systems/benchmarks/*.sys, systems/vins.sys, systems/benchmarks/paper.list) is
translated mechanically from .sys: states get ODEs, params stay free symbols (symident's
parameters), consts become `fixed`, inputs `known_inputs`, outputs `observables`; a named input
restriction is substituted. Every name is renamed to z0, z1, ... first, so that .sys names such
as I, E, S, N, beta or gamma cannot collide with SymPy's built-ins. symident runs in a child
process per model (fresh interpreter, --timeout seconds); its time is that of `detect()` alone,
without the interpreter start and the SymPy import. obsan's time is the wall time of one
`obsan rank --json` process. A variable is non-identifiable in symident when it lies in the
support of one of its directions. Prints one Markdown table.
"""

import importlib.metadata
import json
import os
import re
import resource
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# The smallest obsan CPU time a ratio divides by (a run of obsan takes about 2 ms
# of CPU to start the process alone, so this only guards a division by zero).
CPU_FLOOR = 0.001
# The floor of an in-process time (0.01 ms: below any rank test measured, a guard only).
IN_FLOOR = 0.00001

FUNCS = {"sin", "cos", "tan", "atan", "atan2", "exp", "log", "sqrt", "pi"}


def statements(text):
    """The .sys statements: comments stripped, continuation lines joined (docs/sys-format.md)."""
    out, cur, depth = [], "", 0
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].rstrip()
        if not line.strip() and not cur:
            continue
        cur = (cur + " " + line.strip()) if cur else line.strip()
        depth = cur.count("(") - cur.count(")")
        if depth > 0 or re.search(r"[-+*/^,]$", cur):
            continue
        out.append(cur)
        cur = ""
    if cur:
        out.append(cur)
    return out


def read_sys(path):
    """Parse a .sys file into declarations, equations, outputs and restrictions."""
    m = {"state": [], "param": [], "const": [], "input": [], "ode": {}, "out": {}, "restrict": {}}
    with open(path) as f:
        text = f.read()
    for st in statements(text):
        word = st.split(None, 1)[0]
        rest = st[len(word):].strip()
        key = {"states": "state", "params": "param", "consts": "const", "inputs": "input"}.get(word, word)
        if key in ("state", "param", "const", "input"):
            for d in rest.split(","):
                name = d.split("=", 1)[0].strip()
                if key == "const" and "=" in d:
                    m.setdefault("const_value", {})[name] = d.split("=", 1)[1].strip()
                m[key].append(name)
        elif key in ("system", "description", "delay"):
            continue
        elif key == "output":
            name, expr = rest.split("=", 1)
            m["out"][name.strip()] = expr.strip()
        elif key == "restrict":
            name, body = rest.split(":", 1)
            subs = {}
            for part in body.split(","):
                u, e = part.split("=", 1)
                subs[u.strip()] = e.strip()
            m["restrict"][name.strip()] = subs
        elif re.match(r"^\w+\s*'\s*=", st):
            lhs, rhs = st.split("=", 1)
            m["ode"][lhs.replace("'", "").strip()] = rhs.strip()
        else:
            raise ValueError(f"{path}: cannot read statement '{st}'")
    return m


def translate(m, restriction):
    """symident keyword arguments and the renaming back, for one (restricted) .sys model."""
    import sympy

    names = m["state"] + m["param"] + m["const"] + m["input"]
    subs = m["restrict"].get(restriction, {}) if restriction else {}
    new_inputs = []
    for e in subs.values():
        for tok in re.findall(r"[A-Za-z_]\w*", e):
            if tok not in names and tok not in FUNCS and tok not in new_inputs:
                new_inputs.append(tok)
    all_names = names + new_inputs
    ren = {n: f"z{i}" for i, n in enumerate(all_names)}
    back = {v: k for k, v in ren.items()}
    syms = {z: sympy.Symbol(z) for z in ren.values()}

    def conv(expr):
        e = re.sub(r"[A-Za-z_]\w*", lambda t: ren.get(t.group(0), t.group(0)), expr)
        return sympy.sympify(e.replace("^", "**"), locals=syms)

    sub_exprs = {syms[ren[u]]: conv(e) for u, e in subs.items()}
    const_vals = {syms[ren[c]]: conv(v) for c, v in m.get("const_value", {}).items()}
    odes = {ren[x]: str(conv(e).subs(sub_exprs).subs(const_vals)) for x, e in m["ode"].items()}
    obs = {f"obs{i}": str(conv(e).subs(const_vals)) for i, e in enumerate(m["out"].values())}
    inputs = [ren[u] for u in m["input"] if u not in subs] + [ren[u] for u in new_inputs]
    used = set(re.findall(r"z\d+", " ".join(list(odes.values()) + list(obs.values()))))
    fixed = [ren[c] for c in m["const"] if c not in m.get("const_value", {}) and ren[c] in used]
    kw = dict(odes=odes, observables=obs, known_inputs=inputs, fixed=fixed,
              parameters=[ren[p] for p in m["param"]])
    return kw, back


def exp_log(text):
    """`text` with each power of a compound base to a non-numeric exponent as exp(e*log(b))."""
    import sympy

    e = sympy.sympify(text, rational=True)
    e = e.replace(lambda x: x.is_Pow and not x.base.is_Symbol and not x.exp.is_Number,
                  lambda x: sympy.exp(x.exp * sympy.log(x.base)))
    return str(e)


def run_one(path, restriction, verdict=False):
    """Child: translate, detect, print one JSON line.

    `verdict` (the verdict scripts, never the timing runs) retries where symident's first answer
    is no verdict: a free exponent on a compound base, which its finite-field engine refuses,
    is written exp(e*log(b)) (the same function where b > 0, symident's default domain); a rank
    marked `lower bound` (a direction without closed form) is rerun with reconstruct=True, which
    proves the directions when it succeeds."""
    import symident

    m = read_sys(os.path.join(ROOT, path))
    kw, back = translate(m, restriction)
    model = symident.Model(**kw)
    t, c = time.perf_counter(), time.process_time()
    try:
        try:
            r = symident.detect(model)
        except ValueError:
            if not verdict:
                raise
            kw["odes"] = {k: exp_log(v) for k, v in kw["odes"].items()}
            kw["observables"] = {k: exp_log(v) for k, v in kw["observables"].items()}
            model = symident.Model(**kw)
            r = symident.detect(model)
        if verdict and ((r.info or {}).get("rank_status") or {}).get("status") == "lower bound":
            r = symident.detect(model, reconstruct=True)
    except ValueError as e:
        # Name the offending expression in the .sys names (the message quotes it renamed).
        bad = [ln.strip() for ln in str(e).splitlines() if ln.startswith("  ")]
        what = re.sub(r"z\d+", lambda t: back.get(t.group(0), t.group(0)), "; ".join(bad))
        funcs = sorted(set(re.findall(r"\b(atan2|sqrt|atan|tan|log|exp|sin|cos)\(", what)))
        where = sorted(set(re.findall(r"(\w+) =", what)))
        print(json.dumps({"error": f"its modular engine refuses {', '.join(funcs) or 'a term'} "
                                   f"in {', '.join(where)}; symbolic engine not run"}))
        return
    secs, cpu = time.perf_counter() - t, time.process_time() - c
    un = set()
    for s in r.symmetries:
        for z in s.get("support") or []:
            un.add(back.get(z, z))
    status = (r.info or {}).get("rank_status") or {}
    print(json.dumps({"rank": r.rank, "dim": r.dim, "unobservable": sorted(un), "secs": secs,
                      "cpu": cpu, "status": status.get("status")}))


def parse_verdict(spec):
    v = {"rank": None, "unobservable": None}
    for part in spec.split(";"):
        w = part.split()
        if not w:
            continue
        if w[0] == "observable":
            v["unobservable"] = set()
        elif w[0] == "unobservable":
            v["unobservable"] = set(w[1:])
        elif w[0] == "rank":
            v["rank"] = int(w[1])
    return v


def si_jl_entries():
    """The StructuralIdentifiability.jl models (systems/benchmarks/si-jl/, issue 32), each with
    its cited verdict when it has one (otherwise none: the row is not judged)."""
    d = os.path.join(ROOT, "systems", "benchmarks", "si-jl")
    out = []
    for f in sorted(x for x in os.listdir(d) if x.endswith(".sys")):
        path = f"systems/benchmarks/si-jl/{f}"
        cited = {"rank": None, "unobservable": None}
        with open(os.path.join(ROOT, path)) as fh:
            for line in fh:
                mm = re.match(r"^# verdict: (.*)$", line.rstrip())
                if mm:
                    cited = parse_verdict(mm.group(1))
        out.append((path, None, cited))
    return out


def entries():
    bench = os.path.join(ROOT, "systems", "benchmarks")
    files = sorted(f"systems/benchmarks/{f}" for f in os.listdir(bench) if f.endswith(".sys"))
    files.append("systems/vins.sys")
    out = []
    for path in files:
        with open(os.path.join(ROOT, path)) as f:
            for line in f:
                mm = re.match(r"^# verdict(?:\((\w+)\))?: (.*)$", line.rstrip())
                if mm:
                    out.append((path, mm.group(1), parse_verdict(mm.group(2))))
    with open(os.path.join(bench, "paper.list")) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            lhs, spec = line.split("|", 1)
            w = lhs.split()
            out.append((w[0], w[2] if len(w) > 2 else None, parse_verdict(spec)))
    return out


def run_obsan(obsan, path, restriction, cited, timeout, repeat=1):
    """`obsan rank --json` on one entry, the least of `repeat` runs: (n, rank, verdict against
    the cited one, wall s, CPU s of the process, whether it answered)."""
    cmd = [obsan, "rank", path, "--json", "--timeout", str(int(timeout))]
    if restriction:
        cmd += ["--input", restriction]
    osecs, ocpu = float("inf"), float("inf")
    for _ in range(repeat):
        t, ru = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
        osecs = min(osecs, time.perf_counter() - t)
        rv = resource.getrusage(resource.RUSAGE_CHILDREN)
        # obsan's CPU time (user + system of the child), the machine's load left out;
        # getrusage counts microseconds (os.times() counts 10 ms clock ticks, coarser
        # than most obsan runs).
        ocpu = min(ocpu, (rv.ru_utime - ru.ru_utime) + (rv.ru_stime - ru.ru_stime))
    if p.returncode != 0:
        return "-", "-", f"exit {p.returncode}", osecs, ocpu, False
    v = json.loads(p.stdout)
    overdict = judge(v["rank"], v["n"], v["unobservable_variables"], cited)
    if cited["rank"] is None and cited["unobservable"] is None:
        overdict = "no cited verdict"
    return v["n"], v["rank"], overdict, osecs, ocpu, True


def ratio_summary(rs):
    """`median Mx, min mx, max Xx` of the ratios `rs` (not empty)."""
    rs = sorted(rs)
    k = len(rs)
    med = rs[k // 2] if k % 2 else (rs[k // 2 - 1] + rs[k // 2]) / 2
    return f"median {med:.0f}x, min {rs[0]:.1f}x, max {rs[-1]:.0f}x"


def judge(rank, n, un, cited):
    if rank is None:
        return "no answer"
    diffs = []
    if cited["rank"] is not None and cited["rank"] != rank:
        diffs.append(f"cited rank {cited['rank']}")
    want = cited["unobservable"]
    if want is not None:
        if not want and rank != n:
            diffs.append("cited observable")
        elif set(un) != want:
            diffs.append(f"non-identifiable {sorted(set(un) - want)} extra, {sorted(want - set(un))} missing")
    return "agrees" if not diffs else "DIFFERS: " + "; ".join(diffs)


def main():
    args = sys.argv[1:]
    inproc = {}
    if args[:1] in (["--one"], ["--one-verdict"]):
        run_one(args[1], args[2] if len(args) > 2 and args[2] else None, args[0] == "--one-verdict")
        return
    timeout, obsan, filt, repeat = 120.0, os.path.join(ROOT, "target", "release", "obsan"), [], 1
    suite = entries
    i = 0
    while i < len(args):
        if args[i] == "--si-jl":
            suite = si_jl_entries
            i += 1
        elif args[i] == "--timeout":
            timeout = float(args[i + 1])
            i += 2
        elif args[i] == "--repeat":
            repeat = max(1, int(args[i + 1]))
            i += 2
        elif args[i] == "--obsan":
            obsan = args[i + 1]
            i += 2
        elif args[i] == "--inprocess":
            # path<TAB>least CPU seconds, from `cargo bench --bench rank_inprocess -- --tsv FILE`.
            for line in open(args[i + 1]):
                if line.strip():
                    k, v, c = line.rstrip("\n").split("\t")
                    inproc[k] = (float(v), float(c))
            i += 2
        else:
            filt.append(args[i])
            i += 1
    import symident

    extra = " in-process ratio | computation ratio |" if inproc else ""
    print("| model | n | obsan rank | obsan verdict | obsan s | symident rank | symident verdict "
          "| symident s | CPU ratio |" + extra)
    print("|---|---|---|---|---|---|---|---|---|" + ("---|---|" if inproc else ""))
    in_ratios, comp_ratios = [], []
    score = {"obsan": 0, "symident": 0, "total": 0, "faster": 0, "both": 0}
    ratios = []
    for path, restriction, cited in suite():
        if filt and not any(f in path for f in filt):
            continue
        label = path + (f" --input {restriction}" if restriction else "")
        n, orank, overdict, osecs, ocpu, ok = run_obsan(obsan, path, restriction, cited, timeout, repeat)
        ratio, in_ratio, comp_ratio = "-", "-", "-"
        try:
            s = None
            for k in range(repeat if ok else 1):
                q = subprocess.run([sys.executable, __file__, "--one", path, restriction or ""],
                                   cwd=ROOT, capture_output=True, text=True, timeout=timeout)
                if q.returncode != 0 or not q.stdout.strip():
                    break
                one = json.loads(q.stdout.strip().splitlines()[-1])
                if s is None or "error" in one or "cpu" not in s:
                    s = one
                else:
                    s["cpu"], s["secs"] = min(s["cpu"], one.get("cpu", s["cpu"])), min(s["secs"], one["secs"])
                if "error" in one:
                    break
            if s is not None and "error" in s:
                srank, sverdict, ssecs = "-", "cannot take it: " + s["error"][:120].replace("|", "/"), "-"
            elif s is not None:
                srank = s["rank"]
                sverdict = judge(srank, s["dim"], s["unobservable"], cited)
                if cited["rank"] is None and cited["unobservable"] is None:
                    sverdict = "same rank as obsan" if srank == orank else "RANK DIFFERS from obsan"
                if s.get("status") and s["status"] != "proven":
                    sverdict += f" ({s['status']})"
                ssecs = f"{s['secs']:.2f}"
                if ok and "cpu" in s:
                    r = s["cpu"] / max(ocpu, CPU_FLOOR)
                    ratios.append(r)
                    ratio = f"{r:.0f}x"
                if path in inproc and restriction is None and "cpu" in s:
                    r2 = s["cpu"] / max(inproc[path][0], IN_FLOOR)
                    in_ratios.append(r2)
                    in_ratio = f"{r2:.0f}x"
                    r3 = s["cpu"] / max(inproc[path][1], IN_FLOOR)
                    comp_ratios.append(r3)
                    comp_ratio = f"{r3:.0f}x"
            else:
                lines = q.stderr.strip().splitlines() or ["no output"]
                err = next((ln for ln in lines if re.match(r"^\w+(Error|Exception):", ln)), lines[-1])
                srank, sverdict, ssecs = "-", "cannot take it: " + err[:110].replace("|", "/"), "-"
        except subprocess.TimeoutExpired:
            srank, sverdict, ssecs = "-", f"no answer in {timeout:.0f} s", f">{timeout:.0f}"
        score["total"] += 1
        score["obsan"] += overdict == "agrees"
        score["symident"] += sverdict.startswith("agrees")
        if ssecs != "-" and not ssecs.startswith(">") and ok:
            score["both"] += 1
            score["faster"] += osecs < float(ssecs)
        elif ssecs.startswith(">") and ok:
            score["both"] += 1
            score["faster"] += osecs < timeout
        print(f"| {label} | {n} | {orank} | {overdict} | {osecs:.2f} | {srank} | {sverdict} | {ssecs} "
              f"| {ratio} |" + (f" {in_ratio} | {comp_ratio} |" if inproc else ""), flush=True)
    print()
    if ratios:
        print(f"CPU ratio (symident detect() CPU / obsan process CPU, obsan's floored at 1 ms) on the "
              f"{len(ratios)} models both answered: {ratio_summary(ratios)} (least of {repeat} runs each)")
    for rs, what in ((in_ratios, "obsan's whole rank command in-process"),
                     (comp_ratios, "obsan's rank computation alone, the model parsed beforehand")):
        if rs:
            print(f"Ratio symident detect() CPU / {what} (benches/rank_inprocess.rs, least of its "
                  f"runs) on {len(rs)} models: {ratio_summary(rs)}")
    print(f"{score['total']} entries; cited verdict matched: obsan {score['obsan']}, "
          f"symident {score['symident']}; obsan faster on {score['faster']} of the {score['both']} "
          f"that both answered or symident timed out; symident "
          f"{importlib.metadata.version('symident')}, timeout {timeout:.0f} s")


if __name__ == "__main__":
    main()
