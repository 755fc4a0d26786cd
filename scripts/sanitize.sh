#!/usr/bin/env bash
# The unit tests (ctest label "unit") in the sanitized build (scripts/asan_build.sh,
# docs/sanitizers.md). Every sanitizer report fails its test, and so this script.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FIBRA_ASAN_DIR:-$root/build-asan}"
bash "$root/scripts/asan_build.sh" fibra_unit_tests
cd "$build"
ctest --output-on-failure -j "${FIBRA_JOBS:-$(nproc)}" -L unit --timeout 900
