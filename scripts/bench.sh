#!/usr/bin/env bash
# Performance regression check (not part of the test suite): builds the benchmarks in Release,
# runs them with JSON output into <build>/bench-results/, and compares the figures with
# bench/baseline.json (bench/compare.py: fails if any benchmark is > 30% slower).
#
#   bash scripts/bench.sh                    # build, run everything, compare
#   bash scripts/bench.sh --update-baseline  # ... and rewrite bench/baseline.json from this run
#   bash scripts/bench.sh --benchmark_filter=Assembly   # extra arguments go to every benchmark
#                                                       # (missing baseline entries then tolerated)
# Benchmarks beyond the threshold are re-run once (the best figure counts), so a burst of other
# load on the machine does not fail the check; a real regression fails both runs.
# Environment: FIBRA_BUILD_DIR (default build/), FIBRA_BENCH_THRESHOLD (default 0.30).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FIBRA_BUILD_DIR:-$root/build}"
out="$build/bench-results"
threshold="${FIBRA_BENCH_THRESHOLD:-0.30}"

update=0
extra=()
for a in "$@"; do
  case "$a" in
    --update-baseline) update=1 ;;
    *) extra+=("$a") ;;
  esac
done

benches=(bench_beam bench_newton bench_cholmod_options bench_contact bench_bodies bench_corpus)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFIBRA_BUILD_BENCH=ON >/dev/null
cmake --build "$build" -j "$(nproc)" --target "${benches[@]}"

# Spinning OpenMP workers starve CHOLMOD's BLAS threads (and the other way round) on few cores.
export OMP_WAIT_POLICY=passive
mkdir -p "$out"
rm -f "$out"/*.rerun.json "$out/regressed.txt"
{
  lscpu | grep -E '^(Model name|CPU\(s\)|Thread|Core|Socket|L[23])' || true
  grep MemTotal /proc/meminfo || true
  "${CXX:-c++}" --version 2>/dev/null | head -1 || true
  dpkg-query -W -f='${Package} ${Version}\n' libopenblas0-pthread libcholmod3 libbenchmark1debian 2>/dev/null || true
  echo "OMP_WAIT_POLICY=$OMP_WAIT_POLICY OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-default}"
} >"$out/machine.txt"

load="$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo 0)"
if python3 -c "import sys; sys.exit(0 if float('$load') > 0.5 else 1)"; then
  echo "fibra bench: warning: load average $load before starting; timings need an idle machine" >&2
fi

results=()
for b in "${benches[@]}"; do
  echo "fibra bench: running $b ..." >&2
  "$build/bench/$b" --benchmark_format=json "${extra[@]}" >"$out/$b.json"
  # A --benchmark_filter matching nothing in this binary leaves no JSON at all.
  if [ -s "$out/$b.json" ]; then results+=("$out/$b.json"); else rm -f "$out/$b.json"; fi
done

if ((update)); then
  python3 "$root/bench/compare.py" "$root/bench/baseline.json" "${results[@]}" --write-baseline
fi
flags=(--threshold "$threshold")
((${#extra[@]})) && flags+=(--allow-missing)
compare=(python3 "$root/bench/compare.py" "$root/bench/baseline.json")
if ! "${compare[@]}" "${results[@]}" "${flags[@]}" --regressed-out "$out/regressed.txt" >/dev/null &&
   [ -s "$out/regressed.txt" ]; then
  # Re-run each regressed benchmark once, by exact name, and keep the best figure.
  for b in "${benches[@]}"; do
    names="$(awk -F'\t' -v b="$b" '$1 == b { print $2 }' "$out/regressed.txt")"
    [ -n "$names" ] || continue
    regex="^($(printf '%s\n' "$names" | python3 -c 'import re, sys; print("|".join(re.escape(l.strip()) for l in sys.stdin if l.strip()))'))\$"
    echo "fibra bench: re-running $(printf '%s\n' "$names" | wc -l) benchmark(s) of $b beyond the threshold ..." >&2
    "$build/bench/$b" --benchmark_format=json --benchmark_filter="$regex" >"$out/$b.rerun.json"
    results+=("$out/$b.rerun.json")
  done
fi
"${compare[@]}" "${results[@]}" "${flags[@]}"
