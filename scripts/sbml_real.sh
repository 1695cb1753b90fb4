#!/usr/bin/env bash
# Real SBML models through `obsan import sbml`, one run per model timed with /usr/bin/time:
# counts imported, imported under 1 s, refused with a located error (grouped by reason), and any
# panic or unlocated error (a bug). Nothing of the models is committed here; PATH is either
#  - a folder: every *.xml under it is a model, or
#  - a clone or bare mirror of matthiaskoenig/sbmlutils (MIT/LGPL; its test resources hold the
#    1041 manually curated BioModels as COMBINE archives): the SBML of each
#    `src/sbmlutils/resources/models/biomodels_curated/*.omex` at COMMIT (default 2034da3c, the
#    last commit holding them) is extracted into a temporary folder (the archive's `_url.xml`).
#   cargo build --release -p obsan && scripts/sbml_real.sh PATH [COMMIT]
set -euo pipefail
src="${1:?usage: scripts/sbml_real.sh PATH/TO/folder-or-sbmlutils [COMMIT]}"
commit="${2:-2034da3cd4c7afbc484ada3d57554e6aef87d990}"
obsan="${OBSAN_BIN:-${CARGO_TARGET_DIR:-$(dirname "$0")/../target}/release/obsan}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ ! -d "$src" ]; then
  echo "$src: not a folder"
  exit 1
fi
if git -C "$src" rev-parse --git-dir >/dev/null 2>&1 &&
  git -C "$src" cat-file -e "$commit:src/sbmlutils/resources/models/biomodels_curated" 2>/dev/null; then
  mkdir -p "$tmp/omex" "$tmp/models"
  # (git may complain of large blobs elsewhere in a mirror that it does not hold.)
  { git -C "$src" archive "$commit" src/sbmlutils/resources/models/biomodels_curated 2>/dev/null || true; } |
    tar -x -C "$tmp/omex"
  python3 - "$tmp/omex" "$tmp/models" <<'EOF'
import glob, os, sys, zipfile
out = sys.argv[2]
for f in sorted(glob.glob(os.path.join(sys.argv[1], "**", "*.omex"), recursive=True)):
    z = zipfile.ZipFile(f)
    stem = os.path.basename(f)[: -len(".omex")]
    names = [n for n in z.namelist() if n.endswith(".xml") and n not in ("manifest.xml", "metadata.xml")]
    # The `_url` variant (identifiers.org annotations) when there are two; the SBML is the same.
    pick = next((n for n in names if n.endswith("_url.xml")), names[0] if names else None)
    if pick is not None:
        open(os.path.join(out, stem + ".xml"), "wb").write(z.read(pick))
EOF
  models="$tmp/models"
else
  models="$src"
fi
python3 - "$models" "$obsan" "$tmp" <<'EOF'
import collections, os, re, subprocess, sys
models, obsan, tmp = sys.argv[1], sys.argv[2], sys.argv[3]
files = sorted(os.path.join(d, f) for d, _, fs in os.walk(models) for f in fs if f.endswith(".xml"))
if not files:
    sys.exit(f"no *.xml under {models}")
# A run over LIMIT seconds is stopped and counted apart (neither imported nor refused).
LIMIT = 20
imported, fast, slow, refused, bugs, times = 0, 0, [], collections.Counter(), [], []
timed_out = []
examples = {}
tfile = os.path.join(tmp, "time")
for f in files:
    r = subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", tfile, "timeout", str(LIMIT), obsan,
                        "import", "sbml", f], capture_output=True, text=True, errors="replace")
    secs, kb = open(tfile).read().split()[-2:]
    secs = float(secs)
    times.append(secs)
    if r.returncode == 124:
        timed_out.append(os.path.basename(f))
        continue
    if r.returncode == 0:
        imported += 1
        if secs < 1.0:
            fast += 1
        else:
            slow.append((secs, os.path.basename(f)))
        continue
    first = (r.stderr.strip().splitlines() or ["(no message)"])[0]
    located = re.match(r"^error: .*\.xml:\d+:\d+: ", first)
    if r.returncode != 2 or "panicked" in r.stderr or not located:
        bugs.append(f"{os.path.basename(f)}: exit {r.returncode}: {first}")
        continue
    why = re.sub(r"^error: \S+?:\d+:\d+: ", "", first).replace("obsan's", "obsan\u2019s")
    why = re.sub(r": the term .*", "", why)
    why = re.sub(r"\((u_[^()]*)\)", "(...)", why)
    why = re.sub(r"'[^']*'", "'ID'", why)
    why = re.sub(r"at line \d+", "at line L", why)
    why = re.sub(r"\d+/\d+", "P/Q", why)
    why = re.sub(r"with unit \S+ and with coefficient \S+", "with two units", why)
    why = re.sub(r"\d+ terms", "N terms", why)
    why = re.sub(r"(the dynamics|exp|the coefficient \S+) of \S+ ", r"\1 of X ", why)
    why = why.replace("obsan\u2019s", "obsan's")[:150]
    refused[why] += 1
    examples.setdefault(why, os.path.basename(f))
times.sort()
n = len(files)
print(f"models {n}, imported {imported} (under 1 s: {fast}), refused with a located error "
      f"{sum(refused.values())}, panics or unlocated errors {len(bugs)}")
print(f"stopped after {LIMIT} s: {len(timed_out)} {' '.join(timed_out)}")
print(f"wall time per import: median {times[n // 2]:.2f} s, slowest finished "
      f"{max([t for t in times if t < LIMIT] or [0]):.2f} s")
for s, f in sorted(slow, reverse=True):
    print(f"  imported in {s:.2f} s: {f}")
for b in bugs:
    print(f"  BUG {b}")
print("refused, by reason (one example):")
for why, k in refused.most_common():
    print(f"  {k:5d} {why}  [{examples[why]}]")
EOF
