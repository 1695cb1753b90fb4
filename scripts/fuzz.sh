#!/usr/bin/env bash
# Run every fuzz target for SECONDS each (default 60), on the stable toolchain
# (`--sanitizer none`: the sanitizers need nightly; libFuzzer's coverage
# guidance and the targets' own oracles still run). Seed corpora come from
# systems/ and the test data, copied into fuzz/corpus/TARGET (not committed).
# A crash leaves its input in fuzz/artifacts/TARGET and makes this exit 1;
# turn each into a regression test in the crate that owns the reader.
#   scripts/fuzz.sh 600            # ten minutes per target
#   scripts/fuzz.sh 30 expr sys    # some targets only
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-60}"
shift || true
targets=("$@")
# Default: every [[bin]] of fuzz/Cargo.toml.
[ ${#targets[@]} -gt 0 ] || mapfile -t targets < <(awk '/^\[\[bin\]\]/{b=1; next} b && /^name *=/{gsub(/[" ]/, "", $0); sub(/name=/, "", $0); print; b=0}' fuzz/Cargo.toml)
if [ ${#targets[@]} -eq 0 ]; then
  echo "no fuzz targets in fuzz/Cargo.toml"
  exit 0
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "== installing cargo-fuzz (crates.io)"
  cargo install cargo-fuzz --locked >/dev/null
fi

seed() {
  local t=$1 dir=fuzz/corpus/$1
  mkdir -p "$dir"
  case $t in
    expr)
      # One expression a file: every right-hand side of the shipped systems.
      local i=0
      while IFS= read -r line; do
        i=$((i + 1))
        printf '%s' "$line" > "$dir/seed-$i"
      done < <(grep -h -o "=.*" systems/*.sys systems/classic/*.sys 2>/dev/null | sed 's/^=//; s/#.*//' | sort -u)
      ;;
    sys) cp systems/*.sys systems/classic/*.sys "$dir/" 2>/dev/null || true ;;
    eff) cp systems/*.eff "$dir/" 2>/dev/null || true ;;
    sbml) [ -d fuzz/seeds/sbml ] && cp fuzz/seeds/sbml/* "$dir/" 2>/dev/null || true ;;
    si_jl) [ -d fuzz/seeds/si_jl ] && cp fuzz/seeds/si_jl/* "$dir/" 2>/dev/null || true ;;
    petab) [ -d fuzz/seeds/petab ] && cp fuzz/seeds/petab/* "$dir/" 2>/dev/null || true ;;
    strike_goldd)
      cp systems/benchmarks/strike-goldd/src/*.m "$dir/" 2>/dev/null || true
      # Loops, zeros and indexed assignment, and their limits.
      [ -d fuzz/seeds/strike_goldd ] && cp fuzz/seeds/strike_goldd/* "$dir/" 2>/dev/null || true
      ;;
    dataset)
      # A dataset's files framed as the target reads them (see fuzz_targets/dataset.rs).
      [ -d fuzz/seeds/dataset ] && cp fuzz/seeds/dataset/* "$dir/" 2>/dev/null || true
      ;;
    dec)
      cp systems/*.dec "$dir/" 2>/dev/null || true
      [ -d fuzz/seeds/dec ] && cp fuzz/seeds/dec/* "$dir/" 2>/dev/null || true
      ;;
    mrclam | mcpart | inputs_csv)
      # Framed seeds (see fuzz_targets/$t.rs).
      [ -d "fuzz/seeds/$t" ] && cp "fuzz/seeds/$t"/* "$dir/" 2>/dev/null || true
      ;;
  esac
}

# FUZZ_SEED fixes libFuzzer's seed (CI sets it, so a failure there reproduces
# with the same command); unset, every run explores afresh.
seed_arg=()
[ -n "${FUZZ_SEED:-}" ] && seed_arg=(-seed="$FUZZ_SEED")

status=0
for t in "${targets[@]}"; do
  seed "$t"
  echo "== fuzz $t for ${secs}s"
  if ! cargo fuzz run --sanitizer none "$t" "fuzz/corpus/$t" -- \
      -max_total_time="$secs" -timeout=10 -rss_limit_mb=1024 -print_final_stats=1 "${seed_arg[@]}" \
      >"fuzz/$t.log" 2>&1; then
    echo "   FAILED: see fuzz/$t.log and fuzz/artifacts/$t/"
    tail -30 "fuzz/$t.log"
    status=1
  else
    grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "fuzz/$t.log" | sed 's/^/   /'
  fi
done
exit $status
