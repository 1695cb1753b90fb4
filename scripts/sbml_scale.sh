#!/usr/bin/env bash
# SBML scale test (issue 32): `obsan import sbml` on every Level 3 Version 1 model of the SBML
# test suite's semantic cases (public repository sbmlteam/sbml-test-suite; clone it yourself,
# nothing of it is committed here). Prints the count converted, the count refused (each with a
# located error: file:line:col), the refusals grouped by reason, and the slowest import.
#   cargo build --release && scripts/sbml_scale.sh PATH/TO/sbml-test-suite
set -euo pipefail
suite="${1:?usage: scripts/sbml_scale.sh PATH/TO/sbml-test-suite}"
obsan="${CARGO_TARGET_DIR:-$(dirname "$0")/../target}/release/obsan"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
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
  if [ "$ms" -gt "$slowest" ]; then slowest=$ms slowest_file=$f; fi
done < <(find "$suite/cases/semantic" -name '*-sbml-l3v1.xml' | sort)
echo "$ok of $n models converted, $((n - ok)) refused; slowest import ${slowest} ms wall ($slowest_file)"
if [ -s "$tmp/refused" ]; then
  # Group by reason: the message without file, place and quoted ids.
  sed -E "s/^error: .*\.xml:[0-9]+:[0-9]+: //; s/'[^']*'/'ID'/g" "$tmp/refused" | sort | uniq -c | sort -rn
fi
