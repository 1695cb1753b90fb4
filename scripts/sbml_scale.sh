#!/usr/bin/env bash
# SBML scale test: `obsan import sbml` on every model of a folder (nothing of it is committed
# here): the SBML test suite (public repository sbmlteam/sbml-test-suite: its semantic cases'
# Level 3 Version 1 files), or any folder of real models (every *.xml under it, e.g. a BioModels
# or PEtab benchmark-collection clone). Prints the count converted, the count refused (each with a
# located error: file:line:col), the refusals grouped by reason, the median and slowest import.
#   cargo build --release -p obsan && scripts/sbml_scale.sh PATH/TO/sbml-test-suite-or-folder
set -euo pipefail
suite="${1:?usage: scripts/sbml_scale.sh PATH/TO/sbml-test-suite-or-folder}"
obsan="${OBSAN_BIN:-${CARGO_TARGET_DIR:-$(dirname "$0")/../target}/release/obsan}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if [ ! -d "$suite/cases/semantic" ] && git -C "$suite" rev-parse --git-dir >/dev/null 2>&1; then
  # A bare mirror (no work tree): check out the semantic cases, as sbml_roundtrip.sh does.
  git -C "$suite" archive HEAD cases/semantic 2>/dev/null | tar -x -C "$tmp"
  suite=$tmp
fi
if [ -d "$suite/cases/semantic" ]; then
  files() { find "$suite/cases/semantic" -name '*-sbml-l3v1.xml' | sort; }
else
  files() { find "$suite" -name '*.xml' | sort; }
fi
ok=0 n=0 slowest=0 slowest_file=""
while IFS= read -r f; do
  n=$((n + 1))
  s=$(date +%s%N)
  if "$obsan" import sbml "$f" >/dev/null 2>"$tmp/err"; then
    ok=$((ok + 1))
  else
    head -1 "$tmp/err" >>"$tmp/refused"
  fi
  ms=$((($(date +%s%N) - s) / 1000000))
  echo "$ms" >>"$tmp/times"
  if [ "$ms" -gt "$slowest" ]; then slowest=$ms slowest_file=$f; fi
done < <(files)
[ "$n" -gt 0 ] || { echo "no models under $suite"; exit 1; }
median=$(sort -n "$tmp/times" | awk '{a[NR] = $1} END {print (NR ? a[int((NR + 1) / 2)] : 0)}')
echo "$ok of $n models converted, $((n - ok)) refused; median import ${median} ms wall, slowest ${slowest} ms ($slowest_file)"
if [ -s "$tmp/refused" ]; then
  # Group by reason: the message without file, place and quoted ids.
  sed -E "s/^error: .*\.xml:[0-9]+:[0-9]+: //; s/'[^']*'/'ID'/g" "$tmp/refused" | sort | uniq -c | sort -rn
fi
