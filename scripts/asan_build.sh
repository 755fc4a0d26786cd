#!/usr/bin/env bash
# Configures the sanitized build in build-asan/ (or $FIBRA_ASAN_DIR) and builds the targets
# given: Clang, AddressSanitizer and UndefinedBehaviorSanitizer, libFuzzer's coverage in
# fibra's library and its harnesses (fuzz/), -O1 with assertions on (no NDEBUG: Eigen checks
# its indices too); FIBRA_SANITIZE (CMakeLists.txt) adds the sanitizers and line tables only for
# debug information (-g1: the reports' stacks still name files and lines; full debug information
# makes the objects up to 5 times larger and most units' compiling 20-35 % slower). Used by
# scripts/sanitize.sh and scripts/fuzz.sh (docs/sanitizers.md).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FIBRA_ASAN_DIR:-$root/build-asan}"
bash "$root/scripts/deps.sh" sanitize
CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1" \
  -DFIBRA_FUZZ=ON -DFIBRA_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "${FIBRA_JOBS:-$(nproc)}" --target "$@"
