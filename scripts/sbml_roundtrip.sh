#!/usr/bin/env bash
# SBML round trip: every semantic case of the SBML test suite (public repository
# sbmlteam/sbml-test-suite, LGPL; clone it yourself, nothing of it is committed here) that obsan's
# class covers is imported (`obsan import sbml --values`), simulated (`obsan simulate MODEL.sys
# --values`) at the case's times, and compared with the case's results CSV at its stated
# tolerances (|obsan - expected| <= absolute + relative |expected|, as the suite's settings say).
# Prints a tally: cases, time courses, imported, simulated, passed, failed (with ids), and the
# reasons the rest are not covered (import refusals grouped, values the file does not give, ...).
#   cargo build --release -p obsan && scripts/sbml_roundtrip.sh PATH/TO/sbml-test-suite [FIRST LAST]
set -euo pipefail
suite="${1:?usage: scripts/sbml_roundtrip.sh PATH/TO/sbml-test-suite [FIRST LAST]}"
first="${2:-1}"
last="${3:-99999}"
obsan="${OBSAN_BIN:-${CARGO_TARGET_DIR:-$(dirname "$0")/../target}/release/obsan}"
if [ ! -d "$suite/cases/semantic" ] && git -C "$suite" rev-parse --git-dir >/dev/null 2>&1; then
  # A bare mirror (no work tree): check out the semantic cases into a temporary folder.
  tree=$(mktemp -d)
  trap 'rm -rf "$tree"' EXIT
  # (git may warn of large binaries elsewhere in the mirror that it does not hold.)
  git -C "$suite" archive HEAD cases/semantic 2>/dev/null | tar -x -C "$tree"
  suite=$tree
fi
python3 - "$suite" "$obsan" "$first" "$last" <<'EOF'
import collections, csv, os, re, subprocess, sys, tempfile
import xml.etree.ElementTree as ET

suite, obsan, first, last = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
root = os.path.join(suite, "cases", "semantic")
if not os.path.isdir(root):
    sys.exit(f"{root}: not a folder")
LEVELS = ["l3v2", "l3v1", "l2v5", "l2v4", "l2v3"]
tally = collections.Counter()
reasons = collections.Counter()
failed = []


def settings(path):
    s = {}
    for line in open(path):
        if ":" in line:
            k, v = line.split(":", 1)
            s[k.strip()] = v.strip()
    return s


def names(v):
    return [x.strip() for x in v.split(",") if x.strip()]


def species_info(xml):
    """species id -> (compartment size or None, hasOnlySubstanceUnits, compartment id)."""
    t = ET.parse(xml).getroot()
    ns = t.tag[: t.tag.index("}") + 1] if t.tag.startswith("{") else ""
    sizes = {c.get("id"): c.get("size") or c.get("volume") for c in t.iter(ns + "compartment")}
    out = {}
    for s in t.iter(ns + "species"):
        size = sizes.get(s.get("compartment"))
        out[s.get("id")] = (float(size) if size else None, s.get("hasOnlySubstanceUnits") == "true",
                            s.get("compartment"))
    return out


def rows(path):
    """A CSV as dicts, the header names stripped (some results files put spaces after commas)."""
    r = list(csv.reader(open(path)))
    head = [h.strip() for h in r[0]]
    return [dict(zip(head, (x.strip() for x in row))) for row in r[1:] if row]


def run(args):
    return subprocess.run([obsan] + args, capture_output=True, text=True)


def reason(err):
    line = (err.strip().splitlines() or ["?"])[0]
    line = re.sub(r"^error: \S+?:\d+:\d+: ", "", line)
    line = re.sub(r"'[^']*'", "'ID'", line)
    return re.sub(r"missing values: .*", "missing values (initial assignments, ...)", line)


cases = sorted(d for d in os.listdir(root) if d.isdigit() and first <= int(d) <= last)
with tempfile.TemporaryDirectory() as tmp:
    for case in cases:
        d = os.path.join(root, case)
        tally["cases"] += 1
        model_m = open(os.path.join(d, f"{case}-model.m")).read()
        if "TimeCourse" not in re.findall(r"testType:\s*(\S+)", model_m):
            reasons["not a time course"] += 1
            continue
        tally["time courses"] += 1
        xml = next((os.path.join(d, f"{case}-sbml-{l}.xml") for l in LEVELS
                    if os.path.exists(os.path.join(d, f"{case}-sbml-{l}.xml"))), None)
        st = settings(os.path.join(d, f"{case}-settings.txt"))
        if xml is None or float(st.get("start", "0")) != 0.0:
            reasons["no Level 2/3 file or a start time other than 0"] += 1
            continue
        sys_f, val_f, out_f, in_f = (os.path.join(tmp, f"{case}.{e}")
                                     for e in ("sys", "values", "csv", "inputs.csv"))
        duration, steps = float(st["duration"]), int(st["steps"])
        if os.path.exists(in_f):
            os.remove(in_f)
        # A <piecewise> of time is a known input: its exact course over the case's horizon.
        r = run(["import", "sbml", xml, "--out", sys_f, "--values", val_f, "--force",
                 "--inputs-out", in_f, "--until", repr(duration)])
        if r.returncode != 0:
            reasons["import: " + reason(r.stderr)] += 1
            continue
        tally["imported"] += 1
        inputs = ["--inputs", in_f] if os.path.exists(in_f) else []
        if inputs:
            tally["with piecewise inputs"] += 1
        r = run(["simulate", sys_f, "--values", val_f, "--until", repr(duration),
                 "--every", repr(duration / steps), "--out", out_f, "--force", "--timeout", "60"]
                + inputs)
        if r.returncode != 0:
            reasons["simulate: " + reason(r.stderr)] += 1
            continue
        tally["simulated"] += 1
        got = rows(out_f)
        want = rows(os.path.join(d, f"{case}-results.csv"))
        values = {}
        for line in open(val_f):
            k, v = line.split("=")
            values[k.strip()] = float(v)
        info = species_info(xml)
        # Constant in time: the .sys params (an assignment-rule variable also has a value in the
        # file, its initial one, but it varies: not compared).
        params = {n.strip() for line in open(sys_f) if line.startswith("param ")
                  for n in line[len("param "):].split(",")}
        amount, atol, rtol = names(st.get("amount", "")), float(st["absolute"]), float(st["relative"])
        ok, missing = True, None
        for v in names(st["variables"]):
            col = v if v in got[0] else v + "_" if v + "_" in got[0] else None
            const = next((values[n] for n in (v, v + "_") if n in params and n in values), None)
            if col is None and const is None:
                missing = v
                break
            size, amount_units, comp = info.get(v, (None, True, None))
            # An initial assignment may set the size: the values file holds it then.
            size = values.get(comp, values.get(f"{comp}_", size))
            # The .sys state is a concentration unless hasOnlySubstanceUnits.
            scale = 1.0
            if v in info and v in amount and not amount_units:
                scale = size if size is not None else float("nan")
            elif v in info and v not in amount and amount_units:
                scale = 1.0 / size if size else float("nan")
            for g, w in zip(got, want):
                e = float(w[v])
                x = (float(g[col]) if col else const) * scale
                if e == e and abs(x - e) > atol + rtol * abs(e):
                    ok = False
        if missing is not None:
            reasons["a result variable is no state nor given value (assignment rule)"] += 1
            continue
        if len(got) != len(want):
            ok = False
        tally["compared"] += 1
        if ok:
            tally["passed"] += 1
        else:
            failed.append(case)

print(", ".join(f"{k} {v}" for k, v in tally.items()))
print(f"failed {len(failed)}: {' '.join(failed)}")
print("not covered:")
for r, n in reasons.most_common():
    print(f"  {n:5d} {r}")
EOF
