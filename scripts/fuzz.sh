#!/usr/bin/env bash
# Runs each libFuzzer harness of fuzz/ (docs/sanitizers.md) for FIBRA_FUZZ_SECONDS seconds (60 by
# default), as many at a time as the machine has cores (FIBRA_JOBS), each from its seeds: the case
# readers from every case file of the repository (the JSON harness from their conversion to JSON),
# the state reader from fuzz/seeds/state, the nodes.csv reader from fuzz/seeds/nodes_csv and
# tests/malformed/nodes.csv.
# A crash, an exception other than InputError, a sanitizer report, a leak, an input that takes
# more than 10 s or 2 GiB is a finding: the harness stops, its input is kept in
# build-asan/fuzz-runs/<harness>/ (crash-*, leak-*, timeout-*, oom-*) and this script fails.
#   bash scripts/fuzz.sh [HARNESS...]     (fuzz_case_toml fuzz_case_json fuzz_state fuzz_nodes_csv)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FIBRA_ASAN_DIR:-$root/build-asan}"
seconds="${FIBRA_FUZZ_SECONDS:-60}"
harnesses=("$@")
((${#harnesses[@]})) || harnesses=(fuzz_case_toml fuzz_case_json fuzz_state fuzz_nodes_csv)
parallel="${FIBRA_JOBS:-$(nproc)}"
[[ $parallel =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: FIBRA_JOBS must be a positive whole number, got \"$parallel\"" >&2; exit 2; }
# FIBRA_FUZZ_NO_BUILD=1: run the harnesses as built (while build-asan/ builds something else).
[ -n "${FIBRA_FUZZ_NO_BUILD:-}" ] || bash "$root/scripts/asan_build.sh" "${harnesses[@]}"
# shellcheck disable=SC1091
source "$build/sanitizer_env.sh"
export ASAN_SYMBOLIZER_PATH=/usr/bin/llvm-symbolizer-14

case_files() {
  find "$root/examples" "$root/tests/robustness/cases" "$root/tests/malformed" "$root/bench" \
    -type f -name "*.$1" | sort
}

# Seeds of a harness into the directory $2 (emptied first).
seed() {
  rm -rf "$2" && mkdir -p "$2"
  case "$1" in
    fuzz_case_toml) case_files toml | while read -r f; do cp "$f" "$2/$(echo "$f" | md5sum | cut -c1-16).toml"; done ;;
    fuzz_case_json)
      case_files json | while read -r f; do cp "$f" "$2/$(echo "$f" | md5sum | cut -c1-16).json"; done
      # The TOML cases converted (those that TOML reads; dates, which JSON lacks, as text).
      case_files toml | python3 -c '
import hashlib, json, sys, tomllib
for path in sys.stdin.read().split():
    try:
        data = tomllib.load(open(path, "rb"))
    except Exception:  # not TOML (the malformed corpus), or nested too deep for Python
        continue
    name = hashlib.md5(path.encode()).hexdigest()[:16]
    with open(sys.argv[1] + "/" + name + "-from-toml.json", "w") as out:
        json.dump(data, out, indent=1, default=str)
' "$2" ;;
    fuzz_state) cp "$root"/fuzz/seeds/state/* "$2/" ;;
    fuzz_nodes_csv) cp "$root"/fuzz/seeds/nodes_csv/* "$2/" && cp "$root/tests/malformed/nodes.csv" "$2/malformed.csv" ;;
    *) echo "fuzz.sh: unknown harness $1" >&2; exit 2 ;;
  esac
}

# One harness: its seeds, then its run; the outcome in $work/status, the lines to print in
# $work/report (printed in the harnesses' order once all have run).
fuzz_one() {
  local h=$1 work="$build/fuzz-runs/$1" dict=() start status stats execs seeds
  seed "$h" "$work/corpus"
  seeds=$(ls "$work/corpus" | wc -l)
  case "$h" in fuzz_case_toml | fuzz_case_json) dict=(-dict="$root/fuzz/case.dict") ;; esac
  start=$(date +%s)
  if "$build/fuzz/$h" "$work/corpus" "${dict[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$work/" -print_final_stats=1 >"$work/log" 2>&1; then
    status=ok
  else
    status=FAILED
  fi
  stats=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/log" | tail -1 || true)
  execs=$(grep -E '^stat::number_of_executed_units' "$work/log" | awk '{print $2}' || true)
  {
    echo "fuzz.sh: $h: $status after $(($(date +%s) - start)) s from $seeds seeds, ${execs:-?} runs; ${stats:-no final stats}"
    if [ "$status" = FAILED ]; then
      tail -60 "$work/log"
      ls "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* 2>/dev/null || true
    fi
  } >"$work/report"
  echo "$status" >"$work/status"
}

# A harness named twice runs once (two runs would share its directory).
mapfile -t harnesses < <(printf '%s\n' "${harnesses[@]}" | awk '!seen[$0]++')
# Stopped from outside (a CI timeout), the script stops its harnesses too.
trap 'kill $(jobs -p) 2>/dev/null; exit 143' INT TERM
for h in "${harnesses[@]}"; do
  rm -f "$build/fuzz-runs/$h/status" "$build/fuzz-runs/$h/report"
  mkdir -p "$build/fuzz-runs/$h"
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
  echo "fuzz.sh: $h for $seconds s"
  fuzz_one "$h" &
done
wait
failed=0
for h in "${harnesses[@]}"; do
  cat "$build/fuzz-runs/$h/report" 2>/dev/null ||
    echo "fuzz.sh: $h: FAILED before its run ended (its seeds or its run; the messages above say why)"
  [ "$(cat "$build/fuzz-runs/$h/status" 2>/dev/null)" = ok ] || failed=1
done
exit "$failed"
